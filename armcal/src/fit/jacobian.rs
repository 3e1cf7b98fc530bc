//! The analytic Jacobian of the probe-ball centre with respect to every calibration parameter.
//!
//! Every term of the model moves the tip in one of three ways, and the chain the reference
//! evaluates already holds what each needs (origins o_k, actual axes a_k, rotations R_0k):
//!
//! - an angle added to joint k (zero offset, harmonics, gravity deflection) turns everything
//!   beyond joint k about a_k through o_k: ∂p = a_k × (p − o_k);
//! - a tilt turns the same part about the tilt's own axis through o_k: for δα the axis e1 in
//!   the frame before the joint, for δβ the axis e2 after the δα rotation (both at the tilt
//!   the joint has at this reading: an axis wobble varies it, and its column is the tilt's
//!   times sin or cos of its order times the reading);
//! - a link or probe error (or its thermal scaling) moves everything beyond it by R_0k times
//!   the change of the vector.
//!
//! Gravity compliance is evaluated exactly by the reference (a second pass with deflected
//! angles); its column uses the first-order lever e_k = a_k · ((p − o_k) × ẑ) of the spec, and
//! the other columns ignore how the deflection itself varies with them. Both approximations are
//! of relative size g·L (≈ 3e-5): they change how fast a fit converges, never where it
//! converges, because residuals are always evaluated exactly.

use crate::effects::TipPoint;
use crate::params::{Param, ParamExt};
use nalgebra::Vector3;
use quatarm_ref::arm::Arm;
use quatarm_ref::forward::{self, thermal_scale};

/// The tip p at readings `theta` and temperature `temp_c`, with ∂p/∂param written into
/// `cols` (one 3-vector per entry of `params`; zero for frame parameters and for the other
/// probes' unknowns, which do not move this ball).
///
/// `arm` is the arm as it measured the reading, its probe already mounted
/// ([`Arm::for_probe`], [`crate::fit::probes::Mounted::of`]), as [`TipPoint::arm`] is; `probe` is
/// that probe's index among the whole arm's (`quatarm_ref::Arm::probes` order), which the
/// parameters' probe indices refer to.
pub fn tip_jacobian(
    arm: &Arm,
    probe: usize,
    params: &[Param],
    theta: &[f64],
    temp_c: f64,
    cols: &mut [Vector3<f64>],
) -> Vector3<f64> {
    let c = forward::evaluate(arm, theta, temp_c);
    let p = c.p;
    let n = arm.dof();
    let turn = |j: usize| -> Vector3<f64> { c.axes[j].cross(&(p - c.origins[j])) };
    let at = TipPoint {
        arm,
        probe,
        chain: &c,
        theta,
        temp_c,
    };
    for (param, col) in params.iter().zip(cols.iter_mut()) {
        if let Some((e, k)) = param.effect() {
            *col = e.with(|t| t.column(k, &at));
            continue;
        }
        *col = match *param {
            Param::ZeroOffset(j) => turn(j),
            Param::Tilt(j, k) => at.tilt_turn(j, k),
            Param::LinkError(j, k) => {
                c.rotations[j].column(k) * thermal_scale(arm.joints[j].thermal, temp_c)
            }
            // `arm` is the arm as it measured this reading, its probe mounted first.
            Param::ProbeError(q, k) if q == probe => {
                c.rotations[n - 1].column(k) * thermal_scale(arm.probe.thermal, temp_c)
            }
            _ => Vector3::zeros(),
        };
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{apply, Effect, Link, Terms};
    use quatarm_ref::arm::{Harmonic, Wobble};

    fn check(arm: &Arm, params: &[Param], theta: &[f64], temp: f64, rel_tol: f64) {
        let mut cols = vec![Vector3::zeros(); params.len()];
        tip_jacobian(arm, 0, params, theta, temp, &mut cols);
        for (i, p) in params.iter().enumerate() {
            let h = match p.unit() {
                "mm" => 1e-4,
                "rad/mm" => 1e-10,
                "1/°C" => 1e-7,
                _ => 1e-7,
            };
            let mut x = vec![0.0; params.len()];
            x[i] = h;
            let plus = forward::forward(&apply(arm, params, &x), theta, temp).p;
            x[i] = -h;
            let minus = forward::forward(&apply(arm, params, &x), theta, temp).p;
            let numeric = (plus - minus) / (2.0 * h);
            let err = (numeric - cols[i]).norm();
            let scale = numeric.norm().max(cols[i].norm()).max(1e-9);
            // Central differences of ~1000 mm values carry ~1e-13 mm of rounding, over 2h.
            let rounding = 1e-12 / h;
            assert!(
                err <= rel_tol * scale + rounding,
                "{p}: analytic {:?} numeric {:?}",
                cols[i].as_slice(),
                numeric.as_slice()
            );
        }
    }

    fn every_term(dof: usize) -> Vec<Param> {
        let harmonics =
            (1..=2).flat_map(|order| (0..dof).map(move |joint| Effect::Harmonic { joint, order }));
        let thermal = (0..dof)
            .map(Link::Joint)
            .chain([Link::Probe])
            .map(Effect::Thermal);
        let wobble =
            (1..=2).flat_map(|order| (0..dof).map(move |joint| Effect::Wobble { joint, order }));
        Terms::with(&harmonics.chain(thermal).chain(wobble).collect::<Vec<_>>()).params(dof)
    }

    #[test]
    fn matches_finite_differences_on_default6() {
        let mut arm = Arm::default6();
        for (k, j) in arm.joints.iter_mut().enumerate() {
            j.zero_offset = 1e-3 * k as f64;
            j.tilt = [2e-4, -3e-4 * k as f64];
            j.link_error = [0.1, -0.2, 0.05 * k as f64];
            j.thermal = 1e-5;
            j.harmonics.push(Harmonic {
                order: 1,
                sin: 1e-4,
                cos: -5e-5,
            });
            // A wobble large enough that the tilt at the reading differs from the fixed one
            // by more than the tolerance would hide.
            j.wobble.push(Wobble {
                order: 2,
                alpha: [3e-3, -2e-3],
                beta: [1e-3, 4e-3 * k as f64],
            });
        }
        let theta = [0.3, -0.7, 1.1, 0.9, -2.0, 0.4];
        check(&arm, &every_term(6), &theta, 27.0, 1e-6);
    }

    #[test]
    fn matches_finite_differences_on_a_twisted_7_axis_arm() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../data/mukca/mukca-panda-panda_2-repo-calibrated.toml");
        let arm = quatarm_ref::calfile::read(&path).unwrap().arm;
        let theta = [0.3, -0.7, 1.1, -1.9, -2.0, 1.4, 0.2];
        check(&arm, &every_term(7), &theta, 14.0, 1e-6);
    }

    #[test]
    fn gravity_column_matches_to_first_order() {
        let mut arm = Arm::default6();
        arm.joints[1].gravity = 3e-8;
        arm.joints[3].gravity = 2e-8;
        let params = Terms::with(&[Effect::Gravity(1), Effect::Gravity(3)]).params(6);
        let theta = [0.3, 0.9, 0.1, -0.8, 0.5, 0.6];
        check(&arm, &params, &theta, 20.0, 2e-4);
    }
}
