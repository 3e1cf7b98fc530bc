//! Fleet diagnosis: which causes belong to an arm *design* (every unit built to it shows them)
//! and which to single units, from the recordings of several units.
//!
//! Units of one design share their physics (a shoulder that bends under the weight it
//! carries) but not their magnitudes or their geometry. So nothing is fitted across units:
//! every unit gets its own geometric model, and every candidate of the single-arm vocabulary
//! ([`super::candidates`]) is tried on each unit by real refits, its sessions held out one at
//! a time ([`crate::fit::holdout::by_group`]). The evidence of a unit for a candidate is how much the
//! candidate lowers the held-out error of each of its sessions:
//!
//! y_s = ½ ln(SS_before,s / SS_after,s)   (the log of the held-out RMS ratio of session s)
//!
//! and the unit's estimate is their mean ȳ_u with standard error s_u / √n_u (n_u sessions).
//! Sessions, not rows, are the replications: the rows of one session share its placement and
//! its day, and a gain that does not repeat from session to session is no gain.
//!
//! **Why a log-ratio.** Units differ in how wrong their geometric model is (MUKCa's Pandas
//! leave 0.2 to 0.5 mm) and in how large their effect is; the log of the ratio is free of the
//! unit's scale, symmetric between gain and loss, and near normal for sums of many squared
//! residuals, so units are comparable and their means can be pooled.
//!
//! **Why random effects (DerSimonian–Laird, with Hartung–Knapp's test).** The units' true
//! gains differ (the magnitudes differ), so a fixed-effect pooling would test "every unit
//! gains the same", which is false by design, and would let one unit with a large, precise
//! gain carry the fleet: a cause of a single unit would pass for the design's. The
//! random-effects model y_u ~ N(μ, v_u + τ²) estimates the spread τ² of the true gains between
//! units (DerSimonian and Laird's moment estimator from Cochran's Q) and tests the *mean* gain
//! μ of the design. One unit alone with a gain inflates τ² and with it se(μ̂), so it cannot
//! make a design cause; a cause every unit shows, at whatever magnitude, does.
//!
//! The test of μ̂ is Hartung and Knapp's (also Sidik and Jonkman's): its variance is the
//! weighted scatter of the units around μ̂, Σ w*_u (y_u − μ̂)² / ((k − 1) Σ w*_u), never less
//! than DerSimonian–Laird's 1 / Σ w*_u, and μ̂ / se is referred to Student's t with k − 1
//! degrees of freedom. The plain DL z-test treats the v_u as known, and here they are not: a
//! unit of three sessions estimates its v_u from two degrees of freedom, and one whose three
//! sessions happen to agree takes an enormous weight. On MUKCa's ten Pandas the z-test named
//! joint 2's gravity compliance for the design (z = 3.9) with fitted compliances of both signs
//! over the units and a held-out gain of 3 %; the Hartung–Knapp test does not. With few units
//! it is conservative, which is what a claim about every unit of a design should be.
//! [`MIN_FLEET_UNITS`] tested units are required.
//!
//! **Design-level** causes are chosen stepwise: at each step every remaining candidate is
//! pooled against each unit's current model (geometry + the design causes named so far), the
//! p-values are corrected by Holm's step-down over the candidates at `alpha`, and of those
//! that pass the one with the largest pooled gain is added; a candidate that only stood in for one already named
//! (an alias) loses its gain and stops. **Unit-level** causes are those the unit's own test
//! names beyond the design's: the single-arm diagnosis ([`super::diagnose`], sessions held out
//! whole), each kept only when its real held-out gain, given the design's causes, still passes
//! the single-arm rule (paired t-test over the sessions at the level of `z`). A unit with fewer
//! than [`crate::stats::MIN_UNITS`] sessions cannot be tested ("cannot test: N sessions") and
//! contributes nothing.
//!
//! **Arms, not files.** The pooled test's units are physical arms ([`diagnose_arms`]): the
//! recordings of one arm, found from their geometry by [`super::same_arm`] or given by hand,
//! each keep their own geometric model (their tool, their frame) and validation, and the arm's
//! evidence for a candidate is the per-session log-ratios of all of them together. Two
//! recordings of one arm are not two draws from the design; pooled as two, one arm's effect
//! would count twice and look like the design's.

use super::candidates::{self, Candidates};
use super::select::{compare, Confirmation};
use super::{Cause, Options as DiagOptions};
use crate::data::Dataset;
use crate::fit::calib::{self};
use crate::fit::error::CalibError;
use crate::fit::finish::Fit;
use crate::fit::holdout::{self, Folds, Holdout};
use crate::params::{Effect, Terms};
use crate::progress::{Observer, Silent};
use crate::stats::{normal_tail, t_tail, MIN_UNITS};
use quatarm_ref::arm::Arm;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Default family-wise level of the design-level and unit-level tests (Holm over the
/// candidates at each step).
pub const ALPHA: f64 = 0.01;

/// Fewest units with a held-out test for any cause to be called design-level: with two, the
/// spread of the true gains between units (τ²) rests on a single difference.
pub const MIN_FLEET_UNITS: usize = 3;

/// Settings of a fleet diagnosis.
#[derive(Clone, Debug)]
pub struct Options {
    /// The single-arm settings (calibration, highest harmonic order, steps).
    pub diagnose: DiagOptions,
    /// Family-wise level of each step's test (Holm over the candidates).
    pub alpha: f64,
    /// The errors the pooled stage weighs each arm by ([`super::fleet_pooled`]).
    pub error_scale: ErrorScale,
    /// The model each pooled candidate is estimated in ([`super::fleet_pooled`]).
    pub pooled_model: PooledModel,
    /// Whether an arm with no recording of [`MIN_UNITS`] sessions, but one of
    /// [`super::fleet_pooled::MIN_JOINED`], joins the pool on the fleet's error scale (its φ
    /// assumed the others': nothing can test it). Off by default.
    pub join_short: bool,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            diagnose: DiagOptions::default(),
            alpha: ALPHA,
            error_scale: ErrorScale::default(),
            pooled_model: PooledModel::default(),
            join_short: false,
        }
    }
}

/// Which standard error each arm is pooled with: its own jackknife error over its sessions
/// ([`super::pooling::pool`]), or that error's scale pooled across the fleet
/// ([`super::pooling::pool_fleet_scale`]: √φ̂ times the arm's in-sample error where the arms'
/// ratios pass Bartlett's test, else their own).
/// The fleet diagnosis's choice (`armcal diagnose --fleet --error-scale`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum ErrorScale {
    /// Each arm's own jackknife error on its sessions − 1 df.
    Own,
    /// The jackknife errors' scale pooled over the arms (docs/results/claims.md §7.10).
    #[default]
    Fleet,
}

/// The model each candidate of the fleet's pooled stage is estimated in: against the
/// geometric model alone, or with every shared candidate at once, each conditional on all the
/// others (the full model, [`super::fleet_pooled::pool_candidates_full`]). The fleet
/// diagnosis's choice (`armcal diagnose --fleet --pooled-model`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum PooledModel {
    /// Each candidate fitted with the geometric model alone: another joint's compliance
    /// sharing a strong one's gravity lever takes up part of it (an alias).
    Alone,
    /// Every candidate in one fit: on the fleet's error scale no alias named in 1,500 mixed
    /// fleets at α = 0.01 (docs/results/claims.md §7.11). Where an arm's full fit cannot be
    /// made, the stage falls back to `alone` for the fleet and says so.
    #[default]
    Full,
}

/// One unit's recordings.
#[derive(Clone, Debug)]
pub struct UnitData {
    /// The unit's name ([`unit_names`]).
    pub name: String,
    /// The file it was read from.
    pub file: String,
    /// Its rows; `group` numbers are its sessions.
    pub data: Dataset,
}

/// Why a fleet cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum FleetError {
    /// Fewer than two files.
    #[error("a fleet needs two units or more, got {0} file(s)")]
    TooFew(usize),
    /// A file could not be read (missing, malformed, another joint count).
    #[error("unit {unit}: {source}")]
    Data {
        /// The unit's name.
        unit: String,
        /// The reader's error (it names the file, line and column).
        source: crate::data::DataError,
    },
    /// A grouping of recordings into arms that cannot be honoured (it names the option and
    /// the recording).
    #[error("{0}")]
    Grouping(String),
    /// Two files give the same unit name.
    #[error("{a} and {b} give the same unit name `{name}`")]
    SameName {
        /// The name.
        name: String,
        /// One file.
        a: String,
        /// The other.
        b: String,
    },
}

/// The units' names from their files: the file stem, less the longest prefix all the stems
/// share up to and including its last `-` (`mukca-panda-panda_3.csv` among MUKCa's Pandas is
/// `panda_3`). The rule is generic: the shared prefix is what the files have in common, not
/// a unit's name; it stops at a `-` because names themselves are joined by `_`
/// (`panda_3_bis`). When stripping would leave a name empty, the whole stems are the names.
/// The data format has no `unit` column, so the file is the only source of a name.
pub fn unit_names(paths: &[&Path]) -> Vec<String> {
    let stems: Vec<String> = paths
        .iter()
        .map(|p| {
            p.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| p.display().to_string())
        })
        .collect();
    let Some(first) = stems.first() else {
        return Vec::new();
    };
    let mut common = first.len();
    for s in &stems[1..] {
        common = common.min(
            first
                .char_indices()
                .zip(s.chars())
                .find(|((_, a), b)| a != b)
                .map_or(first.len().min(s.len()), |((i, _), _)| i),
        );
    }
    let cut = first[..common].rfind('-').map_or(0, |i| i + 1);
    if stems.iter().any(|s| s.len() <= cut) {
        return stems;
    }
    stems.iter().map(|s| s[cut..].to_string()).collect()
}

/// Reads every unit's file for an arm of `dof` joints; an error names the unit and the file.
pub fn read_units(paths: &[&Path], dof: usize) -> Result<Vec<UnitData>, FleetError> {
    if paths.len() < 2 {
        return Err(FleetError::TooFew(paths.len()));
    }
    let names = unit_names(paths);
    let mut seen: BTreeMap<&str, &Path> = BTreeMap::new();
    for (n, p) in names.iter().zip(paths) {
        if let Some(a) = seen.insert(n, p) {
            return Err(FleetError::SameName {
                name: n.clone(),
                a: a.display().to_string(),
                b: p.display().to_string(),
            });
        }
    }
    names
        .into_iter()
        .zip(paths)
        .map(|(name, p)| {
            let data = crate::data::read(p, dof).map_err(|source| FleetError::Data {
                unit: name.clone(),
                source,
            })?;
            Ok(UnitData {
                name,
                file: p.display().to_string(),
                data,
            })
        })
        .collect()
}

/// A unit's held-out evidence for one candidate, against its current model.
#[derive(Clone, Debug)]
pub struct UnitTest {
    /// The candidate.
    pub effect: Effect,
    /// Sessions judged by both models.
    pub sessions: usize,
    /// Each session's ½ ln(SS before / SS after), session order.
    pub per_session: Vec<f64>,
    /// Mean over sessions of ½ ln(SS before / SS after): the log of the held-out RMS ratio
    /// (positive: the candidate helps).
    pub log_ratio: f64,
    /// Its standard error (sd / √sessions).
    pub se: f64,
    /// The unit's own one-sided p-value (t-test, sessions − 1 degrees of freedom; 1 below
    /// [`MIN_UNITS`] sessions).
    pub p: f64,
    /// Held-out RMS with the candidate (µm).
    pub holdout_rms_um_with: f64,
    /// The validation with it.
    pub holdout: Holdout,
}

/// The random-effects pooling of one candidate over the units.
#[derive(Clone, Debug)]
pub struct Pooled {
    /// The candidate.
    pub effect: Effect,
    /// The pooled statistics.
    pub pooling: Pooling,
    /// Every pooled arm's (index among the fleet's arms, mean log-ratio, standard error):
    /// the sessions of all its recordings together.
    pub per_unit: Vec<(usize, f64, f64)>,
}

/// A pooled test's statistics, as the report gives them too.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Pooling {
    /// Units pooled.
    pub units: usize,
    /// Units whose own mean log-ratio is positive.
    pub units_gaining: usize,
    /// The pooled mean log-ratio μ̂ of ½ ln(held-out SS before / after) (the design's typical
    /// ln of its held-out RMS ratio).
    pub mean_log_ratio: f64,
    /// Its standard error.
    pub se: f64,
    /// DerSimonian–Laird spread of the units' true log-ratios (variance).
    pub tau2: f64,
    /// Cochran's Q.
    pub q: f64,
    /// μ̂ / se (Hartung–Knapp).
    pub t: f64,
    /// One-sided p-value P(T > t), Student's t with units − 1 degrees of freedom.
    #[serde(rename = "p_value")]
    pub p: f64,
}

/// DerSimonian–Laird random-effects pooling of estimates `y` with variances `v`, and
/// Hartung–Knapp's standard error of the pooled mean (see the module text): (μ̂, se_HK(μ̂),
/// τ², Q). Variances are floored at 1e-12 so a unit whose sessions agree exactly does not
/// take infinite weight.
pub fn dersimonian_laird(y: &[f64], v: &[f64]) -> (f64, f64, f64, f64) {
    let k = y.len();
    if k == 0 {
        return (0.0, f64::INFINITY, 0.0, 0.0);
    }
    let w: Vec<f64> = v.iter().map(|v| 1.0 / v.max(1e-12)).collect();
    let sw: f64 = w.iter().sum();
    let fixed = w.iter().zip(y).map(|(w, y)| w * y).sum::<f64>() / sw;
    let q: f64 = w.iter().zip(y).map(|(w, y)| w * (y - fixed).powi(2)).sum();
    let c = sw - w.iter().map(|w| w * w).sum::<f64>() / sw;
    let tau2 = if c > 0.0 {
        ((q - (k as f64 - 1.0)) / c).max(0.0)
    } else {
        0.0
    };
    let ws: Vec<f64> = v.iter().map(|v| 1.0 / (v.max(1e-12) + tau2)).collect();
    let sws: f64 = ws.iter().sum();
    let mu = ws.iter().zip(y).map(|(w, y)| w * y).sum::<f64>() / sws;
    let hk = if k > 1 {
        ws.iter()
            .zip(y)
            .map(|(w, y)| w * (y - mu).powi(2))
            .sum::<f64>()
            / ((k - 1) as f64 * sws)
    } else {
        f64::INFINITY
    };
    (mu, hk.max(1.0 / sws).sqrt(), tau2, q)
}

/// Holm's step-down at family-wise level `alpha`: which of `p` are rejected.
pub fn holm(p: &[f64], alpha: f64) -> Vec<bool> {
    let m = p.len();
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| p[a].total_cmp(&p[b]));
    let mut out = vec![false; m];
    for (i, &k) in order.iter().enumerate() {
        if p[k] < alpha / (m - i) as f64 {
            out[k] = true;
        } else {
            break;
        }
    }
    out
}

/// Whether a cause belongs to the design or to one unit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    /// Named by the pooled test over the units.
    Design,
    /// Named by the unit's own test only.
    Unit,
}

/// One unit's outcome.
#[derive(Clone, Debug)]
pub struct UnitResult {
    /// The unit's name.
    pub name: String,
    /// Its file.
    pub file: String,
    /// Its sessions (group numbers).
    pub sessions: usize,
    /// Why it contributes nothing ("cannot test: 2 sessions"), when it does not.
    pub cannot_test: Option<String>,
    /// The candidates its data can test.
    pub candidates: Candidates,
    /// Its geometric model on all its data (`None` when it could not be fitted).
    pub geometric: Option<Fit>,
    /// Held-out validation of the geometric model (`None` with one session).
    pub baseline: Option<Holdout>,
    /// Its causes, in the order named, with their level; their values in the final fit.
    pub causes: Vec<(Level, Cause)>,
    /// Held-out validation of its final model (geometry + its causes).
    pub extended: Option<Holdout>,
    /// Its own test of every candidate at the first unit-level step (strongest first).
    pub tests: Vec<UnitTest>,
}

/// One step of the design-level selection.
#[derive(Clone, Debug)]
pub struct DesignStep {
    /// Every candidate pooled at this step, strongest first, with whether Holm rejects it.
    pub pooled: Vec<(Pooled, bool)>,
    /// The candidate named (none at the last step).
    pub named: Option<Effect>,
}

/// A whole fleet diagnosis.
#[derive(Clone, Debug)]
pub struct Fleet {
    /// The design-level causes, in the order named.
    pub design: Vec<Effect>,
    /// The selection's steps.
    pub steps: Vec<DesignStep>,
    /// Every unit.
    pub units: Vec<UnitResult>,
    /// Arms whose sessions allow a held-out test (the units of the pooled test).
    pub tested_units: usize,
    /// The arms' names and their recordings (indices into `units`).
    pub arms: Vec<(String, Vec<usize>)>,
    /// The level used.
    pub alpha: f64,
}

/// The sum of squared held-out errors per session (a group whose rows were not all judged is
/// left out), bar length errors included.
fn session_ss(data: &Dataset, h: &Holdout) -> BTreeMap<i64, f64> {
    let mut ss: BTreeMap<i64, f64> = BTreeMap::new();
    let mut bad: BTreeSet<i64> = BTreeSet::new();
    for (i, r) in data.rows.iter().enumerate() {
        if h.judged[i] {
            *ss.entry(r.group).or_default() += h.residuals.rows[i].norm_squared();
        } else {
            bad.insert(r.group);
        }
    }
    for (g, e) in &h.residuals.lengths {
        *ss.entry(*g).or_default() += e * e;
    }
    ss.retain(|g, _| !bad.contains(g));
    ss
}

/// The mean of per-session log-ratios `y`, its standard error and the one-sided t-test's
/// p-value (1 below [`MIN_UNITS`] sessions or when some fold failed, `complete` false).
fn session_summary(y: &[f64], complete: bool) -> (f64, f64, f64) {
    let n = y.len();
    let mean = y.iter().sum::<f64>() / n.max(1) as f64;
    let se = if n > 1 {
        (y.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64 / n as f64).sqrt()
    } else {
        f64::INFINITY
    };
    let p = if n < MIN_UNITS || !complete {
        1.0
    } else if se > 0.0 {
        t_tail(mean / se, (n - 1) as f64)
    } else if mean > 0.0 {
        0.0
    } else {
        1.0
    };
    (mean, se, p)
}

/// The held-out evidence of `after` against `before` on one unit.
fn unit_test(effect: Effect, data: &Dataset, before: &Holdout, after: Holdout) -> UnitTest {
    let a = session_ss(data, before);
    let b = session_ss(data, &after);
    let y: Vec<f64> = a
        .iter()
        .filter_map(|(g, sa)| {
            let sb = *b.get(g)?;
            (*sa > 0.0 && sb > 0.0).then(|| 0.5 * (sa / sb).ln())
        })
        .collect();
    let (mean, se, p) = session_summary(&y, after.failed.is_empty());
    UnitTest {
        effect,
        sessions: y.len(),
        per_session: y,
        log_ratio: mean,
        se,
        p,
        holdout_rms_um_with: after.summary.all.rms_um,
        holdout: after,
    }
}

/// A unit under selection: its data, folds, candidates and current model.
struct Work<'a> {
    unit: &'a UnitData,
    folds: Folds,
    cands: Candidates,
    effects: Vec<Effect>,
    levels: Vec<Level>,
    /// The validation after each cause (index 0: the geometric model).
    chain: Vec<Holdout>,
    testable: bool,
    /// Whether its sessions count in its arm's evidence (two or more, every fold refitted).
    contributes: bool,
    /// Its arm (index into the arms).
    arm: usize,
}

impl Work<'_> {
    fn current(&self) -> &Holdout {
        self.chain.last().expect("the geometric validation")
    }

    fn can_test(&self, e: Effect) -> bool {
        self.cands.testable.iter().any(|c| c.effect == e)
    }

    /// The unit's test of `e` added to its current model.
    fn test(&self, start: &Arm, inner: &crate::fit::options::Options, e: Effect) -> UnitTest {
        let mut trial = self.effects.clone();
        trial.push(e);
        let o = crate::fit::options::Options {
            terms: Terms::with(&trial),
            ..inner.clone()
        };
        let h = holdout::validate(start, &self.unit.data, &o, &self.folds);
        unit_test(e, &self.unit.data, self.current(), h)
    }

    fn add(&mut self, level: Level, t: UnitTest) {
        self.effects.push(t.effect);
        self.levels.push(level);
        self.chain.push(t.holdout);
    }
}

/// The calibration settings of every unit's geometric model (and of its refits with
/// candidates): the data's own rank is trusted and what it cannot determine is held, since a
/// unit's sessions are what they are.
pub fn geometric_options(opts: &Options) -> crate::fit::options::Options {
    crate::fit::options::Options {
        terms: Terms::geometric(),
        design_check: false,
        allow_degenerate: true,
        ..opts.diagnose.calib.clone()
    }
}

/// A unit's geometric model: its folds (one session each), their held-out validation (`None`
/// with fewer than two sessions) and the fit on all its data (`None` when it failed).
#[derive(Clone, Debug)]
pub struct Geometric {
    /// One fold per session.
    pub folds: Folds,
    /// Held-out validation of the geometric model.
    pub baseline: Option<Holdout>,
    /// The fit on all the unit's sessions.
    pub fit: Option<Fit>,
}

/// The geometric model of `data` with `inner` ([`geometric_options`]); the fleet diagnosis
/// and the same-arm test ([`super::same_arm`]) both start from it.
pub fn geometric(start: &Arm, data: &Dataset, inner: &crate::fit::options::Options) -> Geometric {
    let folds = holdout::by_group(data);
    let baseline = (folds.len() >= 2).then(|| holdout::validate(start, data, inner, &folds));
    Geometric {
        fit: calib::calibrate(start, data, inner).ok(),
        folds,
        baseline,
    }
}

/// Diagnoses a fleet of units of one design, every unit's model starting at `start`, each
/// unit an arm of its own.
pub fn diagnose_fleet(
    start: &Arm,
    units: &[UnitData],
    opts: &Options,
) -> Result<Fleet, CalibError> {
    let arms: Vec<(String, Vec<usize>)> = units
        .iter()
        .enumerate()
        .map(|(i, u)| (u.name.clone(), vec![i]))
        .collect();
    diagnose_arms(start, units, &arms, opts)
}

/// Diagnoses a fleet whose recordings `units` are grouped into physical arms `arms` (name,
/// recordings), every recording's model starting at `start`. Each recording keeps its own
/// geometric model (its tool, its frame) and its own held-out validation; an arm's evidence
/// for a candidate is the per-session log-ratios of all its recordings together (one mean,
/// one standard error), so the pooled test has one entry per arm, not per file. An arm is
/// tested when its recordings that can be validated (two sessions or more, every fold
/// refitted) give [`MIN_UNITS`] sessions together. Unit-level causes remain each
/// recording's own.
pub fn diagnose_arms(
    start: &Arm,
    units: &[UnitData],
    arms: &[(String, Vec<usize>)],
    opts: &Options,
) -> Result<Fleet, CalibError> {
    diagnose_arms_observed(start, units, arms, opts, &mut Silent)
}

/// [`diagnose_arms`], telling `obs` each counted step (the recordings' geometric fits, the
/// design-level steps and each recording's tests within them, the units' own diagnoses), so
/// that a command can show the count and the time left.
pub fn diagnose_arms_observed(
    start: &Arm,
    units: &[UnitData],
    arms: &[(String, Vec<usize>)],
    opts: &Options,
    obs: &mut dyn Observer,
) -> Result<Fleet, CalibError> {
    let arm_of = arm_of(units, arms)?;
    let inner = geometric_options(opts);
    let (mut work, geometric_fits) = start_work(start, units, &arm_of, opts, &inner, obs);
    // An arm is tested when its contributing recordings give MIN_UNITS sessions together;
    // its recordings are then tested whenever they contribute.
    let arm_tested: Vec<bool> = (0..arms.len())
        .map(|a| {
            work.iter()
                .filter(|w| w.arm == a && w.contributes)
                .map(|w| w.folds.len())
                .sum::<usize>()
                >= MIN_UNITS
        })
        .collect();
    let tested_units = arm_tested.iter().filter(|t| **t).count();
    let ctx = Context {
        start,
        inner: &inner,
        arm_tested: &arm_tested,
        arms: arms.len(),
    };
    let (design, steps, mut last) = design_level(&ctx, &mut work, opts, obs);
    design_to_untested(&ctx, &mut work, &design);
    // The last design step's per-unit tests are the first unit-level step's.
    let first_tests: Vec<Vec<UnitTest>> = (0..work.len())
        .map(|k| {
            let mut t = last.get_mut(k).map(std::mem::take).unwrap_or_default();
            t.sort_by(|a, b| a.p.total_cmp(&b.p));
            t
        })
        .collect();
    unit_level(&ctx, &mut work, opts, obs)?;
    let mut out = Vec::new();
    for ((w, geo), tests) in work.into_iter().zip(geometric_fits).zip(first_tests) {
        out.push(unit_result(&ctx, w, geo, tests, arms)?);
    }
    Ok(Fleet {
        design,
        steps,
        units: out,
        tested_units,
        arms: arms.to_vec(),
        alpha: opts.alpha,
    })
}

/// What every stage of a fleet diagnosis shares.
struct Context<'a> {
    start: &'a Arm,
    /// The geometric model's settings ([`geometric_options`]).
    inner: &'a crate::fit::options::Options,
    /// Whether each arm's sessions allow the pooled test.
    arm_tested: &'a [bool],
    /// Arms.
    arms: usize,
}

impl Context<'_> {
    /// Whether a recording's evidence enters the pooled test.
    fn in_test(&self, w: &Work) -> bool {
        w.contributes && self.arm_tested[w.arm]
    }
}

/// Each recording's arm (index into `arms`); an error names a recording in no arm.
fn arm_of(units: &[UnitData], arms: &[(String, Vec<usize>)]) -> Result<Vec<usize>, CalibError> {
    let mut arm_of = vec![usize::MAX; units.len()];
    for (a, (_, recs)) in arms.iter().enumerate() {
        for &r in recs {
            arm_of[r] = a;
        }
    }
    if let Some(r) = arm_of.iter().position(|a| *a == usize::MAX) {
        return Err(CalibError::Mismatch(format!(
            "recording {} is in no arm",
            units[r].name
        )));
    }
    Ok(arm_of)
}

/// Every recording's geometric model, folds and candidates: the work list, and the fits on
/// all data (`None` where one failed).
fn start_work<'a>(
    start: &Arm,
    units: &'a [UnitData],
    arm_of: &[usize],
    opts: &Options,
    inner: &crate::fit::options::Options,
    obs: &mut dyn Observer,
) -> (Vec<Work<'a>>, Vec<Option<Fit>>) {
    let mut work: Vec<Work> = Vec::new();
    let mut geometric_fits = Vec::new();
    for (k, u) in units.iter().enumerate() {
        obs.step("geometric fit of recording", k, units.len());
        let cands = candidates::candidates_up_to(start, &u.data, opts.diagnose.max_order);
        let Geometric {
            folds,
            baseline,
            fit,
        } = geometric(start, &u.data, inner);
        let chain: Vec<Holdout> = baseline.into_iter().collect();
        geometric_fits.push(fit);
        let valid = chain.iter().all(|h| h.failed.is_empty());
        let testable = folds.len() >= MIN_UNITS && valid;
        let contributes = folds.len() >= 2 && valid;
        work.push(Work {
            unit: u,
            folds,
            cands,
            effects: Vec::new(),
            levels: Vec::new(),
            chain,
            testable,
            contributes,
            arm: arm_of[k],
        });
    }
    (work, geometric_fits)
}

/// The design level: pool every candidate over the tested arms, Holm, add the strongest;
/// until none passes or the steps run out. Returns the causes, the steps and the last step's
/// per-recording tests (emptied when that step named a cause: they went into the models).
fn design_level(
    ctx: &Context,
    work: &mut [Work],
    opts: &Options,
    obs: &mut dyn Observer,
) -> (Vec<Effect>, Vec<DesignStep>, Vec<Vec<UnitTest>>) {
    let mut design: Vec<Effect> = Vec::new();
    let mut steps = Vec::new();
    let mut last: Vec<Vec<UnitTest>> = Vec::new();
    for step in 0..opts.diagnose.select.max_steps {
        let vocabulary: Vec<Effect> = work
            .iter()
            .filter(|w| ctx.in_test(w))
            .flat_map(|w| w.cands.testable.iter().map(|c| c.effect))
            .filter(|e| !design.contains(e))
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect();
        let what = format!("design step {}: tests of recording", step + 1);
        last = work
            .iter()
            .enumerate()
            .map(|(k, w)| {
                obs.step(&what, k, work.len());
                if !ctx.in_test(w) {
                    return Vec::new();
                }
                vocabulary
                    .iter()
                    .filter(|e| w.can_test(**e))
                    .map(|e| w.test(ctx.start, ctx.inner, *e))
                    .collect()
            })
            .collect();
        let pooled: Vec<Pooled> = vocabulary
            .iter()
            .map(|&e| pool_candidate(e, &last, work, ctx.arms))
            .collect();
        let ps: Vec<f64> = pooled.iter().map(|p| p.pooling.p).collect();
        let rejected = holm(&ps, opts.alpha);
        let mut ranked: Vec<(Pooled, bool)> = pooled.into_iter().zip(rejected).collect();
        ranked.sort_by(|a, b| {
            let (a, b) = (&a.0.pooling, &b.0.pooling);
            a.p.total_cmp(&b.p).then(b.t.total_cmp(&a.t))
        });
        // Of those that pass, the largest pooled gain (a near alias of the true cause passes
        // too, with less gain: the single-arm selection's lowest held-out error likewise).
        let named = ranked
            .iter()
            .filter(|(_, r)| *r)
            .max_by(|a, b| {
                a.0.pooling
                    .mean_log_ratio
                    .total_cmp(&b.0.pooling.mean_log_ratio)
            })
            .map(|(p, _)| p.effect);
        steps.push(DesignStep {
            pooled: ranked,
            named,
        });
        let Some(e) = named else { break };
        design.push(e);
        for (w, ts) in work.iter_mut().zip(std::mem::take(&mut last)) {
            if let Some(t) = ts.into_iter().find(|t| t.effect == e) {
                w.add(Level::Design, t);
            }
        }
    }
    (design, steps, last)
}

/// The random-effects pooling of candidate `e` over the arms: each arm's entry is the
/// sessions of every recording of it that tested `e` (`tests`, one list per recording).
fn pool_candidate(e: Effect, tests: &[Vec<UnitTest>], work: &[Work], arms: usize) -> Pooled {
    let ts: Vec<(usize, f64, f64)> = (0..arms)
        .filter_map(|a| {
            let ys: Vec<f64> = tests
                .iter()
                .zip(work)
                .filter(|(_, w)| w.arm == a)
                .filter_map(|(ts, _)| ts.iter().find(|t| t.effect == e))
                .flat_map(|t| t.per_session.iter().copied())
                .collect();
            let (mean, se, _) = session_summary(&ys, true);
            (ys.len() >= 2).then_some((a, mean, se))
        })
        .collect();
    let y: Vec<f64> = ts.iter().map(|t| t.1).collect();
    let v: Vec<f64> = ts.iter().map(|t| t.2 * t.2).collect();
    let (mu, se, tau2, q) = dersimonian_laird(&y, &v);
    let t = if se > 0.0 { mu / se } else { 0.0 };
    let k = ts.len();
    Pooled {
        effect: e,
        pooling: Pooling {
            units: k,
            units_gaining: y.iter().filter(|y| **y > 0.0).count(),
            mean_log_ratio: mu,
            se,
            tau2,
            q,
            t,
            p: if k >= MIN_FLEET_UNITS {
                t_tail(t, (k - 1) as f64)
            } else {
                1.0
            },
        },
        per_unit: ts,
    }
}

/// Recordings outside the pooled test still get the design's causes when they can be
/// validated.
fn design_to_untested(ctx: &Context, work: &mut [Work], design: &[Effect]) {
    for w in work
        .iter_mut()
        .filter(|w| !ctx.in_test(w) && w.folds.len() >= 2)
    {
        for &e in design {
            if w.can_test(e) {
                let t = w.test(ctx.start, ctx.inner, e);
                w.add(Level::Design, t);
            }
        }
    }
}

/// Unit level: each testable recording alone, by its own test (the single-arm diagnosis,
/// sessions held out whole); a cause it names beyond the design's is kept when its real
/// held-out gain still passes the single-arm rule given the design's causes.
fn unit_level(
    ctx: &Context,
    work: &mut [Work],
    opts: &Options,
    obs: &mut dyn Observer,
) -> Result<(), CalibError> {
    let single = DiagOptions {
        folds: super::FoldChoice::ByGroup,
        ..opts.diagnose.clone()
    };
    let testable = work.iter().filter(|w| w.testable).count();
    for (k, w) in work.iter_mut().filter(|w| w.testable).enumerate() {
        obs.step("own diagnosis of recording", k, testable);
        let own = super::diagnose(ctx.start, &w.unit.data, &single)
            .map_err(|e| CalibError::Mismatch(format!("unit {}: {e}", w.unit.name)))?;
        for c in &own.causes {
            if w.effects.contains(&c.effect) {
                continue;
            }
            let t = w.test(ctx.start, ctx.inner, c.effect);
            let paired = compare(&w.unit.data, w.current(), &t.holdout);
            if paired.p_value() < normal_tail(opts.diagnose.select.z)
                && t.holdout.failed.len() <= w.current().failed.len()
            {
                w.add(Level::Unit, t);
            }
        }
    }
    Ok(())
}

/// One recording's outcome: why it could not be tested, and its causes with their values in
/// a fit of all its data.
fn unit_result(
    ctx: &Context,
    w: Work,
    geo: Option<Fit>,
    tests: Vec<UnitTest>,
    arms: &[(String, Vec<usize>)],
) -> Result<UnitResult, CalibError> {
    let sessions = w.folds.len();
    let counted = if ctx.in_test(&w) && arms[w.arm].1.len() > 1 {
        format!("; its sessions count in arm {}'s evidence", arms[w.arm].0)
    } else {
        String::new()
    };
    let cannot_test = (!w.testable).then(|| {
        if sessions < MIN_UNITS {
            format!(
                "cannot test: {sessions} session{}{counted}",
                plural(sessions)
            )
        } else {
            "cannot test: its geometric model could not be refitted on every fold".into()
        }
    });
    let causes = if w.effects.is_empty() {
        Vec::new()
    } else {
        let fit = super::select::fit_with(ctx.start, &w.unit.data, ctx.inner, &w.effects)?;
        w.effects
            .iter()
            .enumerate()
            .map(|(i, &e)| {
                let c = Confirmation {
                    effect: e,
                    named: true,
                    paired: compare(&w.unit.data, &w.chain[i], &w.chain[i + 1]),
                    holdout: w.chain[i + 1].clone(),
                };
                let indistinguishable = w
                    .cands
                    .testable
                    .iter()
                    .find(|t| t.effect == e)
                    .map(|t| t.indistinguishable.clone())
                    .unwrap_or_default();
                (
                    w.levels[i],
                    super::cause(&fit, &w.unit.data, &c, indistinguishable, None, None),
                )
            })
            .collect()
    };
    Ok(UnitResult {
        name: w.unit.name.clone(),
        file: w.unit.file.clone(),
        sessions,
        cannot_test,
        geometric: geo,
        baseline: w.chain.first().cloned(),
        extended: w.chain.last().cloned(),
        causes,
        candidates: w.cands,
        tests,
    })
}

fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pooling_matches_a_hand_computed_example() {
        // Equal variances 0.01: fixed mean 0.2, Q = Σ (y − 0.2)² / 0.01 = 8, C = 300 − 30000/300
        // = 200, τ² = (8 − 2) / 200 = 0.03, weights 1/0.04 each: μ = 0.2; Hartung–Knapp:
        // Σ w (y − μ)² / (2 Σ w) = 25 · 0.08 / (2 · 75) = 0.04/3, DL's 1/Σw the same.
        let (mu, se, tau2, q) = dersimonian_laird(&[0.0, 0.2, 0.4], &[0.01; 3]);
        assert!((q - 8.0).abs() < 1e-9, "{q}");
        assert!((tau2 - 0.03).abs() < 1e-12, "{tau2}");
        assert!((mu - 0.2).abs() < 1e-12);
        assert!((se - (0.04f64 / 3.0).sqrt()).abs() < 1e-12);
        // Homogeneous units: no spread, the fixed-effect answer (Hartung–Knapp's scatter is
        // 0, floored at DL's variance).
        let (_, se, tau2, _) = dersimonian_laird(&[0.3, 0.3, 0.3], &[0.01; 3]);
        assert_eq!(tau2, 0.0);
        assert!((se - (0.01f64 / 3.0).sqrt()).abs() < 1e-12);
        // Units closer than their variances say: the scatter is below DL's, DL's is kept.
        let (_, se, tau2, _) = dersimonian_laird(&[0.29, 0.3, 0.31], &[0.01; 3]);
        assert_eq!(tau2, 0.0);
        assert!((se - (0.01f64 / 3.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn one_strong_unit_does_not_make_a_design_cause() {
        let (mu, se, ..) = dersimonian_laird(&[1.0, 0.0, -0.01, 0.01, 0.0], &[1e-4; 5]);
        assert!(t_tail(mu / se, 4.0) > 0.1, "t = {}", mu / se);
        // Every unit gains: t = 7.1 on 4 degrees of freedom, p ≈ 1.1e-3, inside the default
        // `--fleet-alpha` of 0.01.
        let (mu, se, ..) = dersimonian_laird(&[1.0, 0.6, 0.8, 1.3, 0.7], &[1e-4; 5]);
        let p = t_tail(mu / se, 4.0);
        assert!(p < 0.01 && p > 1e-4, "t = {}, p = {p}", mu / se);
    }

    #[test]
    fn holm_steps_down() {
        assert_eq!(
            holm(&[0.001, 0.04, 0.012, 0.5], 0.05),
            vec![true, false, true, false]
        );
        assert_eq!(holm(&[0.02, 0.03], 0.03), vec![false, false]);
    }

    #[test]
    fn names_drop_the_shared_prefix_up_to_a_dash() {
        let p = |s: &'static str| Path::new(s);
        let n = unit_names(&[
            p("d/mukca-panda-panda_3.csv"),
            p("d/mukca-panda-panda_3_bis.csv"),
            p("mukca-panda-panda_right.csv"),
        ]);
        assert_eq!(n, vec!["panda_3", "panda_3_bis", "panda_right"]);
        assert_eq!(unit_names(&[p("a.csv"), p("b.csv")]), vec!["a", "b"]);
        // A stem that is the whole shared prefix keeps every name whole.
        assert_eq!(unit_names(&[p("x-1.csv"), p("x-.csv")]), vec!["x-1", "x-"]);
    }
}
