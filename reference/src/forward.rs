//! Forward kinematics of the arm model in f64, with rotation matrices.
//!
//! The spec writes the chain with quaternions; this module evaluates the same rotations as
//! 3×3 matrices, R_0i = R_0(i-1) · M_i · Rot(u_i, θ_i + Δθ_i + e_i), with
//! M_i = Rot(e1_i, δα_i) · Rot(e2_i, δβ_i) (δα_i, δβ_i varied by any axis wobble at the joint's
//! reading), so that it shares no formula with the firmware.
//! Gravity compliance is evaluated as the spec defines its truth: a first pass without it gives
//! the tip p, the origins o_k and the axes a_k; the deflections
//! e_k = g_k · a_k · ((p − o_k) × ẑ) then enter a second pass.

use crate::arm::{Arm, Axis};
use nalgebra::{Matrix3, Rotation3, Unit, Vector3};

/// The temperature at which links have their nominal length (°C).
pub const REFERENCE_TEMP_C: f64 = 20.0;

/// Probe-ball centre and probe direction in the base frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Probe-ball centre p (mm).
    pub p: Vector3<f64>,
    /// Probe direction n (unit vector).
    pub n: Vector3<f64>,
}

/// Everything a pass through the chain computes, kept for Jacobians and diagnosis.
#[derive(Clone, Debug)]
pub struct Chain {
    /// o_k: origin of joint k in the base frame; `origins[0]` is joint 1's (zero),
    /// `origins[N]` is the end of link N, where the probe vector starts.
    pub origins: Vec<Vector3<f64>>,
    /// R_0k: orientation of joint k's frame after its rotation, base frame (k = 1..N at 0..N-1).
    pub rotations: Vec<Matrix3<f64>>,
    /// a_k: actual axis of joint k in the base frame.
    pub axes: Vec<Vector3<f64>>,
    /// θ_k + Δθ_k + e_k: the angle each joint turned through.
    pub angles: Vec<f64>,
    /// Gravity deflection of each joint (rad), zero where the joint has no compliance.
    pub gravity_deflection: Vec<f64>,
    /// The probe-ball centre.
    pub p: Vector3<f64>,
    /// The probe direction.
    pub n: Vector3<f64>,
}

/// A coordinate axis as a vector.
pub fn axis_vector(a: Axis) -> Vector3<f64> {
    Vector3::from(a.unit())
}

/// Rotation about a unit axis by an angle, as a matrix.
pub fn rotation(axis: &Vector3<f64>, angle: f64) -> Matrix3<f64> {
    Rotation3::from_axis_angle(&Unit::new_normalize(*axis), angle).into_inner()
}

/// M_i: the fixed rotation before joint i from its tilt [δα, δβ].
pub fn tilt_matrix(axis: Axis, tilt: [f64; 2]) -> Matrix3<f64> {
    let (e1, e2) = axis.perpendicular();
    rotation(&axis_vector(e1), tilt[0]) * rotation(&axis_vector(e2), tilt[1])
}

/// The axis a change of tilt component `c` turns joint i's part of the arm about, in the
/// frame before the joint: e1 for δα, and for δβ e2 after the δα rotation (the derivative of
/// [`tilt_matrix`]).
pub fn tilt_axis(axis: Axis, tilt: [f64; 2], c: usize) -> Vector3<f64> {
    let (e1, e2) = axis.perpendicular();
    if c == 0 {
        axis_vector(e1)
    } else {
        rotation(&axis_vector(e1), tilt[0]) * axis_vector(e2)
    }
}

/// The encoder-harmonic part of joint i's angle error at raw reading θ.
pub fn harmonic_error(arm: &Arm, joint: usize, theta: f64) -> f64 {
    arm.joints[joint]
        .harmonics
        .iter()
        .map(|h| {
            let a = f64::from(h.order) * theta;
            h.sin * a.sin() + h.cos * a.cos()
        })
        .sum()
}

/// Thermal scale factor 1 + κ (T − 20).
pub fn thermal_scale(kappa: f64, temp_c: f64) -> f64 {
    1.0 + kappa * (temp_c - REFERENCE_TEMP_C)
}

/// One pass through the chain at raw readings `theta` (rad), temperature `temp_c`, with
/// `extra[k]` added to joint k's angle (the gravity deflections of the second pass).
pub fn pass(arm: &Arm, theta: &[f64], temp_c: f64, extra: &[f64]) -> Chain {
    assert_eq!(theta.len(), arm.dof(), "one reading per joint");
    let n = arm.dof();
    let mut r = Matrix3::identity();
    let mut o = Vector3::zeros();
    let mut chain = Chain {
        origins: Vec::with_capacity(n + 1),
        rotations: Vec::with_capacity(n),
        axes: Vec::with_capacity(n),
        angles: Vec::with_capacity(n),
        gravity_deflection: extra.to_vec(),
        p: Vector3::zeros(),
        n: Vector3::zeros(),
    };
    for (k, j) in arm.joints.iter().enumerate() {
        chain.origins.push(o);
        let u = axis_vector(j.axis);
        let angle = theta[k] + j.zero_offset + harmonic_error(arm, k, theta[k]) + extra[k];
        r = r * tilt_matrix(j.axis, j.tilt_at(theta[k])) * rotation(&u, angle);
        chain.axes.push(r * u);
        chain.rotations.push(r);
        chain.angles.push(angle);
        let link = Vector3::from(j.actual_link()) * thermal_scale(j.thermal, temp_c);
        o += r * link;
    }
    chain.origins.push(o);
    let probe = Vector3::from(arm.probe.actual());
    chain.p = o + r * probe * thermal_scale(arm.probe.thermal, temp_c);
    chain.n = r * probe.normalize();
    chain
}

/// The full model at raw readings `theta` (rad) and temperature `temp_c`, gravity included.
pub fn evaluate(arm: &Arm, theta: &[f64], temp_c: f64) -> Chain {
    let zero = vec![0.0; arm.dof()];
    let first = pass(arm, theta, temp_c, &zero);
    if arm.joints.iter().all(|j| j.gravity == 0.0) {
        return first;
    }
    let z = Vector3::z();
    let deflection: Vec<f64> = arm
        .joints
        .iter()
        .enumerate()
        .map(|(k, j)| {
            if j.gravity == 0.0 {
                0.0
            } else {
                j.gravity * first.axes[k].dot(&(first.p - first.origins[k]).cross(&z))
            }
        })
        .collect();
    pass(arm, theta, temp_c, &deflection)
}

/// Probe-ball centre and direction at raw readings `theta` (rad) and temperature `temp_c`.
pub fn forward(arm: &Arm, theta: &[f64], temp_c: f64) -> Pose {
    let c = evaluate(arm, theta, temp_c);
    Pose { p: c.p, n: c.n }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arm::Harmonic;

    #[test]
    fn default_arm_points_straight_up() {
        let arm = Arm::default6();
        let pose = forward(&arm, &[0.0; 6], 20.0);
        assert!((pose.p - Vector3::new(0.0, 0.0, 1500.0)).norm() < 1e-12);
        assert!((pose.n - Vector3::z()).norm() < 1e-15);
    }

    #[test]
    fn shoulder_quarter_turn() {
        // Joint 2 (x axis) by +90°: everything above it swings to -y (right-handed about x).
        let arm = Arm::default6();
        let pose = forward(
            &arm,
            &[0.0, std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0, 0.0],
            20.0,
        );
        assert!(
            (pose.p - Vector3::new(0.0, -1300.0, 200.0)).norm() < 1e-9,
            "{}",
            pose.p
        );
        assert!((pose.n + Vector3::y()).norm() < 1e-12);
    }

    #[test]
    fn zero_offset_equals_reading_shift() {
        let mut arm = Arm::default6();
        arm.joints[1].zero_offset = 0.01;
        let a = forward(&arm, &[0.3, 0.2, 0.1, 0.4, 0.5, 0.6], 20.0);
        let b = forward(&Arm::default6(), &[0.3, 0.21, 0.1, 0.4, 0.5, 0.6], 20.0);
        assert!((a.p - b.p).norm() < 1e-12);
    }

    #[test]
    fn harmonic_adds_to_angle() {
        let mut arm = Arm::default6();
        arm.joints[3].harmonics.push(Harmonic {
            order: 2,
            sin: 1e-3,
            cos: 2e-3,
        });
        let th = [0.3, 0.2, 0.1, 0.4, 0.5, 0.6];
        let e = 1e-3 * (0.8f64).sin() + 2e-3 * (0.8f64).cos();
        let mut shifted = th;
        shifted[3] += e;
        let a = forward(&arm, &th, 20.0);
        let b = forward(&Arm::default6(), &shifted, 20.0);
        assert!((a.p - b.p).norm() < 1e-12);
    }

    #[test]
    fn wobble_varies_the_tilt_with_the_reading() {
        let mut arm = Arm::default6();
        arm.joints[2].tilt = [1e-4, -2e-4];
        arm.joints[2].wobble.push(crate::arm::Wobble {
            order: 3,
            alpha: [5e-5, -3e-5],
            beta: [2e-5, 4e-5],
        });
        let th = [0.3, 0.2, 0.7, 0.4, 0.5, 0.6];
        let (s, c) = (2.1f64).sin_cos();
        let mut fixed = Arm::default6();
        fixed.joints[2].tilt = [1e-4 + 5e-5 * s - 3e-5 * c, -2e-4 + 2e-5 * s + 4e-5 * c];
        let a = forward(&arm, &th, 20.0);
        let b = forward(&fixed, &th, 20.0);
        assert!((a.p - b.p).norm() < 1e-12);
        assert!((a.p - forward(&Arm::default6(), &th, 20.0).p).norm() > 0.01);
    }

    #[test]
    fn a_wobble_is_the_fixed_tilt_then_two_turns_about_fixed_axes() {
        // What a firmware chain can apply (docs/spec-reading.md, "Axis wobble"): with the
        // varied tilt [α + A, β + B], M(θ) R(u, Δθ) = M R(u, Δθ) R(f1, A) R(f2, B) exactly,
        // f1 = R(u, −Δθ) R(e2, −β) e1 and f2 = R(u, −Δθ) e2 fixed per joint (perpendicular),
        // so only the two angles vary with the reading.
        for axis in [Axis::X, Axis::Y, Axis::Z] {
            let (tilt, dz, a, b) = ([3e-3, -2e-3], 0.7, 4e-5, -6e-5);
            let u = axis_vector(axis);
            let (e1, e2) = axis.perpendicular();
            let (e1, e2) = (axis_vector(e1), axis_vector(e2));
            let f1 = rotation(&u, -dz) * rotation(&e2, -tilt[1]) * e1;
            let f2 = rotation(&u, -dz) * e2;
            assert!(f1.dot(&f2).abs() < 1e-15);
            let varied = tilt_matrix(axis, [tilt[0] + a, tilt[1] + b]) * rotation(&u, dz);
            let split =
                tilt_matrix(axis, tilt) * rotation(&u, dz) * rotation(&f1, a) * rotation(&f2, b);
            assert!((varied - split).norm() < 1e-15, "{axis:?}");
        }
    }

    #[test]
    fn thermal_scales_link_and_error() {
        let mut arm = Arm::default6();
        arm.joints[0].thermal = 1e-4;
        arm.joints[0].link_error = [0.0, 0.0, 1.0];
        let pose = forward(&arm, &[0.0; 6], 30.0);
        // link 1 is 201 mm, scaled by 1.001.
        assert!((pose.p.z - (1300.0 + 201.0 * 1.001)).abs() < 1e-9);
    }

    #[test]
    fn gravity_matches_first_order() {
        let mut arm = Arm::default6();
        arm.joints[1].gravity = 3e-8;
        arm.joints[3].gravity = 2e-8;
        let th = [0.3, 0.9, 0.1, -0.8, 0.5, 0.6];
        let exact = forward(&arm, &th, 20.0).p;
        let c = pass(&arm, &th, 20.0, &[0.0; 6]);
        let mut p = c.p;
        for k in [1usize, 3] {
            let d = c.p - c.origins[k];
            let e = arm.joints[k].gravity * c.axes[k].dot(&d.cross(&Vector3::z()));
            p += e * c.axes[k].cross(&d);
        }
        assert!((exact - c.p).norm() > 1e-3, "the effect is visible");
        assert!(
            (exact - p).norm() < 1e-5,
            "first order agrees: {}",
            (exact - p).norm()
        );
    }
}
