//! Published D–H tables of real arms (mm, rad), for the conversion cross-check.
//!
//! Each function takes the tool vector in the arm's flange frame (the frame the maker's table
//! ends in, or the flange row it lists after the last joint) and returns the arm with that tool.
//! Values are copied from the cited source and converted from metres to millimetres; nothing is
//! fitted or adjusted.

use super::{Convention, DhArm, DhJoint};
use nalgebra::Vector3;
use std::f64::consts::{FRAC_PI_2, PI};

/// Universal Robots UR5 (CB3, "series 3"), classic D–H.
///
/// Source: Universal Robots, "DH Parameters for calculations of kinematics and dynamics"
/// (universal-robots.com support article; also the CB3 manual's appendix, table "UR5 serie 3"):
/// d1 = 0.089159, a2 = −0.425, a3 = −0.39225, d4 = 0.10915, d5 = 0.09465, d6 = 0.0823 m;
/// α = (π/2, 0, 0, π/2, −π/2, 0); θ offsets 0. Frame 6 is the tool flange.
pub fn ur5(tool: Vector3<f64>) -> DhArm {
    DhArm::new(
        "ur5",
        Convention::Classic,
        vec![
            DhJoint::new(89.159, 0.0, FRAC_PI_2),
            DhJoint::new(0.0, -425.0, 0.0),
            DhJoint::new(0.0, -392.25, 0.0),
            DhJoint::new(109.15, 0.0, FRAC_PI_2),
            DhJoint::new(94.65, 0.0, -FRAC_PI_2),
            DhJoint::new(82.3, 0.0, 0.0),
        ],
        tool,
    )
}

/// Kinova Gen3 (7 DoF), classic D–H, with its base row and θ offsets.
///
/// Source: Kinova, "Kinova Gen3 Ultra lightweight robot — User Guide", table of classic D–H
/// parameters (p. 205 of the edition quoted in github.com/mattking-smith/Denavit-Hartenberg-
/// Kinematics, `scripts/KinovaGen3_DH.m`): a base row (α = π, d = 0) from the base frame to
/// frame 0, then for joints 1–7 α = π/2 (joint 7: π), a = 0,
/// d = −(0.1564 + 0.1284), −(0.0054 + 0.0064), −(0.2104 + 0.2104), −(0.0064 + 0.0064),
/// −(0.2084 + 0.1059), 0, −(0.1059 + 0.0615) m, and θ_i = q_i + π for joints 2–7.
///
/// The base row is a fixed `Rot_x(π)` and so becomes the base transform; it exercises the base
/// rotation, the θ offsets and a last twist (α_7 = π) of the conversion on a published arm.
pub fn kinova_gen3(tool: Vector3<f64>) -> DhArm {
    let row = |d: f64, alpha: f64, theta_offset: f64| DhJoint {
        theta_offset,
        d,
        a: 0.0,
        alpha,
    };
    let mut arm = DhArm::new(
        "kinova-gen3",
        Convention::Classic,
        vec![
            row(-(156.4 + 128.4), FRAC_PI_2, 0.0),
            row(-(5.4 + 6.4), FRAC_PI_2, PI),
            row(-(210.4 + 210.4), FRAC_PI_2, PI),
            row(-(6.4 + 6.4), FRAC_PI_2, PI),
            row(-(208.4 + 105.9), FRAC_PI_2, PI),
            row(0.0, FRAC_PI_2, PI),
            row(-(105.9 + 61.5), PI, PI),
        ],
        tool,
    );
    arm.base = super::rot_x(PI);
    arm
}

/// KUKA LBR iiwa 14 R820, modified D–H.
///
/// Source: M. Safeea, P. Neto, "KUKA Sunrise Toolbox" (github.com/Modi1987/KST-Kuka-Sunrise-
/// Toolbox, `constDhDataOf14R820.m`, from KUKA's media-flange manual):
/// α_{i-1} = (0, −π/2, π/2, π/2, −π/2, −π/2, π/2), d = (0.36, 0, 0.42, 0, 0.4, 0, 0.126) m,
/// a = 0. d_7 reaches the flange (media flange "Touch" excluded).
pub fn iiwa14(tool: Vector3<f64>) -> DhArm {
    let h = FRAC_PI_2;
    DhArm::new(
        "kuka-iiwa14",
        Convention::Modified,
        vec![
            DhJoint::new(360.0, 0.0, 0.0),
            DhJoint::new(0.0, 0.0, -h),
            DhJoint::new(420.0, 0.0, h),
            DhJoint::new(0.0, 0.0, h),
            DhJoint::new(400.0, 0.0, -h),
            DhJoint::new(0.0, 0.0, -h),
            DhJoint::new(126.0, 0.0, h),
        ],
        tool,
    )
}

/// Franka Emika Panda, modified D–H, with its flange row folded into the tool.
///
/// Source: Franka Emika, "Robot and interface specifications — Denavit–Hartenberg parameters"
/// (frankaemika.github.io/docs/control_parameters.html): a_{i-1} = (0, 0, 0, 0.0825, −0.0825,
/// 0, 0.088) m, d = (0.333, 0, 0.316, 0, 0.384, 0, 0) m,
/// α_{i-1} = (0, −π/2, π/2, π/2, −π/2, π/2, π/2), and a flange row (a = 0, d = 0.107 m, α = 0)
/// after joint 7. The flange row has no twist, so the tool vector in joint 7's frame is
/// (0, 0, 107) mm + `tool`.
pub fn panda(tool: Vector3<f64>) -> DhArm {
    let h = FRAC_PI_2;
    DhArm::new(
        "franka-panda",
        Convention::Modified,
        vec![
            DhJoint::new(333.0, 0.0, 0.0),
            DhJoint::new(0.0, 0.0, -h),
            DhJoint::new(316.0, 0.0, h),
            DhJoint::new(0.0, 82.5, h),
            DhJoint::new(384.0, -82.5, -h),
            DhJoint::new(0.0, 0.0, h),
            DhJoint::new(0.0, 88.0, h),
        ],
        Vector3::new(0.0, 0.0, PANDA_FLANGE_MM) + tool,
    )
}

/// The Panda's flange offset along joint 7's axis (mm).
pub const PANDA_FLANGE_MM: f64 = 107.0;
