//! The joint leverage in the table (issue 27; `quatarm_ref::uncertainty::JointLeverage`, the
//! contract): what lets the hub widen the pose part at a joint configuration the calibration
//! did not see, whatever the tip's leverage.
//!
//! ℓJ = (θ − μ)ᵀ W (θ − μ), θ the reading's joint angles (rad, 2π · count / counts per
//! revolution, as the host's `Arm::counts_to_rad`), and the factor on the pose part becomes
//! max(1, ℓ, ℓJ) ([`crate::uncertainty::joints`]).
//!
//! It follows the pose part's D ([`super::pose`]) where bit 0 of the pose part's flags (its
//! second field, reserved and 0 before) is set. A hub from before it refuses such a table:
//! its length counts no joint part (`BadLength`), and a length made to agree would still fail
//! the reserved field. A table without it is byte for byte what it was. The Pico's profile
//! (`fixed-u95`) refuses the whole pose part by the parameter block's flag, this part with it.
//!
//! ```text
//! offset       size          field                 (little-endian, right after D)
//! ------       ----          ---------------------------------------------------
//!      0          2          joint count k (the table's own)
//!      2          2          reserved, 0
//!      4        4·k          μ, one angle a joint (f32 rad, |μ| ≤ MEAN_LIMIT)
//!  4+4·k   4·k(k+1)/2        W's upper triangle row by row: W00 W01 … W0(k−1) W11 …
//!                            (f32 1/rad², each within WEIGHT_LIMIT, the diagonal ≥ 0)
//! ```
//!
//! W is symmetric, so its upper triangle is all of it: 28 numbers for 7 joints instead of 49.
//! Whether W is positive semi-definite is checked where the host reads the budget; the hub
//! takes max(0, ℓJ), so a W that is not cannot lower the pose part below C.

use super::{rd_u16, rd_u32, Field, TableError, MAX_JOINTS, MIN_JOINTS};

/// Length of the part's head (k, reserved).
pub const HEAD_LEN: usize = 4;

/// The largest |μ| (rad): the host's `quatarm_ref::uncertainty::JOINT_MEAN_LIMIT`, a few
/// turns, so that a mean in degrees or counts is refused.
pub const MEAN_LIMIT: f32 = 64.0;

/// The largest |W_ij| (1/rad²): a joint whose calibration spread is 1 µrad (a sixth of one
/// count of a 2^20-count encoder). With |θ − μ| ≤ 2π + [`MEAN_LIMIT`] the 28 terms of ℓJ stay
/// below 1e18, far inside f32.
pub const WEIGHT_LIMIT: f32 = 1.0e12;

/// Entries of W's upper triangle for `k` joints.
pub const fn weight_len(k: usize) -> usize {
    k * (k + 1) / 2
}

/// Length of the part for `k` joints.
pub const fn len(k: usize) -> usize {
    HEAD_LEN + 4 * k + 4 * weight_len(k)
}

/// The length the part at `bytes` states (its k clamped to one past [`MAX_JOINTS`], which
/// the check refuses, so that no stated count overflows a length).
pub(super) fn stated_len(bytes: &[u8]) -> usize {
    len(usize::from(rd_u16(bytes, 0)).min(MAX_JOINTS + 1))
}

/// The part to write ([`super::pose::PoseData::joints`]).
#[derive(Clone, Copy, Debug)]
pub struct JointLeverageData<'a> {
    /// μ, one angle a joint (rad).
    pub mean: &'a [f32],
    /// W's upper triangle, row by row ([`weight_len`] entries).
    pub weight: &'a [f32],
}

impl JointLeverageData<'_> {
    /// The part's length; `None` if μ's length is not a joint count the table takes or W's
    /// is not its triangle's.
    pub fn part_len(&self) -> Option<usize> {
        let k = self.mean.len();
        ((MIN_JOINTS..=MAX_JOINTS).contains(&k) && self.weight.len() == weight_len(k))
            .then(|| len(k))
    }

    /// Writes the part into `out` (exactly [`Self::part_len`] bytes).
    pub(super) fn encode(&self, out: &mut [u8]) {
        out[0..2].copy_from_slice(&(self.mean.len() as u16).to_le_bytes());
        out[2..4].copy_from_slice(&0u16.to_le_bytes());
        let numbers = self.mean.iter().chain(self.weight);
        for (chunk, x) in out[HEAD_LEN..].chunks_exact_mut(4).zip(numbers) {
            chunk.copy_from_slice(&x.to_le_bytes());
        }
    }
}

/// A table's joint leverage, borrowing its bytes (length checked by the table).
#[derive(Clone, Copy, Debug)]
pub struct JointLeverage<'a> {
    bytes: &'a [u8],
}

fn rd_f32(b: &[u8], at: usize) -> Option<f32> {
    b.get(at..at + 4).map(|_| f32::from_bits(rd_u32(b, at)))
}

impl<'a> JointLeverage<'a> {
    pub(super) fn new(bytes: &'a [u8]) -> JointLeverage<'a> {
        JointLeverage { bytes }
    }

    /// k, the joints it has.
    pub fn count(&self) -> usize {
        usize::from(rd_u16(self.bytes, 0))
    }

    /// μ_i (rad); `None` past the last joint.
    pub fn mean(&self, i: usize) -> Option<f32> {
        if i >= self.count() {
            return None;
        }
        rd_f32(self.bytes, HEAD_LEN + 4 * i)
    }

    /// W_ij = W_ji (1/rad²); `None` past the last joint.
    pub fn weight(&self, i: usize, j: usize) -> Option<f32> {
        let k = self.count();
        let (i, j) = if i <= j { (i, j) } else { (j, i) };
        if j >= k {
            return None;
        }
        // Rows 0 … i − 1 of the upper triangle hold k + (k − 1) + … + (k − i + 1) entries.
        let at = i * k - i * i.saturating_sub(1) / 2 + (j - i);
        rd_f32(self.bytes, HEAD_LEN + 4 * k + 4 * at)
    }

    /// Everything well formed: k the table's `joints`, the reserved field 0, every μ finite
    /// within [`MEAN_LIMIT`], every W_ij finite within [`WEIGHT_LIMIT`] and W's diagonal ≥ 0.
    pub(super) fn check(&self, joints: usize) -> Result<(), TableError> {
        let bad = TableError::Invalid {
            joint: 0,
            field: Field::Budget,
        };
        let k = self.count();
        if k != joints || !(MIN_JOINTS..=MAX_JOINTS).contains(&k) || rd_u16(self.bytes, 2) != 0 {
            return Err(bad);
        }
        for i in 0..k {
            let m = self.mean(i).ok_or(bad)?;
            if !(m.is_finite() && m.abs() <= MEAN_LIMIT) {
                return Err(TableError::Invalid {
                    joint: i as u8 + 1,
                    field: Field::Budget,
                });
            }
            for j in i..k {
                let w = self.weight(i, j).ok_or(bad)?;
                if !(w.is_finite() && w.abs() <= WEIGHT_LIMIT) || (i == j && w < 0.0) {
                    return Err(TableError::Invalid {
                        joint: i as u8 + 1,
                        field: Field::Budget,
                    });
                }
            }
        }
        Ok(())
    }
}
