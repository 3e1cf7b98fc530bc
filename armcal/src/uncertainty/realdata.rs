//! Coverage on real recordings (MUKCa, `data/mukca/`): whole sessions held out.
//!
//! For each session of a unit, the unit is calibrated on all its other sessions and the
//! budget estimated as `armcal calibrate` does (probing from the training sessions' scatter
//! about their socket centres: on these data that also holds what the model leaves
//! unexplained). The held-out session's probings are then compared with their socket's
//! centre, the mean of the calibrated model's ball centres over that socket's n probings in
//! the session (the authors' metric). The deviation r_i = p_i − (1/n) Σ_j p_j is predicted
//! to first order with its own covariance: the parameters' part through J_i − J̄ (what all
//! the socket's probings share cancels), the readings' own parts as (1 − 2/n) Σ_i +
//! (1/n²) Σ_j Σ_j. A probing is covered when |r_i| is within the U95 of that covariance.
//!
//! The nested budget is what `calibrate --by-group` writes from the training sessions alone:
//! the pose-dependent term ([`super::pose`]) and the isotropic term from their own
//! leave-one-session-out fits, so the scored session never sets either.

pub mod forms;
pub mod placement;

use super::estimate::{self, Settings};
use super::{propagate, u95, Budget};
use crate::data::Dataset;
use crate::fit::residuals::residuals;
use crate::mukca::{self, Unit};
use quatarm_ref::arm::Arm;
use serde::Serialize;
use std::collections::BTreeMap;

/// One unit's figures.
#[derive(Clone, Debug, Serialize)]
pub struct UnitCoverage {
    /// The unit.
    pub unit: String,
    /// Sessions held out and judged.
    pub sessions: usize,
    /// Sessions whose training fit failed, with the reason.
    pub failed: Vec<String>,
    /// Probings judged.
    pub probings: usize,
    /// Fraction within their predicted 95 % region, the budget as `calibrate` writes it.
    pub covered: f64,
    /// The same with a model term from the other sessions' held-out excess.
    pub covered_with_model: f64,
    /// The same with the model term `calibrate --by-group` writes, estimated on the training
    /// sessions alone (each held out in turn: nested, the scored session never sets it).
    pub covered_nested: f64,
    /// Median U95 (mm) and mean model term (mm per axis) of the nested budget.
    pub nested_u95_mm: f64,
    /// Mean nested model term (mm per axis).
    pub nested_model_mm: f64,
    /// Sensitivity of the nested coverage to the pose term: (factor m on its standard
    /// deviation, coverage with m² times the pose term in C). m = 1 is `covered_nested`.
    pub pose_sweep: Vec<(f64, f64)>,
    /// The nested pose term's scale κ per held-out session (0: none) and whether it was
    /// validated (≥ 3 training sessions).
    pub pose_scale: Vec<(f64, bool)>,
    /// Per held-out session: (name, probings, fraction covered by the nested budget,
    /// fraction flagged as extrapolated from the training sessions in tip space, and in
    /// joint space).
    pub per_session: Vec<(String, usize, f64, f64, f64, [f64; 2])>,
    /// Per held-out session, in `per_session`'s order: the median U95 of the nested budget
    /// and the RMS deviation of its probings from their socket's centre (mm). A measurement
    /// of where the budget is wide and where the misfit is large, session by session (the
    /// placement check, [`placement`]).
    pub per_session_u95_rms_mm: Vec<[f64; 2]>,
    /// Median U95 of the probings (mm), without and with the model term.
    pub median_u95_mm: [f64; 2],
    /// RMS distance of the probings from their socket's centre (mm).
    pub rms_deviation_mm: f64,
    /// Mean probing term the training sessions gave (mm per axis).
    pub probing_mm: f64,
    /// Mean model term the other sessions gave (mm per axis).
    pub model_mm: f64,
}

/// How the nested budget sets the pose term's scale (see [`super::estimate::Settings`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rule {
    /// κ where two training sessions cannot set it (the fleet's).
    pub two_group_scale: f64,
    /// The fleet κ's weight in a validated κ ([`super::pose::pooled_scale`]; 0: none).
    pub prior_groups: f64,
    /// The leverage-scaled variant ([`super::pose::leverage_factor`]): the pose part of each
    /// probing's covariance times its leverage ratio, in the validation and in the scoring.
    pub leverage: bool,
    /// With `leverage`, the joints' ℓJ in the factor, max(1, ℓ, ℓJ) (opt-in,
    /// `--joint-leverage`; off: the product's max(1, ℓ)).
    pub joint_leverage: bool,
    /// With `leverage`, κ validated with each held-out row's ℓ against its fold's own
    /// design ([`super::estimate::Settings::fold_leverage`]; off in the product).
    pub fold_leverage: bool,
}

impl Rule {
    /// The budget's settings under this rule (the rest as `calibrate` has them).
    fn settings(&self) -> Settings {
        Settings {
            two_group_scale: self.two_group_scale,
            fleet_prior_groups: self.prior_groups,
            leverage_scaled: self.leverage,
            joint_leverage: self.joint_leverage,
            fold_leverage: self.fold_leverage,
            ..Settings::default()
        }
    }

    /// The product's rule with the fleet's κ `two_group_scale`.
    pub fn product(two_group_scale: f64) -> Rule {
        Rule {
            two_group_scale,
            prior_groups: 0.0,
            leverage: true,
            joint_leverage: false,
            fold_leverage: false,
        }
    }
}

/// Each session's coverage under the budget `calibrate --by-group` writes from *every*
/// session of `unit` under `rule` (the report's "held-out groups" line, and a warning for
/// each group it misses as a whole: [`super::misfit::GroupCoverage::missed`]), by session
/// name. Not nested: the scored session is in the fit and in κ; what it measures is whether
/// the report names the sessions that the nested check ([`unit_coverage`]) finds missed.
/// `None` when the unit cannot be calibrated or has fewer than two sessions.
pub fn named_sessions(
    unit: &Unit,
    rule: Rule,
) -> Option<BTreeMap<String, super::misfit::GroupCoverage>> {
    let opts = mukca::options(None);
    let fit = crate::fit::calib::calibrate(&unit.arm, &unit.data, &opts).ok()?;
    let h = crate::fit::holdout::validate(
        &unit.arm,
        &unit.data,
        &opts,
        &crate::fit::holdout::by_group(&unit.data),
    );
    (h.folds > 1).then_some(())?;
    let e = estimate::from_fit(&fit, &unit.data, Some(&h), 0.0, &rule.settings()).ok()?;
    Some(
        e.model?
            .groups
            .into_iter()
            .filter_map(|g| Some((unit.sessions.get(&g.group)?.clone(), g)))
            .collect(),
    )
}

/// The margin (rad, about 5.7°) of the per-joint range check measured beside the others.
pub const RANGE_MARGIN: f64 = 0.1;

/// A held-out session: its calibration, budget, data and what its probings showed.
struct Held {
    arm: Arm,
    budget: Budget,
    /// The budget with the nested model term.
    nested: Budget,
    /// Its pose-dependent part of C (zero when there is none).
    pose: nalgebra::DMatrix<f64>,
    /// The pose term's scale and whether it was validated.
    pose_scale: (f64, bool),
    /// Fraction of the held-out probings far from every training probing.
    far: f64,
    /// Fraction outside the training sessions' joint-space spread.
    joint_far: f64,
    /// Fraction with a joint outside the training sessions' range, by more than 0 and by
    /// more than [`RANGE_MARGIN`] rad.
    range_far: [f64; 2],
    test: Dataset,
    /// Per probing: (row, U95 of the nested budget under the rule).
    nested_u95: Vec<(usize, f64)>,
    /// Per probing: (row, |deviation|, predicted U95, per-axis variance the budget missed).
    probings: Vec<(usize, f64, f64, f64)>,
}

/// Calibrates on every session but `g` and judges `g` with the budget as written;
/// `two_group_scale` is the pose term's κ when two training sessions cannot set it.
fn hold_out(unit: &Unit, groups: &[i64], g: i64, rule: Rule) -> Result<Held, super::BudgetError> {
    let train: Vec<i64> = groups.iter().copied().filter(|x| *x != g).collect();
    let train_data = unit.sessions_data(&train);
    let opts = mukca::options(None);
    let fit = crate::fit::calib::calibrate(&unit.arm, &train_data, &opts)?;
    let no_model = Settings {
        model_mm: Some(0.0),
        ..Settings::default()
    };
    let budget = estimate::from_fit(&fit, &train_data, None, 0.0, &no_model)?.budget;
    // As `calibrate --by-group` on the training sessions: each held out in turn, the model
    // term from their residuals.
    let inner = crate::fit::holdout::validate(
        &unit.arm,
        &train_data,
        &opts,
        &crate::fit::holdout::by_group(&train_data),
    );
    let (nested, pose, pose_scale) = if inner.folds > 1 {
        let e = estimate::from_fit(&fit, &train_data, Some(&inner), 0.0, &rule.settings())?;
        let without = estimate::from_fit(&fit, &train_data, Some(&inner), 0.0, &no_model)?;
        let scale = e
            .model
            .as_ref()
            .and_then(|m| m.pose.as_ref())
            .map_or((0.0, false), |p| (p.scale, p.validated));
        let pose = &e.budget.cov - &without.budget.cov;
        (e.budget, pose, scale)
    } else {
        let n = budget.params.len();
        (budget.clone(), nalgebra::DMatrix::zeros(n, n), (0.0, false))
    };
    let test = unit.sessions_data(&[g]);
    let res = residuals(&fit.arm, &test, None);
    let mut probings = Vec::new();
    for end in test.layout().length_ends() {
        let n = end.len() as f64;
        for (i, u, trace) in socket_u95(&fit.arm, &budget, &test, end) {
            let d = res.rows[i].norm();
            probings.push((i, d, u, (d * d - trace) / (3.0 * (1.0 - 1.0 / n))));
        }
    }
    let nested_u95 = nested_u95(&fit.arm, &nested, &test);
    let far = super::extrapolation::Support::of(&fit.arm, &train_data).map_or(0.0, |sup| {
        let m = crate::fit::probes::Mounted::new(&fit.arm);
        let n = test.rows.iter().filter(|r| sup.far(&m.tip(r))).count();
        n as f64 / test.rows.len().max(1) as f64
    });
    let range_far = super::extrapolation::JointRange::of(&train_data).map_or([0.0; 2], |r| {
        let n = test.rows.len().max(1) as f64;
        let share = |m: f64| test.rows.iter().filter(|t| r.excess(&t.theta) > m).count() as f64 / n;
        [share(0.0), share(RANGE_MARGIN)]
    });
    let joint_far = super::extrapolation::JointSupport::of(&train_data).map_or(0.0, |sup| {
        let n = test.rows.iter().filter(|r| sup.far(&r.theta)).count();
        n as f64 / test.rows.len().max(1) as f64
    });
    Ok(Held {
        nested_u95,
        joint_far,
        range_far,
        pose,
        pose_scale,
        far,
        arm: fit.arm,
        budget,
        nested,
        test,
        probings,
    })
}

/// Each held-out probing's U95 under the nested budget `nested` as `calibrate --by-group`
/// writes it: with the leverage rule its pose part is kept apart and scaled per probing by
/// its tip's leverage ratio, by the product's own propagation.
fn nested_u95(arm: &Arm, nested: &Budget, test: &Dataset) -> Vec<(usize, f64)> {
    let ends = |d: &Dataset| -> Vec<Vec<usize>> { d.layout().length_ends().cloned().collect() };
    // The nested budget as written, the leverage-scaled pose part applied per probing by
    // the product's own propagation (`propagate::group_deviations`).
    ends(test)
        .iter()
        .flat_map(|end| socket_u95(arm, nested, test, end))
        .map(|(i, u, _)| (i, u))
        .collect()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// Leave-one-session-out coverage of a unit (`None` with fewer than two sessions). The
/// model term of session g is the mean per-axis variance the budget missed on the other
/// sessions' held-out probings (g's own probings never set it). `two_group_scale`: the pose
/// term's κ where only two training sessions are left (from other units: see
/// [`two_group_scores`]).
/// `rule`: how the nested budget sets the pose term's scale ([`Rule::product`] for the
/// budget `calibrate --by-group` writes).
pub fn unit_coverage(unit: &Unit, rule: Rule) -> Option<UnitCoverage> {
    let groups = unit.groups();
    if groups.len() < 2 {
        return None;
    }
    let (mut held, mut failed) = (Vec::new(), Vec::new());
    for &g in &groups {
        match hold_out(unit, &groups, g, rule) {
            Ok(h) => held.push(h),
            Err(e) => failed.push(format!(
                "{}: {e}",
                unit.sessions.get(&g).cloned().unwrap_or_default()
            )),
        }
    }
    let all: Vec<&(usize, f64, f64, f64)> = held.iter().flat_map(|h| &h.probings).collect();
    let judged = all.len().max(1) as f64;
    let (mut inside_model, mut u_model, mut model_sum) = (0usize, Vec::new(), 0.0);
    for (k, h) in held.iter().enumerate() {
        let others: Vec<f64> = held
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != k)
            .flat_map(|(_, o)| o.probings.iter().map(|p| p.3))
            .collect();
        let mut b = h.budget.clone();
        b.model_mm = (others.iter().sum::<f64>() / others.len().max(1) as f64)
            .max(0.0)
            .sqrt();
        model_sum += b.model_mm;
        for end in h.test.layout().length_ends() {
            for (i, u, _) in socket_u95(&h.arm, &b, &h.test, end) {
                let d = h.probings.iter().find(|p| p.0 == i).map_or(0.0, |p| p.1);
                inside_model += usize::from(d <= u);
                u_model.push(u);
            }
        }
    }
    let (mut inside_nested, mut u_nested, mut per_session) = (0usize, Vec::new(), Vec::new());
    let mut per_session_u95_rms_mm = Vec::new();
    for h in &held {
        let (mut n, mut k, mut sq, mut us) = (0usize, 0usize, 0.0, Vec::new());
        for &(i, u) in &h.nested_u95 {
            let d = h.probings.iter().find(|p| p.0 == i).map_or(0.0, |p| p.1);
            k += usize::from(d <= u);
            n += 1;
            sq += d * d;
            us.push(u);
            u_nested.push(u);
        }
        inside_nested += k;
        per_session_u95_rms_mm.push([median(us), (sq / n.max(1) as f64).sqrt()]);
        let g = h.test.rows.first().map_or(0, |r| r.group);
        per_session.push((
            unit.sessions.get(&g).cloned().unwrap_or_default(),
            n,
            k as f64 / n.max(1) as f64,
            h.far,
            h.joint_far,
            h.range_far,
        ));
    }
    let pose_sweep = [0.0, 0.5, 1.0, 1.5, 2.0, 3.0]
        .into_iter()
        .map(|m: f64| {
            let mut inside = 0usize;
            for h in &held {
                let mut b = h.nested.clone();
                b.cov = &b.cov + &h.pose * (m * m - 1.0);
                b.pose = b.pose.map(|p| p.scaled(m));
                for end in h.test.layout().length_ends() {
                    for (i, u, _) in socket_u95(&h.arm, &b, &h.test, end) {
                        let d = h.probings.iter().find(|p| p.0 == i).map_or(0.0, |p| p.1);
                        inside += usize::from(d <= u);
                    }
                }
            }
            (m, inside as f64 / judged)
        })
        .collect();
    let sessions = held.len().max(1) as f64;
    Some(UnitCoverage {
        pose_sweep,
        pose_scale: held.iter().map(|h| h.pose_scale).collect(),
        covered_nested: inside_nested as f64 / judged,
        nested_u95_mm: median(u_nested),
        nested_model_mm: held.iter().map(|h| h.nested.model_mm).sum::<f64>() / sessions,
        per_session,
        per_session_u95_rms_mm,
        unit: unit.name.clone(),
        sessions: held.len(),
        failed,
        probings: all.len(),
        covered: all.iter().filter(|p| p.1 <= p.2).count() as f64 / judged,
        covered_with_model: inside_model as f64 / judged,
        median_u95_mm: [median(all.iter().map(|p| p.2).collect()), median(u_model)],
        rms_deviation_mm: (all.iter().map(|p| p.1 * p.1).sum::<f64>() / judged).sqrt(),
        probing_mm: held.iter().map(|h| h.budget.probing_mm).sum::<f64>() / sessions,
        model_mm: model_sum / sessions,
    })
}

/// (row, U95 of its deviation from the socket's centre, trace of that deviation's
/// covariance) for the probings `rows` of a socket.
fn socket_u95(arm: &Arm, b: &Budget, data: &Dataset, rows: &[usize]) -> Vec<(usize, f64, f64)> {
    propagate::group_deviations(arm, b, data, rows)
        .into_iter()
        .map(|(i, s)| (i, u95::u95(&s), s.trace()))
        .collect()
}

/// The (leverage-scaled) pose term's least covering κ for held-out probings when S_b comes
/// from two sessions
/// (the regime where the data cannot set κ, [`super::pose::TWO_GROUP_SCALE`]): for each pair
/// of consecutive sessions (cyclic) of a unit with ≥ 3 sessions, the unit is calibrated on
/// the pair, S_b (1 + 1/2) taken from the pair's two leave-one-session-out fits, and every
/// other session's probings scored against it beyond the rest of the budget
/// ([`super::pose::least_scales`]). Empty with fewer than 3 sessions. A fleet's κ for a unit
/// is taken from the *other* units' scores, so a unit never sets its own.
pub fn two_group_scores(unit: &Unit) -> Vec<f64> {
    two_group_scores_with(unit, true)
}

/// [`two_group_scores`] under the factor max(1, ℓ, ℓJ) (`joint_leverage`, the product's) or
/// max(1, ℓ) (stop 37's).
pub fn two_group_scores_with(unit: &Unit, joint_leverage: bool) -> Vec<f64> {
    let lambda = super::pose::prior_weight(1);
    // [λ form, C itself, λ form × max(1, ℓ), ℓ, λ form × max(1, ℓ, ℓJ)]: the product's is
    // the leverage-scaled one.
    let at = if joint_leverage { 4 } else { 2 };
    two_group_scores_by_form(unit, &[lambda])
        .into_iter()
        .map(|(_, t)| t[at])
        .collect()
}

/// [`two_group_scores`] under several forms of the term at once, measured for issue 27
/// (`coverage` bench, `mukca-variants`): per scored probing, (its session, its least
/// covering κ under each shrinkage weight λ of `lambdas` ([`super::pose::between_with`]),
/// then under C itself (a term ∝ J C Jᵀ = σ̂² times the probing's leverage), then under the
/// budget's form times max(1, ℓ), then ℓ itself, then the budget's form times
/// max(1, ℓ, ℓJ), ℓJ against the pair's joint angles). ℓ is the probing's leverage ratio as the
/// product computes it: its tip's tr(J C Jᵀ) over the mean of the same over the training
/// rows, large where the placement is one the training design did not see (the budget's
/// form × max(1, ℓ) is the product's, the file's `pose_*` keys). For a unit with three sessions the pairs are the outer folds of the nested
/// run, so these scores are its nested coverage as a function of κ.
pub fn two_group_scores_by_form(unit: &Unit, lambdas: &[f64]) -> Vec<(i64, Vec<f64>)> {
    let groups = unit.groups();
    let mut out = Vec::new();
    if groups.len() < 3 {
        return out;
    }
    let opts = mukca::options(None);
    let no_model = Settings {
        model_mm: Some(0.0),
        ..Settings::default()
    };
    for k in 0..groups.len() {
        let pair = [groups[k], groups[(k + 1) % groups.len()]];
        let data = unit.sessions_data(&pair);
        let Ok(fit) = crate::fit::calib::calibrate(&unit.arm, &data, &opts) else {
            continue;
        };
        let inner = crate::fit::holdout::validate(
            &unit.arm,
            &data,
            &opts,
            &crate::fit::holdout::by_group(&data),
        );
        if inner.fits.len() < 2 {
            continue;
        }
        let Ok(e) = estimate::from_fit(&fit, &data, Some(&inner), 0.0, &no_model) else {
            continue;
        };
        let rest = e.budget;
        let fits: Vec<&crate::fit::holdout::FoldFit> = inner.fits.iter().collect();
        // A budget of the parameters' covariance `cov` alone.
        let only = |cov: nalgebra::DMatrix<f64>| Budget::of_parameters(&rest.params, cov, data.dof);
        let poses: Vec<Budget> = lambdas
            .iter()
            .map(|&l| only(super::pose::between_with(&rest.params, &fits, 2, &rest.cov, l) * 1.5))
            .collect();
        let budget_form = only(super::pose::between(&rest.params, &fits, 2, &rest.cov) * 1.5);
        let c_only = only(rest.cov.clone());
        // The leverage ratio's normaliser: the mean tip tr(J C Jᵀ) over the training rows
        // (the product's `pose_leverage_mean`).
        let lev = |d: &Dataset| super::pose::tip_leverages(&fit.arm, &rest.params, &rest.cov, d);
        let train_lev = lev(&data);
        let mean_lev = train_lev.iter().sum::<f64>() / train_lev.len().max(1) as f64;
        let joints = super::extrapolation::joint_leverage(&data);
        for &s in groups.iter().filter(|s| !pair.contains(s)) {
            let test = unit.sessions_data(&[s]);
            let res = residuals(&fit.arm, &test, None);
            let test_lev = lev(&test);
            for end in test.layout().length_ends() {
                let m = 1.0 - 1.0 / end.len() as f64;
                let (rows, d): (Vec<_>, Vec<_>) =
                    propagate::group_deviations(&fit.arm, &rest, &test, end)
                        .into_iter()
                        .map(|(i, s)| (super::misfit::RowCov { row: i, s, m }, res.rows[i].norm()))
                        .unzip();
                let mut per_form: Vec<Vec<f64>> = poses
                    .iter()
                    .map(|pose| {
                        let extra: Vec<_> = propagate::group_deviations(&fit.arm, pose, &test, end)
                            .into_iter()
                            .map(|(_, p)| p)
                            .collect();
                        super::pose::least_scales(&rows, &extra, &d)
                    })
                    .collect();
                let jc: Vec<_> = propagate::group_deviations(&fit.arm, &c_only, &test, end)
                    .into_iter()
                    .map(|(_, p)| p)
                    .collect();
                let l: Vec<f64> = rows.iter().map(|r| test_lev[r.row] / mean_lev).collect();
                per_form.push(super::pose::least_scales(&rows, &jc, &d));
                let ext: Vec<_> = propagate::group_deviations(&fit.arm, &budget_form, &test, end)
                    .into_iter()
                    .zip(&l)
                    .map(|((_, p), l)| p * l.max(1.0))
                    .collect();
                per_form.push(super::pose::least_scales(&rows, &ext, &d));
                let ext_j: Vec<_> = ext
                    .iter()
                    .zip(&rows)
                    .zip(&l)
                    .map(|((p, r), l)| {
                        let ratio = propagate::Leverage {
                            tip: Some(*l),
                            joints: joints.as_ref().map(|j| j.ratio(&test.rows[r.row].theta)),
                        }
                        .ratio()
                        .unwrap_or(1.0);
                        p * (super::pose::leverage_factor(ratio) / l.max(1.0))
                    })
                    .collect();
                per_form.push(l);
                per_form.push(super::pose::least_scales(&rows, &ext_j, &d));
                out.extend((0..rows.len()).map(|r| (s, per_form.iter().map(|f| f[r]).collect())));
            }
        }
    }
    out
}

/// The fleet's two-session κ: the median over units of each unit's conformal κ
/// ([`super::pose::conformal_scale`] of its [`two_group_scores`]). 0 without units.
pub fn fleet_scale(per_unit: &[f64]) -> f64 {
    let mut v = per_unit.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => 0.0,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// A sensitivity beside [`fleet_scale`]: the least κ at which the units' mean coverage of
/// their [`two_group_scores`] reaches 95 % (each unit weighted alike, whatever its rows).
/// [`SCALE_MAX`](super::pose::SCALE_MAX) when none does; 0 without units.
pub fn fleet_scale_mean_coverage(per_unit: &[Vec<f64>]) -> f64 {
    let units: Vec<&Vec<f64>> = per_unit.iter().filter(|t| !t.is_empty()).collect();
    if units.is_empty() {
        return 0.0;
    }
    let mean = |k: f64| {
        units
            .iter()
            .map(|t| t.iter().filter(|x| **x <= k).count() as f64 / t.len() as f64)
            .sum::<f64>()
            / units.len() as f64
    };
    let mut candidates: Vec<f64> = units
        .iter()
        .flat_map(|t| t.iter().copied())
        .filter(|x| x.is_finite())
        .collect();
    candidates.sort_by(f64::total_cmp);
    candidates
        .into_iter()
        .find(|&k| mean(k) >= super::u95::LEVEL)
        .unwrap_or(super::pose::SCALE_MAX)
}
