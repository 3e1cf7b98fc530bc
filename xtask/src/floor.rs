//! The counted floors of the lean forward chain: one instruction an operation, counted from
//! each form's structure. Two forms, two counts:
//!
//! - [`c_lean`]: the C baseline's form (`bench/c/chain_lean.c`, `bench/c/turn.h`), a
//!   multiply–add as one (the Cortex-M4F's `vfma`, which gcc fuses by default), the whole
//!   cosine and sine of each angle;
//! - [`product_lean`]: the product's form (`src/lean.rs`), no fused multiply–add (the host's
//!   f32 results are the hub's bit for bit), each turn an exact quarter turn plus a small
//!   correction, the first pass's records stored and read back.
//!
//! A floor for each form, not for every evaluation of the model.

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

/// The C form's floor for `arm`: (floating-point operations, all instructions) a point.
pub fn c_lean(arm: &Arm) -> (u32, u32) {
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

/// The lean chain's operations a point, counted from its source (`src/lean.rs`): what the
/// hub's chain would take with no register moves, selections or tests.
#[derive(Debug, PartialEq, Eq)]
pub struct Floor {
    /// Floating-point instructions, a multiply-add (`vmla`) as one.
    pub fp: u32,
    /// Loads and stores: the joints' constants, the count, the first pass's records.
    pub memory: u32,
    /// Integer instructions: the count's range check, binary angle, quadrant and remainder.
    pub integer: u32,
}

/// [`Floor`] of the product's form for `arm` (the power-of-two scales of the hub's encoders).
/// Per joint, first pass: the remainder r to f32 in radians and its square (2 + 1), sin r
/// (4: two multiply–adds of the Horner form, r·r², the last multiply–add) and 1 − cos r (4:
/// three multiply–adds, the product by r²), cos r (1), the harmonic error (5), the vertical
/// turned by Rx and Rz (4 + 4; 2 for the first joint, whose vertical is ẑ); second pass (the
/// remainder's turn by e in the first pass for a joint without gravity: the same count): the
/// link at temperature added (6; 3 for the tip's), the turn by e (10), Rz on the tip and the
/// direction (6 + 4), Rx on both (6 + 4), gravity's deflection (3 where compliant). Per point:
/// the temperature (1), the base's Rz (6 + 4).
pub fn product_lean(arm: &Arm) -> Floor {
    let compliant = arm.joints.iter().filter(|j| j.gravity != 0.0).count() as u32;
    product_counts(arm.dof() as u32, compliant)
}

/// [`product_lean`] for `joints` joints, `compliant` of them with gravity.
fn product_counts(joints: u32, compliant: u32) -> Floor {
    let first = 2 + 1 + 4 + 4 + 1 + 5 + 8;
    let second = 6 + 10 + 6 + 4 + 6 + 4;
    let fp = joints * (first + second) + 3 * compliant + 1 + 10 - (8 - 2) - 3;
    // Count, its limit, the unit, the offset, 4 harmonic coefficients and cos α, sin α (10);
    // the record (q, sin r, 1 − cos r; e as well where compliant) and the vertical (2) stored
    // and read back (10, 2 more where compliant); the link and its rate (6), Rx's sin and
    // 1 − cos (2), cos α and sin α again (2); gravity and the vertical (3 where compliant).
    // The base turn's 3 and the probe direction's 3, the point's 6 stores.
    let memory = joints * (10 + 10 + 10) + (2 + 3) * compliant + 12;
    // Range check (2), multiply, offset, quadrant (add, and, subtract, shift), to f32 (1).
    let integer = joints * 9;
    Floor {
        fp,
        memory,
        integer,
    }
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
        let (fp, all) = c_lean(&arm);
        assert_eq!(fp, 2 + 6 * 35 + 6 * 13 + 6 * 8 + 3 * 11 + 8);
        assert_eq!(all, fp + 6 * 20 + 6);
        // A plain arm (no harmonics, no gravity): no vertical, no deflections.
        let (fp, _) = c_lean(&quatarm_ref::arm::Arm::default6());
        assert_eq!(fp, 2 + 6 * 35 + 8);
    }

    /// The hub's arm (6 joints, 3 compliant): the counts the docs quote.
    #[test]
    fn the_lean_floor_of_the_hub_arm() {
        let f = product_counts(6, 3);
        assert_eq!((f.fp, f.memory, f.integer), (377, 207, 54));
        // Each joint and each compliant joint adds its share.
        assert_eq!(product_counts(7, 3).fp - f.fp, 61);
        assert_eq!(product_counts(6, 4).fp - f.fp, 3);
    }
}
