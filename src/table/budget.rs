//! The uncertainty budget in the table (`spec/uncertainty.md`): the reading's own terms.
//!
//! What a point's Σ_p takes from the reading itself — the encoder's standard uncertainty per
//! joint, the probing, the model's unexplained part and the temperature sensor — is four
//! numbers and a vector, and the hub differentiates its own chain for their Jacobians
//! ([`crate::uncertainty`]). The calibration's parameter covariance follows it, behind its
//! own flag ([`super::parameters`]: why it is the exact factor of C and not a low-rank one).
//!
//! ```text
//! offset  size  field                                   (little-endian, after the probe)
//! ------  ----  ---------------------------------------------------------------
//!      0    56  encoder reading's standard uncertainty per joint (counts, f64 ×7;
//!               joints past N are 0)
//!     56     8  probing, per axis (mm, f64)
//!     64     8  model, per axis (mm, f64)
//!     72     8  temperature reading (°C, f64)
//! ```

use super::{rd_f64, Field, Table, TableError, MAX_JOINTS};

/// Length of the budget.
pub const LEN: usize = 80;

mod off {
    pub const ENCODER: usize = 0;
    pub const PROBING: usize = 56;
    pub const MODEL: usize = 64;
    pub const TEMPERATURE: usize = 72;
}

/// Limits of a budget's standard uncertainties.
pub mod limits {
    /// Encoder reading (counts).
    pub const ENCODER_COUNTS: f64 = 1.0e4;
    /// Probing and model, per axis (mm).
    pub const LENGTH_MM: f64 = 10.0;
    /// Temperature reading (°C).
    pub const TEMPERATURE_C: f64 = 50.0;
}

/// A budget to write ([`super::TableData::encode_with`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct BudgetData {
    /// Encoder reading's standard uncertainty per joint (counts).
    pub encoder_counts: [f64; MAX_JOINTS],
    /// Probing, per axis (mm).
    pub probing_mm: f64,
    /// Model, per axis (mm).
    pub model_mm: f64,
    /// Temperature reading (°C).
    pub temperature_c: f64,
}

impl BudgetData {
    /// Writes the budget into `out` (exactly [`LEN`] bytes).
    pub(super) fn encode(&self, out: &mut [u8]) {
        super::put_f64s(&mut out[off::ENCODER..], &self.encoder_counts);
        super::put_f64s(&mut out[off::PROBING..], &[self.probing_mm]);
        super::put_f64s(&mut out[off::MODEL..], &[self.model_mm]);
        super::put_f64s(&mut out[off::TEMPERATURE..], &[self.temperature_c]);
    }
}

/// A table's budget, borrowing its bytes.
#[derive(Clone, Copy, Debug)]
pub struct Budget<'a> {
    bytes: &'a [u8],
}

impl<'a> Budget<'a> {
    pub(super) fn new(bytes: &'a [u8]) -> Budget<'a> {
        Budget { bytes }
    }

    /// Encoder reading's standard uncertainty of joint `i` (counts; 0 past the last).
    pub fn encoder_counts(&self, i: usize) -> f64 {
        if i < MAX_JOINTS {
            rd_f64(self.bytes, off::ENCODER + 8 * i)
        } else {
            0.0
        }
    }

    /// Probing, per axis (mm).
    pub fn probing_mm(&self) -> f64 {
        rd_f64(self.bytes, off::PROBING)
    }

    /// Model, per axis (mm).
    pub fn model_mm(&self) -> f64 {
        rd_f64(self.bytes, off::MODEL)
    }

    /// Temperature reading (°C).
    pub fn temperature_c(&self) -> f64 {
        rd_f64(self.bytes, off::TEMPERATURE)
    }

    /// Everything, as plain values (what [`super::TableData::encode_with`] writes back).
    pub fn data(&self) -> BudgetData {
        BudgetData {
            encoder_counts: core::array::from_fn(|i| self.encoder_counts(i)),
            probing_mm: self.probing_mm(),
            model_mm: self.model_mm(),
            temperature_c: self.temperature_c(),
        }
    }

    /// Every value in range.
    pub(super) fn check(&self, main: &Table<'_>) -> Result<(), TableError> {
        let bad = |joint: usize| TableError::Invalid {
            joint: joint as u8,
            field: Field::Budget,
        };
        let n = main.joint_count();
        let sigma_ok = |x: f64, limit: f64| x.is_finite() && (0.0..=limit).contains(&x);
        for i in 0..MAX_JOINTS {
            let c = self.encoder_counts(i);
            let ok = if i < n {
                sigma_ok(c, limits::ENCODER_COUNTS)
            } else {
                c.to_bits() == 0
            };
            if !ok {
                return Err(bad(if i < n { i + 1 } else { 0 }));
            }
        }
        let ok = sigma_ok(self.probing_mm(), limits::LENGTH_MM)
            && sigma_ok(self.model_mm(), limits::LENGTH_MM)
            && sigma_ok(self.temperature_c(), limits::TEMPERATURE_C);
        if !ok {
            return Err(bad(0));
        }
        Ok(())
    }
}
