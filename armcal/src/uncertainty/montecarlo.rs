//! Monte Carlo propagation of the same budget (GUM Supplement 1, JCGM 101:2008): draw every
//! input from its distribution, evaluate the f64 reference exactly (no linearisation), and
//! read the output's distribution from the draws.
//!
//! Inputs per draw: the parameters from N(estimate, C) (a symmetric square root of C, so a
//! semi-definite C is fine), each joint angle from N(θ, σ_θ²), the temperature from
//! N(T, σ_T²), and the probing and model terms as N(0, (σ_probe² + σ_model²) I₃) added to the
//! tip. With a leverage-scaled pose part P (issue 27) the parameters also move by √(f − 1)
//! times a draw of N(0, P), f = max(1, ℓ) the reading's factor ([`super::propagate`]): the
//! parameters' variance is then cov + (f − 1) P, the first order's. The covariance reported is the draws' about their mean; U95 is the 95th percentile of
//! the draws' distances from the estimate p (the centre the spec's sphere is about), which is
//! what the first-order radius predicts.

use super::Budget;
use crate::params::apply;
use crate::rng::{normal, SimRng};
use nalgebra::{DMatrix, DVector, Matrix3, SymmetricEigen, Vector3};
use quatarm_ref::arm::Arm;
use quatarm_ref::forward;

/// A symmetric square root of a covariance (negative rounding eigenvalues taken as 0).
pub fn sqrt_cov(c: &DMatrix<f64>) -> DMatrix<f64> {
    if c.nrows() == 0 {
        return c.clone();
    }
    let e = SymmetricEigen::new(c.clone());
    let d = DMatrix::from_diagonal(&e.eigenvalues.map(|l| l.max(0.0).sqrt()));
    &e.eigenvectors * d * e.eigenvectors.transpose()
}

/// √(max(1, ℓ, ℓJ) − 1) at a reading: the factor of its extra pose draw (0 without a pose
/// part or at ℓ, ℓJ ≤ 1; [`super::propagate::Leverage::ratio`]).
pub fn pose_scale(arm: &Arm, probe: usize, budget: &Budget, theta: &[f64], temp_c: f64) -> f64 {
    if budget.pose.is_none() {
        return 0.0;
    }
    let j = super::propagate::jacobians(arm, probe, budget, theta, temp_c);
    pose_scale_at(budget, &j)
}

/// [`pose_scale`] from a reading's Jacobians.
pub fn pose_scale_at(budget: &Budget, j: &super::propagate::Jacobians) -> f64 {
    let l = super::propagate::leverages_at(budget, j).ratio();
    l.map_or(0.0, |l| (super::pose::leverage_factor(l) - 1.0).sqrt())
}

/// One draw of the parameters from N(0, P), P = (D Dᵀ + b cov)/(1 + b) the budget's pose
/// part: (D z + √b · `root` z′)/√(1 + b), `root` the square root of cov. Zero without one.
pub fn pose_draw(budget: &Budget, root: &DMatrix<f64>, rng: &mut SimRng) -> DVector<f64> {
    let k = budget.params.len();
    let Some(p) = &budget.pose else {
        return DVector::zeros(k);
    };
    let z = DVector::from_fn(p.factor.ncols(), |_, _| normal(rng));
    let mut x = &p.factor * z;
    if p.shrink > 0.0 {
        x += root * DVector::from_fn(k, |_, _| normal(rng)) * p.shrink.sqrt();
    }
    x / (1.0 + p.shrink).sqrt()
}

/// What the draws say about one reading.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The estimate p (no draw).
    pub p: Vector3<f64>,
    /// Covariance of the draws about their mean (mm²).
    pub cov: Matrix3<f64>,
    /// 95th percentile of |draw − p| (mm).
    pub u95: f64,
}

/// `draws` draws for the reading (θ rad, T °C) taken with the arm's probe at index `probe`;
/// `root` is [`sqrt_cov`] of the budget's C. Each draw moves the whole arm's parameters,
/// then evaluates it with that probe mounted.
#[allow(clippy::too_many_arguments)]
pub fn point(
    arm: &Arm,
    probe: usize,
    budget: &Budget,
    root: &DMatrix<f64>,
    theta: &[f64],
    temp_c: f64,
    draws: usize,
    rng: &mut SimRng,
) -> Outcome {
    let mounted = |a: &Arm, th: &[f64], tc: f64| {
        let a = a
            .for_probe(probe)
            .expect("a reading's probe is one of the arm's");
        forward::forward(&a, th, tc).p
    };
    let p = mounted(arm, theta, temp_c);
    let st = budget.sigma_theta(arm);
    let extra = (budget.probing_mm.powi(2) + budget.model_mm.powi(2)).sqrt();
    let k = budget.params.len();
    let widen = pose_scale(arm, probe, budget, theta, temp_c);
    let mut samples = Vec::with_capacity(draws);
    let mut th = theta.to_vec();
    for _ in 0..draws {
        let z = DVector::from_fn(k, |_, _| normal(rng));
        let mut dx = root * z;
        if widen > 0.0 {
            dx += pose_draw(budget, root, rng) * widen;
        }
        let a = apply(arm, &budget.params, dx.as_slice());
        for (t, (t0, s)) in th.iter_mut().zip(theta.iter().zip(&st)) {
            *t = t0 + s * normal(rng);
        }
        let tc = temp_c + budget.temperature_c * normal(rng);
        let noise = Vector3::new(normal(rng), normal(rng), normal(rng)) * extra;
        samples.push(mounted(&a, &th, tc) + noise);
    }
    let m = draws.max(1) as f64;
    let mean = samples.iter().sum::<Vector3<f64>>() / m;
    let cov = samples
        .iter()
        .map(|s| (s - mean) * (s - mean).transpose())
        .sum::<Matrix3<f64>>()
        / (m - 1.0).max(1.0);
    let mut dist: Vec<f64> = samples.iter().map(|s| (s - p).norm()).collect();
    dist.sort_by(f64::total_cmp);
    let u95 = dist
        .get(((0.95 * m).ceil() as usize).saturating_sub(1))
        .copied()
        .unwrap_or(0.0);
    Outcome { p, cov, u95 }
}
