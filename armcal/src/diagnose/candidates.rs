//! The candidate causes: every term of the spec's vocabulary, and which of them these data can
//! see at all.
//!
//! Candidates are every effect's vocabulary ([`crate::effects::Family::vocabulary`]): the
//! encoder harmonics of every joint and every order up to the smaller of a cap (default
//! [`MAX_ORDER`], `diagnose --max-order`) and what the joint's readings resolve
//! ([`crate::effects::harmonic::resolvable_order`]; orders beyond it are listed as not
//! testable, with the reason), the gravity compliance of every joint, and
//! the thermal expansion of every link and the probe when the data have a temperature spread. Before any is tested, the structural identifiability of the geometric
//! model with all of them (the calibration's own analysis, at the arm's nominal skeleton) sorts
//! them:
//! - no effect on these data: gravity on a joint whose axis stays vertical (joint 1 of
//!   `default-6` or of a Panda: a_k · ((p − o_k) × ẑ) is identically 0), thermal terms without
//!   a temperature spread;
//! - indistinguishable from another candidate: the thermal expansion of collinear links
//!   (links 2 and 3, 4 and 5, link 6 and the probe of `default-6`). The pair is one candidate,
//!   named by its lower joint with the other listed;
//! - indistinguishable from the geometric model (or the instrument frame): the data could
//!   never name it, so it is not tested, and the report says so. An effect only part of
//!   whose unknowns the geometry absorbs (an order-1 axis wobble: its co-rotating half is the
//!   next link's frame turned) is tested with that part held.

use crate::data::Dataset;
use crate::fit::ident::{Fixed, Identifiability, Why};
use crate::fit::structure::{structural, unknowns};
use crate::params::{Effect, Param, ParamExt, Terms};
use quatarm_ref::arm::Arm;

/// Highest harmonic order tried by default.
pub const MAX_ORDER: u32 = crate::effects::harmonic::DIAGNOSIS_MAX_ORDER;

/// Smallest temperature spread (°C, max − min) for which thermal terms are candidates.
pub const MIN_TEMP_SPREAD_C: f64 = 1.0;

/// A candidate the data can test.
#[derive(Clone, Debug, PartialEq)]
pub struct Candidate {
    /// The effect fitted when it is named.
    pub effect: Effect,
    /// Effects the data cannot tell from it (a collinear link's thermal expansion): they are
    /// named with it, and never fitted.
    pub indistinguishable: Vec<Effect>,
    /// Its unknowns the test fits: all of the effect's, less those the geometric model
    /// absorbs (the co-rotating half of an order-1 axis wobble), which a calibration holds.
    pub fitted: Vec<Param>,
}

/// A candidate the data cannot test, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Untestable {
    /// The effect.
    pub effect: Effect,
    /// Why, in words.
    pub reason: String,
}

/// The candidates for an arm and data set.
#[derive(Clone, Debug, Default)]
pub struct Candidates {
    /// Those to test.
    pub testable: Vec<Candidate>,
    /// Those the data cannot see or separate.
    pub untestable: Vec<Untestable>,
    /// Whether thermal terms were considered (the data have a temperature spread).
    pub thermal: bool,
    /// Temperature range of the data (°C), when it has a temperature column.
    pub temp_range: Option<(f64, f64)>,
}

pub use crate::effects::vocabulary;

/// The effect a calibration unknown belongs to.
pub fn effect_of(p: Param) -> Option<Effect> {
    p.effect().map(|(e, _)| e)
}

/// The data's temperature range, when they record temperatures.
pub fn temperature_range(data: &Dataset) -> Option<(f64, f64)> {
    if !data.has_temperature || data.rows.is_empty() {
        return None;
    }
    Some(
        data.rows
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
                (a.min(r.temp_c), b.max(r.temp_c))
            }),
    )
}

/// Sorts the vocabulary into what these data can test, harmonics up to [`MAX_ORDER`].
pub fn candidates(start: &Arm, data: &Dataset) -> Candidates {
    candidates_up_to(start, data, MAX_ORDER)
}

/// Sorts the vocabulary into what these data can test, harmonics up to order `max_order` or
/// what each joint's readings resolve, whichever is lower.
///
/// Each effect is judged with every candidate at once first; one held there is judged again
/// alone with the geometric model (`alone_with_geometry`) unless another candidate alone
/// explains it (`twin_of`), so that an effect is refused only for what it cannot be told
/// from.
pub fn candidates_up_to(start: &Arm, data: &Dataset, max_order: u32) -> Candidates {
    let temp_range = temperature_range(data);
    let thermal = temp_range.is_some_and(|(lo, hi)| hi - lo >= MIN_TEMP_SPREAD_C);
    let mut out = Candidates {
        thermal,
        temp_range,
        ..Candidates::default()
    };
    let vocab = resolvable_vocabulary(data, thermal, max_order, &mut out.untestable);
    let terms = Terms::with(&vocab);
    let all = unknowns(start, &terms, data);
    let (id, _) = structural(start, data, &all, 1e-8);
    // Effects of which some unknown is held, and why.
    for e in &vocab {
        let held = held_of(&id, &all, *e);
        if held.is_empty() {
            out.testable.push(Candidate {
                effect: *e,
                indistinguishable: Vec::new(),
                fitted: e.params(),
            });
            continue;
        }
        if held.iter().all(|f| f.why == Why::NoEffect) {
            out.untestable.push(Untestable {
                effect: *e,
                reason: no_effect_reason(start, *e, thermal),
            });
            continue;
        }
        if let Some(t) = twin_of(&held, &all, *e) {
            out.untestable.push(Untestable {
                effect: *e,
                reason: format!(
                    "indistinguishable from {} (named with it)",
                    describe_effect(start, t)
                ),
            });
            if let Some(c) = out.testable.iter_mut().find(|c| c.effect == t) {
                c.indistinguishable.push(*e);
            }
            continue;
        }
        match alone_with_geometry(start, data, *e) {
            Ok(c) => out.testable.push(c),
            Err(u) => out.untestable.push(u),
        }
    }
    out
}

/// The vocabulary of `dof` joints (thermal terms where the temperatures spread), harmonics and
/// wobbles above `max_order` left out, and those above what a joint's readings resolve
/// added to `untestable` with the reason.
fn resolvable_vocabulary(
    data: &Dataset,
    thermal: bool,
    max_order: u32,
    untestable: &mut Vec<Untestable>,
) -> Vec<Effect> {
    let resolvable: Vec<u32> = (0..data.dof)
        .map(|k| crate::effects::harmonic::resolvable_order(data, k))
        .collect();
    let mut vocab = Vec::new();
    for e in vocabulary(data.dof, thermal) {
        match e {
            Effect::Harmonic { order, .. } | Effect::Wobble { order, .. } if order > max_order => {}
            Effect::Harmonic { joint, order } | Effect::Wobble { joint, order }
                if order > resolvable[joint] =>
            {
                untestable.push(Untestable {
                    effect: e,
                    reason: format!(
                        "joint {}'s readings resolve waves up to order {} (their widest gap \
                         and count)",
                        joint + 1,
                        resolvable[joint]
                    ),
                })
            }
            _ => vocab.push(e),
        }
    }
    vocab
}

/// The one other candidate that alone absorbs a held unknown of `e` exactly (its twin: the
/// two are named together), if there is one; `all` are the unknowns `held` indexes.
fn twin_of(held: &[&Fixed], all: &[Param], e: Effect) -> Option<Effect> {
    held.iter().find_map(|f| {
        let by = &f.absorbed_by;
        (by.len() == 1 && f.unexplained < 1e-6)
            .then(|| effect_of(all[by[0].0]))
            .flatten()
            .filter(|t| *t != e)
    })
}

/// Effect `e` judged alone with the geometric model: held among all candidates, it may be
/// inseparable only together with others. A candidate when nothing of it is held, or when
/// what is held is geometry (the co-rotating half of an order-1 axis wobble is the next
/// link's frame turned): then it is fitted with the geometry's share held as the calibration
/// holds it. Otherwise untestable, with the parameters it cannot be told from.
fn alone_with_geometry(start: &Arm, data: &Dataset, e: Effect) -> Result<Candidate, Untestable> {
    let alone = unknowns(start, &Terms::with(&[e]), data);
    let (id1, _) = structural(start, data, &alone, 1e-8);
    let blocked = held_of(&id1, &alone, e);
    let partly_geometric = blocked.len() < e.params().len()
        && blocked.iter().all(|f| {
            f.why == Why::Inseparable
                && f.absorbed_by
                    .iter()
                    .all(|&(k, _)| effect_of(alone[k]).is_none_or(|o| o == e))
        });
    if blocked.is_empty() || partly_geometric {
        let held: Vec<Param> = blocked.iter().map(|f| alone[f.index]).collect();
        return Ok(Candidate {
            effect: e,
            indistinguishable: Vec::new(),
            fitted: e
                .params()
                .into_iter()
                .filter(|p| !held.contains(p))
                .collect(),
        });
    }
    let by: Vec<String> = blocked
        .iter()
        .flat_map(|f| f.absorbed_by.iter().take(3))
        .map(|&(k, _)| alone[k].describe(start))
        .collect();
    Err(Untestable {
        effect: e,
        reason: if by.is_empty() {
            "its effect on these data equals that of the geometric model's parameters".into()
        } else {
            format!("its effect on these data equals that of {}", by.join(", "))
        },
    })
}

/// The unknowns of effect `e` that the identifiability analysis `id` of `unknowns` held.
fn held_of<'a>(id: &'a Identifiability, unknowns: &[Param], e: Effect) -> Vec<&'a Fixed> {
    id.fixed
        .iter()
        .filter(|f| effect_of(unknowns[f.index]) == Some(e))
        .collect()
}

fn no_effect_reason(arm: &Arm, e: Effect, thermal: bool) -> String {
    e.with(|t| t.no_effect_reason(arm, thermal))
        .unwrap_or_else(|| {
            format!(
                "{} does not change any residual of these data",
                e.describe()
            )
        })
}

/// An effect in words, joints 1-based.
pub fn describe_effect(_arm: &Arm, e: Effect) -> String {
    e.describe()
}
