//! Geometry with no model in it: the frames of an instrument ([`frame_matrix`],
//! [`frame_from`]), an arm's reach, and least-squares spheres ([`sphere`]).
//!
//! A leaf: the fit (a sphere group's unknown centre, the instrument frame), the acceptance
//! tests and the simulation share these, and it imports nothing of the crate.

pub mod sphere;

use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use quatarm_ref::arm::{Arm, Frame};

/// R_T of a frame as a matrix.
pub fn frame_matrix(f: &Frame) -> Matrix3<f64> {
    let [w, x, y, z] = f.rotation;
    UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, x, y, z))
        .to_rotation_matrix()
        .into_inner()
}

/// A frame from a rotation matrix and a translation.
///
/// The nearest rotation by at most 100 iterations: nalgebra's `from_matrix` iterates until
/// convergence, which a matrix holding NaN never reaches (a start arm with a 1e300 link hung
/// `calibrate` here). A non-finite matrix gives a non-finite frame, which the calibration
/// file's reader refuses.
pub fn frame_from(r: &Matrix3<f64>, t: &Vector3<f64>) -> Frame {
    let q = UnitQuaternion::from_matrix_eps(r, f64::EPSILON, 100, UnitQuaternion::identity());
    let mut c = [q.w, q.i, q.j, q.k];
    if c[0] < 0.0 {
        c = c.map(|v| -v);
    }
    Frame {
        rotation: c,
        translation: [t.x, t.y, t.z],
    }
}

/// The arm's reach: the sum of its link and probe lengths (mm).
pub fn reach(arm: &Arm) -> f64 {
    arm.joints
        .iter()
        .map(|j| Vector3::from(j.actual_link()).norm())
        .sum::<f64>()
        + Vector3::from(arm.probe.actual()).norm()
}
