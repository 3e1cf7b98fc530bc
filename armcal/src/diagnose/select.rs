//! Choosing the causes: stepwise selection on evidence in sample and on held-out data, then a
//! confirmation by real refits on held-out data.
//!
//! ## Selection (linearised, [`super::linear`])
//! From the geometric fit, every candidate is scored by what adding it would do:
//! - **in sample**, the partial F-test of the extra unknowns (q = 2 for a harmonic's sin and
//!   cos, 1 otherwise) against the residual variance of the larger model; with m candidates
//!   tested, a candidate passes at p < α/m (Bonferroni), so that the chance of naming any
//!   cause in pure noise stays below α at every step;
//! - **out of sample**, k-fold cross-validation: the paired gain of the held-out squared
//!   errors over the units (a `point` row, a `spat` or `length` group), which must be
//!   significant by a one-sided paired t-test (units − 1 degrees of freedom) at the level of
//!   `z` normal standard errors (z = 2: 2.3 %). With 600 rows that is a gain of about 2
//!   standard errors; with three sessions held out one at a time, of 4.5.
//!
//! Of the candidates that pass both, the one with the lowest cross-validated error is added
//! and the model refitted exactly. Then every effect already named is tested for removal by the
//! same two criteria (it must still pass them given the others), the weakest failing one is
//! removed: a term that stood in for two true causes before both were in the model (an
//! alias) leaves again. Selection stops when no candidate passes.
//!
//! ## Confirmation (real refits)
//! The causes are then added one at a time, in the order chosen, and each model is validated
//! by refitting it on every fold's training part and judging the held-out part
//! ([`crate::fit::holdout::validate`]). A cause is named only if this real held-out error drops
//! significantly by the same paired t-test; one that does not is reported as rejected, with
//! the numbers.

use super::candidates::{Candidate, Candidates};
use super::linear::{Linearisation, Set};
use super::stats::{f_tail, normal_tail, Paired};
use crate::data::Dataset;
use crate::fit::calib::calibrate;
use crate::fit::error::CalibError;
use crate::fit::finish::Fit;
use crate::fit::holdout::{self, Folds, Holdout};
use crate::fit::options::Options;
use crate::params::{Effect, Param, Terms};
use quatarm_ref::arm::Arm;
use std::collections::BTreeMap;

/// Thresholds of the selection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Family-wise level of the in-sample test at each step (split over the candidates).
    pub alpha: f64,
    /// Held-out evidence: the paired t-test of the held-out errors must reach the one-sided
    /// level of a normal deviate of `z` standard errors (z = 2: 2.3 %).
    pub z: f64,
    /// Most add/remove steps.
    pub max_steps: usize,
}

impl Default for Settings {
    fn default() -> Settings {
        Settings {
            alpha: 1e-3,
            z: 2.0,
            max_steps: 24,
        }
    }
}

/// How one candidate scored at one step.
#[derive(Clone, Debug, PartialEq)]
pub struct Score {
    /// The candidate.
    pub effect: Effect,
    /// F statistic of its unknowns.
    pub f: f64,
    /// Its p-value.
    pub p: f64,
    /// Held-out gain (linearised k-fold) in standard errors.
    pub z: f64,
    /// One-sided p-value of that gain (paired t-test over the held-out units).
    pub p_holdout: f64,
    /// Held-out RMS per equation (a coordinate, or a bar's length) of the linearised k-fold
    /// validation (µm).
    pub cv_rms_um: f64,
    /// Whether the data can tell it from the model at all.
    pub separable: bool,
}

impl Score {
    fn passes(&self, p_cut: f64, p_holdout: f64) -> bool {
        self.separable && self.p < p_cut && self.p_holdout < p_holdout
    }
}

/// One step of the selection.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    /// `true`: added; `false`: removed.
    pub added: bool,
    /// The effect.
    pub score: Score,
}

/// The outcome of the selection.
#[derive(Clone, Debug)]
pub struct Selection {
    /// Effects chosen, in the order they entered (and stayed).
    pub chosen: Vec<Effect>,
    /// The steps taken.
    pub steps: Vec<Step>,
    /// Scores of the candidates left out, at the last step (strongest first).
    pub left_out: Vec<Score>,
    /// The exact fit of the chosen model on all data.
    pub fit: Fit,
    /// The p-value cut used (α / m).
    pub p_cut: f64,
}

/// Fits the geometric model plus `effects`.
pub fn fit_with(
    start: &Arm,
    data: &Dataset,
    opts: &Options,
    effects: &[Effect],
) -> Result<Fit, CalibError> {
    let o = Options {
        terms: Terms::with(effects),
        ..opts.clone()
    };
    calibrate(start, data, &o)
}

fn params_of(effects: &[Effect]) -> Vec<Param> {
    effects.iter().flat_map(|e| e.params()).collect()
}

/// What one step's candidate sets are scored from: the linearisation, the sets (0 is the
/// current model), their per-unit held-out errors, the model's RSS and the equations.
struct Scoring<'a> {
    lin: &'a Linearisation,
    sets: &'a [Set],
    held: &'a [Vec<f64>],
    rss_m: f64,
    n_eq: f64,
}

impl Scoring<'_> {
    /// Cross-validated RMS (µm) of set `k`.
    fn cv_rms(&self, k: usize) -> f64 {
        let ss: f64 = self.held[k].iter().sum();
        1e3 * (ss / self.lin.equations.max(1) as f64).sqrt()
    }

    /// The removal step: the chosen effect with the least support, if it no longer passes
    /// (the highest p among those that fail), scored against the model of `model_len`
    /// parameters.
    fn worst_removal(
        &self,
        back: &[Back],
        model_len: usize,
        p_cut: f64,
        p_level: f64,
    ) -> Option<Score> {
        let mut worst: Option<Score> = None;
        for &(e, q, k) in back {
            let score = self.removal(e, q, k, model_len);
            if !score.passes(p_cut, p_level) && worst.as_ref().is_none_or(|w| score.p > w.p) {
                worst = Some(score);
            }
        }
        worst
    }

    /// The support of chosen effect `e` (`q` unknowns), set `k` being the model without it.
    fn removal(&self, e: Effect, q: usize, k: usize, model_len: usize) -> Score {
        let rss_s = self.lin.rss(&self.sets[k]);
        let dof = self.n_eq - model_len as f64;
        let f = ((rss_s - self.rss_m) / q as f64) / (self.rss_m / dof);
        let paired = Paired::of(&self.held[k], &self.held[0]);
        Score {
            effect: e,
            f,
            p: f_tail(f, q as f64, dof),
            z: paired.z(),
            p_holdout: paired.p_value(),
            cv_rms_um: self.cv_rms(k),
            separable: true,
        }
    }

    /// The gain of candidate `e` (`q` unknowns), set `k` being the model with it.
    fn addition(&self, e: Effect, q: usize, k: usize, separable: bool) -> Score {
        let rss_s = self.lin.rss(&self.sets[k]);
        let dof = self.n_eq - self.sets[k].free.len() as f64;
        let f = if separable && q > 0 {
            ((self.rss_m - rss_s) / q as f64) / (rss_s / dof)
        } else {
            0.0
        };
        let paired = Paired::of(&self.held[0], &self.held[k]);
        Score {
            effect: e,
            f,
            p: f_tail(f, q.max(1) as f64, dof),
            z: paired.z(),
            p_holdout: paired.p_value(),
            cv_rms_um: self.cv_rms(k),
            separable,
        }
    }
}

/// A chosen effect's removal: (effect, unknowns, position of the set without it).
type Back = (Effect, usize, usize);
/// A candidate's addition: (effect, unknowns, position of the set with it, separable).
type Forward = (Effect, usize, usize, bool);

/// The sets one step scores: the model (position 0), the model without each chosen effect,
/// with each remaining candidate.
fn candidate_sets(
    lin: &Linearisation,
    fit: &Fit,
    model: &[usize],
    chosen: &[Effect],
    remaining: &[&Candidate],
) -> (Vec<Set>, Vec<Back>, Vec<Forward>) {
    let mut sets = vec![Set::of(model.to_vec())];
    let mut back = Vec::new();
    for e in chosen {
        let cols = lin.positions(&e.params());
        let without = Set {
            free: model
                .iter()
                .copied()
                .filter(|c| !cols.contains(c))
                .collect(),
            fixed: lin.removal(fit, &e.params()),
        };
        back.push((*e, cols.len(), sets.len()));
        sets.push(without);
    }
    let mut fwd = Vec::new();
    for c in remaining {
        let cols = lin.positions(&c.fitted);
        let separable = !cols.is_empty() && lin.unexplained(&cols, model) > 1e-3;
        let mut with = model.to_vec();
        with.extend(&cols);
        fwd.push((c.effect, cols.len(), sets.len(), separable));
        sets.push(Set::of(with));
    }
    (sets, back, fwd)
}

/// Stepwise selection from the geometric fit `baseline` (see the module's text).
pub fn select(
    start: &Arm,
    data: &Dataset,
    opts: &Options,
    baseline: &Fit,
    cands: &Candidates,
    folds: &Folds,
    s: &Settings,
) -> Result<Selection, CalibError> {
    let m = cands.testable.len().max(1);
    let p_cut = s.alpha / m as f64;
    let p_level = normal_tail(s.z);
    let mut chosen: Vec<Effect> = Vec::new();
    let mut fit = baseline.clone();
    let mut steps = Vec::new();
    let mut removals: BTreeMap<Effect, usize> = BTreeMap::new();
    let mut left_out = Vec::new();
    for _ in 0..s.max_steps {
        let remaining: Vec<&Candidate> = cands
            .testable
            .iter()
            .filter(|c| !chosen.contains(&c.effect))
            .filter(|c| removals.get(&c.effect).copied().unwrap_or(0) < 2)
            .collect();
        let extra = params_of(&remaining.iter().map(|c| c.effect).collect::<Vec<_>>());
        let lin = Linearisation::at(&fit, data, &extra, folds);
        let model = lin.model();
        let rss_m = lin.rss(&Set::of(model.clone()));
        let n_eq = lin.equations as f64;

        let (sets, back, fwd) = candidate_sets(&lin, &fit, &model, &chosen, &remaining);
        let held = lin.heldout(data, &sets);
        let scoring = Scoring {
            lin: &lin,
            sets: &sets,
            held: &held,
            rss_m,
            n_eq,
        };

        if let Some(w) = scoring.worst_removal(&back, model.len(), p_cut, p_level) {
            chosen.retain(|e| *e != w.effect);
            *removals.entry(w.effect).or_default() += 1;
            steps.push(Step {
                added: false,
                score: w,
            });
            fit = fit_with(start, data, opts, &chosen)?;
            continue;
        }

        // Addition: the passing candidate with the lowest cross-validated error.
        let mut scores: Vec<Score> = fwd
            .iter()
            .map(|&(e, q, k, separable)| scoring.addition(e, q, k, separable))
            .collect();
        scores.sort_by(|a, b| a.cv_rms_um.total_cmp(&b.cv_rms_um));
        let Some(best) = scores.iter().find(|c| c.passes(p_cut, p_level)).cloned() else {
            left_out = scores;
            break;
        };
        let mut trial = chosen.clone();
        trial.push(best.effect);
        let Some(next) = exact_fit_determines(start, data, opts, &trial, &remaining, best.effect)
        else {
            removals.insert(best.effect, usize::MAX);
            continue;
        };
        chosen = trial;
        fit = next;
        steps.push(Step {
            added: true,
            score: best,
        });
    }
    Ok(Selection {
        chosen,
        steps,
        left_out,
        fit,
        p_cut,
    })
}

/// The exact fit with `trial` (the chosen effects and `added`), if it determines every
/// parameter of `added` the candidate fits: the linearised score may have passed an effect
/// the exact fit holds as weak or inseparable, or does not converge with; such an effect
/// cannot be named, and the selection tries the others.
fn exact_fit_determines(
    start: &Arm,
    data: &Dataset,
    opts: &Options,
    trial: &[Effect],
    remaining: &[&Candidate],
    added: Effect,
) -> Option<Fit> {
    let fitted = remaining
        .iter()
        .find(|c| c.effect == added)
        .map_or_else(|| added.params(), |c| c.fitted.clone());
    fit_with(start, data, opts, trial).ok().filter(|next| {
        fitted
            .iter()
            .all(|p| next.ident.kept.iter().any(|&k| next.params[k] == *p))
    })
}

/// Per-unit held-out squared error (mm²) of a validation, in the units of
/// [`crate::data::Layout::units`] (a `length` group with its bar error); `None` for a unit not
/// judged.
pub fn unit_errors(data: &Dataset, h: &Holdout) -> Vec<Option<f64>> {
    let layout = data.layout();
    let row = |i: usize| h.judged[i].then(|| h.residuals.rows[i].norm_squared());
    let group = |rows: &[usize]| -> Option<f64> { rows.iter().map(|&i| row(i)).sum() };
    let bars: BTreeMap<i64, f64> = h.residuals.lengths.iter().copied().collect();
    layout
        .units()
        .iter()
        .map(|u| {
            let bar = u.bar.and_then(|g| bars.get(&g)).map_or(0.0, |e| e * e);
            group(&u.rows).map(|s| s + bar)
        })
        .collect()
}

/// The paired comparison of two validations over the units both judged.
pub fn compare(data: &Dataset, before: &Holdout, after: &Holdout) -> Paired {
    let a = unit_errors(data, before);
    let b = unit_errors(data, after);
    let (x, y): (Vec<f64>, Vec<f64>) = a
        .iter()
        .zip(&b)
        .filter_map(|(a, b)| Some(((*a)?, (*b)?)))
        .unzip();
    Paired::of(&x, &y)
}

/// A cause confirmed (or not) by real refits on held-out data.
#[derive(Clone, Debug)]
pub struct Confirmation {
    /// The effect.
    pub effect: Effect,
    /// Whether it is named.
    pub named: bool,
    /// The held-out comparison with the model before it.
    pub paired: Paired,
    /// The validation of the model with it (and the causes named before it).
    pub holdout: Holdout,
}

/// Adds the chosen effects one at a time and keeps those whose real held-out validation
/// improves on the model before them at the one-sided level of `z` standard errors (paired
/// t-test over the held-out units).
pub fn confirm(
    start: &Arm,
    data: &Dataset,
    opts: &Options,
    folds: &Folds,
    baseline: &Holdout,
    chosen: &[Effect],
    z: f64,
) -> Vec<Confirmation> {
    let mut named: Vec<Effect> = Vec::new();
    let mut current = baseline.clone();
    let mut out = Vec::new();
    for &e in chosen {
        let mut trial = named.clone();
        trial.push(e);
        let o = Options {
            terms: Terms::with(&trial),
            ..opts.clone()
        };
        let h = holdout::validate(start, data, &o, folds);
        let paired = compare(data, &current, &h);
        let ok = paired.p_value() < normal_tail(z) && h.failed.len() <= current.failed.len();
        if ok {
            named = trial;
            current = h.clone();
        }
        out.push(Confirmation {
            effect: e,
            named: ok,
            paired,
            holdout: h,
        });
    }
    out
}
