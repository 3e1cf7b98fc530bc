//! Partial pooling of one effect's size over the arms of a design: power from the fleet.
//!
//! An arm with few sessions cannot tell a small effect from its noise alone (four sessions:
//! no sign test below 0.0625). Its siblings of the same design carry information about it, but
//! not its value: MUKCa's Pandas have shoulder compliances from −4.0 to +1.3 µrad/mm, so
//! forcing one shared value on them ([`super::fleet`]'s design test of a common gain) has
//! little to find. The normal–normal hierarchical model says what is shared:
//!
//! y_u ~ N(θ_u, s_u²),  θ_u ~ N(μ, τ²)
//!
//! each arm's estimate y_u (standard error s_u, from its own sessions) measures its own true
//! value θ_u, and the θ_u are drawn from the design's distribution (mean μ, spread τ). μ and τ²
//! are estimated from all arms together (empirical Bayes: DerSimonian–Laird's moment estimator
//! and Hartung–Knapp's standard error of μ̂, [`super::fleet::dersimonian_laird`]); each arm's
//! pooled estimate is then its posterior mean
//!
//! θ̃_u = μ̂ + (1 − B_u)(y_u − μ̂),  B_u = s_u² / (s_u² + τ̂²)
//!
//! an arm measured precisely keeps its own value (B → 0), one measured poorly borrows from the
//! design (B → 1), and with τ̂² = 0 every arm gets μ̂. Its variance is Morris's (1983)
//!
//! (1 − B_u) s_u² + B_u² se(μ̂)² + V(B̂_u) (y_u − μ̂)²
//!
//! the uncertainty of μ̂ (its Hartung–Knapp error) and, in the last term, of τ̂²: B̂_u is itself
//! an estimate, and an arm far from the mean is the one whose pooled value moves most with it.
//! V(B̂_u) = 2 B_u² w_u² / ((k − 3)/k · Σ w_j²), w = 1/(s² + τ̂²): the delta method on τ̂²'s
//! information (½ Σ w²) with Morris's small-sample divisor k − 3 in place of k, which for equal
//! errors is his 2 B²/(k − 3). With 3 arms k − 3 is floored at 1. Without the last term (the
//! plug-in error, kept as `pooled_se_plugin`) the interval of an arm far from the mean covers
//! its true value too seldom when τ̂² is small: measured by [`simulated_coverage`] (see
//! `docs/results/claims.md`).
//!
//! **An arm of several recordings** (the same arm measured again, each recording with its own
//! tool and frame, so each fitted with its own probe) gives one estimate per recording with
//! ≥ 3 sessions; [`combine_recordings`] weighs them by inverse variance into the arm's
//! estimate, its error widened when the recordings disagree beyond their errors.
//!
//! **What is named.** The design's mean is tested first (t = μ̂ / se_HK, arms − 1 degrees of
//! freedom, two-sided at `alpha`); only when it passes is the effect named for an arm, and then
//! for every arm whose pooled interval θ̃_u ± t_df·se excludes zero, df the arm's own error's
//! degrees of freedom (its sessions − 1) or arms − 1 where fewer ([`interval_df`]): each arm's
//! error is itself estimated from a few sessions, and every part of its pooled error rests on
//! such estimates (measured: [`simulated_coverage`]). The gate keeps the chance of
//! naming the effect anywhere in a null fleet at `alpha`, not `alpha` per arm. Rules that
//! would name more (a one-sided arm test, longer df, the design's predictive distribution) are
//! counted beside this one in [`super::pooling_rules`] and not used: their intervals cover
//! too seldom, or their false causes on fleets where some arms lack the effect are measured on
//! too few such arms to say they stay at `alpha` (docs/results/claims.md §7.6).
//!
//! **The error's scale pooled across the fleet** ([`dispersion`], [`pool_fleet_scale`]; the
//! fleet diagnosis's default since stop 40, `ErrorScale::Fleet`, [`pool_with`]): each arm's
//! jackknife error rests on 3 df, so its interval needs t₃; its fit's in-sample error v_u
//! rests on hundreds of residuals but misses their correlation within a session. With one ratio φ = s²/v² for the
//! design, φ̂ pooled over the arms (Σν df, tested for homogeneity) and s̃_u = √φ̂·v_u give every
//! arm an error whose scale has the fleet's df (docs/results/claims.md §7.10–§7.11). Where the
//! test rejects one φ, each arm keeps its own error.
//!
//! **The design's spread** has a Q-profile interval (Viechtbauer 2007): the τ² at which the
//! generalised Q statistic equals the χ²_{k−1} quantiles.

use super::fleet::{dersimonian_laird, ErrorScale};
use crate::data::Dataset;
use crate::fit::calib::{self};
use crate::fit::error::CalibError;
use crate::params::{Effect, ParamExt, Terms};
use crate::stats::{chi2_tail, t_tail};

/// One arm, alone and pooled.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Arm {
    /// Its own estimate.
    pub estimate: f64,
    /// Its standard error.
    pub se: f64,
    /// The degrees of freedom of that error (its sessions − 1 for a jackknife; see
    /// [`Estimate::df`]).
    pub se_df: f64,
    /// Whether its own estimate differs from zero at `alpha` (two-sided, Student's t on
    /// `se_df` degrees of freedom).
    pub named_alone: bool,
    /// The shrinkage factor B (0: its own value kept, 1: the design's mean).
    pub shrinkage: f64,
    /// The pooled estimate θ̃.
    pub pooled: f64,
    /// Its standard error, with the uncertainty of μ̂ and of τ̂² (Morris's first-order terms).
    pub pooled_se: f64,
    /// The plug-in standard error (τ̂² taken as known): shorter, kept for comparison.
    pub pooled_se_plugin: f64,
    /// The degrees of freedom of its interval θ̃ ± t_df·`pooled_se` ([`interval_df`]: its
    /// own error's `se_df`, or arms − 1 where fewer).
    pub df: f64,
    /// Whether the pooled model names the effect for this arm.
    pub named_pooled: bool,
}

/// The design's distribution of the effect.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Design {
    /// Arms pooled.
    pub arms: usize,
    /// The mean μ̂.
    pub mean: f64,
    /// Its standard error (Hartung–Knapp).
    pub mean_se: f64,
    /// The interval of μ at 1 − `alpha` (Student's t, arms − 1 degrees of freedom).
    pub mean_interval: [f64; 2],
    /// Two-sided p of μ = 0.
    pub mean_p: f64,
    /// The spread τ̂ (the square root of DerSimonian–Laird's τ̂²).
    pub spread: f64,
    /// The interval of τ at 1 − `alpha` (Q-profile).
    pub spread_interval: [f64; 2],
    /// Whether the design's mean passes at `alpha` (the gate for naming per arm).
    pub named: bool,
}

pub use crate::stats::t_critical;

/// The generalised Q at `tau2`: Σ w (y − μ̂(τ²))², w = 1 / (v + τ²).
fn q_at(y: &[f64], v: &[f64], tau2: f64) -> f64 {
    let w: Vec<f64> = v.iter().map(|v| 1.0 / (v.max(1e-300) + tau2)).collect();
    let sw: f64 = w.iter().sum();
    let mu = w.iter().zip(y).map(|(w, y)| w * y).sum::<f64>() / sw;
    w.iter().zip(y).map(|(w, y)| w * (y - mu).powi(2)).sum()
}

/// The τ² at which Q equals `target` (Q falls as τ² grows); 0 when Q(0) is already below.
fn tau2_for(y: &[f64], v: &[f64], target: f64) -> f64 {
    if q_at(y, v, 0.0) <= target {
        return 0.0;
    }
    let spread = y
        .iter()
        .map(|a| y.iter().map(|b| (a - b).powi(2)).fold(0.0, f64::max))
        .fold(0.0, f64::max);
    let (mut lo, mut hi) = (0.0f64, spread.max(1e-300) * 1e3);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if q_at(y, v, mid) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The χ²_k quantile with upper tail `p` (bisection on [`chi2_tail`]).
fn chi2_upper(p: f64, k: usize) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 1e4f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if chi2_tail(mid, k) > p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The degrees of freedom of an arm's pooled interval: its own error's `nu` (sessions − 1),
/// or the design's `arms` − 1 where that is fewer. Every part of the pooled variance rests on
/// the arms' estimated errors, not only the arm's own part (1 − B)s²: μ̂'s weights and τ̂²
/// are computed from them too, so the design's part is no surer than they are. Measured
/// (`examples/pooling_coverage.rs`, docs/results/claims.md §7.5): Satterthwaite's df, which
/// gives the design's part its arms − 1, covers 0.87–0.94 with 8 arms of 4 sessions; this
/// 0.93–0.96.
pub fn interval_df(nu: f64, arms: usize) -> f64 {
    nu.min(arms.saturating_sub(1).max(1) as f64)
}

/// A candidate df for an arm's pooled interval that grows with its shrinkage (issue 30, round
/// 5): the pooled value θ̃ = B·μ̂ + (1 − B)·y is a share B of the design's mean, whose error
/// rests on the arms' scatter (arms − 1 degrees of freedom), and a share 1 − B of the arm's
/// own estimate, whose error rests on its own `nu`; the df are the shares' mix,
/// (1 − B)·ν + B·(k − 1) where ν is the fewer, and [`interval_df`]'s k − 1 otherwise (it never
/// gives fewer than the product's df). An arm pulled wholly to the mean (B = 1) gets the
/// design's k − 1, one that keeps its own value (B = 0) its own ν. Simulated beside
/// [`interval_df`] ([`Coverage::shrinkage`]), not used by [`pool`]: where B̂ ≈ 1 the interval
/// is the design mean's on k − 1 df, and μ̂'s weights rest on the arms' estimated errors.
pub fn shrinkage_df(b: f64, nu: f64, arms: usize) -> f64 {
    let floor = interval_df(nu, arms);
    let design = arms.saturating_sub(1).max(1) as f64;
    let b = if b.is_finite() {
        b.clamp(0.0, 1.0)
    } else {
        1.0
    };
    floor + b * (design - floor).max(0.0)
}

/// The Satterthwaite (1946) degrees of freedom of an arm's pooled variance `own` + `design`:
/// `own` = (1 − B)s² moves with the arm's estimated error (ν = `nu`; its relative variance
/// 2/ν scaled by (1 − B)², the part's sensitivity to s²), `design` = μ̂'s and τ̂²'s terms with
/// the arms' `arms` − 1. Simulated beside [`interval_df`] and not used: it takes the design's
/// part as resting on arms − 1 degrees of freedom whatever the arms' own, and covers too
/// seldom (docs/results/claims.md §7.5).
pub fn satterthwaite_df(own: f64, b: f64, nu: f64, design: f64, arms: usize) -> f64 {
    let total = own + design;
    if total.is_nan() || total <= 0.0 {
        return arms.saturating_sub(1).max(1) as f64;
    }
    let (o, d) = (own / total, design / total);
    let own_part = if nu.is_finite() {
        (o * (1.0 - b)).powi(2) / nu
    } else {
        0.0
    };
    let design_part = d * d / arms.saturating_sub(1).max(1) as f64;
    (1.0 / (own_part + design_part).max(1e-6)).min(1e6)
}

/// Whether `value` ± t_df·`se` excludes zero at `alpha` (two-sided Student's t).
fn excludes_zero(value: f64, se: f64, df: f64, alpha: f64) -> bool {
    2.0 * t_tail((value / se).abs(), df) < alpha
}

/// Pools the arms' estimates `y` with standard errors `se` of `df` degrees of freedom each
/// (see the module's text; `f64::INFINITY` for an error taken as known). `None` with fewer
/// than [`super::fleet::MIN_FLEET_UNITS`] arms, or when some standard error is not a positive
/// finite number or some `df` is not positive (an arm whose estimate has no error bar cannot
/// be weighed).
pub fn pool(y: &[f64], se: &[f64], df: &[f64], alpha: f64) -> Option<(Design, Vec<Arm>)> {
    let k = y.len();
    if k < super::fleet::MIN_FLEET_UNITS
        || se.len() != k
        || df.len() != k
        || se.iter().any(|s| !(s.is_finite() && *s > 0.0))
        || df.iter().any(|d| d.is_nan() || *d <= 0.0)
        || y.iter().any(|v| !v.is_finite())
    {
        return None;
    }
    // In units of the largest standard error: `dersimonian_laird` floors variances at 1e-12
    // (for log-ratios near one), which a compliance of 1e-8 rad/mm would fall under.
    let unit = se.iter().copied().fold(0.0, f64::max);
    let ys: Vec<f64> = y.iter().map(|v| v / unit).collect();
    let vs: Vec<f64> = se.iter().map(|s| (s / unit).powi(2)).collect();
    let (mu, mu_se, tau2, _q) = dersimonian_laird(&ys, &vs);
    let (mu, mu_se, tau2) = (mu * unit, mu_se * unit, tau2 * unit * unit);
    let v: Vec<f64> = se.iter().map(|s| s * s).collect();
    let design_df = (k - 1) as f64;
    let tc = t_critical(alpha, design_df);
    let mean_p = 2.0 * t_tail((mu / mu_se).abs(), design_df);
    let named = mean_p < alpha;
    let lo = unit * unit * tau2_for(&ys, &vs, chi2_upper(alpha / 2.0, k - 1));
    let hi = unit * unit * tau2_for(&ys, &vs, chi2_upper(1.0 - alpha / 2.0, k - 1));
    let design = Design {
        arms: k,
        mean: mu,
        mean_se: mu_se,
        mean_interval: [mu - tc * mu_se, mu + tc * mu_se],
        mean_p,
        spread: tau2.sqrt(),
        spread_interval: [lo.sqrt(), hi.sqrt()],
        named,
    };
    // τ̂²'s information in units of the largest error (as `dersimonian_laird` ran).
    let w: Vec<f64> = vs
        .iter()
        .map(|v| 1.0 / (v + tau2 / (unit * unit)))
        .collect();
    let sw2: f64 = w.iter().map(|w| w * w).sum();
    let small = (k as f64 - 3.0).max(1.0) / k as f64;
    let arms = y
        .iter()
        .zip(&v)
        .zip(&w)
        .zip(df)
        .map(|(((&y, &v), &w), &nu)| {
            let b = v / (v + tau2);
            let pooled = mu + (1.0 - b) * (y - mu);
            let own = (1.0 - b) * v;
            let plugin = own + b * b * mu_se * mu_se;
            let var_b = 2.0 * b * b * w * w / (small * sw2);
            let pooled_se = (plugin + var_b * (y - mu).powi(2)).sqrt();
            let df = interval_df(nu, k);
            Arm {
                estimate: y,
                se: v.sqrt(),
                se_df: nu,
                named_alone: excludes_zero(y, v.sqrt(), nu.min(1e6), alpha),
                shrinkage: b,
                pooled,
                pooled_se,
                pooled_se_plugin: plugin.sqrt(),
                df,
                named_pooled: named && excludes_zero(pooled, pooled_se, df, alpha),
            }
        })
        .collect();
    Some((design, arms))
}

/// The fleet's dispersion of the jackknife variance over the model's ([`dispersion`]): how
/// much the in-sample error of a design's fits misses, estimated once from every arm.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Dispersion {
    /// Each arm's ratio r_u = s_u²/v_u² of its jackknife variance to its model-based one.
    pub ratios: Vec<f64>,
    /// φ̂ = Σ ν_u r_u / Σ ν_u: the pooled ratio.
    pub phi: f64,
    /// Its degrees of freedom, Σ ν_u.
    pub df: f64,
    /// Bartlett's statistic of the r_u's homogeneity (χ² on arms − 1 df when one φ holds).
    pub bartlett: f64,
    /// Its upper-tail p.
    pub p: f64,
}

/// The dispersion φ of the arms' jackknife variances over their model-based ones, assumed
/// common to a design measured by one protocol: s_u² ≈ φ·v_u²·χ²_ν/ν, so ν_u r_u/φ ~ χ²_ν_u
/// with r_u = s_u²/v_u². φ̂ = Σ ν_u r_u / Σ ν_u is the pooled variance of those scaled
/// "sample variances" (on Σ ν_u degrees of freedom), and the assumption is tested where it is
/// used by **Bartlett's test** of their homogeneity: M = N ln φ̂ − Σ ν_u ln r_u (N = Σ ν_u),
/// divided by 1 + (Σ 1/ν_u − 1/N)/(3(k − 1)), on χ²_{k−1}. Why φ: the in-sample error σ̂·√((JᵀJ)⁻¹)
/// rests on hundreds of residuals but misses their correlation within a session (φ ≫ 1 on
/// real arms); the jackknife sees it, but from 4 sessions, 3 df. Where one φ holds, the model
/// gives each arm's error's shape and the fleet its scale. `None` with fewer than 2 arms, or
/// when some `se`/`model_se` is not a positive finite number or some `df` is not positive and
/// finite (an error taken as known has no ratio to pool).
pub fn dispersion(se: &[f64], df: &[f64], model_se: &[f64]) -> Option<Dispersion> {
    let k = se.len();
    let ok = |x: &f64| x.is_finite() && *x > 0.0;
    if k < 2
        || df.len() != k
        || model_se.len() != k
        || !se.iter().all(ok)
        || !df.iter().all(ok)
        || !model_se.iter().all(ok)
    {
        return None;
    }
    let ratios: Vec<f64> = se
        .iter()
        .zip(model_se)
        .map(|(s, v)| (s / v).powi(2))
        .collect();
    let n: f64 = df.iter().sum();
    let phi = df.iter().zip(&ratios).map(|(nu, r)| nu * r).sum::<f64>() / n;
    let m = n * phi.ln()
        - df.iter()
            .zip(&ratios)
            .map(|(nu, r)| nu * r.ln())
            .sum::<f64>();
    let c = 1.0 + (df.iter().map(|nu| 1.0 / nu).sum::<f64>() - 1.0 / n) / (3.0 * (k - 1) as f64);
    let bartlett = (m / c).max(0.0);
    Some(Dispersion {
        ratios,
        phi,
        df: n,
        bartlett,
        p: chi2_tail(bartlett, k - 1),
    })
}

/// A pool with its errors' scale: the dispersion (where one was formed), whether the fleet's
/// scale was used, the design and the arms.
pub type ScaledPool = (Option<Dispersion>, bool, Design, Vec<Arm>);

/// The arms pooled with the error `scale` says ([`ErrorScale`]): the dispersion (only with
/// [`ErrorScale::Fleet`] and where one can be formed), whether the fleet's scale was used, and
/// the pool. `joined` are arms with no jackknife error, (value, in-sample error), pooled after
/// the others only where the fleet's scale is used ([`pool_fleet_scale_joined`]); elsewhere
/// the pool has `y.len()` arms.
pub fn pool_with(
    scale: ErrorScale,
    y: &[f64],
    se: &[f64],
    df: &[f64],
    model_se: &[f64],
    joined: &[(f64, f64)],
    alpha: f64,
) -> Option<ScaledPool> {
    match scale {
        ErrorScale::Own => pool(y, se, df, alpha).map(|(d, a)| (None, false, d, a)),
        ErrorScale::Fleet => pool_fleet_scale_joined(y, se, df, model_se, joined, alpha),
    }
}

/// The arms pooled with the error's scale pooled across the fleet (issue 30, round 6;
/// [`super::pooling_rules::Rule::FleetScale`], the product's naming since stop 40): when the
/// arms' ratios pass [`dispersion`]'s homogeneity test at `alpha` (the gate's α), each arm's error
/// is s̃_u = √φ̂·v_u on φ̂'s Σ ν_u degrees of freedom and the arms are [`pool`]ed with them;
/// when it fails (or some arm has no model error), with their own jackknife errors, as
/// [`ErrorScale::Own`]. Returns the dispersion (if any), whether the fleet's scale was used,
/// and the pool.
///
/// **The interval's df.** [`pool`] gives each arm [`interval_df`] of its error's df, here
/// min(Σ ν_u, k − 1) = k − 1 for 8 arms of 4 sessions (24 against 7). Why not Σ ν_u: what
/// φ̂'s 24 df make sure is the errors' common scale; μ̂'s Hartung–Knapp error and τ̂² still rest
/// on the k arms' scatter about μ̂, k − 1 df, and every arm's pooled variance carries them.
/// With the errors' scale known this is the product's interval with errors known, whose 8-arm
/// coverage was 0.94–1.00 (claims.md §7.4); measured for this rule in §7.10.
pub fn pool_fleet_scale(
    y: &[f64],
    se: &[f64],
    df: &[f64],
    model_se: &[f64],
    alpha: f64,
) -> Option<ScaledPool> {
    pool_fleet_scale_joined(y, se, df, model_se, &[], alpha)
}

/// [`pool_fleet_scale`] with arms that have **no jackknife error** joining (issue 30's
/// recordings of fewer than 3 sessions, panda_7's 2): `joined` holds each such arm's value
/// and model-based error, (y, v). They take no part in φ̂ (they have no ratio to give); when
/// the fleet's scale is used they are pooled with s̃ = √φ̂·v on φ̂'s df like every other arm,
/// their arms after `y`'s; when it is not (the ratios are not homogeneous, or there is no
/// dispersion), they cannot be weighed and are left out (the pool then has `y.len()` arms).
/// What it assumes beyond [`pool_fleet_scale`]: the arm without a jackknife shares the
/// others' φ, which nothing can test (no ratio of its own); with 2 sessions its residuals'
/// correlation within a session is no better known than theirs.
pub fn pool_fleet_scale_joined(
    y: &[f64],
    se: &[f64],
    df: &[f64],
    model_se: &[f64],
    joined: &[(f64, f64)],
    alpha: f64,
) -> Option<ScaledPool> {
    let disp = dispersion(se, df, model_se);
    match &disp {
        Some(d) if d.p >= alpha => {
            let ys: Vec<f64> = y
                .iter()
                .copied()
                .chain(joined.iter().map(|j| j.0))
                .collect();
            let scaled: Vec<f64> = model_se
                .iter()
                .chain(joined.iter().map(|j| &j.1))
                .map(|v| d.phi.sqrt() * v)
                .collect();
            let (design, arms) = pool(&ys, &scaled, &vec![d.df; ys.len()], alpha)?;
            Some((disp, true, design, arms))
        }
        _ => {
            let (design, arms) = pool(y, se, df, alpha)?;
            Some((disp, false, design, arms))
        }
    }
}

/// An effect's value and its fit's model-based (in-sample) error from one fit on all of
/// `data`'s sessions, with no jackknife: for a recording of too few sessions to have one,
/// which can join a pool only through the fleet's error scale ([`pool_fleet_scale_joined`]).
/// `None` for an effect of more than one unknown.
pub fn estimate_in_sample(
    start: &quatarm_ref::arm::Arm,
    data: &Dataset,
    opts: &crate::fit::options::Options,
    effect: Effect,
) -> Result<Option<(f64, f64)>, CalibError> {
    Ok(estimate_joint_in_sample(start, data, opts, &[effect])?.and_then(|v| v.first().copied()))
}

/// [`estimate_in_sample`] of every effect of `effects` at once, each conditional on the others
/// (the full model of [`estimate_joint`], its one fit on all the sessions without the
/// leave-one-session-out fits): what a recording of too few sessions for a jackknife gives
/// the full model of `armcal diagnose --fleet --join-short`. `None` for an empty list, a repeated effect or an
/// effect of more than one unknown; the values in `effects`' order.
pub fn estimate_joint_in_sample(
    start: &quatarm_ref::arm::Arm,
    data: &Dataset,
    opts: &crate::fit::options::Options,
    effects: &[Effect],
) -> Result<Option<Vec<(f64, f64)>>, CalibError> {
    let params: Vec<_> = effects.iter().map(|e| e.params()).collect();
    let repeated = effects
        .iter()
        .enumerate()
        .any(|(i, e)| effects[..i].contains(e));
    if effects.is_empty() || repeated || params.iter().any(|p| p.len() != 1) {
        return Ok(None);
    }
    let o = crate::fit::options::Options {
        terms: Terms::with(effects),
        ..opts.clone()
    };
    let all = calib::calibrate(start, data, &o)?;
    Ok(Some(
        params
            .iter()
            .map(|p| (p[0].value(&all.arm), model_se(&all, &p[0])))
            .collect(),
    ))
}

/// One estimate of a one-unknown effect ([`estimate`]): its value, its standard error and the
/// degrees of freedom of that error.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Estimate {
    /// The value.
    pub value: f64,
    /// Its standard error.
    pub se: f64,
    /// The error's degrees of freedom: a jackknife over n sessions has n − 1 (the error of a
    /// 4-session recording is itself uncertain by a factor χ²₃/3, which an interval that
    /// takes it as known ignores).
    pub df: f64,
    /// The model-based (in-sample) standard error of the value from the same fit on all the
    /// sessions, σ̂·√((JᵀJ)⁻¹) (the fit's `uncertainty`); `NaN` where the fit gave none. On
    /// real data it is too small (the residuals are not white), which is why the jackknife
    /// `se` is the one the product weighs by; its *shape* over the arms is what
    /// [`pool_fleet_scale`] borrows (docs/results/claims.md §7.10).
    pub model_se: f64,
}

impl Estimate {
    /// A recording's estimate with no jackknife (too few sessions): its value and in-sample
    /// error, `se` and `df` not numbers ([`estimate_joint_in_sample`]).
    pub fn in_sample((value, model_se): (f64, f64)) -> Estimate {
        Estimate {
            value,
            se: f64::NAN,
            df: f64::NAN,
            model_se,
        }
    }
}

/// One arm's estimate from its recordings ([`combine_recordings`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Combined {
    /// The inverse-variance mean of the recordings' estimates.
    pub estimate: f64,
    /// Its standard error (widened by √(Q/(r − 1)) when that exceeds 1).
    pub se: f64,
    /// The degrees of freedom of that error: Satterthwaite's (Σw)²/Σ(w²/ν_r) over the
    /// recordings' errors (w = 1/s²; one recording: its own ν), combined with the Birge
    /// ratio's r − 1 (1/df = 1/df_s + 1/(r − 1), relative variances adding) when it widens.
    pub df: f64,
    /// Recordings combined.
    pub recordings: usize,
    /// Cochran's Q of the recordings about their mean (0 for one recording).
    pub q: f64,
    /// Its upper-tail p on r − 1 degrees of freedom (1 for one recording): a small p says the
    /// recordings of "one arm" disagree beyond their errors (another arm, or a changed one).
    pub q_p: f64,
    /// The model-based error of the combination: one recording's own
    /// [`Estimate::model_se`], several recordings' 1/√Σ(1/v_r²) (their inverse-variance mean's
    /// in-sample error, with no Birge widening: the widening is the jackknife's side of the
    /// ratio [`pool_fleet_scale`] estimates); `NaN` when some recording has none.
    pub model_se: f64,
}

impl Combined {
    /// An arm's one recording with no jackknife error ([`Estimate::in_sample`]) as its
    /// combination: its value and in-sample error, `se` and `df` not numbers.
    pub fn in_sample(e: &Estimate) -> Combined {
        Combined {
            estimate: e.value,
            se: f64::NAN,
            df: f64::NAN,
            recordings: 1,
            q: 0.0,
            q_p: 1.0,
            model_se: e.model_se,
        }
    }
}

/// One arm's estimate from its recordings' estimates `est`, each fitted on its own recording
/// with its own probe and frame: the inverse-variance mean, its error 1/√Σw widened by the
/// Birge ratio √(Q/(r − 1)) when the recordings scatter more than their errors say (a level of
/// the hierarchy with r = 2 or 3 recordings would estimate its spread from one or two
/// differences; the ratio uses the same evidence without pretending to a variance), and that
/// error's degrees of freedom ([`Combined::df`]). `None` for no recording, an error that is
/// not a positive finite number or degrees of freedom that are not positive.
pub fn combine_recordings(est: &[Estimate]) -> Option<Combined> {
    if est.is_empty()
        || est
            .iter()
            .any(|e| !(e.value.is_finite() && e.se.is_finite() && e.se > 0.0 && e.df > 0.0))
    {
        return None;
    }
    // In units of the largest error, so tiny values (rad/mm) keep their precision.
    let unit = est.iter().map(|e| e.se).fold(0.0, f64::max);
    let w: Vec<f64> = est.iter().map(|e| (unit / e.se).powi(2)).collect();
    let sw: f64 = w.iter().sum();
    let mean = w.iter().zip(est).map(|(w, e)| w * e.value).sum::<f64>() / sw;
    let q: f64 = w
        .iter()
        .zip(est)
        .map(|(w, e)| w * ((e.value - mean) / unit).powi(2))
        .sum();
    let w_df: f64 = w
        .iter()
        .zip(est)
        .filter(|(_, e)| e.df.is_finite())
        .map(|(w, e)| w * w / e.df)
        .sum();
    let df_s = if w_df > 0.0 {
        sw * sw / w_df
    } else {
        f64::INFINITY
    };
    let r = est.len();
    let (birge, q_p, df) = if r > 1 {
        let between = (r - 1) as f64;
        let birge = (q / between).max(1.0);
        let df = if birge > 1.0 {
            1.0 / (1.0 / df_s + 1.0 / between)
        } else {
            df_s
        };
        (birge, chi2_tail(q, r - 1), df)
    } else {
        (1.0, 1.0, df_s)
    };
    let model_se = if r == 1 {
        est[0].model_se
    } else {
        1.0 / est
            .iter()
            .map(|e| (e.model_se / unit).powi(-2))
            .sum::<f64>()
            .sqrt()
            * unit
    };
    Some(Combined {
        estimate: mean,
        se: unit * (birge / sw).sqrt(),
        df,
        recordings: r,
        q,
        q_p,
        model_se,
    })
}

/// Coverage of the pooled intervals on simulated fleets ([`simulated_coverage`]): six
/// intervals of an arm's true value side by side.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Coverage {
    /// Arm intervals drawn (fleets × arms).
    pub intervals: usize,
    /// Share of arms whose true value lies in θ̃ ± t_df·`pooled_se`, df = [`interval_df`]:
    /// the interval [`pool`] names by.
    pub with_df: f64,
    /// The same with t on the [`satterthwaite_df`] (simulated, not used).
    pub satterthwaite: f64,
    /// The same with t on arms − 1 degrees of freedom (each arm's own error taken as known;
    /// issue 30's round 3).
    pub with_tau: f64,
    /// θ̃ ± t_{k−1}·√(f (1 − B)s² + B² se_HK(μ̂)²), f = se_HK(μ̂)² Σw ≥ 1 the Knapp–Hartung
    /// factor (the arms' scatter about μ̂ over what their errors and τ̂² say), scaling the
    /// arm's own part as Hartung–Knapp scales μ̂'s; no τ̂² term.
    pub kh: f64,
    /// The Knapp–Hartung interval with t on [`interval_df`].
    pub kh_df: f64,
    /// θ̃ ± t_{k−1}·`pooled_se_plugin` (τ̂² and the errors taken as known).
    pub plugin: f64,
    /// Morris's error on t with [`shrinkage_df`] (simulated, not used).
    pub shrinkage: f64,
    /// Share of fleets whose design-mean interval holds μ.
    pub mean: f64,
    /// Mean half-width of each interval over the plug-in's, in the order `with_df`,
    /// `satterthwaite`, `with_tau`, `kh`, `kh_df`, `shrinkage` (measured on every tenth
    /// fleet: t on fractional degrees of freedom is a search).
    pub width: [f64; 6],
    /// Share of arms whose true value lies in the interval of [`pool_fleet_scale`] (t on its
    /// arm's [`Arm::df`]), falling back to the arms' own errors where the ratios' homogeneity
    /// test fails at `alpha`.
    pub fleet_scale: f64,
    /// Share of fleets where that test failed (the fleet's scale not used).
    pub fleet_scale_fallback: f64,
    /// Its mean half-width over the plug-in's (every tenth fleet, as `width`).
    pub fleet_scale_width: f64,
    /// `fleet_scale` over the odd arms only: those of high φ in [`simulated_coverage_phi`]
    /// (with one φ, half the arms drawn as any others).
    pub fleet_scale_high_phi: f64,
}

/// The simulated fleets' arms' true errors, 0.5 to 1.5 evenly: the same in every fleet.
fn simulated_true_se(arms: usize) -> Vec<f64> {
    (0..arms)
        .map(|u| 0.5 + u as f64 / (arms.max(2) - 1) as f64)
        .collect()
}

/// One simulated fleet of arms whose true errors are `true_se`: per arm its true value
/// 1 + τ·N(0, 1), its estimate with its true error s, and its jackknife error s·√(χ²_ν/ν)
/// over ν = `nu` degrees of freedom, drawn arm by arm; (true values, estimates, errors).
fn simulated_fleet(
    rng: &mut crate::rng::SimRng,
    tau: f64,
    true_se: &[f64],
    nu: usize,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut theta = Vec::with_capacity(true_se.len() + 1);
    let mut y = Vec::with_capacity(true_se.len());
    let mut se = Vec::with_capacity(true_se.len());
    for &s in true_se {
        let t = 1.0 + tau * crate::rng::normal(rng);
        y.push(t + s * crate::rng::normal(rng));
        let chi2: f64 = (0..nu).map(|_| crate::rng::normal(rng).powi(2)).sum();
        se.push(s * (chi2 / nu as f64).sqrt());
        theta.push(t);
    }
    (theta, y, se)
}

/// What [`simulated_joined_coverage`] measures: a fleet's arms with a jackknife error and one
/// arm without, joined on the fleet's error scale ([`pool_fleet_scale_joined`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JoinedCoverage {
    /// Fleets drawn.
    pub fleets: usize,
    /// Share of fleets where the joined arm was pooled (the homogeneity test kept one φ).
    pub joined: f64,
    /// Share of those fleets whose joined arm's interval (1 − `alpha`, t on its df) holds its
    /// true value.
    pub joined_coverage: f64,
    /// The same over the arms with a jackknife error, in the same fleets.
    pub others_coverage: f64,
    /// The joined arm's mean half-width over the mean of the others'.
    pub joined_width: f64,
}

/// [`simulated_coverage`]'s fleets of `arms` arms with a jackknife error from `sessions`
/// sessions and one φ ([`SIMULATED_PHI`]), and one more arm **without** a jackknife error
/// (a 2-session recording, `armcal diagnose --fleet --join-short`): its value drawn with true
/// error `joined_se` (in the others' units: theirs run 0.5–1.5), its in-sample error
/// `joined_se`/√(φ·`phi_ratio`). With `phi_ratio` 1 it shares the others' φ, the assumption
/// the join makes and nothing on the data can test; above 1 its in-sample error understates
/// its error more than the others' do. The joined arm is pooled with √φ̂ times its in-sample
/// error where the others' ratios pass the homogeneity test at `alpha`, else left out
/// (counted in [`JoinedCoverage::joined`]).
pub fn simulated_joined_coverage(
    arms: usize,
    tau: f64,
    sessions: usize,
    fleets: usize,
    seed: u64,
    alpha: f64,
    (joined_se, phi_ratio): (f64, f64),
) -> JoinedCoverage {
    let mut rng = crate::rng::rng(seed);
    let nu = sessions.saturating_sub(1).max(1);
    let df = vec![nu as f64; arms];
    let true_se = simulated_true_se(arms);
    let model: Vec<f64> = true_se.iter().map(|s| s / SIMULATED_PHI.sqrt()).collect();
    let joined_model = joined_se / (SIMULATED_PHI * phi_ratio).sqrt();
    let (mut pooled, mut hits, mut others, mut other_hits) = (0usize, 0usize, 0usize, 0usize);
    let (mut width, mut other_width) = (0.0, 0.0);
    for _ in 0..fleets {
        let (mut theta, y, se) = simulated_fleet(&mut rng, tau, &true_se, nu);
        let tj = 1.0 + tau * crate::rng::normal(&mut rng);
        let yj = tj + joined_se * crate::rng::normal(&mut rng);
        let Some((_, scaled, _, a)) =
            pool_fleet_scale_joined(&y, &se, &df, &model, &[(yj, joined_model)], alpha)
        else {
            continue;
        };
        if !scaled || a.len() != arms + 1 {
            continue;
        }
        pooled += 1;
        theta.push(tj);
        for (u, (a, t)) in a.iter().zip(&theta).enumerate() {
            let half = t_critical(alpha, a.df) * a.pooled_se;
            let hit = (a.pooled - t).abs() <= half;
            if u == arms {
                hits += hit as usize;
                width += half;
            } else {
                others += 1;
                other_hits += hit as usize;
                other_width += half;
            }
        }
    }
    JoinedCoverage {
        fleets,
        joined: pooled as f64 / fleets.max(1) as f64,
        joined_coverage: hits as f64 / pooled.max(1) as f64,
        others_coverage: other_hits as f64 / others.max(1) as f64,
        joined_width: (width / pooled.max(1) as f64)
            / (other_width / others.max(1) as f64).max(f64::MIN_POSITIVE),
    }
}

/// The dispersion φ of the jackknife variance over the model's in [`simulated_coverage`]'s
/// fleets: the model error v_u = s_u/√φ of an arm whose true error is s_u (four times too
/// small a variance, as a fit whose residuals are correlated within sessions reports). The
/// coverage does not depend on its value: φ̂ scales it out.
pub const SIMULATED_PHI: f64 = 4.0;

/// The Knapp–Hartung standard error of arm `a`'s pooled value in a fleet pooled as `d` whose
/// arms' errors are `se` ([`Coverage::kh`]).
fn kh_se(a: &Arm, d: &Design, se: &[f64]) -> f64 {
    let tau2 = d.spread * d.spread;
    let sw: f64 = se.iter().map(|s| 1.0 / (s * s + tau2)).sum();
    let f = (d.mean_se * d.mean_se * sw).max(1.0);
    let b = a.shrinkage;
    (f * (1.0 - b) * a.se * a.se + b * b * d.mean_se * d.mean_se).sqrt()
}

/// The coverage of [`pool`]'s intervals at 1 − `alpha` over `fleets` simulated fleets of
/// `arms` arms (seeds from `seed`): each arm's true value θ_u ~ N(1, τ²), its error s_u
/// spread 0.5…1.5 (mean 1), its estimate y_u ~ N(θ_u, s_u²), and the error the pooling sees
/// estimated from `sessions` sessions (a jackknife: s_u² χ²/(sessions − 1), sessions − 1
/// degrees of freedom), as on real arms. `tau` is in units of the mean error. The coverage is
/// the frequentist one of an empirical Bayes interval: over arms whose values are drawn from
/// the design's distribution. Each arm's model error is known, s_u/√[`SIMULATED_PHI`], for
/// [`pool_fleet_scale`]'s interval ([`Coverage::fleet_scale`]): its jackknife variance is
/// then φ v_u² χ²_ν/ν, one φ for the fleet.
pub fn simulated_coverage(
    arms: usize,
    tau: f64,
    sessions: usize,
    fleets: usize,
    seed: u64,
    alpha: f64,
) -> Coverage {
    simulated_coverage_phi(arms, tau, sessions, fleets, seed, alpha, 1.0)
}

/// [`simulated_coverage`] where the fleet's arms do **not** share one φ: arm u's model error
/// is s_u/√φ_u with φ_u = [`SIMULATED_PHI`]·`phi_ratio`^(±½), low for even u and high for
/// odd u (the ratio between them `phi_ratio`; MUKCa's Pandas' r_u range over 1.1–19). What
/// it measures: how often the homogeneity test catches it, and what [`pool_fleet_scale`]'s
/// interval covers where it does not ([`Coverage::fleet_scale_high_phi`]: the arms whose
/// errors the fleet's scale makes too short). With `phi_ratio` 1 it is
/// [`simulated_coverage`], draw for draw.
pub fn simulated_coverage_phi(
    arms: usize,
    tau: f64,
    sessions: usize,
    fleets: usize,
    seed: u64,
    alpha: f64,
    phi_ratio: f64,
) -> Coverage {
    let mut rng = crate::rng::rng(seed);
    let nu = sessions.saturating_sub(1).max(1);
    // Hits of `with_df`, `satterthwaite`, `with_tau`, `kh`, `kh_df`, `plugin`, `shrinkage`.
    let mut hits = [0usize; 7];
    let (mut n, mut mean, mut pooled_fleets) = (0, 0, 0);
    let mut widths = [0.0; 7];
    let tc = t_critical(alpha, (arms.max(2) - 1) as f64);
    let tdf = t_critical(alpha, interval_df(nu as f64, arms));
    let df = vec![nu as f64; arms];
    // Each arm's true error, and its model error: the same in every fleet.
    let true_se = simulated_true_se(arms);
    let model: Vec<f64> = true_se
        .iter()
        .enumerate()
        .map(|(u, s)| s / (SIMULATED_PHI * phi_ratio.powf((u % 2) as f64 - 0.5)).sqrt())
        .collect();
    let (mut fs_hits, mut fs_fallback, mut fs_width) = (0usize, 0usize, 0.0);
    // The odd arms' (the high φ's) intervals of the fleet-scale pool, and their hits.
    let (mut high_n, mut high_hits) = (0usize, 0usize);
    for f in 0..fleets {
        let (theta, y, se) = simulated_fleet(&mut rng, tau, &true_se, nu);
        let Some((d, a)) = pool(&y, &se, &df, alpha) else {
            continue;
        };
        if let Some((_, scaled, _, fa)) = pool_fleet_scale(&y, &se, &df, &model, alpha) {
            fs_fallback += !scaled as usize;
            for (u, (a, t)) in fa.iter().zip(&theta).enumerate() {
                let half = t_critical(alpha, a.df) * a.pooled_se;
                let hit = (a.pooled - t).abs() <= half;
                fs_hits += hit as usize;
                if u % 2 == 1 {
                    high_n += 1;
                    high_hits += hit as usize;
                }
                if f % 10 == 0 {
                    fs_width += half;
                }
            }
        }
        pooled_fleets += 1;
        mean += (d.mean_interval[0] <= 1.0 && 1.0 <= d.mean_interval[1]) as usize;
        for (a, t) in a.iter().zip(&theta) {
            n += 1;
            let miss = (a.pooled - t).abs();
            let kse = kh_se(a, &d, &se);
            let own = (1.0 - a.shrinkage) * a.se * a.se;
            let satt =
                satterthwaite_df(own, a.shrinkage, nu as f64, a.pooled_se.powi(2) - own, arms);
            let shrunk = shrinkage_df(a.shrinkage, nu as f64, arms);
            // Satterthwaite's (index 1) and the shrinkage df's (index 6) are tested by their
            // p: their t is a search.
            let half = [
                tdf * a.pooled_se,
                0.0,
                tc * a.pooled_se,
                tc * kse,
                tdf * kse,
                tc * a.pooled_se_plugin,
                0.0,
            ];
            let holds = |df: f64| 2.0 * t_tail(miss / a.pooled_se, df) >= alpha;
            for (i, (h, w)) in hits.iter_mut().zip(half).enumerate() {
                *h += match i {
                    1 => holds(satt),
                    6 => holds(shrunk),
                    _ => miss <= w,
                } as usize;
            }
            if f % 10 == 0 {
                for (acc, w) in widths.iter_mut().zip(half) {
                    *acc += w;
                }
                widths[1] += t_critical(alpha, satt) * a.pooled_se;
                widths[6] += t_critical(alpha, shrunk) * a.pooled_se;
            }
        }
    }
    let share = |c: usize| c as f64 / n.max(1) as f64;
    let of_plugin = |w: f64| w / widths[5].max(f64::MIN_POSITIVE);
    Coverage {
        intervals: n,
        with_df: share(hits[0]),
        satterthwaite: share(hits[1]),
        with_tau: share(hits[2]),
        kh: share(hits[3]),
        kh_df: share(hits[4]),
        plugin: share(hits[5]),
        shrinkage: share(hits[6]),
        mean: mean as f64 / pooled_fleets.max(1) as f64,
        width: [
            of_plugin(widths[0]),
            of_plugin(widths[1]),
            of_plugin(widths[2]),
            of_plugin(widths[3]),
            of_plugin(widths[4]),
            of_plugin(widths[6]),
        ],
        fleet_scale: share(fs_hits),
        fleet_scale_fallback: fs_fallback as f64 / pooled_fleets.max(1) as f64,
        fleet_scale_width: of_plugin(fs_width),
        fleet_scale_high_phi: high_hits as f64 / high_n.max(1) as f64,
    }
}

/// One arm's estimate of a one-unknown `effect` (a gravity compliance) from its sessions: the
/// value fitted on all of them with the geometric model, and its jackknife standard error over
/// the sessions (each left out in turn): √((n − 1)/n Σ (θ₋ₛ − θ̄)²), on n − 1 degrees of
/// freedom. The sessions, not the rows,
/// are the replications (the in-sample error of a fit on real data is far too small: its
/// residuals are not white). `None` below [`crate::stats::MIN_UNITS`] sessions or for an
/// effect of more than one unknown.
pub fn estimate(
    start: &quatarm_ref::arm::Arm,
    data: &Dataset,
    opts: &crate::fit::options::Options,
    effect: Effect,
) -> Result<Option<Estimate>, CalibError> {
    let params = effect.params();
    let folds = crate::fit::holdout::by_group(data);
    if params.len() != 1 || folds.len() < crate::stats::MIN_UNITS {
        return Ok(None);
    }
    let Some((value, model_se)) = estimate_in_sample(start, data, opts, effect)? else {
        return Ok(None);
    };
    let o = crate::fit::options::Options {
        terms: Terms::with(&[effect]),
        ..opts.clone()
    };
    let n = data.rows.len();
    let mut loo = Vec::new();
    for out in &folds {
        let keep: Vec<usize> = (0..n).filter(|i| !out.contains(i)).collect();
        let fit = calib::calibrate(start, &data.subset(&keep), &o)?;
        loo.push(params[0].value(&fit.arm));
    }
    let k = loo.len() as f64;
    let mean = loo.iter().sum::<f64>() / k;
    let se = ((k - 1.0) / k * loo.iter().map(|x| (x - mean).powi(2)).sum::<f64>()).sqrt();
    Ok(Some(Estimate {
        value,
        se,
        df: k - 1.0,
        model_se,
    }))
}

/// The fit's own (in-sample) standard error of `p`, `NaN` where it was held or not fitted.
fn model_se(fit: &crate::fit::finish::Fit, p: &crate::params::Param) -> f64 {
    fit.params
        .iter()
        .position(|q| q == p)
        .and_then(|k| fit.uncertainty[k])
        .unwrap_or(f64::NAN)
}

/// Every one-unknown effect of `effects` estimated at once, each conditional on all the others
/// (the full model, "type III"): one fit with all their terms (`Terms::with(effects)`) on all
/// of the arm's sessions, and each effect's jackknife error over the sessions from the same
/// leave-one-session-out fits, on n − 1 degrees of freedom as [`estimate`]. Why: fitted against
/// the geometric model alone, a candidate sharing a strong effect's lever takes up a share of it
/// in every arm (the alias of docs/results/claims.md §7.6); in the full model each candidate is
/// measured for what the others do not explain, in one model fixed before the data are seen
/// (no selection), at the price of the variance their collinearity adds. `None` below
/// [`crate::stats::MIN_UNITS`] sessions, for an empty list, a repeated effect or an effect of
/// more than one unknown. The values are in `effects`' order.
pub fn estimate_joint(
    start: &quatarm_ref::arm::Arm,
    data: &Dataset,
    opts: &crate::fit::options::Options,
    effects: &[Effect],
) -> Result<Option<Vec<Estimate>>, CalibError> {
    let folds = crate::fit::holdout::by_group(data);
    let params: Vec<_> = effects.iter().map(|e| e.params()).collect();
    let repeated = effects
        .iter()
        .enumerate()
        .any(|(i, e)| effects[..i].contains(e));
    if effects.is_empty()
        || repeated
        || params.iter().any(|p| p.len() != 1)
        || folds.len() < crate::stats::MIN_UNITS
    {
        return Ok(None);
    }
    let o = crate::fit::options::Options {
        terms: Terms::with(effects),
        ..opts.clone()
    };
    let all = calib::calibrate(start, data, &o)?;
    let n = data.rows.len();
    let mut loo: Vec<Vec<f64>> = vec![Vec::new(); effects.len()];
    for out in &folds {
        let keep: Vec<usize> = (0..n).filter(|i| !out.contains(i)).collect();
        let fit = calib::calibrate(start, &data.subset(&keep), &o)?;
        for (l, p) in loo.iter_mut().zip(&params) {
            l.push(p[0].value(&fit.arm));
        }
    }
    let k = folds.len() as f64;
    Ok(Some(
        params
            .iter()
            .zip(&loo)
            .map(|(p, l)| {
                let mean = l.iter().sum::<f64>() / k;
                let ss = l.iter().map(|x| (x - mean).powi(2)).sum::<f64>();
                Estimate {
                    value: p[0].value(&all.arm),
                    se: ((k - 1.0) / k * ss).sqrt(),
                    df: k - 1.0,
                    model_se: model_se(&all, &p[0]),
                }
            })
            .collect(),
    ))
}

/// One session of an arm scored with the pooled value fixed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PooledFold {
    /// The session (group number).
    pub group: i64,
    /// The pooled value fixed in the model (from the arm's other sessions and the other arms).
    pub value: f64,
    /// Held-out mean squared error per row (mm²) of the geometric model fitted on the others.
    pub before_ms: f64,
    /// The same with the effect fixed at `value`.
    pub after_ms: f64,
}

/// The held-out gain of the pooled estimate on one arm, nested: for each session, the arm's
/// estimate from its other sessions ([`estimate`]), combined with its other recordings'
/// `siblings` ([`combine_recordings`]), is pooled with the other arms'
/// `others`, the pooled value θ̃ is fixed in the arm's model, the geometric
/// unknowns are fitted on the other sessions, and the session is scored against the
/// geometric model fitted on the same sessions. The held-out session never informs θ̃.
/// Sessions whose training part cannot be estimated (fewer than three sessions left) or pooled
/// are skipped.
pub fn pooled_holdout(
    start: &quatarm_ref::arm::Arm,
    data: &Dataset,
    opts: &crate::fit::options::Options,
    effect: Effect,
    siblings: &[Estimate],
    others: &[Estimate],
    alpha: f64,
) -> Result<Vec<PooledFold>, CalibError> {
    let params = effect.params();
    if params.len() != 1 {
        return Ok(Vec::new());
    }
    let geometric = crate::fit::options::Options {
        terms: Terms::geometric(),
        ..opts.clone()
    };
    let n = data.rows.len();
    let mut out = Vec::new();
    for held in crate::fit::holdout::by_group(data) {
        let keep: Vec<usize> = (0..n).filter(|i| !held.contains(i)).collect();
        let train = data.subset(&keep);
        let Some(own) = estimate(start, &train, opts, effect)? else {
            continue;
        };
        let mut recs = vec![own];
        recs.extend_from_slice(siblings);
        let Some(arm) = combine_recordings(&recs) else {
            continue;
        };
        let mut y: Vec<f64> = others.iter().map(|e| e.value).collect();
        let mut se: Vec<f64> = others.iter().map(|e| e.se).collect();
        let mut df: Vec<f64> = others.iter().map(|e| e.df).collect();
        y.push(arm.estimate);
        se.push(arm.se);
        df.push(arm.df);
        let Some((_, arms)) = pool(&y, &se, &df, alpha) else {
            continue;
        };
        let value = arms.last().map_or(arm.estimate, |a| a.pooled);
        let mut fixed = start.clone();
        params[0].add_to(&mut fixed, value - params[0].value(start));
        let session = data.subset(&held);
        let base = calib::calibrate(start, &train, &geometric)?;
        let with = calib::calibrate(&fixed, &train, &geometric)?;
        let rows = held.len().max(1) as f64;
        out.push(PooledFold {
            group: data.rows[held[0]].group,
            value,
            before_ms: super::nested::session_ss(&base, &session).map_err(CalibError::Mismatch)?
                / rows,
            after_ms: super::nested::session_ss(&with, &session).map_err(CalibError::Mismatch)?
                / rows,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Errors taken as known (infinite degrees of freedom).
    fn known(k: usize) -> Vec<f64> {
        vec![f64::INFINITY; k]
    }

    /// A recording's estimate whose error comes from 4 sessions.
    fn est(value: f64, se: f64) -> Estimate {
        Estimate {
            value,
            se,
            df: 3.0,
            model_se: se,
        }
    }

    #[test]
    fn t_critical_matches_tables() {
        for (df, t) in [(2.0, 4.303), (7.0, 2.365), (30.0, 2.042), (1e12, 1.960)] {
            assert!(
                (t_critical(0.05, df) - t).abs() < 2e-3,
                "{df}: {}",
                t_critical(0.05, df)
            );
        }
    }

    #[test]
    fn arms_that_agree_are_pooled_to_the_mean_and_named_together() {
        // Eight arms, true values 1 ± 50 %, each measured with an error of 0.6: alone, few are
        // two errors from zero; pooled, all are.
        let y = [0.5, 1.4, 0.9, 1.2, 0.6, 1.5, 0.8, 1.1];
        let se = [0.6; 8];
        let (d, arms) = pool(&y, &se, &known(y.len()), 0.05).unwrap();
        assert!(d.named && d.mean_p < 0.01, "{d:?}");
        assert!((d.mean - 1.0).abs() < 1e-12);
        // The arms scatter less than their errors say: no spread between them is seen.
        assert_eq!(d.spread, 0.0);
        assert_eq!(d.spread_interval[0], 0.0);
        assert!(d.spread_interval[1] > 0.0);
        assert!(arms.iter().filter(|a| a.named_alone).count() < 4);
        assert!(arms.iter().all(|a| a.named_pooled && a.shrinkage == 1.0));
        assert!(arms
            .iter()
            .all(|a| (a.pooled - 1.0).abs() < 1e-12 && a.pooled_se < 0.6));
    }

    #[test]
    fn a_precise_arm_keeps_its_own_value_and_a_spread_is_seen() {
        let y = [-4.0, -1.3, 1.34, 0.5, -2.0];
        let se = [0.1, 0.1, 0.1, 3.0, 0.2];
        let (d, arms) = pool(&y, &se, &known(y.len()), 0.05).unwrap();
        assert!(d.spread > 1.0 && d.spread_interval[0] > 0.5, "{d:?}");
        assert!(d.spread_interval[0] <= d.spread && d.spread <= d.spread_interval[1]);
        // Precise arms keep their values; the poorly measured one is pulled to the mean.
        assert!((arms[0].pooled + 4.0).abs() < 0.02);
        assert!(arms[3].shrinkage > 0.5);
        assert!((arms[3].pooled - d.mean).abs() < (arms[3].estimate - d.mean).abs());
        // The mean is not distinguishable from zero: the gate names no arm.
        assert!(!d.named && arms.iter().all(|a| !a.named_pooled));
    }

    #[test]
    fn the_scale_of_the_effect_does_not_matter() {
        // The same fleet in rad/mm (1e-8) gives the same pooling, scaled.
        let y = [-4.0, -1.3, 1.34, 0.5, -2.0];
        let se = [0.1, 0.1, 0.1, 3.0, 0.2];
        let (d, arms) = pool(&y, &se, &known(y.len()), 0.05).unwrap();
        let ys: Vec<f64> = y.iter().map(|v| v * 1e-8).collect();
        let ses: Vec<f64> = se.iter().map(|v| v * 1e-8).collect();
        let (ds, arms_s) = pool(&ys, &ses, &known(ys.len()), 0.05).unwrap();
        assert!((ds.spread / 1e-8 - d.spread).abs() < 1e-9 * d.spread.max(1.0));
        assert!((ds.mean_se / 1e-8 - d.mean_se).abs() < 1e-9);
        for (a, b) in arms.iter().zip(&arms_s) {
            assert!((b.pooled / 1e-8 - a.pooled).abs() < 1e-9);
            assert!((b.pooled_se / 1e-8 - a.pooled_se).abs() < 1e-9);
            assert_eq!(a.named_pooled, b.named_pooled);
        }
    }

    #[test]
    fn recordings_of_one_arm_are_weighed_by_their_errors() {
        // Two recordings that agree: the inverse-variance mean, the error of their sum of
        // weights, no widening.
        let c = combine_recordings(&[est(1.0, 0.1), est(1.1, 0.2)]).unwrap();
        assert!((c.estimate - (1.0 / 0.01 + 1.1 / 0.04) / (1.0 / 0.01 + 1.0 / 0.04)).abs() < 1e-12);
        assert!((c.se - (1.0f64 / (100.0 + 25.0)).sqrt()).abs() < 1e-12);
        assert!(c.q < 1.0 && c.q_p > 0.3 && c.recordings == 2);
        // Two that disagree by ten errors: widened by the Birge ratio, and the p says so.
        let d = combine_recordings(&[est(1.0, 0.1), est(2.0, 0.1)]).unwrap();
        assert!((d.estimate - 1.5).abs() < 1e-12);
        assert!(
            (d.se - (0.005f64 * d.q).sqrt()).abs() < 1e-12 && d.q_p < 1e-6,
            "{d:?}"
        );
        // One recording is itself; the scale does not matter; a bad error is refused.
        assert_eq!(combine_recordings(&[est(3.0, 0.5)]).unwrap().se, 0.5);
        let s = combine_recordings(&[est(1e-8, 1e-9), est(2e-8, 1e-9)]).unwrap();
        assert!((s.se / 1e-8 - d.se).abs() < 1e-12);
        assert!(combine_recordings(&[est(1.0, 0.0)]).is_none());
        assert!(combine_recordings(&[]).is_none());
    }

    #[test]
    fn an_arm_far_from_the_mean_gets_the_uncertainty_of_tau() {
        // Morris's term grows with the distance from the mean and vanishes at the mean; it
        // never shortens the plug-in error.
        let y = [0.0, 0.2, -0.1, 0.1, 3.0];
        let se = [1.0; 5];
        let (d, arms) = pool(&y, &se, &known(y.len()), 0.05).unwrap();
        for a in &arms {
            assert!(a.pooled_se >= a.pooled_se_plugin);
        }
        let far = arms.iter().max_by(|a, b| {
            (a.estimate - d.mean)
                .abs()
                .total_cmp(&(b.estimate - d.mean).abs())
        });
        let near = arms.iter().min_by(|a, b| {
            (a.estimate - d.mean)
                .abs()
                .total_cmp(&(b.estimate - d.mean).abs())
        });
        let gap = |a: &Arm| a.pooled_se / a.pooled_se_plugin;
        assert!(gap(far.unwrap()) > gap(near.unwrap()) + 0.05, "{arms:?}");
    }

    #[test]
    fn the_uncertainty_of_tau_brings_four_arms_nearer_their_nominal_coverage() {
        // Fleets of 4 arms whose errors come from 4 sessions (as MUKCa's): the plug-in interval
        // covers too seldom where the spread is about the arms' error; Morris's term gives part
        // of it back (the long run: `examples/pooling_coverage.rs`, docs/results/claims.md).
        // With 4 arms of 3 df each, the arm's own df and arms − 1 agree: the same interval.
        for (tau, lo) in [(0.0, 0.93), (1.0, 0.89)] {
            let c = simulated_coverage(4, tau, 4, 300, 7, 0.05);
            assert_eq!(c.intervals, 1200);
            assert!(c.with_tau >= c.plugin + 0.015, "tau = {tau}: {c:?}");
            assert!(c.with_tau > lo && c.with_tau < 0.99, "tau = {tau}: {c:?}");
            assert_eq!(c.with_df, c.with_tau);
            assert!(c.mean > 0.9 && c.width[2] > 1.1, "tau = {tau}: {c:?}");
        }
    }

    #[test]
    fn the_arms_own_degrees_of_freedom_bring_eight_arms_to_their_nominal_coverage() {
        // 8 arms of 4 sessions: t on arms − 1 = 7 covers 0.87–0.92 (each arm's 3-df error taken
        // as known); t on the arms' own 3 df 0.93–0.96 (20 000 fleets a cell: claims.md §7.5).
        // Here 300 fleets a cell; 2400 correlated intervals, so a tolerance of about 0.02.
        for tau in [0.0, 1.0] {
            let c = simulated_coverage(8, tau, 4, 300, 7, 0.05);
            assert_eq!(c.intervals, 2400);
            assert!(c.with_df >= c.with_tau + 0.02, "tau = {tau}: {c:?}");
            assert!(c.with_df > 0.91 && c.with_df < 0.98, "tau = {tau}: {c:?}");
            assert!(c.with_tau < 0.94, "tau = {tau}: {c:?}");
            // Satterthwaite's df (the design's part on 7) and the Knapp–Hartung factor on 7 df
            // fall short as the round-3 interval does.
            assert!(
                c.satterthwaite < c.with_df && c.kh < c.with_df,
                "tau = {tau}: {c:?}"
            );
            assert!(c.width[0] > c.width[2], "tau = {tau}: {c:?}");
            // The df that grow with the shrinkage (round 5's candidate) lie between the two,
            // and where the spread is about an arm's error they cover too seldom (0.90 over
            // 20 000 fleets: claims.md §7.6).
            assert!(
                c.with_tau <= c.shrinkage && c.shrinkage <= c.with_df,
                "tau = {tau}: {c:?}"
            );
            if tau == 1.0 {
                assert!(c.shrinkage < 0.93, "{c:?}");
            }
        }
    }

    #[test]
    fn an_arm_interval_is_on_its_own_degrees_of_freedom_where_fewer_than_the_arms() {
        let y = [0.5, 1.4, 0.9, 1.2, 0.6, 1.5, 0.8, 1.1];
        let se = [0.6, 0.3, 0.6, 0.5, 0.6, 0.4, 0.6, 0.6];
        let (_, sure) = pool(&y, &se, &known(8), 0.05).unwrap();
        assert!(sure.iter().all(|a| a.df == 7.0), "{sure:?}");
        let (_, four) = pool(&y, &se, &[3.0; 8], 0.05).unwrap();
        assert!(
            four.iter().all(|a| a.df == 3.0 && a.se_df == 3.0),
            "{four:?}"
        );
        // Ten sessions an arm, four arms: the arms' 3 df are the fewer.
        let (_, ten) = pool(&y[..4], &se[..4], &[9.0; 4], 0.05).unwrap();
        assert!(ten.iter().all(|a| a.df == 3.0), "{ten:?}");
        // The same fleet, the same pooled values and errors: only t changes.
        for (a, b) in sure.iter().zip(&four) {
            assert_eq!((a.pooled, a.pooled_se), (b.pooled, b.pooled_se));
        }
        // An estimate three errors from zero: named alone with its error known (z = 1.96), not
        // with a 4-session error (t₃ = 3.18).
        let y = [3.0, 0.1, -0.2, 0.3];
        let (_, z) = pool(&y, &[1.0; 4], &known(4), 0.05).unwrap();
        let (_, t) = pool(&y, &[1.0; 4], &[3.0; 4], 0.05).unwrap();
        assert!(z[0].named_alone && !t[0].named_alone);
    }

    #[test]
    fn satterthwaite_df_is_the_arms_where_its_own_part_dominates() {
        assert!((satterthwaite_df(1.0, 0.0, 3.0, 0.0, 8) - 3.0).abs() < 1e-12);
        assert!((satterthwaite_df(0.0, 1.0, 3.0, 1.0, 8) - 7.0).abs() < 1e-12);
        // Two equal parts on 3 and 7 df: more than either, fewer than their sum.
        let both = satterthwaite_df(1.0, 0.0, 3.0, 1.0, 8);
        assert!(both > 7.0 && both < 10.0, "{both}");
        // Shrunk by B = 0.5, the own part moves half as much with its error.
        assert!((satterthwaite_df(1.0, 0.5, 3.0, 0.0, 8) - 12.0).abs() < 1e-9);
    }

    #[test]
    fn the_error_of_an_arm_of_several_recordings_has_their_degrees_of_freedom() {
        // Two 4-session recordings that agree, equal errors: 6 df; one: its own 3.
        let c = combine_recordings(&[est(1.0, 0.1), est(1.05, 0.1)]).unwrap();
        assert!((c.df - 6.0).abs() < 1e-9, "{c:?}");
        assert_eq!(combine_recordings(&[est(1.0, 0.1)]).unwrap().df, 3.0);
        // A precise recording and a poor one: about the precise one's 3.
        let c = combine_recordings(&[est(1.0, 0.01), est(1.05, 1.0)]).unwrap();
        assert!(c.df > 3.0 && c.df < 3.01, "{c:?}");
        // Two that disagree: the Birge ratio's 1 df joins the errors' 6.
        let d = combine_recordings(&[est(1.0, 0.1), est(2.0, 0.1)]).unwrap();
        assert!((d.df - 1.0 / (1.0 / 6.0 + 1.0)).abs() < 1e-9, "{d:?}");
    }

    #[test]
    fn the_fleets_dispersion_recovers_a_known_phi() {
        // 64 arms of 4 sessions whose jackknife variances are φ v² χ²₃/3, φ = 4: φ̂ on 192 df
        // is within about two of its standard errors (φ √(2/192) = 0.41) of 4.
        let mut rng = crate::rng::rng(3);
        let v: Vec<f64> = (0..64).map(|u| 0.5 + u as f64 / 63.0).collect();
        let se: Vec<f64> = v
            .iter()
            .map(|v| {
                let chi2: f64 = (0..3).map(|_| crate::rng::normal(&mut rng).powi(2)).sum();
                (4.0 * v * v * chi2 / 3.0).sqrt()
            })
            .collect();
        let d = dispersion(&se, &[3.0; 64], &v).unwrap();
        assert_eq!(d.df, 192.0);
        assert!((d.phi - 4.0).abs() < 0.8, "{d:?}");
        assert!(d.p > 0.01, "one φ holds: {d:?}");
        // The scale of the effect does not matter.
        let tiny = |x: &[f64]| x.iter().map(|x| x * 1e-9).collect::<Vec<_>>();
        let ds = dispersion(&tiny(&se), &[3.0; 64], &tiny(&v)).unwrap();
        assert!((ds.phi - d.phi).abs() < 1e-9 && (ds.p - d.p).abs() < 1e-9);
    }

    #[test]
    fn equal_ratios_pass_the_homogeneity_test_and_wildly_unequal_fail() {
        let v = [0.5, 1.0, 1.5, 0.7, 0.9, 1.2, 0.6, 1.1];
        let same: Vec<f64> = v.iter().map(|v| 3.0 * v).collect();
        let d = dispersion(&same, &[3.0; 8], &v).unwrap();
        assert!(
            (d.phi - 9.0).abs() < 1e-9 && d.bartlett < 1e-9 && d.p > 0.999,
            "{d:?}"
        );
        // Half the arms with a ratio 100 times the others': one φ cannot hold.
        let mixed: Vec<f64> = v
            .iter()
            .enumerate()
            .map(|(u, v)| if u < 4 { *v } else { 10.0 * v })
            .collect();
        let d = dispersion(&mixed, &[3.0; 8], &v).unwrap();
        assert!(d.p < 1e-4, "{d:?}");
        // No model error, or an error taken as known: nothing to pool.
        assert!(dispersion(&same, &[3.0; 8], &[f64::NAN; 8]).is_none());
        assert!(dispersion(&same, &[f64::INFINITY; 8], &v).is_none());
    }

    /// Eight arms' estimates, their in-sample errors and jackknife errors scattering about
    /// 2·v as 3-df errors do.
    const Y: [f64; 8] = [0.5, 1.4, 0.9, 1.2, 0.6, 1.5, 0.8, 1.1];
    const V: [f64; 8] = [0.3; 8];
    const SE: [f64; 8] = [0.45, 0.7, 0.5, 0.8, 0.6, 0.55, 0.75, 0.65];

    #[test]
    fn the_fleets_scale_is_used_only_where_one_phi_holds() {
        let (y, v, se) = (Y, V, SE);
        // The scale is pooled, every arm's error is 2·v on 24 df and its interval on
        // min(24, 7) = 7.
        let (d, scaled, _, arms) = pool_fleet_scale(&y, &se, &[3.0; 8], &v, 0.01).unwrap();
        let d = d.unwrap();
        assert!(scaled && d.p >= 0.01, "{d:?}");
        for a in &arms {
            assert!((a.se - d.phi.sqrt() * 0.3).abs() < 1e-12 && a.se_df == 24.0 && a.df == 7.0);
        }
        // One arm's ratio far from the others': the arms' own errors, as the product's pool.
        let mut wild = se;
        wild[7] = 30.0;
        let (d, scaled, design, arms) = pool_fleet_scale(&y, &wild, &[3.0; 8], &v, 0.01).unwrap();
        assert!(!scaled && d.unwrap().p < 0.01);
        let (pd, pa) = pool(&y, &wild, &[3.0; 8], 0.01).unwrap();
        assert_eq!((design, arms), (pd, pa));
    }

    #[test]
    fn an_arm_without_a_jackknife_joins_only_through_the_fleets_scale() {
        let (y, v, se) = (Y, V, SE);
        let (d, scaled, _, alone) = pool_fleet_scale(&y, &se, &[3.0; 8], &v, 0.01).unwrap();
        let (dj, scaled_j, _, arms) =
            pool_fleet_scale_joined(&y, &se, &[3.0; 8], &v, &[(1.0, 0.6)], 0.01).unwrap();
        // φ̂ is the other arms' alone; the joined arm gets √φ̂ times its model error.
        assert!(scaled && scaled_j && d == dj && arms.len() == 9 && alone.len() == 8);
        let phi = dj.unwrap().phi;
        assert!((arms[8].se - phi.sqrt() * 0.6).abs() < 1e-12 && arms[8].se_df == 24.0);
        // Where one φ does not hold, it cannot be weighed and is left out.
        let mut wild = se;
        wild[7] = 30.0;
        let (_, scaled, _, arms) =
            pool_fleet_scale_joined(&y, &wild, &[3.0; 8], &v, &[(1.0, 0.6)], 0.01).unwrap();
        assert!(!scaled && arms.len() == 8);
    }

    #[test]
    fn the_fleets_scale_covers_as_an_interval_with_errors_known() {
        // 300 fleets of 8 arms: the interval on the pooled scale covers near 0.95 (0.94–1.00
        // with errors known, claims.md §7.4); the homogeneity test fails on about α of them.
        for tau in [0.0, 1.0] {
            let c = simulated_coverage(8, tau, 4, 300, 7, 0.05);
            assert!(
                c.fleet_scale > 0.93 && c.fleet_scale < 0.995,
                "tau = {tau}: {c:?}"
            );
            assert!(c.fleet_scale_fallback < 0.12, "tau = {tau}: {c:?}");
        }
    }

    #[test]
    fn too_few_arms_or_bad_errors_are_refused() {
        assert!(pool(&[1.0, 2.0], &[1.0, 1.0], &[3.0; 2], 0.05).is_none());
        assert!(pool(&[1.0, 2.0, 3.0], &[1.0, 0.0, 1.0], &[3.0; 3], 0.05).is_none());
        assert!(pool(&[1.0, 2.0, 3.0], &[1.0, 1.0, 1.0], &[3.0, 0.0, 3.0], 0.05).is_none());
        assert!(pool(&[1.0, 2.0, 3.0], &[1.0, 1.0, 1.0], &[3.0; 2], 0.05).is_none());
        assert!(pool(&[1.0, f64::NAN, 3.0], &[1.0, 1.0, 1.0], &[3.0; 3], 0.05).is_none());
    }

    /// An arm joined without a jackknife covers as its φ allows: over-covers with no spread
    /// where it shares the others' φ (the join's assumption), covers less where its φ is four
    /// times theirs; the others' coverage barely depends on it. (2,000 fleets a cell; the
    /// example's 20,000: 0.993, 0.903 and 0.786.)
    #[test]
    fn a_joined_arm_covers_as_its_phi_allows() {
        let c = |tau: f64, ratio: f64| {
            simulated_joined_coverage(8, tau, 4, 2000, 48, 0.05, (2f64.sqrt(), ratio))
        };
        let (same, spread, high) = (c(0.0, 1.0), c(1.0, 1.0), c(1.0, 4.0));
        assert!(same.joined > 0.9 && same.joined < 1.0, "{same:?}");
        assert!(same.joined_coverage > 0.97, "{same:?}");
        assert!(
            spread.joined_coverage > 0.87 && spread.joined_coverage < 0.94,
            "{spread:?}"
        );
        assert!(
            high.joined_coverage < spread.joined_coverage - 0.05,
            "{high:?}"
        );
        // The others' barely move (the joined arm enters τ̂² only).
        assert!(
            (high.others_coverage - spread.others_coverage).abs() < 0.01,
            "{high:?} {spread:?}"
        );
    }
}
