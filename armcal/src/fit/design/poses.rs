//! Poses of an arm: joint travel ([`Limits`]), a pose drawn inside it, readings rounded to
//! encoder counts, and the numeric inverse that puts the ball on a target. The design's groups
//! and the simulation's data are both made of these.

use crate::rng::{normal, SimRng};
use nalgebra::{Matrix3, Vector3};
use quatarm_ref::arm::Arm;
use quatarm_ref::forward;
use rand::Rng;
use std::f64::consts::PI;

/// Joint travel: readings (rad) from `lo[k]` to `hi[k]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Limits {
    /// Lower bounds.
    pub lo: Vec<f64>,
    /// Upper bounds.
    pub hi: Vec<f64>,
}

/// Hinges travel ±170° (the spec's `default-6`), swivels a full turn (±180°).
pub fn limits(arm: &Arm) -> Limits {
    let h = 170f64.to_radians();
    let (lo, hi) = (0..arm.dof())
        .map(|k| if arm.is_hinge(k) { (-h, h) } else { (-PI, PI) })
        .unzip();
    Limits { lo, hi }
}

/// A pose drawn uniformly inside the limits.
pub fn random_pose(limits: &Limits, rng: &mut SimRng) -> Vec<f64> {
    limits
        .lo
        .iter()
        .zip(&limits.hi)
        .map(|(lo, hi)| rng.gen_range(*lo..*hi))
        .collect()
}

/// Readings as the encoders give them: each angle rounded to a whole count, swivels wrapped
/// into (−π, π].
pub fn quantise(arm: &Arm, theta: &[f64]) -> Vec<f64> {
    theta
        .iter()
        .zip(&arm.joints)
        .map(|(t, j)| count_angle(*t, j.encoder_counts, 0.0))
        .collect()
}

/// The angle of the count nearest to `t` plus `extra` counts, wrapped into (−π, π].
pub(crate) fn count_angle(t: f64, counts: u32, extra: f64) -> f64 {
    let mut t = t;
    if t > PI {
        t -= 2.0 * PI * ((t + PI) / (2.0 * PI)).floor();
    } else if t <= -PI {
        t += 2.0 * PI * ((PI - t) / (2.0 * PI)).floor();
    }
    let counts = f64::from(counts);
    let c = (t * counts / (2.0 * PI) + extra).round();
    2.0 * PI * c / counts
}

/// Joint angles that put the ball of `arm` on `target` at temperature `temp_c`, found by damped
/// least squares from `start` within `limits`; `None` if it does not get within 1e-9 mm.
pub fn inverse(
    arm: &Arm,
    target: &Vector3<f64>,
    start: &[f64],
    temp_c: f64,
    limits: &Limits,
) -> Option<Vec<f64>> {
    let n = arm.dof();
    let mut th = start.to_vec();
    for _ in 0..200 {
        let c = forward::evaluate(arm, &th, temp_c);
        let e = target - c.p;
        if e.norm() < 1e-9 {
            return Some(th);
        }
        // J (3 × n) and the minimum-norm damped step Jᵀ (J Jᵀ + μ² I)⁻¹ e.
        let cols: Vec<Vector3<f64>> = (0..n)
            .map(|k| c.axes[k].cross(&(c.p - c.origins[k])))
            .collect();
        let mut jjt = Matrix3::zeros();
        for col in &cols {
            jjt += col * col.transpose();
        }
        let mu2 = 1e-6 * jjt.trace() + 1e-9;
        jjt += Matrix3::identity() * mu2;
        let w = jjt.try_inverse()? * e;
        let mut step: Vec<f64> = cols.iter().map(|col| col.dot(&w)).collect();
        let big = step.iter().fold(0.0f64, |m, s| m.max(s.abs()));
        if big > 0.3 {
            step.iter_mut().for_each(|s| *s *= 0.3 / big);
        }
        for k in 0..n {
            th[k] = (th[k] + step[k]).clamp(limits.lo[k], limits.hi[k].max(limits.lo[k]));
            if limits.hi[k] - limits.lo[k] >= 2.0 * PI - 1e-9 {
                // A swivel: no end stop, only wrap.
                th[k] = (th[k] + PI).rem_euclid(2.0 * PI) - PI;
            }
        }
    }
    None
}

/// Poses putting the ball on `target` (missed by the noise), from random starts.
#[allow(clippy::too_many_arguments)]
pub(crate) fn probe_point(
    truth: &Arm,
    lim: &Limits,
    target: &Vector3<f64>,
    noise_mm: f64,
    tc: f64,
    rng: &mut SimRng,
) -> Option<Vec<f64>> {
    let aim = target + Vector3::new(normal(rng), normal(rng), normal(rng)) * noise_mm;
    for _ in 0..40 {
        let start = random_pose(lim, rng);
        if let Some(th) = inverse(truth, &aim, &start, tc, lim) {
            return Some(th);
        }
    }
    None
}
