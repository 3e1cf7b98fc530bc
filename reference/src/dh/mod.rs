//! Denavit–Hartenberg arms, evaluated the classic way: a product of 4×4 homogeneous matrices.
//!
//! The first paper behind this product (Sładek et al.) models the measuring arm with a
//! Denavit–Hartenberg (D–H) table; robot makers publish their arms the same way. This module
//! keeps that formulation as it is written in the literature — one 4×4 matrix per joint,
//! multiplied out — so that it can serve as an independent check of the spec's quaternion
//! model (`spec/arm-model.md`): [`convert`] turns any D–H arm into a spec [`Arm`],
//! and the two evaluations must agree (see [`agreement`] and `docs/results/dh.md`).
//!
//! Two conventions exist and are kept strictly apart, because the same four numbers mean
//! different transforms in each:
//! - [`Convention::Classic`] (standard D–H, Denavit & Hartenberg 1955, Paul 1981; used by
//!   Universal Robots): `T_i = Rot_z(θ_i + offset_i) · Trans_z(d_i) · Trans_x(a_i) · Rot_x(α_i)`.
//!   Row i's `a` and `α` describe the link *after* joint i.
//! - [`Convention::Modified`] (Craig 1986; used by Franka Emika):
//!   `T_i = Rot_x(α_{i-1}) · Trans_x(a_{i-1}) · Rot_z(θ_i + offset_i) · Trans_z(d_i)`.
//!   Row i's `a` and `α` describe the link *before* joint i.
//!
//! Both evaluate `T = B · T_1 · … · T_N`, B an optional base transform, and the probe-ball
//! centre is `T · [t; 1]` with t the tool (probe) vector in the last frame. The probe direction is
//! the tool vector's direction, as in the spec.

pub mod convert;
pub mod tables;

use crate::arm::Arm;
use crate::forward::{forward, REFERENCE_TEMP_C};
use nalgebra::{Matrix4, Vector3, Vector4};

pub use convert::{to_spec_arm, to_spec_arm_with_frame, BASE_TOLERANCE_MM, RIGID_TOLERANCE};

/// Which D–H convention a table is written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Convention {
    /// Standard D–H: `Rot_z(θ) · Trans_z(d) · Trans_x(a) · Rot_x(α)`; a, α follow the joint.
    Classic,
    /// Modified D–H (Craig): `Rot_x(α) · Trans_x(a) · Rot_z(θ) · Trans_z(d)`; a, α precede it.
    Modified,
}

/// One row of a D–H table: a revolute joint (mm, rad).
///
/// The joint variable θ is not stored: it is the encoder reading, supplied at evaluation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DhJoint {
    /// Constant added to the joint variable (the table's θ column for a revolute joint).
    pub theta_offset: f64,
    /// Offset along the joint axis z (mm).
    pub d: f64,
    /// Common-normal length along x (mm): a_i (classic) or a_{i-1} (modified).
    pub a: f64,
    /// Twist about x (rad): α_i (classic) or α_{i-1} (modified).
    pub alpha: f64,
}

impl DhJoint {
    /// A row without θ offset.
    pub fn new(d: f64, a: f64, alpha: f64) -> DhJoint {
        DhJoint {
            theta_offset: 0.0,
            d,
            a,
            alpha,
        }
    }
}

/// A D–H arm: table, convention, base transform and tool vector.
#[derive(Clone, Debug, PartialEq)]
pub struct DhArm {
    /// Free-text name, carried into the converted arm.
    pub name: String,
    /// How the rows are to be read.
    pub convention: Convention,
    /// Rows, base first.
    pub joints: Vec<DhJoint>,
    /// Base transform B: from the world (base-plate) frame to the table's frame 0. Identity for
    /// most published tables.
    pub base: Matrix4<f64>,
    /// Tool (probe) vector t in the last frame (frame N), to the probe-ball centre (mm).
    pub tool: Vector3<f64>,
}

/// Probe-ball centre and probe direction of a D–H arm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DhPose {
    /// Probe-ball centre (mm), world frame.
    pub p: Vector3<f64>,
    /// Direction of the tool vector, world frame (unit vector).
    pub n: Vector3<f64>,
}

/// Why a D–H arm cannot be evaluated or converted.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DhError {
    /// The number of joint angles differs from the number of rows.
    #[error("{got} joint angles for a {expected}-joint table")]
    AngleCount {
        /// Rows in the table.
        expected: usize,
        /// Angles supplied.
        got: usize,
    },
    /// The spec model takes 6 or 7 joints.
    #[error("the spec model takes 6 or 7 joints, this table has {0}")]
    JointCount(usize),
    /// A table entry, the base or the tool holds NaN or infinity.
    #[error("non-finite number in {0}")]
    NonFinite(&'static str),
    /// The tool vector is zero, so the probe direction is undefined.
    #[error("tool vector is zero: the probe direction is undefined")]
    ZeroTool,
    /// The base transform is not a rigid motion (orthonormal rotation, det +1, last row 0 0 0 1).
    #[error("base transform is not rigid (deviation {deviation:e})")]
    NotRigid {
        /// Largest deviation from a rigid transform found.
        deviation: f64,
    },
    /// The base translation has a part across joint 1's axis, which the spec model cannot
    /// hold: its joint 1 sits at the base-frame origin.
    #[error(
        "base translation has {across_mm} mm across joint 1's axis; the spec model puts joint 1 \
         at the base origin (use to_spec_arm_with_frame to carry the base as a reference frame)"
    )]
    BaseOffsetAcrossAxis {
        /// Length of the translation's component perpendicular to joint 1's axis (mm).
        across_mm: f64,
    },
}

/// Rotation about x by `angle` as a homogeneous matrix.
pub fn rot_x(angle: f64) -> Matrix4<f64> {
    let (s, c) = angle.sin_cos();
    Matrix4::new(
        1.0, 0.0, 0.0, 0.0, //
        0.0, c, -s, 0.0, //
        0.0, s, c, 0.0, //
        0.0, 0.0, 0.0, 1.0,
    )
}

/// Rotation about z by `angle` as a homogeneous matrix.
pub fn rot_z(angle: f64) -> Matrix4<f64> {
    let (s, c) = angle.sin_cos();
    Matrix4::new(
        c, -s, 0.0, 0.0, //
        s, c, 0.0, 0.0, //
        0.0, 0.0, 1.0, 0.0, //
        0.0, 0.0, 0.0, 1.0,
    )
}

/// Translation by (x, y, z) as a homogeneous matrix.
pub fn trans(x: f64, y: f64, z: f64) -> Matrix4<f64> {
    Matrix4::new(
        1.0, 0.0, 0.0, x, //
        0.0, 1.0, 0.0, y, //
        0.0, 0.0, 1.0, z, //
        0.0, 0.0, 0.0, 1.0,
    )
}

/// Classic D–H link transform `Rot_z(θ + offset) · Trans_z(d) · Trans_x(a) · Rot_x(α)`.
///
/// Written as the product of the four elementary matrices, not as the closed form, so that it
/// reads exactly like the textbook definition it checks against.
pub fn classic_link(j: &DhJoint, theta: f64) -> Matrix4<f64> {
    rot_z(theta + j.theta_offset) * trans(0.0, 0.0, j.d) * trans(j.a, 0.0, 0.0) * rot_x(j.alpha)
}

/// Modified (Craig) D–H link transform `Rot_x(α) · Trans_x(a) · Rot_z(θ + offset) · Trans_z(d)`,
/// with this row's `alpha` and `a` being α_{i-1} and a_{i-1}.
pub fn modified_link(j: &DhJoint, theta: f64) -> Matrix4<f64> {
    rot_x(j.alpha) * trans(j.a, 0.0, 0.0) * rot_z(theta + j.theta_offset) * trans(0.0, 0.0, j.d)
}

impl DhArm {
    /// An arm with identity base.
    pub fn new(
        name: impl Into<String>,
        convention: Convention,
        joints: Vec<DhJoint>,
        tool: Vector3<f64>,
    ) -> DhArm {
        DhArm {
            name: name.into(),
            convention,
            joints,
            base: Matrix4::identity(),
            tool,
        }
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// The link transform of row `i` at joint angle `theta`, in this arm's convention.
    pub fn link(&self, i: usize, theta: f64) -> Matrix4<f64> {
        match self.convention {
            Convention::Classic => classic_link(&self.joints[i], theta),
            Convention::Modified => modified_link(&self.joints[i], theta),
        }
    }

    /// `B · T_1 · … · T_N`: the last frame in the world frame at joint angles `theta` (rad).
    pub fn frame(&self, theta: &[f64]) -> Result<Matrix4<f64>, DhError> {
        if theta.len() != self.dof() {
            return Err(DhError::AngleCount {
                expected: self.dof(),
                got: theta.len(),
            });
        }
        Ok(theta
            .iter()
            .enumerate()
            .fold(self.base, |t, (i, &th)| t * self.link(i, th)))
    }

    /// Probe-ball centre `T · [t; 1]` and probe direction at joint angles `theta` (rad).
    pub fn pose(&self, theta: &[f64]) -> Result<DhPose, DhError> {
        let t = self.frame(theta)?;
        let tip = t * Vector4::new(self.tool.x, self.tool.y, self.tool.z, 1.0);
        let dir = t * self.tool.normalize().push(0.0);
        Ok(DhPose {
            p: tip.xyz(),
            n: dir.xyz(),
        })
    }
}

/// How closely a D–H arm and a spec arm agree over a set of poses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Agreement {
    /// Poses compared.
    pub poses: usize,
    /// Largest probe-ball distance between the two evaluations (mm).
    pub max_position_mm: f64,
    /// Root mean square of that distance (mm).
    pub rms_position_mm: f64,
    /// Largest difference of the probe directions (norm of the difference of unit vectors).
    pub max_direction: f64,
}

/// Evaluates `dh` with its 4×4 matrices and `arm` with [`forward`] (at 20 °C, where the
/// converted arm has its nominal lengths) at every pose, and reports the largest and RMS
/// difference.
///
/// This is the cross-check of the conversion: the two evaluations share no formula, so a
/// mapping mistake shows up as a difference of millimetres, rounding as ~1e-13 mm.
pub fn agreement<P: AsRef<[f64]>>(
    dh: &DhArm,
    arm: &Arm,
    poses: impl IntoIterator<Item = P>,
) -> Result<Agreement, DhError> {
    let mut result = Agreement {
        poses: 0,
        max_position_mm: 0.0,
        rms_position_mm: 0.0,
        max_direction: 0.0,
    };
    let mut sum_sq = 0.0;
    for theta in poses {
        let theta = theta.as_ref();
        if theta.len() != arm.dof() {
            return Err(DhError::AngleCount {
                expected: arm.dof(),
                got: theta.len(),
            });
        }
        let a = dh.pose(theta)?;
        let b = forward(arm, theta, REFERENCE_TEMP_C);
        let dp = (a.p - b.p).norm();
        let dn = (a.n - b.n).norm();
        sum_sq += dp * dp;
        result.max_position_mm = result.max_position_mm.max(dp);
        result.max_direction = result.max_direction.max(dn);
        result.poses += 1;
    }
    if result.poses > 0 {
        result.rms_position_mm = (sum_sq / result.poses as f64).sqrt();
    }
    Ok(result)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn classic_link_matches_closed_form() {
        // The textbook closed form of the classic D–H matrix (Spong, Hutchinson & Vidyasagar,
        // eq. 3.10), written out here so that the product of elementary matrices is checked
        // against an independent expression.
        let j = DhJoint {
            theta_offset: 0.3,
            d: 12.0,
            a: -7.0,
            alpha: 0.9,
        };
        let th = 1.1 + j.theta_offset;
        let (st, ct) = th.sin_cos();
        let (sa, ca) = j.alpha.sin_cos();
        let closed = Matrix4::new(
            ct,
            -st * ca,
            st * sa,
            j.a * ct,
            st,
            ct * ca,
            -ct * sa,
            j.a * st,
            0.0,
            sa,
            ca,
            j.d,
            0.0,
            0.0,
            0.0,
            1.0,
        );
        assert!((classic_link(&j, 1.1) - closed).amax() < 1e-14);
    }

    #[test]
    fn modified_link_matches_closed_form() {
        // Craig, Introduction to Robotics, eq. 3.6.
        let j = DhJoint {
            theta_offset: -0.2,
            d: 5.0,
            a: 3.0,
            alpha: -0.7,
        };
        let th = 0.4 + j.theta_offset;
        let (st, ct) = th.sin_cos();
        let (sa, ca) = j.alpha.sin_cos();
        let closed = Matrix4::new(
            ct,
            -st,
            0.0,
            j.a,
            st * ca,
            ct * ca,
            -sa,
            -sa * j.d,
            st * sa,
            ct * sa,
            ca,
            ca * j.d,
            0.0,
            0.0,
            0.0,
            1.0,
        );
        assert!((modified_link(&j, 0.4) - closed).amax() < 1e-14);
    }

    #[test]
    fn two_link_planar_arm() {
        // Two classic rows with α = 0 form a planar arm: tip at (a1 cos q1 + a2 cos(q1+q2), …).
        let arm = DhArm::new(
            "planar",
            Convention::Classic,
            vec![DhJoint::new(0.0, 300.0, 0.0), DhJoint::new(0.0, 200.0, 0.0)],
            Vector3::new(50.0, 0.0, 0.0),
        );
        let (q1, q2) = (0.4, FRAC_PI_2);
        let p = arm.pose(&[q1, q2]).unwrap().p;
        let expect = Vector3::new(
            300.0 * q1.cos() + 250.0 * (q1 + q2).cos(),
            300.0 * q1.sin() + 250.0 * (q1 + q2).sin(),
            0.0,
        );
        assert!((p - expect).norm() < 1e-12, "{p}");
    }

    #[test]
    fn wrong_angle_count_is_an_error() {
        let arm = tables::ur5(Vector3::new(0.0, 0.0, 100.0));
        assert_eq!(
            arm.pose(&[0.0; 5]),
            Err(DhError::AngleCount {
                expected: 6,
                got: 5
            })
        );
    }
}
