//! Partial pooling as a candidate of the fleet diagnosis (`armcal diagnose --fleet`).
//!
//! The fleet's design-level test ([`super::fleet`]) asks whether a cause's held-out gain is
//! shared by the design's arms; an effect whose size differs from arm to arm, and which each
//! arm measures poorly, passes neither that test nor any arm's own. This stage gives every
//! one-unknown candidate of the vocabulary (a joint's gravity compliance, a thermal
//! coefficient) its hierarchical model ([`super::pooling`]): each arm's value, with its
//! jackknife error over its sessions, drawn from the design's distribution (mean μ, spread τ).
//!
//! **What is named.** The design's mean of each candidate is tested two-sided (Hartung–Knapp,
//! arms − 1 degrees of freedom) and the p-values corrected by Holm over the candidates at the
//! fleet's `alpha`; for a candidate that passes, the effect is named for every arm whose pooled
//! interval (at 1 − `alpha`, t on the arm's own error's degrees of freedom or arms − 1 where
//! fewer: [`super::pooling::interval_df`]) excludes zero, each arm weighed by the error
//! `opts.error_scale` says (by default its jackknife error's scale pooled over the fleet where
//! Bartlett's test does not reject one scale for the design, [`super::pooling::pool_fleet_scale`];
//! else its own), and each such arm's **held-out
//! gain** is measured nested ([`super::pooling::pooled_holdout`]: each session scored with the
//! value pooled from the arm's other sessions and the other arms).
//!
//! **Every recording of an arm.** The pooled model needs one estimate per physical arm; an arm
//! of several recordings (each with its own tool and frame, so each fitted with its own probe:
//! the probe is one of the geometric unknowns every recording's fit refits) gives one estimate
//! per recording of [`crate::stats::MIN_UNITS`] sessions or more, combined by inverse variance
//! ([`super::pooling::combine_recordings`]). Recordings with fewer sessions have no jackknife
//! error and are left out of an arm that has a longer one. An arm with none, but a recording
//! of [`MIN_JOINED`] sessions or more (MUKCa's panda_7), is left out, said, unless
//! `opts.join_short` (`--join-short`; off by default, its φ cannot be tested): then it
//! **joins on the fleet's error scale**:
//! its value from one fit on all its sessions, weighed by √φ̂ times that fit's in-sample error
//! ([`super::pooling::pool_fleet_scale_joined`]; it gives nothing to φ̂ and does not count
//! towards the fleet's least number of arms), with no held-out gain (too few sessions to leave
//! one out). Where the fleet's scale is not used (`--error-scale own`, or Bartlett's test
//! rejects one scale for a candidate) it cannot be weighed and is left out, said; so is an arm
//! of one session. Which recordings are one arm is the fleet's grouping (`arms`), whose source
//! (detected from the data, given by hand, or each file an arm) the fleet report says.
//!
//! This module sits above both [`super::fleet`] (whose arms and candidates it reads) and
//! [`super::pooling`] (which it calls): neither of them knows it.

use super::fleet::{geometric_options, holm, ErrorScale, Fleet, Options, PooledModel, UnitData};
use super::pooling::{self, Arm as PooledValue, Combined, Design, Dispersion, Estimate};
use crate::data::Dataset;
use crate::fit::error::CalibError;
use crate::fit::holdout::by_group;
use crate::params::Effect;
use crate::stats::{min_sign_p, sign_test_p, Paired, MIN_UNITS};
use quatarm_ref::arm::Arm;
use std::collections::BTreeSet;

/// One arm in a pooled candidate.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PooledArm {
    /// The arm's name.
    pub arm: String,
    /// The recordings whose sessions gave its estimate.
    pub recordings: Vec<String>,
    /// Their sessions, in all.
    pub sessions: usize,
    /// Each recording's own estimate (value, jackknife standard error and its degrees of
    /// freedom), in `recordings`' order.
    pub per_recording: Vec<Estimate>,
    /// Their combination (the arm's "alone" estimate below).
    pub combined: Combined,
    /// Whether its estimate has a jackknife error; `false` for an arm whose one recording has
    /// too few sessions ([`MIN_JOINED`] to [`MIN_UNITS`] − 1), pooled only on the fleet's error
    /// scale (√φ̂ times its in-sample error), with no held-out gain.
    pub jackknife: bool,
    /// Alone and pooled.
    #[serde(flatten)]
    pub value: PooledValue,
    /// The nested held-out gain of its pooled value (only where the effect is named for it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub holdout: Option<PooledGain>,
}

/// The nested held-out gain of an arm's pooled value.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PooledGain {
    /// Sessions scored.
    pub sessions: usize,
    /// Held-out RMS (µm) of the geometric model and of the model with the pooled value fixed,
    /// every session weighing the same.
    pub rms_um: [f64; 2],
    /// Sessions on which the pooled value predicts strictly better.
    pub sessions_better: usize,
    /// Paired t of the per-session mean squared errors and its one-sided p.
    pub t: f64,
    /// Its one-sided p.
    pub t_p_value: f64,
    /// Exact one-sided sign-test p.
    pub sign_test_p_value: f64,
    /// The smallest p a sign test on these sessions can give.
    pub smallest_possible_p: f64,
}

/// One candidate pooled over the arms.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PooledEffect {
    /// The candidate (`+gravity_compliance:2`).
    pub term: String,
    /// The effect.
    #[serde(skip)]
    pub effect: Effect,
    /// The design's distribution of its value.
    pub design: Design,
    /// Whether the design's mean passes Holm over the pooled candidates at `alpha`.
    pub named: bool,
    /// The arms' errors' dispersion over their in-sample errors and its homogeneity test
    /// (with [`ErrorScale::Fleet`], where every arm has both errors).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dispersion: Option<Dispersion>,
    /// Whether the arms were pooled with the fleet's error scale (√φ̂ times their in-sample
    /// error); false with [`ErrorScale::Own`] or where the homogeneity test failed at `alpha`
    /// (then each arm's own jackknife error, as with `Own`).
    pub fleet_scaled: bool,
    /// Every pooled arm.
    pub arms: Vec<PooledArm>,
}

/// The pooled stage of a fleet diagnosis.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct PooledFleet {
    /// The family-wise level (Holm over the candidates) and 1 − the intervals' level.
    pub alpha: f64,
    /// The model the candidates were estimated in.
    pub model: PooledModel,
    /// Every one-unknown candidate pooled, the most significant design mean first.
    pub effects: Vec<PooledEffect>,
    /// Arms, recordings of an arm, or candidates left out, with why.
    pub left_out: Vec<(String, String)>,
}

/// Fewest sessions of a recording that joins the pool without a jackknife error (issue 30's
/// panda_7): two, so that its in-sample error is not one placement's alone.
pub const MIN_JOINED: usize = 2;

/// An arm pooled: its name, its recordings used (index, sessions), and whether they have a
/// jackknife error (else one recording of [`MIN_JOINED`] to [`MIN_UNITS`] − 1 sessions,
/// joined on the fleet's error scale). The arms without come last: the pool takes them after
/// the others ([`pooling::pool_fleet_scale_joined`]).
struct Used {
    name: String,
    recs: Vec<(usize, usize)>,
    jackknife: bool,
}

/// An arm or a recording left out: (name, why).
type LeftOut = (String, String);

/// An arm's estimate of a candidate: each recording's, and their combination.
type ArmEstimate = (Vec<Estimate>, Combined);

/// Each arm's recordings of [`MIN_UNITS`] sessions or more, then, with `opts.join_short`, the
/// arms with none but one of [`MIN_JOINED`] sessions or more (their longest recording; only
/// where the error scale is the fleet's, the one way they can be weighed), and the arms and
/// recordings left out with why.
fn recordings(
    units: &[UnitData],
    arms: &[(String, Vec<usize>)],
    opts: &Options,
) -> (Vec<Used>, Vec<LeftOut>) {
    let mut used = Vec::new();
    let mut joined = Vec::new();
    let mut left_out = Vec::new();
    for (name, recs) in arms {
        let sessions: Vec<(usize, usize)> = recs
            .iter()
            .filter(|&&r| r < units.len())
            .map(|&r| (r, by_group(&units[r].data).len()))
            .collect();
        let mine: Vec<(usize, usize)> = sessions
            .iter()
            .copied()
            .filter(|(_, n)| *n >= MIN_UNITS)
            .collect();
        if !mine.is_empty() {
            for &(r, n) in sessions.iter().filter(|(_, n)| *n < MIN_UNITS) {
                left_out.push((
                    format!("{name}: recording {}", units[r].name),
                    format!(
                        "{n} session(s), fewer than {MIN_UNITS}: no jackknife error to weigh \
                         it by; the arm's other recordings are pooled"
                    ),
                ));
            }
            used.push(Used {
                name: name.clone(),
                recs: mine,
                jackknife: true,
            });
            continue;
        }
        // The longest recording (the first of the longest).
        let longest = sessions
            .iter()
            .copied()
            .fold(None, |b: Option<(usize, usize)>, s| match b {
                Some(b) if b.1 >= s.1 => Some(b),
                _ => Some(s),
            });
        match longest {
            Some((r, n))
                if n >= MIN_JOINED && opts.join_short && opts.error_scale == ErrorScale::Fleet =>
            {
                for &(o, m) in sessions.iter().filter(|(o, _)| *o != r) {
                    left_out.push((
                        format!("{name}: recording {}", units[o].name),
                        format!(
                            "{m} session(s): the arm joins by its longest recording, {}",
                            units[r].name
                        ),
                    ));
                }
                joined.push(Used {
                    name: name.clone(),
                    recs: vec![(r, n)],
                    jackknife: false,
                });
            }
            Some((_, n)) if n >= MIN_JOINED && opts.join_short => left_out.push((
                name.clone(),
                format!(
                    "no recording of {MIN_UNITS} sessions or more (its longest has {n}): \
                     without a jackknife error it joins only on the fleet's error scale \
                     (--error-scale fleet)"
                ),
            )),
            Some((_, n)) if n >= MIN_JOINED => left_out.push((
                name.clone(),
                format!(
                    "no recording of {MIN_UNITS} sessions or more (its longest has {n}): no \
                     jackknife error to weigh its estimate by (--join-short weighs it on the \
                     fleet's error scale)"
                ),
            )),
            _ => left_out.push((
                name.clone(),
                format!(
                    "no recording of {MIN_JOINED} sessions or more: neither a jackknife error \
                     nor an in-sample error over sessions to weigh its estimate by"
                ),
            )),
        }
    }
    used.extend(joined);
    (used, left_out)
}

/// The pooled stage of the fleet diagnosis `f` of `units` (see the module's text): its arms,
/// and the candidates each recording could test.
pub fn pool_fleet(
    start: &Arm,
    units: &[UnitData],
    f: &Fleet,
    opts: &Options,
) -> Result<PooledFleet, CalibError> {
    let testable: Vec<Vec<Effect>> = f
        .units
        .iter()
        .map(|u| u.candidates.testable.iter().map(|c| c.effect).collect())
        .collect();
    pool_arms(start, units, &f.arms, &testable, opts)
}

/// Pools every one-unknown candidate that every used arm's recording can test (`testable`,
/// one list per recording) over the arms `arms` (name, recordings) of `units`, names them
/// ([`pool_candidates`]) and measures each named arm's nested held-out gain.
pub fn pool_arms(
    start: &Arm,
    units: &[UnitData],
    arms: &[(String, Vec<usize>)],
    testable: &[Vec<Effect>],
    opts: &Options,
) -> Result<PooledFleet, CalibError> {
    let mut out = match opts.pooled_model {
        PooledModel::Alone => pool_candidates(start, units, arms, testable, opts),
        PooledModel::Full => match try_full(start, units, arms, testable, opts) {
            Ok(full) => full,
            // A recording's full fit could not be made: every candidate alone, said.
            Err((_, (what, why))) => {
                let mut alone = pool_candidates(start, units, arms, testable, opts);
                alone
                    .left_out
                    .push((what, format!("{why}; each candidate pooled alone")));
                alone
            }
        },
    };
    let (used, _) = recordings(units, arms, opts);
    let calib = geometric_options(opts);
    let data: Vec<Vec<&Dataset>> = used
        .iter()
        .map(|u| u.recs.iter().map(|(r, _)| &units[*r].data).collect())
        .collect();
    for p in out.effects.iter_mut().filter(|p| p.named) {
        held_out_gains(start, &data, &calib, opts.alpha, p)?;
    }
    Ok(out)
}

/// [`pool_arms`] without the held-out gains: the candidates pooled and named (Holm over them
/// at `opts.alpha`, each arm by its pooled interval). What the power over simulated fleets
/// counts (`examples/pooling_power.rs`), at a fifth of the fits.
pub fn pool_candidates(
    start: &Arm,
    units: &[UnitData],
    arms: &[(String, Vec<usize>)],
    testable: &[Vec<Effect>],
    opts: &Options,
) -> PooledFleet {
    let (used, out) = match begin(units, arms, opts) {
        Ok(begun) => begun,
        Err(out) => return out,
    };
    pool_alone(start, units, &used, out, testable, opts)
}

/// [`pool_candidates`] with every candidate estimated in the **full model**: each recording's
/// values of all the shared candidates from one fit with all their terms
/// ([`pooling::estimate_joint`]), so each candidate is conditional on all the others (a Wald
/// test in one model fixed before the data, whose level depends on no selection); then pooled
/// and named exactly as the product does (Holm over the candidates at `opts.alpha`, each arm by
/// its pooled interval). `armcal diagnose --fleet`'s default since stop 40 (with the fleet's
/// error scale: no alias named in 1,500 mixed fleets at α = 0.01, docs/results/claims.md
/// §7.9, §7.11). When a recording's full fit fails or cannot be made, nothing is pooled and
/// the reason is in `left_out` ([`pool_arms`] then pools each candidate alone).
pub fn pool_candidates_full(
    start: &Arm,
    units: &[UnitData],
    arms: &[(String, Vec<usize>)],
    testable: &[Vec<Effect>],
    opts: &Options,
) -> PooledFleet {
    try_full(start, units, arms, testable, opts).unwrap_or_else(|(mut out, failed)| {
        out.left_out.push(failed);
        out
    })
}

/// [`pool_candidates_full`], with a recording whose full fit fails or cannot be made an `Err`
/// of the fleet so far (nothing pooled) and why, so that [`pool_arms`] can pool each
/// candidate alone instead.
fn try_full(
    start: &Arm,
    units: &[UnitData],
    arms: &[(String, Vec<usize>)],
    testable: &[Vec<Effect>],
    opts: &Options,
) -> Result<PooledFleet, (PooledFleet, LeftOut)> {
    let (used, mut out) = match begin(units, arms, opts) {
        Ok(begun) => begun,
        Err(out) => return Ok(out),
    };
    out.model = PooledModel::Full;
    let calib = geometric_options(opts);
    let vocabulary: Vec<Effect> = shared_vocabulary(&used, testable).into_iter().collect();
    let terms: Vec<String> = vocabulary.iter().map(|e| e.spec()).collect();
    // Per arm, per recording: every candidate's estimate in the full model.
    let mut per_arm: Vec<Vec<Vec<Estimate>>> = Vec::new();
    for u in &used {
        let mut est = Vec::new();
        for (r, _) in &u.recs {
            let data = &units[*r].data;
            let fit = if u.jackknife {
                pooling::estimate_joint(start, data, &calib, &vocabulary)
            } else {
                pooling::estimate_joint_in_sample(start, data, &calib, &vocabulary)
                    .map(|v| v.map(|v| v.into_iter().map(Estimate::in_sample).collect()))
            };
            let why = match fit {
                Ok(Some(v)) => {
                    est.push(v);
                    continue;
                }
                Ok(None) => "it cannot be estimated".to_string(),
                Err(err) => err.to_string(),
            };
            let failed = format!(
                "the full model failed on recording {}: {why}",
                units[*r].name
            );
            return Err((out, (terms.join(" "), failed)));
        }
        per_arm.push(est);
    }
    let how = (opts.error_scale, opts.alpha);
    for (i, &e) in vocabulary.iter().enumerate() {
        let mine: Option<Vec<ArmEstimate>> = per_arm
            .iter()
            .zip(&used)
            .map(|(recs, u)| {
                let est: Vec<Estimate> = recs.iter().map(|v| v[i]).collect();
                let c = combine(u, &est)?;
                Some((est, c))
            })
            .collect();
        if let Some(p) =
            mine.and_then(|m| pool_estimates(units, &used, e, m, how, &mut out.left_out))
        {
            out.effects.push(p);
        }
    }
    Ok(named(out))
}

/// The recordings each arm pools ([`recordings`]) and the fleet's result so far (nothing
/// named, what was left out and why); `Err` with that result where fewer arms than a fleet
/// needs are left, so that both namings (alone and in the full model) start and stop alike.
fn begin(
    units: &[UnitData],
    arms: &[(String, Vec<usize>)],
    opts: &Options,
) -> Result<(Vec<Used>, PooledFleet), PooledFleet> {
    let (used, left_out) = recordings(units, arms, opts);
    let out = PooledFleet {
        alpha: opts.alpha,
        model: PooledModel::Alone,
        effects: Vec::new(),
        left_out,
    };
    // The arms without a jackknife error do not count: φ̂ and the design rest on the others.
    if used.iter().filter(|u| u.jackknife).count() < super::fleet::MIN_FLEET_UNITS {
        return Err(out);
    }
    Ok((used, out))
}

/// `out` with its candidates named by Holm at its α and listed by their design mean's p,
/// smallest first: the last step of both namings.
fn named(mut out: PooledFleet) -> PooledFleet {
    name_by_holm(&mut out.effects, out.alpha);
    out.effects
        .sort_by(|a, b| a.design.mean_p.total_cmp(&b.design.mean_p));
    out
}

/// [`pool_candidates`] on the used arms: each candidate estimated against the geometric model
/// alone.
fn pool_alone(
    start: &Arm,
    units: &[UnitData],
    used: &[Used],
    mut out: PooledFleet,
    testable: &[Vec<Effect>],
    opts: &Options,
) -> PooledFleet {
    let calib = geometric_options(opts);
    let how = (opts.error_scale, opts.alpha);
    for e in shared_vocabulary(used, testable) {
        if let Some(p) = pool_effect(start, units, used, &calib, e, how, &mut out.left_out) {
            out.effects.push(p);
        }
    }
    named(out)
}

/// The one-unknown candidates every used recording can test (`testable`, one list per
/// recording): a value missing for one arm would leave the design's distribution estimated
/// from the others only, unsaid.
fn shared_vocabulary(used: &[Used], testable: &[Vec<Effect>]) -> BTreeSet<Effect> {
    let one_unknown = |r: usize| -> BTreeSet<Effect> {
        testable
            .get(r)
            .map(|t| {
                t.iter()
                    .copied()
                    .filter(|e| e.params().len() == 1)
                    .collect()
            })
            .unwrap_or_default()
    };
    let mut all_recordings = used.iter().flat_map(|u| u.recs.iter().map(|(r, _)| *r));
    let mut vocabulary = all_recordings.next().map(one_unknown).unwrap_or_default();
    for r in all_recordings {
        vocabulary = vocabulary.intersection(&one_unknown(r)).copied().collect();
    }
    vocabulary
}

/// Each used arm's estimate of `e`: every recording's own (its own probe and frame), then
/// their combination. `None` when a recording cannot estimate it or its estimates do not
/// combine; a fit that fails (one candidate on one recording) also pushes the reason to
/// `left_out`, leaving that candidate unpooled rather than failing the whole fleet report.
fn arm_estimates(
    start: &Arm,
    units: &[UnitData],
    used: &[Used],
    calib: &crate::fit::options::Options,
    e: Effect,
    left_out: &mut Vec<LeftOut>,
) -> Option<Vec<ArmEstimate>> {
    let mut per_arm = Vec::new();
    for u in used {
        let mut est = Vec::new();
        for (r, _) in &u.recs {
            let data = &units[*r].data;
            let fit = if u.jackknife {
                pooling::estimate(start, data, calib, e)
            } else {
                pooling::estimate_in_sample(start, data, calib, e)
                    .map(|v| v.map(Estimate::in_sample))
            };
            match fit {
                Ok(Some(v)) => est.push(v),
                Ok(None) => return None,
                Err(err) => {
                    left_out.push((
                        e.spec(),
                        format!("the fit of recording {} failed: {err}", units[*r].name),
                    ));
                    return None;
                }
            }
        }
        let c = combine(u, &est)?;
        per_arm.push((est, c));
    }
    Some(per_arm)
}

/// The candidate `e` pooled over the used arms (not yet named: [`name_by_holm`] does that
/// over all candidates), or `None` when it cannot be (see [`arm_estimates`]).
fn pool_effect(
    start: &Arm,
    units: &[UnitData],
    used: &[Used],
    calib: &crate::fit::options::Options,
    e: Effect,
    (scale, alpha): (ErrorScale, f64),
    left_out: &mut Vec<LeftOut>,
) -> Option<PooledEffect> {
    let per_arm = arm_estimates(start, units, used, calib, e, left_out)?;
    pool_estimates(units, used, e, per_arm, (scale, alpha), left_out)
}

/// An arm's combination of its recordings' estimates `est`: by inverse variance where they
/// have a jackknife error ([`pooling::combine_recordings`]), else its one recording's value
/// and in-sample error ([`Combined::in_sample`]).
fn combine(u: &Used, est: &[Estimate]) -> Option<Combined> {
    if u.jackknife {
        pooling::combine_recordings(est)
    } else {
        est.first().map(Combined::in_sample)
    }
}

/// The candidate `e` pooled from each used arm's estimates `per_arm` with the errors `scale`
/// says (not yet named). An arm without a jackknife error that the pool could not weigh (the
/// fleet's scale rejected for this candidate) is pushed to `left_out` with why.
fn pool_estimates(
    units: &[UnitData],
    used: &[Used],
    e: Effect,
    per_arm: Vec<ArmEstimate>,
    (scale, alpha): (ErrorScale, f64),
    left_out: &mut Vec<LeftOut>,
) -> Option<PooledEffect> {
    let combined: Vec<&Combined> = per_arm.iter().map(|(_, c)| c).collect();
    let jackknife: Vec<bool> = used.iter().map(|u| u.jackknife).collect();
    let (dispersion, fleet_scaled, design, values) =
        pool_combined(&combined, &jackknife, scale, alpha)?;
    for u in used.iter().skip(values.len()) {
        left_out.push(unweighed(&u.name, &e.spec()));
    }
    let arms = used
        .iter()
        .zip(per_arm)
        .zip(values)
        .map(|((u, (est, combined)), value)| PooledArm {
            arm: u.name.clone(),
            recordings: u.recs.iter().map(|(r, _)| units[*r].name.clone()).collect(),
            sessions: u.recs.iter().map(|(_, n)| n).sum(),
            per_recording: est,
            combined,
            jackknife: u.jackknife,
            value,
            holdout: None,
        })
        .collect();
    Some(PooledEffect {
        term: e.spec(),
        effect: e,
        design,
        named: false,
        dispersion,
        fleet_scaled,
        arms,
    })
}

/// An arm without a jackknife error left out of candidate `term`'s pool (the one way to
/// weigh it, the fleet's error scale, not used for it).
fn unweighed(arm: &str, term: &str) -> LeftOut {
    (
        format!("{arm}: {term}"),
        "no jackknife error, and the fleet's error scale was not used for this candidate \
         (`--error-scale own`, or Bartlett's test rejected one scale): nothing to weigh its \
         estimate by"
            .to_string(),
    )
}

/// The arms' estimates `combined` pooled with the errors `scale` says: the one place both
/// [`pool_estimates`] and [`repool`] pool.
/// `jackknife` says which arms have a jackknife error; those without come last and are
/// pooled only on the fleet's scale.
fn pool_combined(
    combined: &[&Combined],
    jackknife: &[bool],
    scale: ErrorScale,
    alpha: f64,
) -> Option<pooling::ScaledPool> {
    let n = jackknife.iter().filter(|j| **j).count();
    let (own, joined) = combined.split_at(n.min(combined.len()));
    let y: Vec<f64> = own.iter().map(|c| c.estimate).collect();
    let se: Vec<f64> = own.iter().map(|c| c.se).collect();
    let df: Vec<f64> = own.iter().map(|c| c.df).collect();
    let model: Vec<f64> = own.iter().map(|c| c.model_se).collect();
    let joined: Vec<(f64, f64)> = joined.iter().map(|c| (c.estimate, c.model_se)).collect();
    pooling::pool_with(scale, &y, &se, &df, &model, &joined, alpha)
}

/// `fleet`'s candidates pooled again from the same estimates with the errors `scale` says and
/// named afresh at `alpha` (Holm over the candidates, intervals at 1 − `alpha`; no held-out
/// gains): what the choice of errors or level changes, without a fit
/// (`examples/pooling_power.rs` counts both choices on each simulated fleet). A candidate that
/// cannot be pooled so is left out with the reason.
pub fn repool(fleet: &PooledFleet, scale: ErrorScale, alpha: f64) -> PooledFleet {
    let mut out = PooledFleet {
        alpha,
        model: fleet.model,
        effects: Vec::new(),
        left_out: fleet.left_out.clone(),
    };
    for p in &fleet.effects {
        let combined: Vec<&Combined> = p.arms.iter().map(|a| &a.combined).collect();
        let jackknife: Vec<bool> = p.arms.iter().map(|a| a.jackknife).collect();
        let Some((dispersion, fleet_scaled, design, values)) =
            pool_combined(&combined, &jackknife, scale, alpha)
        else {
            out.left_out
                .push((p.term.clone(), "cannot be pooled again".to_string()));
            continue;
        };
        for a in p.arms.iter().skip(values.len()) {
            out.left_out.push(unweighed(&a.arm, &p.term));
        }
        let arms = p
            .arms
            .iter()
            .zip(values)
            .map(|(a, value)| PooledArm {
                value,
                holdout: None,
                ..a.clone()
            })
            .collect();
        out.effects.push(PooledEffect {
            design,
            named: false,
            dispersion,
            fleet_scaled,
            arms,
            ..p.clone()
        });
    }
    named(out)
}

/// Names the candidates whose design mean passes Holm at `alpha` over all of them, and keeps
/// an arm's pooled naming only where its candidate is named.
fn name_by_holm(effects: &mut [PooledEffect], alpha: f64) {
    let ps: Vec<f64> = effects.iter().map(|p| p.design.mean_p).collect();
    for (p, named) in effects.iter_mut().zip(holm(&ps, alpha)) {
        p.named = named;
        p.design.named = named;
        for a in &mut p.arms {
            a.value.named_pooled &= named;
        }
    }
}

/// The nested held-out gain of every arm the pooled effect `p` is named for, over the sessions
/// of all its recordings (`data`, one list per arm): each recording's sessions scored in turn,
/// its estimate from its other sessions combined with the arm's other recordings.
fn held_out_gains(
    start: &Arm,
    data: &[Vec<&Dataset>],
    calib: &crate::fit::options::Options,
    alpha: f64,
    p: &mut PooledEffect,
) -> Result<(), CalibError> {
    let all: Vec<Estimate> = p
        .arms
        .iter()
        .map(|a| Estimate {
            value: a.value.estimate,
            se: a.value.se,
            df: a.value.se_df,
            model_se: a.combined.model_se,
        })
        .collect();
    for (i, a) in p.arms.iter_mut().enumerate() {
        // An arm without a jackknife has too few sessions to leave one out and estimate again.
        if !a.value.named_pooled || !a.jackknife {
            continue;
        }
        let others: Vec<Estimate> = all
            .iter()
            .enumerate()
            .filter(|(k, _)| *k != i)
            .map(|(_, v)| *v)
            .collect();
        let mut folds = Vec::new();
        for (k, d) in data[i].iter().enumerate() {
            let siblings: Vec<Estimate> = a
                .per_recording
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != k)
                .map(|(_, v)| *v)
                .collect();
            folds.extend(pooling::pooled_holdout(
                start, d, calib, p.effect, &siblings, &others, alpha,
            )?);
        }
        a.holdout = Some(gain(&folds));
    }
    Ok(())
}

/// The evidence over an arm's scored sessions.
fn gain(folds: &[pooling::PooledFold]) -> PooledGain {
    let (b, a): (Vec<f64>, Vec<f64>) = folds.iter().map(|f| (f.before_ms, f.after_ms)).unzip();
    let n = folds.len();
    let better = b.iter().zip(&a).filter(|(x, y)| y < x).count();
    let rms = |x: &[f64]| 1e3 * (x.iter().sum::<f64>() / n.max(1) as f64).sqrt();
    let paired = Paired::of(&b, &a);
    PooledGain {
        sessions: n,
        rms_um: [rms(&b), rms(&a)],
        sessions_better: better,
        t: paired.z(),
        t_p_value: paired.p_value(),
        sign_test_p_value: sign_test_p(better, n),
        smallest_possible_p: min_sign_p(n),
    }
}

impl PooledFleet {
    /// The text section of the fleet report.
    pub fn write_text(&self, s: &mut String) {
        use std::fmt::Write;
        let _ = writeln!(
            s,
            "\npooled effects (each arm's value drawn from the design's distribution, \
             DerSimonian–Laird; the design's mean tested two-sided, Holm at α = {}; named for \
             an arm whose pooled {:.0} % interval, t on its error's df or arms − 1 where \
             fewer, excludes 0; each arm's error its jackknife over its sessions, or where the \
             fleet's errors share one scale, √φ̂ times its fit's in-sample error; {})",
            self.alpha,
            100.0 * (1.0 - self.alpha),
            match self.model {
                PooledModel::Full =>
                    "each candidate fitted with all the others at once, the full model",
                PooledModel::Alone => "each candidate fitted with the geometric model alone",
            }
        );
        if self.effects.is_empty() {
            let _ = writeln!(s, "  none pooled (fewer than 3 arms with 3 sessions)");
        }
        for p in &self.effects {
            let d = &p.design;
            let joined: Vec<&str> = p
                .arms
                .iter()
                .filter(|a| !a.jackknife)
                .map(|a| a.arm.as_str())
                .collect();
            let _ = writeln!(
                s,
                "  {}: {} arms{}; design mean {:+.3e} [{:+.3e}, {:+.3e}], p = {:.1e}; spread τ \
                 {:.2e} [{:.2e}, {:.2e}]; {}",
                p.term,
                p.arms.len(),
                if joined.is_empty() {
                    String::new()
                } else {
                    format!(" ({} without a jackknife)", joined.join(", "))
                },
                d.mean,
                d.mean_interval[0],
                d.mean_interval[1],
                d.mean_p,
                d.spread,
                d.spread_interval[0],
                d.spread_interval[1],
                if p.named {
                    "named for the design"
                } else {
                    "not named"
                }
            );
            if let Some(d) = &p.dispersion {
                let _ = writeln!(
                    s,
                    "    errors: jackknife over in-sample variance φ̂ = {:.2} on {:.0} df, \
                     Bartlett's test of one φ p = {:.2}: {}",
                    d.phi,
                    d.df,
                    d.p,
                    if p.fleet_scaled {
                        "the fleet's scale used (√φ̂ × each arm's in-sample error)"
                    } else {
                        "rejected, each arm's own jackknife error used"
                    }
                );
            }
            if !p.named {
                continue;
            }
            for a in &p.arms {
                let _ = write!(
                    s,
                    "    {} ({}): alone {:+.3e} ± {:.1e} ({:.0} df), pooled {:+.3e} ± {:.1e} \
                     ({:.1} df, B = {:.2}){}",
                    a.arm,
                    a.recordings.join(" + "),
                    a.value.estimate,
                    a.value.se,
                    a.value.se_df,
                    a.value.pooled,
                    a.value.pooled_se,
                    a.value.df,
                    a.value.shrinkage,
                    if a.value.named_pooled { ", named" } else { "" }
                );
                if !a.jackknife {
                    let _ = write!(
                        s,
                        " [{} sessions: no jackknife, its in-sample error ± {:.1e} on the \
                         fleet's scale; no held-out gain]",
                        a.sessions, a.combined.model_se
                    );
                }
                if a.combined.recordings > 1 {
                    let each: Vec<String> = a
                        .recordings
                        .iter()
                        .zip(&a.per_recording)
                        .map(|(r, e)| format!("{r} {:+.3e} ± {:.1e}", e.value, e.se))
                        .collect();
                    let _ = write!(
                        s,
                        " [{}: Q = {:.2}, p = {:.2e}]",
                        each.join(", "),
                        a.combined.q,
                        a.combined.q_p
                    );
                }
                if let Some(g) = &a.holdout {
                    let _ = write!(
                        s,
                        "; held-out RMS {:.2} → {:.2} µm, better on {} of {}, t = {:.2} (p = \
                         {:.2e}), sign test p = {:.3} (smallest possible {:.3})",
                        g.rms_um[0],
                        g.rms_um[1],
                        g.sessions_better,
                        g.sessions,
                        g.t,
                        g.t_p_value,
                        g.sign_test_p_value,
                        g.smallest_possible_p
                    );
                }
                let _ = writeln!(s);
            }
        }
        for (arm, why) in &self.left_out {
            let _ = writeln!(s, "  {arm} not pooled: {why}");
        }
    }
}
