//! The pose-dependent model term: how much the model's parameters move from one group of the
//! data to another (a session, an artefact placement), propagated to the tip by the chain's
//! Jacobian (`spec/uncertainty.md`, real arms; argued in `docs/spec-reading.md`).
//!
//! A geometric model that misses an effect (compliance, a harmonic, a thermal drift) fits
//! each placement of the work with slightly different parameters: what it cannot represent
//! is absorbed differently where the arm is posed differently. At a new placement the error
//! is then that of a new draw of the parameters, which is large where the chain amplifies
//! it (a raised artefact, full reach) and small near the base: a pose-dependent error that
//! one isotropic radius cannot describe.
//!
//! - **Its estimate.** Held-out validation by group fits the model on all groups but g, for
//!   each g: θ₋g. Were a fit the mean of per-group parameters θ_h, θ₋g − mean = (mean −
//!   θ_g)/(G − 1), so the between-group covariance of the θ_h is S_b = (G − 1)² · the sample
//!   covariance of the θ₋g (the jackknife's pseudo-values, without fitting any group alone,
//!   which a single degenerate session could not support). A new group's parameters differ
//!   from the fit on all G by S_b (1 + 1/G): that is what joins the budget's C, so the
//!   table's format and the hub are unchanged (the hub propagates C).
//! - **Its scale, nested.** S_b has G − 1 degrees of freedom and is noisy with few groups.
//!   With G ≥ 3 its scale κ is set by split-conformal prediction on the held-out rows: each
//!   row of group g is scored against S_b estimated *without* g (from the other θ₋h, in
//!   which g's own parameters cancel) times (1 + 1/(G − 1)), and κ is the ⌈0.95 (n + 1)⌉-th
//!   smallest of the rows' least covering scales. The held-out spread has one degree of
//!   freedom fewer than the one written, so κ carries the few-groups correction a Student-t
//!   factor would (measured, not assumed). With G = 2 no row can be scored without its own
//!   group: κ is then borrowed from other arms ([`TWO_GROUP_SCALE`], `--fleet-kappa`), the
//!   κ that covers a third session when S_b comes from two, measured in that regime, and the
//!   report says the term was not validated on this arm.
//! - **Shrunk.** With few groups S_b has rank G − 1: no spread in the directions the groups
//!   did not happen to differ in. It is shrunk towards the fit's own covariance C, scaled to
//!   the same size in C's metric, with the weight of one group ([`shrink`]).
//! - An unknown a fold's fit held (not identified without that group) has no value there
//!   and no deviation.

use super::misfit::RowCov;
use super::{u95, Budget};
use crate::data::Dataset;
use crate::fit::holdout::{FoldFit, Holdout};
use crate::params::{Param, ParamExt};
use nalgebra::{DMatrix, DVector, Matrix3};
use std::collections::BTreeSet;

/// Largest scale κ tried: a row the term cannot cover within it is left to the isotropic
/// term.
pub const SCALE_MAX: f64 = 30.0;

/// κ for two groups, where the data cannot set it: borrowed from a fleet of other arms,
/// measured in the same regime. On each MUKCa unit with ≥ 3 sessions, each pair of
/// consecutive sessions (cyclic) is calibrated, S_b taken from its two leave-one-session-out
/// fits, and every other session's probings scored ([`least_scales`]) under the product's
/// form (each probing's pose part times its tip's max(1, ℓ)); the unit's κ is the conformal
/// quantile of its scores ([`conformal_scale`]) and this is the median over the 9 units
/// (`cargo test --profile test -p armcal --bench coverage -- mukca`, the line `two-session κ
/// of the fleet`; `docs/results/uncertainty.md`). 1.104 for the term without the leverage
/// factor (stop 35's form, `Settings::leverage_scaled` off); with the joint leverage
/// [`TWO_GROUP_SCALE_WITH_JOINTS`]. A median over units, not a quantile over their pooled
/// rows: the target is each unit's coverage, and one unit whose bad session no scale covers
/// (panda_2 `high`) must not set every other unit's width. `--fleet-kappa` replaces it with
/// the caller's fleet.
pub const TWO_GROUP_SCALE: f64 = 0.968;

/// [`TWO_GROUP_SCALE`] measured the same way with the factor max(1, ℓ, ℓJ) (the opt-in
/// joint leverage, `--joint-leverage`; `mukca joints`, round 6): a smaller κ, because ℓJ
/// widens the far sessions' scores' own factor.
pub const TWO_GROUP_SCALE_WITH_JOINTS: f64 = 0.760;

/// The fleet's two-group κ for the factor in use: with the joint leverage or without.
pub fn two_group_scale(joint_leverage: bool) -> f64 {
    if joint_leverage {
        TWO_GROUP_SCALE_WITH_JOINTS
    } else {
        TWO_GROUP_SCALE
    }
}

/// Where the term came from (the report's provenance).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PoseSource {
    /// Groups whose held-out fits gave it.
    pub groups: usize,
    /// κ, the factor of S_b (1 + 1/G) (its square multiplies the covariance).
    pub scale: f64,
    /// Whether κ was set on rows scored without their own group's spread (G ≥ 3).
    pub validated: bool,
    /// Held-out rows scored.
    pub rows: usize,
    /// Fraction of them inside their 95 % region without the term, and with it.
    pub covered: [f64; 2],
    /// RMS of the tip's standard deviation the term adds at the held-out rows (mm per axis).
    pub rms_mm: f64,
    /// The leverage-scaled form's figures, when the term is kept apart for it.
    pub leverage: Option<LeverageSource>,
}

/// What the report says of a leverage-scaled term (the file's `pose_*` keys).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LeverageSource {
    /// D's columns r.
    pub rank: usize,
    /// b.
    pub shrink: f64,
    /// The calibration rows' mean tr(J C_fit Jᵀ) of the tip (mm²).
    pub mean_mm2: f64,
    /// The least and the largest ℓ among the calibration rows: above the largest, a reading
    /// is extrapolated ([`super::extrapolation`]'s sense, in the parameters' leverage).
    pub range: [f64; 2],
    /// Directions of the between-group spread beyond [`POSE_RANK_MAX`] folded into b (0:
    /// none, the written covariance is today's exactly).
    pub folded: usize,
    /// The joint leverage written beside it (the file's `pose_joint_*` keys), when the
    /// calibration's joint angles had a spread to estimate it from.
    pub joints: Option<JointsSource>,
}

/// What the report says of the joint leverage ℓJ: estimated from which rows and joints.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct JointsSource {
    /// Calibration rows its mean and covariance were taken over.
    pub rows: usize,
    /// The joints that moved (1-based, as the data's j1..jN), the others' rows and columns
    /// of W being 0.
    pub joints: Vec<usize>,
}

pub use quatarm_ref::uncertainty::POSE_RANK_MAX;

/// The term.
#[derive(Clone, Debug)]
pub struct PoseTerm {
    /// To add to the budget's C (the budget's parameter order).
    pub cov: DMatrix<f64>,
    /// Per row of the `rows` it was estimated on: the term's part of that row's prediction.
    pub extra: Vec<Matrix3<f64>>,
    /// Its provenance.
    pub source: PoseSource,
    /// `cov` as D and b, with the calibration rows' leverage mean, for the leverage-scaled
    /// form (`None`: the term is `cov` alone at every reading).
    pub split: Option<super::PoseSplit>,
}

/// The group of each fold that fitted, when each left out one whole group.
pub(crate) fn fold_groups(data: &Dataset, fits: &[FoldFit]) -> Option<Vec<i64>> {
    let mut seen = BTreeSet::new();
    let mut out = Vec::new();
    for f in fits {
        let g = data.rows.get(*f.rows.first()?)?.group;
        if !f.rows.iter().all(|&i| data.rows[i].group == g) || !seen.insert(g) {
            return None;
        }
        out.push(g);
    }
    (out.len() >= 2).then_some(out)
}

/// Each fit's parameters `params` less their mean over the fits that estimated them.
fn deviations(params: &[Param], fits: &[&FoldFit]) -> Vec<DVector<f64>> {
    let vals: Vec<Vec<Option<f64>>> = fits
        .iter()
        .map(|f| {
            params
                .iter()
                .map(|q| f.fitted.contains(q).then(|| q.value(&f.arm)))
                .collect()
        })
        .collect();
    let mut out = vec![DVector::zeros(params.len()); fits.len()];
    for k in 0..params.len() {
        let have: Vec<f64> = vals.iter().filter_map(|v| v[k]).collect();
        if have.len() < 2 {
            continue;
        }
        let mean = have.iter().sum::<f64>() / have.len() as f64;
        for (d, v) in out.iter_mut().zip(&vals) {
            if let Some(x) = v[k] {
                d[k] = x - mean;
            }
        }
    }
    out
}

/// S_b from the leave-one-group-out fits `fits` of `groups` groups in all: (G − 1)² times
/// their sample covariance, shrunk towards the fit's own covariance `c` (see [`shrink`]).
pub fn between(
    params: &[Param],
    fits: &[&FoldFit],
    groups: usize,
    c: &DMatrix<f64>,
) -> DMatrix<f64> {
    let nu = fits.len().saturating_sub(1);
    between_with(params, fits, groups, c, prior_weight(nu))
}

/// [`between`] with the shrinkage weight `lambda` given (0: the raw spread, 1: C alone, at
/// the spread's size in C's metric). The benchmark measures the family; the budget uses
/// [`prior_weight`].
pub fn between_with(
    params: &[Param],
    fits: &[&FoldFit],
    groups: usize,
    c: &DMatrix<f64>,
    lambda: f64,
) -> DMatrix<f64> {
    shrink_by(raw_between(params, fits, groups), c, lambda)
}

/// S_b before shrinking: (G − 1)² times the sample covariance of the fits' parameters.
fn raw_between(params: &[Param], fits: &[&FoldFit], groups: usize) -> DMatrix<f64> {
    let p = params.len();
    let mut s = DMatrix::zeros(p, p);
    if fits.len() < 2 {
        return s;
    }
    for d in deviations(params, fits) {
        s += &d * d.transpose();
    }
    let g = groups as f64 - 1.0;
    s * (g * g / (fits.len() - 1) as f64)
}

/// The weight of the prior (C's shape) in a spread of ν degrees of freedom: that of one
/// group, 1/(ν + 1).
pub fn prior_weight(nu: usize) -> f64 {
    1.0 / (nu as f64 + 1.0)
}

/// A spread `s` of ν degrees of freedom shrunk towards the shape of `c`:
/// (1 − λ) s + λ t c with t = tr(c⁻¹ s)/p (the same size in the metric of c) and
/// λ = 1/(ν + 1), a prior worth one group. With few groups s has rank ν and no spread at
/// all in the directions the groups did not happen to differ in; a new group will differ
/// there too, and the fit's own covariance is the best shape known for them. `s` unchanged
/// when `c` is not positive definite.
pub fn shrink(s: DMatrix<f64>, c: &DMatrix<f64>, nu: usize) -> DMatrix<f64> {
    shrink_by(s, c, prior_weight(nu))
}

/// [`shrink`] with the weight λ given.
pub fn shrink_by(s: DMatrix<f64>, c: &DMatrix<f64>, lambda: f64) -> DMatrix<f64> {
    let (s, w) = shrink_parts(s, c, lambda);
    s + c * w
}

/// [`shrink_by`] in its two parts: ((1 − λ) s, λ t), the shrunk spread being the first plus
/// the second times `c`; (s, 0) where it leaves `s` unchanged.
fn shrink_parts(s: DMatrix<f64>, c: &DMatrix<f64>, lambda: f64) -> (DMatrix<f64>, f64) {
    let p = s.nrows();
    let Some(ch) = c.clone().cholesky() else {
        return (s, 0.0);
    };
    let t = ch.solve(&s).trace() / p.max(1) as f64;
    if !(t.is_finite() && t > 0.0) {
        return (s, 0.0);
    }
    (s * (1.0 - lambda), lambda * t)
}

/// A spread `s` (positive semi-definite) as D Dᵀ with at most [`POSE_RANK_MAX`] columns, and
/// what did not fit: the largest eigenvalue, in `c`'s metric, of the directions left out
/// (so that D Dᵀ + that × `c` ≥ `s`: the widening stays on the safe side). Eigenvectors in
/// `c`'s metric (whitened by its Cholesky factor) when `c` is positive definite, so the
/// columns kept are the directions the spread exceeds the fit's own covariance most; plain
/// otherwise (nothing folded then: with no positive definite C the budget has no shrink
/// either). Directions below 1e-12 of the largest are rounding: dropped. (D, folded weight,
/// directions folded)
fn factor_of(s: &DMatrix<f64>, c: &DMatrix<f64>) -> (DMatrix<f64>, f64, usize) {
    let n = s.nrows();
    if n == 0 {
        return (DMatrix::zeros(0, 0), 0.0, 0);
    }
    let ch = c.clone().cholesky();
    let w = match &ch {
        Some(ch) => {
            let l = ch.l();
            let li = l
                .clone()
                .try_inverse()
                .unwrap_or_else(|| DMatrix::identity(n, n));
            let m = &li * s * li.transpose();
            (m.clone() + m.transpose()) * 0.5
        }
        None => (s.clone() + s.transpose()) * 0.5,
    };
    let e = nalgebra::SymmetricEigen::new(w);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|a, b| e.eigenvalues[*b].total_cmp(&e.eigenvalues[*a]));
    let top = e.eigenvalues[order[0]].max(0.0);
    let kept: Vec<usize> = order
        .iter()
        .copied()
        .filter(|&k| e.eigenvalues[k] > 1e-12 * top)
        .collect();
    let r = kept.len().min(POSE_RANK_MAX);
    let mut d = DMatrix::zeros(n, r);
    for (col, &k) in kept[..r].iter().enumerate() {
        let v = e.eigenvectors.column(k) * e.eigenvalues[k].sqrt();
        d.set_column(col, &v);
    }
    if let Some(ch) = &ch {
        d = ch.l() * d;
    }
    let folded = kept.len() - r;
    let weight = if folded > 0 && ch.is_some() {
        e.eigenvalues[kept[r]]
    } else {
        0.0
    };
    (d, weight, folded)
}

/// The tip's tr(J C Jᵀ) at every row of `data` (its own probe), C a covariance of `params`
/// on the calibrated `arm`: the leverage of each calibration reading, whose mean is the
/// file's `pose_leverage_mean` and against which a reading's ℓ is taken.
pub fn tip_leverages(
    arm: &quatarm_ref::arm::Arm,
    params: &[Param],
    c: &DMatrix<f64>,
    data: &Dataset,
) -> Vec<f64> {
    let b = Budget::of_parameters(params, c.clone(), data.dof);
    data.rows
        .iter()
        .map(|r| {
            let probe = crate::fit::probes::index(arm, r);
            super::propagate::point(arm, probe, &b, &r.theta, r.temp_c)
                .1
                .trace()
        })
        .collect()
}

/// Each row's tip leverage ratio against the fold that held it out: tr(J C_f Jᵀ) over the
/// mean of the same over that fold's training rows, C_f the fold fit's covariance of
/// `params` (an unknown it held has none); NaN for a row no fold held out or a fold without
/// a covariance.
pub fn fold_tip_ratios(
    arm: &quatarm_ref::arm::Arm,
    params: &[Param],
    data: &Dataset,
    fits: &[FoldFit],
) -> Vec<f64> {
    let mut out = vec![f64::NAN; data.rows.len()];
    for f in fits {
        let Some((order, c)) = &f.covariance else {
            continue;
        };
        let at: Vec<Option<usize>> = params
            .iter()
            .map(|p| order.iter().position(|q| q == p))
            .collect();
        let cf = DMatrix::from_fn(params.len(), params.len(), |a, b| match (at[a], at[b]) {
            (Some(i), Some(j)) => c[(i, j)],
            _ => 0.0,
        });
        let lev = tip_leverages(arm, params, &cf, data);
        let mut held = vec![false; data.rows.len()];
        f.rows.iter().for_each(|&i| held[i] = true);
        let train: Vec<f64> = (0..lev.len())
            .filter(|&i| !held[i])
            .map(|i| lev[i])
            .collect();
        let mean = train.iter().sum::<f64>() / train.len().max(1) as f64;
        if mean.is_finite() && mean > 0.0 {
            f.rows.iter().for_each(|&i| out[i] = lev[i] / mean);
        }
    }
    out
}

/// What a covariance `cov` of the parameters alone predicts for the rows `judged`, in the
/// order of [`super::misfit::row_covariances`].
fn tip_part(
    arm: &quatarm_ref::arm::Arm,
    params: &[Param],
    cov: DMatrix<f64>,
    data: &Dataset,
    judged: &[bool],
) -> Vec<RowCov> {
    let b = Budget::of_parameters(params, cov, data.dof);
    super::misfit::row_covariances(arm, &b, data, judged, 0.0)
}

/// The least κ in [0, [`SCALE_MAX`]] with |r| inside U95(s + κ² p); infinite when none.
fn least_scale(s: &Matrix3<f64>, p: &Matrix3<f64>, deviation: f64) -> f64 {
    let covered = |k: f64| {
        let l = u95::eigenvalues(&(s + p * (k * k))).map(|x| x.max(0.0));
        if l[0] <= 0.0 {
            return deviation <= 0.0;
        }
        u95::probability_within(l, deviation) <= u95::LEVEL
    };
    if covered(0.0) {
        return 0.0;
    }
    if !covered(SCALE_MAX) {
        return f64::INFINITY;
    }
    let (mut lo, mut hi) = (0.0, SCALE_MAX);
    while hi - lo > 1e-4 * hi {
        let mid = 0.5 * (lo + hi);
        if covered(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// Each row's least covering κ ([`SCALE_MAX`] at most, infinite beyond): `rows` the rest of
/// the budget's prediction, `extra` the pose term's part at κ = 1, `deviation` |r| per row.
pub fn least_scales(rows: &[RowCov], extra: &[Matrix3<f64>], deviation: &[f64]) -> Vec<f64> {
    rows.iter()
        .zip(extra)
        .zip(deviation)
        .map(|((r, p), d)| least_scale(&r.s, p, *d))
        .collect()
}

/// The split-conformal κ of rows' least covering scales: the ⌈0.95 (n + 1)⌉-th smallest,
/// but no more than the largest finite one (rows the term cannot cover at all are left to
/// the isotropic term). 0 without scores.
pub fn conformal_scale(mut t: Vec<f64>) -> f64 {
    if t.is_empty() {
        return 0.0;
    }
    t.sort_by(f64::total_cmp);
    let n = t.len();
    let k = ((u95::LEVEL * (n + 1) as f64).ceil() as usize).clamp(1, n);
    let finite = t
        .iter()
        .copied()
        .filter(|x| x.is_finite())
        .fold(0.0, f64::max);
    t[k - 1].min(finite)
}

/// The factor of the leverage-scaled term at a reading of leverage ratio `l` (its tip's
/// tr J C_fit Jᵀ over the mean on the calibration's rows, or the larger of that and its
/// joints' ℓJ where the budget has a joint leverage: [`super::propagate::Leverage::ratio`]):
/// max(1, l). The budget carries the
/// term apart from C for it (the file's `pose_*` keys); [`super::propagate::widening`]
/// applies it.
pub fn leverage_factor(l: f64) -> f64 {
    if l.is_finite() {
        l.max(1.0)
    } else {
        1.0
    }
}

/// A unit's own κ from `groups` held-out groups pooled with the fleet's, the fleet's worth
/// `prior_groups` groups: κ² = (G κ_own² + w κ_fleet²)/(G + w), a random effect's
/// shrinkage (the own value's weight grows with its groups). `own` unchanged when w = 0.
pub fn pooled_scale(own: f64, groups: usize, fleet: f64, prior_groups: f64) -> f64 {
    if prior_groups <= 0.0 {
        return own;
    }
    let g = groups as f64;
    ((g * own * own + prior_groups * fleet * fleet) / (g + prior_groups)).sqrt()
}

/// The pose term of a held-out validation by group `h` of `data`, for the budget's `params`
/// on the calibrated `arm`; `rows` what the rest of the budget predicts for the held-out rows
/// ([`super::misfit::row_covariances`]) and `res` their residuals
/// ([`super::misfit::without_frame`]); `two_group_scale` κ when only two groups fitted
/// (see [`TWO_GROUP_SCALE`]); `leverage` the leverage-scaled form, `joint_leverage` with
/// the joints' ℓJ in its factor (both the product's). `None` unless the folds were whole groups, at least two of
/// them fitted and the term is not zero.
#[allow(clippy::too_many_arguments)]
pub fn estimate(
    arm: &quatarm_ref::arm::Arm,
    params: &[Param],
    c: &DMatrix<f64>,
    data: &Dataset,
    h: &Holdout,
    rows: &[RowCov],
    res: &[nalgebra::Vector3<f64>],
    two_group_scale: f64,
    prior_groups: f64,
    leverage: bool,
    joint_leverage: bool,
    fold_leverage: bool,
) -> Option<PoseTerm> {
    let groups = fold_groups(data, &h.fits)?;
    let g_all = groups.len();
    let all: Vec<&FoldFit> = h.fits.iter().collect();
    let sb = between(params, &all, g_all, c);
    if sb.iter().all(|x| *x == 0.0) || rows.is_empty() {
        return None;
    }
    let validated = g_all >= 3;
    // Each held-out row's part of the term, from the spread of the groups other than its
    // own (G ≥ 3), or of all (G = 2, in-sample).
    let mut extra = vec![Matrix3::zeros(); rows.len()];
    let at: std::collections::HashMap<usize, usize> =
        rows.iter().enumerate().map(|(k, r)| (r.row, k)).collect();
    for (f, fit) in h.fits.iter().enumerate() {
        let cov = if validated {
            let others: Vec<&FoldFit> = (0..g_all).filter(|&o| o != f).map(|o| all[o]).collect();
            between(params, &others, g_all, c)
        } else {
            sb.clone()
        } * (1.0 + 1.0 / (g_all as f64 - 1.0));
        let mut judged = vec![false; data.rows.len()];
        fit.rows.iter().for_each(|&i| judged[i] = h.judged[i]);
        for r in tip_part(arm, params, cov, data, &judged) {
            if let Some(&k) = at.get(&r.row) {
                extra[k] = r.s;
            }
        }
    }
    // The leverage-scaled form: each held-out row's part times its tip's factor, ℓ against
    // the mean over every calibration row (what the file's `pose_leverage_mean` holds, and
    // what eval and the hub compute for a reading).
    let lev = leverage.then(|| tip_leverages(arm, params, c, data));
    let lev_mean = lev
        .as_ref()
        .map(|l| l.iter().sum::<f64>() / l.len().max(1) as f64)
        .filter(|m| m.is_finite() && *m > 0.0);
    // With it the joints' ℓJ, the factor max(1, ℓ, ℓJ) that eval applies: κ is validated
    // with the factor it is applied with. A held-out row's ℓJ is taken against the joint
    // angles of the groups other than its own (what a fit without its group saw: a new
    // session's ℓJ against the calibration), the written one against every row.
    let joints = lev_mean
        .filter(|_| joint_leverage)
        .and_then(|_| super::extrapolation::JointSupport::of(data));
    // The variant measured at stop 42 (`fold_leverage`, off in the product): a held-out
    // row's ℓ against the design of the fit that did not see it (that fold's C, over the
    // mean of its own training rows), as a fresh reading's is against the calibration's.
    let fold_ratio = lev_mean
        .filter(|_| fold_leverage)
        .map(|_| fold_tip_ratios(arm, params, data, &h.fits));
    if let (Some(lev), Some(mean)) = (&lev, lev_mean) {
        let mut without: std::collections::HashMap<
            i64,
            Option<quatarm_ref::uncertainty::JointLeverage>,
        > = std::collections::HashMap::new();
        for (k, r) in rows.iter().enumerate() {
            let row = &data.rows[r.row];
            let lj = joints.as_ref().and_then(|_| {
                without
                    .entry(row.group)
                    .or_insert_with(|| {
                        super::extrapolation::joint_leverage_without(data, row.group)
                    })
                    .as_ref()
                    .map(|j| j.ratio(&row.theta))
            });
            let tip = fold_ratio
                .as_ref()
                .map(|f| f[r.row])
                .filter(|x| x.is_finite())
                .unwrap_or(lev[r.row] / mean);
            let l = super::propagate::Leverage {
                tip: Some(tip),
                joints: lj,
            };
            extra[k] *= leverage_factor(l.ratio().unwrap_or(1.0));
        }
    }
    let deviation = |r: &RowCov| res[r.row].norm();
    let scale = if validated {
        let d: Vec<f64> = rows.iter().map(deviation).collect();
        pooled_scale(
            conformal_scale(least_scales(rows, &extra, &d)),
            g_all,
            two_group_scale,
            prior_groups,
        )
    } else {
        two_group_scale
    };
    let covered = |k: f64| {
        rows.iter()
            .zip(&extra)
            .filter(|(r, p)| {
                let l = u95::eigenvalues(&(r.s + *p * (k * k))).map(|x| x.max(0.0));
                l[0] > 0.0 && u95::probability_within(l, deviation(r)) <= u95::LEVEL
            })
            .count() as f64
            / rows.len() as f64
    };
    let source = PoseSource {
        groups: g_all,
        scale,
        validated,
        rows: rows.len(),
        covered: [covered(0.0), covered(scale)],
        rms_mm: (extra.iter().map(|p| p.trace() / 3.0).sum::<f64>() / rows.len() as f64).sqrt()
            * scale,
        leverage: None,
    };
    let k2 = scale * scale;
    let kk = k2 * (1.0 + 1.0 / g_all as f64);
    let mut term = PoseTerm {
        cov: sb * kk,
        extra: extra.into_iter().map(|p| p * k2).collect(),
        source,
        split: None,
    };
    if let (Some(lev), Some(mean)) = (lev, lev_mean) {
        // The same term as D Dᵀ + b C: κ²(1 + 1/G) ((1 − λ) S + λ t C), D from the first
        // part, b = κ²(1 + 1/G) λ t; `cov` rebuilt from them so that the written
        // covariance is C + D Dᵀ + b C to the bit the file holds.
        let nu = h.fits.len().saturating_sub(1);
        let (spread, w) = shrink_parts(raw_between(params, &all, g_all), c, prior_weight(nu));
        let (d, fold, folded) = factor_of(&(spread * kk), c);
        let split = super::PoseSplit {
            factor: d,
            shrink: kk * w + fold,
            leverage_mean: mean,
            // The joint leverage estimated beside the pose part over every calibration row
            // (issue 27, round 5): its mean over them is 1.
            joints: joints.as_ref().map(|j| j.leverage.clone()),
        };
        let ratio = |x: &f64| x / mean;
        term.source.leverage = Some(LeverageSource {
            rank: split.factor.ncols(),
            shrink: split.shrink,
            mean_mm2: mean,
            range: [
                lev.iter().map(ratio).fold(f64::INFINITY, f64::min),
                lev.iter().map(ratio).fold(0.0, f64::max),
            ],
            folded,
            joints: joints.as_ref().map(|j| JointsSource {
                rows: j.rows,
                joints: j.moving.iter().map(|&k| k + 1).collect(),
            }),
        });
        term.cov = &split.factor * split.factor.transpose() + c * split.shrink;
        term.split = Some(split);
    }
    Some(term)
}

#[cfg(test)]
mod tests {
    use super::*;
    use quatarm_ref::arm::Arm;

    fn fold(z: [f64; 2], fitted: &[Param]) -> FoldFit {
        let mut arm = Arm::default6();
        arm.joints[0].zero_offset = z[0];
        arm.joints[1].zero_offset = z[1];
        FoldFit {
            rows: vec![0],
            arm,
            fitted: fitted.to_vec(),
            covariance: None,
        }
    }

    /// S_b is (G − 1)² times the sample covariance of the leave-one-group-out values, shrunk
    /// with weight 1/G towards C at C's own scale; an unknown a fold held has no deviation.
    #[test]
    fn the_between_group_spread_is_the_jackknife_one_shrunk_towards_c() {
        let p = [Param::ZeroOffset(0), Param::ZeroOffset(1)];
        let fits = [
            fold([1e-4, 0.0], &p),
            fold([-1e-4, 2e-4], &p),
            fold([3e-4, -2e-4], &p),
        ];
        let refs: Vec<&FoldFit> = fits.iter().collect();
        let c = DMatrix::from_diagonal_element(2, 2, 1e-10);
        let s = between(&p, &refs, 3, &c);
        // Sample covariance (divisor 2) of x = (1, −1, 3)e-4, y = (0, 2, −2)e-4: var x 4e-8,
        // var y 4e-8, cov −4e-8; times (3 − 1)² = 4.
        let raw = DMatrix::from_row_slice(2, 2, &[16e-8, -16e-8, -16e-8, 16e-8]);
        let t = (raw[(0, 0)] + raw[(1, 1)]) / 1e-10 / 2.0;
        let expect = &raw * (2.0 / 3.0) + &c * (t / 3.0);
        assert!(
            (&s - &expect).norm() < 1e-12 * expect.norm(),
            "{s} vs {expect}"
        );
        // A fold that held ZeroOffset(1): its y is no evidence, and y's spread is that of
        // the other two.
        let held = [fold([1e-4, 0.0], &p), fold([-1e-4, 9.0], &p[..1])];
        let refs: Vec<&FoldFit> = held.iter().collect();
        let d = deviations(&p, &refs);
        assert_eq!(d[1][1], 0.0);
        assert_eq!(d[0][1], 0.0);
        assert!((d[0][0] - 1e-4).abs() < 1e-15);
    }

    /// The fleet's κ pooled into a unit's own weighs as `prior_groups` groups against the
    /// unit's G, in κ²; weight 0 leaves the own κ, many groups leave it nearly so.
    #[test]
    fn a_pooled_scale_weighs_the_fleet_as_prior_groups() {
        assert_eq!(pooled_scale(0.3, 3, 1.2, 0.0), 0.3);
        let k = pooled_scale(0.0, 3, 2.0, 1.0);
        assert!((k - 1.0).abs() < 1e-12, "{k}");
        let many = pooled_scale(1.0, 1000, 3.0, 1.0);
        assert!(many > 1.0 && many < 1.01, "{many}");
    }

    /// The leverage factor only widens (floored at 1) and ignores a ratio that is not a
    /// number (a calibration with no spread in C).
    #[test]
    fn the_leverage_factor_only_widens() {
        assert_eq!(leverage_factor(0.3), 1.0);
        assert_eq!(leverage_factor(4.0), 4.0);
        assert_eq!(leverage_factor(f64::NAN), 1.0);
        assert_eq!(leverage_factor(f64::INFINITY), 1.0);
    }

    /// λ = 0 leaves the spread, λ = 1 is C at the spread's size in C's metric.
    #[test]
    fn the_shrinkage_weight_runs_from_the_spread_to_c() {
        let s = DMatrix::from_row_slice(2, 2, &[4.0, 0.0, 0.0, 0.0]);
        let c = DMatrix::from_diagonal_element(2, 2, 2.0);
        assert_eq!(shrink_by(s.clone(), &c, 0.0), s);
        // tr(c⁻¹ s)/p = (4/2)/2 = 1: C itself.
        assert!((shrink_by(s.clone(), &c, 1.0) - &c).norm() < 1e-12);
        assert_eq!(shrink(s.clone(), &c, 1), shrink_by(s, &c, prior_weight(1)));
    }

    /// κ is the least scale that covers: more than 0 for a far row, and covering there.
    #[test]
    fn the_least_scale_covers_and_no_less_does() {
        let s = Matrix3::identity() * 1e-6;
        let p = Matrix3::from_diagonal(&nalgebra::Vector3::new(1e-2, 1e-4, 1e-4));
        assert_eq!(least_scale(&s, &p, 1e-3), 0.0);
        let k = least_scale(&s, &p, 0.3);
        assert!(k > 0.0 && k.is_finite(), "{k}");
        let covered = |k: f64| {
            let l = u95::eigenvalues(&(s + p * (k * k)));
            u95::probability_within(l, 0.3) <= u95::LEVEL
        };
        assert!(covered(k) && !covered(0.99 * k));
        // No direction to grow in: never covered.
        assert!(least_scale(&s, &Matrix3::zeros(), 0.3).is_infinite());
    }

    /// κ is the ⌈0.95 (n + 1)⌉-th smallest score, capped at the largest finite one.
    #[test]
    fn the_conformal_scale_is_the_finite_sample_rank() {
        let t: Vec<f64> = (1..=39).map(f64::from).collect();
        // n = 39: rank ⌈0.95 × 40⌉ = 38.
        assert_eq!(conformal_scale(t.clone()), 38.0);
        let mut inf = t;
        inf[37] = f64::INFINITY;
        inf[38] = f64::INFINITY;
        assert_eq!(conformal_scale(inf), 37.0);
        assert_eq!(conformal_scale(vec![]), 0.0);
    }
}
