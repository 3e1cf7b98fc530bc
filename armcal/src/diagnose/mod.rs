//! Diagnosis: what the geometric model gets wrong, which physical cause explains it, and how
//! much a model extended with that cause gains on data it did not fit.
//!
//! 1. The geometric model (the 6N + 3 parameters and the instrument frame) is calibrated on
//!    all data and validated on held-out folds (k-fold over units, or whole groups).
//! 2. Every term of the spec's vocabulary is a candidate ([`candidates`]); those the data
//!    cannot see or separate are set aside with the reason.
//! 3. Stepwise selection ([`select`]) names the candidates that explain the residuals with
//!    evidence in sample (F-test, Bonferroni over the candidates) and on held-out folds
//!    (linearised k-fold, [`linear`]); each is then confirmed by real refits on held-out data.
//! 4. The model extended with the named causes is refitted on all data: its parameters, its
//!    residuals, its held-out gain.
//!
//! 5. What the extended model still leaves is searched for structure against every variable of
//!    the data ([`unexplained`]) and reported without naming a cause.
//!
//! [`patterns`] turns residuals into what a person reads (the apparent angle error of each
//! joint against its reading and its gravity lever, the apparent elongation of each link
//! against temperature) and [`plots`] draws them; [`report`] writes the result as text or
//! JSON.

pub mod candidates;
pub mod fleet;
pub mod fleet_pooled;
pub mod fleet_report;
pub mod gauge_free;
pub mod level;
pub mod linear;
pub mod nested;
pub mod patterns;
pub mod plots;
pub mod pooling;
pub mod pooling_rules;
pub mod report;
pub mod same_arm;
pub mod scenario;
pub mod select;
pub mod sessions;
pub mod unexplained;
pub use crate::stats;

use crate::data::Dataset;
use crate::fit::calib::{self};
use crate::fit::error::CalibError;
use crate::fit::finish::Fit;
use crate::fit::holdout::{self, Folds, Holdout};
use crate::fit::probes::Mounted;
use crate::fit::residuals::{residuals, summarise, Summary};
use crate::params::{Effect, Param, ParamExt};
use candidates::Candidates;
use quatarm_ref::arm::Arm;
use select::{Confirmation, Selection, Settings};
use stats::Paired;

/// How held-out folds are made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FoldChoice {
    /// k folds of units (a `point` row, a `spat` or `length` group whole), shuffled by a seed.
    KFold {
        /// Folds.
        k: usize,
        /// Shuffle seed.
        seed: u64,
    },
    /// One fold per group number (a session, an artefact position).
    ByGroup,
}

/// Settings of a diagnosis.
#[derive(Clone, Debug)]
pub struct Options {
    /// The calibration settings of every fit (its `terms` are set by the diagnosis).
    pub calib: crate::fit::options::Options,
    /// Held-out folds.
    pub folds: FoldChoice,
    /// Selection thresholds.
    pub select: Settings,
    /// Highest encoder-harmonic order tried (the data may resolve less:
    /// [`crate::effects::harmonic::resolvable_order`]).
    pub max_order: u32,
    /// Family-wise level of the search for unexplained structure ([`unexplained`], Holm over
    /// every test).
    pub unexplained_alpha: f64,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            calib: crate::fit::options::Options::default(),
            folds: FoldChoice::KFold {
                k: 5,
                seed: 0x0f01d,
            },
            select: Settings::default(),
            max_order: candidates::MAX_ORDER,
            unexplained_alpha: unexplained::ALPHA,
        }
    }
}

/// A model fitted on all data and validated on held-out folds.
#[derive(Clone, Debug)]
pub struct Model {
    /// The effects on top of the geometric model.
    pub effects: Vec<Effect>,
    /// The fit on all data.
    pub fit: Fit,
    /// Its residuals on the data it fitted.
    pub in_sample: Summary,
    /// Its residuals on held-out data (refitted without them).
    pub holdout: Holdout,
}

/// A named cause, with its fitted size in the extended model.
#[derive(Clone, Debug)]
pub struct Cause {
    /// The effect fitted.
    pub effect: Effect,
    /// Effects the data cannot tell from it (named with it, never fitted).
    pub indistinguishable: Vec<Effect>,
    /// Its unknowns' values in the extended arm (the whole key) and standard uncertainties.
    pub values: Vec<(Param, f64, Option<f64>)>,
    /// Its size: a harmonic's amplitude √(s² + c²) (rad), g (rad/mm), κ (1/°C).
    pub magnitude: f64,
    /// Standard uncertainty of the magnitude.
    pub magnitude_uncertainty: f64,
    /// Unit of the magnitude.
    pub unit: &'static str,
    /// RMS distance (µm) the term moves the ball over the data's poses: what it matters.
    pub rms_effect_um: f64,
    /// Held-out RMS (µm) of the model with this cause and those named before it.
    pub holdout_rms_um_after: f64,
    /// The real held-out comparison with the model before it.
    pub paired: Paired,
    /// When several causes are named: the validation of the extended model without this
    /// one (what the others alone leave).
    pub without: Option<Holdout>,
    /// Its in-sample and linearised held-out scores when it entered the selection.
    pub score: Option<select::Score>,
}

/// A whole diagnosis.
#[derive(Clone, Debug)]
pub struct Diagnosis {
    /// The candidates and what could not be tested.
    pub candidates: Candidates,
    /// How the folds were made, in words.
    pub folds_method: String,
    /// The folds.
    pub folds: Folds,
    /// The geometric model.
    pub baseline: Model,
    /// The selection's record.
    pub selection: Selection,
    /// The confirmation of each chosen effect by real refits.
    pub confirmations: Vec<Confirmation>,
    /// The causes named.
    pub causes: Vec<Cause>,
    /// The geometric model extended with the causes (the baseline again when none).
    pub extended: Model,
    /// The thresholds used.
    pub settings: Settings,
    /// Structure left in the extended model's residuals, against every variable of the data.
    pub unexplained: unexplained::Search,
    /// Units the held-out test pairs (a `point` row, a `spat` or `length` group) that were
    /// judged: below [`crate::stats::MIN_UNITS`] no cause can be confirmed, and the report
    /// says "cannot test".
    pub held_out_units: usize,
}

impl Diagnosis {
    /// Whether the held-out test has too few units to confirm anything.
    pub fn cannot_test(&self) -> bool {
        self.held_out_units < crate::stats::MIN_UNITS
    }

    /// Held-out RMS gain of the extended model over the geometric one (%).
    pub fn gain_percent(&self) -> f64 {
        let b = self.baseline.holdout.summary.all.rms_um;
        let e = self.extended.holdout.summary.all.rms_um;
        if b > 0.0 {
            100.0 * (1.0 - e / b)
        } else {
            0.0
        }
    }
}

/// Makes the folds of a choice, with the method in words.
pub fn make_folds(data: &Dataset, choice: FoldChoice) -> (Folds, String) {
    match choice {
        FoldChoice::KFold { k, seed } => {
            let f = holdout::kfold(data, k, seed);
            let n = f.len();
            (f, format!("{n}-fold"))
        }
        FoldChoice::ByGroup => {
            let f = holdout::by_group(data);
            let n = f.len();
            (f, format!("one group at a time ({n} groups)"))
        }
    }
}

/// Diagnoses `data` measured with an arm whose model starts at `start`: the geometric
/// baseline, the candidates, the selection and its confirmation by real refits, the model
/// extended with the named causes, each cause's figures, and what the extended model leaves.
pub fn diagnose(start: &Arm, data: &Dataset, opts: &Options) -> Result<Diagnosis, CalibError> {
    let (folds, folds_method) = make_folds(data, opts.folds);
    if folds.len() < 2 {
        return Err(CalibError::Mismatch(
            "cannot hold out data: the data form a single unit (one group); a diagnosis needs \
             held-out evidence"
                .into(),
        ));
    }
    let geometric = crate::fit::options::Options {
        terms: crate::params::Terms::geometric(),
        ..opts.calib.clone()
    };
    let base_fit = calib::calibrate(start, data, &geometric)?;
    // The design has been checked once; the extended fits and the folds go on without.
    let inner = crate::fit::options::Options {
        design_check: false,
        allow_degenerate: true,
        ..geometric.clone()
    };
    let base_holdout = holdout::validate(start, data, &inner, &folds);
    let baseline = Model {
        effects: Vec::new(),
        in_sample: summarise(&residuals(&base_fit.arm, data, base_fit.frame), data),
        fit: base_fit,
        holdout: base_holdout,
    };
    let cands = candidates::candidates_up_to(start, data, opts.max_order);
    let selection = select::select(
        start,
        data,
        &inner,
        &baseline.fit,
        &cands,
        &folds,
        &opts.select,
    )?;
    let confirmations = select::confirm(
        start,
        data,
        &inner,
        &folds,
        &baseline.holdout,
        &selection.chosen,
        opts.select.z,
    );
    let extended = extended_model(start, data, &inner, &baseline, &selection, &confirmations)?;
    let causes = named_causes(
        start,
        data,
        &inner,
        &folds,
        &cands,
        &selection,
        &confirmations,
        &extended,
    );
    let unexplained = unexplained::search(&extended, data, opts.unexplained_alpha);
    let held_out_units = select::unit_errors(data, &baseline.holdout)
        .iter()
        .filter(|u| u.is_some())
        .count();
    Ok(Diagnosis {
        held_out_units,
        candidates: cands,
        folds_method,
        folds,
        baseline,
        selection,
        confirmations,
        causes,
        extended,
        settings: opts.select,
        unexplained,
    })
}

/// The effects the confirmation named, in the order they were chosen.
fn named_effects(confirmations: &[Confirmation]) -> Vec<Effect> {
    confirmations
        .iter()
        .filter(|c| c.named)
        .map(|c| c.effect)
        .collect()
}

/// The geometric model extended with the named effects, fitted on all data (the selection's
/// fit reused when it chose exactly those), with the held-out figures of the last named
/// effect's confirmation; the baseline itself when none was named.
fn extended_model(
    start: &Arm,
    data: &Dataset,
    inner: &crate::fit::options::Options,
    baseline: &Model,
    selection: &Selection,
    confirmations: &[Confirmation],
) -> Result<Model, CalibError> {
    let named = named_effects(confirmations);
    if named.is_empty() {
        return Ok(baseline.clone());
    }
    let fit = if named == selection.chosen {
        selection.fit.clone()
    } else {
        select::fit_with(start, data, inner, &named)?
    };
    let holdout = confirmations
        .iter()
        .rev()
        .find(|c| c.named)
        .map(|c| c.holdout.clone())
        .unwrap_or_else(|| baseline.holdout.clone());
    Ok(Model {
        effects: named,
        in_sample: summarise(&residuals(&fit.arm, data, fit.frame), data),
        fit,
        holdout,
    })
}

/// Each named effect as a cause: its size in the extended fit, the candidates it cannot be
/// told from, its selection score, and (with two causes or more) the held-out figures of the
/// model without it, so that each cause's own share shows.
#[allow(clippy::too_many_arguments)]
fn named_causes(
    start: &Arm,
    data: &Dataset,
    inner: &crate::fit::options::Options,
    folds: &Folds,
    cands: &Candidates,
    selection: &Selection,
    confirmations: &[Confirmation],
    extended: &Model,
) -> Vec<Cause> {
    let named = named_effects(confirmations);
    let without = |e: Effect| -> Option<Holdout> {
        (named.len() > 1).then(|| {
            let others: Vec<Effect> = named.iter().copied().filter(|x| *x != e).collect();
            let o = crate::fit::options::Options {
                terms: crate::params::Terms::with(&others),
                ..inner.clone()
            };
            holdout::validate(start, data, &o, folds)
        })
    };
    confirmations
        .iter()
        .filter(|c| c.named)
        .map(|c| {
            let indistinguishable = cands
                .testable
                .iter()
                .find(|t| t.effect == c.effect)
                .map(|t| t.indistinguishable.clone())
                .unwrap_or_default();
            let score = selection
                .steps
                .iter()
                .rev()
                .find(|s| s.added && s.score.effect == c.effect)
                .map(|s| s.score.clone());
            cause(
                &extended.fit,
                data,
                c,
                indistinguishable,
                score,
                without(c.effect),
            )
        })
        .collect()
}

pub(crate) fn cause(
    fit: &Fit,
    data: &Dataset,
    c: &Confirmation,
    indistinguishable: Vec<Effect>,
    score: Option<select::Score>,
    without_cause: Option<Holdout>,
) -> Cause {
    let params = c.effect.params();
    let pos = |p: &Param| fit.params.iter().position(|q| q == p);
    let values: Vec<(Param, f64, Option<f64>)> = params
        .iter()
        .map(|p| {
            (
                *p,
                p.value(&fit.arm),
                pos(p).and_then(|k| fit.uncertainty[k]),
            )
        })
        .collect();
    let rho = if params.len() == 2 {
        correlation(fit, &params[0], &params[1])
    } else {
        0.0
    };
    let sized: Vec<(f64, f64)> = values
        .iter()
        .map(|(_, v, u)| (*v, u.unwrap_or(f64::NAN)))
        .collect();
    let ((magnitude, magnitude_uncertainty), unit) =
        c.effect.with(|t| (t.magnitude(&sized, rho), t.unit()));
    // What the term moves the ball by: the arm with and without it.
    let mut without = fit.arm.clone();
    for (p, v, _) in &values {
        p.add_to(&mut without, p.value(&fit.start) - v);
    }
    let (with, without) = (Mounted::new(&fit.arm), Mounted::new(&without));
    let ss: f64 = data
        .rows
        .iter()
        .map(|r| (with.tip(r) - without.tip(r)).norm_squared())
        .sum();
    Cause {
        effect: c.effect,
        indistinguishable,
        values,
        magnitude,
        magnitude_uncertainty,
        unit,
        rms_effect_um: 1e3 * (ss / data.rows.len().max(1) as f64).sqrt(),
        holdout_rms_um_after: c.holdout.summary.all.rms_um,
        paired: c.paired,
        without: without_cause,
        score,
    }
}

/// Correlation of two fitted unknowns (0 when either is not fitted).
fn correlation(fit: &Fit, a: &Param, b: &Param) -> f64 {
    let kept = |p: &Param| fit.ident.kept.iter().position(|&k| fit.params[k] == *p);
    match (kept(a), kept(b)) {
        (Some(i), Some(j)) if i < fit.correlation.nrows() && j < fit.correlation.ncols() => {
            fit.correlation[(i, j)]
        }
        _ => 0.0,
    }
}
