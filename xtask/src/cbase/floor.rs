//! The counted floor of the lean forward chain: its floating-point operations a point,
//! counted from the form's structure (`bench/c/chain_lean.c` and `bench/c/turn.h`, step by
//! step below), one instruction an operation and a multiply–add as one (the Cortex-M4F's
//! `vmla`/`vfma`), plus the fewest loads and integer instructions the form needs. A floor for
//! this form, not for every evaluation of the model.

use quatarm_ref::arm::Arm;

/// Floating-point operations of each step.
mod ops {
    /// The remainder as a float and scaled to radians (convert, multiply), its square.
    pub const ANGLE: u32 = 3;
    /// sin: 3 multiply–adds of the Horner form in z, x·z, one last multiply–add.
    pub const SIN: u32 = 5;
    /// cos: 5 multiply–adds of the Horner form in z.
    pub const COS: u32 = 5;
    /// e = s (h0 + c h2 − s h3) + c (h1 + c h3): 3 multiply–adds, a multiply, a multiply–add.
    pub const HARMONIC: u32 = 5;
    /// (c, s) turned by e to second order: e·e, ·½, then 3 for each of c and s.
    pub const TURN_BY: u32 = 8;
    /// The vertical turned by Rx(−α) then Rz(−θ): 2 a component, 4 components.
    pub const VERTICAL: u32 = 8;
    /// The link with its expansion added to the sum: a multiply–add and an add a component.
    pub const LINK: u32 = 6;
    /// Rz(θ) and Rx(α) on the sum and on the direction: 2 a component, 2 components each.
    pub const TURNS: u32 = 16;
    /// The gravity deflection g (w × v)·z + e: a multiply, a multiply–subtract, a multiply–add.
    pub const DEFLECTION: u32 = 3;
    /// The base's Rz(a₁) on the sum and the direction.
    pub const BASE: u32 = 8;
    /// The temperature difference: convert, multiply.
    pub const DT: u32 = 2;
    /// Loads a joint: count, scale and offset (integers), 4 harmonic coefficients, link and
    /// rate (6), cos α and sin α.
    pub const LOADS: u32 = 14;
    /// Integer work a joint: scale, add the offset, the quadrant and the remainder, the range
    /// check and its branch.
    pub const INTEGER: u32 = 6;
    /// The six results stored.
    pub const STORES: u32 = 6;
}

/// The floor for `arm`: (floating-point operations, all instructions) a point.
pub fn lean_floor(arm: &Arm) -> (u32, u32) {
    let n = arm.dof() as u32;
    let harmonics = arm
        .joints
        .iter()
        .filter(|j| !j.harmonics.is_empty())
        .count() as u32;
    let compliant = arm.joints.iter().filter(|j| j.gravity != 0.0).count() as u32;
    // The vertical is carried up to the last compliant joint.
    let vertical = arm
        .joints
        .iter()
        .rposition(|j| j.gravity != 0.0)
        .map_or(0, |k| k as u32 + 1);
    let fp = ops::DT
        + n * (ops::ANGLE + ops::SIN + ops::COS + ops::LINK + ops::TURNS)
        + harmonics * (ops::HARMONIC + ops::TURN_BY)
        + vertical * ops::VERTICAL
        + compliant * (ops::DEFLECTION + ops::TURN_BY)
        + ops::BASE;
    (fp, fp + n * (ops::LOADS + ops::INTEGER) + ops::STORES)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped calibration: 6 joints, each with harmonics, gravity on joints 2, 4 and 6
    /// (the vertical carried through all six): 2 + 6·35 + 6·13 + 6·8 + 3·11 + 8.
    #[test]
    fn the_shipped_calibrations_floor() {
        let path = host_tests::boards::root().join("data/default-6-full.toml");
        let arm = quatarm_ref::calfile::read(&path).unwrap().arm;
        let (fp, all) = lean_floor(&arm);
        assert_eq!(fp, 2 + 6 * 35 + 6 * 13 + 6 * 8 + 3 * 11 + 8);
        assert_eq!(all, fp + 6 * 20 + 6);
        // A plain arm (no harmonics, no gravity): no vertical, no deflections.
        let (fp, _) = lean_floor(&quatarm_ref::arm::Arm::default6());
        assert_eq!(fp, 2 + 6 * 35 + 8);
    }
}
