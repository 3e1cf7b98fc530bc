//! The reading's own terms of Σ_p: the encoder, the temperature sensor, the probing and the
//! model, each Jacobian column analytic, from the joints' frames the matrix chain composes
//! for the parameter part anyway ([`Frames`]).
//!
//! - **Joints**: ∂p/∂θ_i = a_i × (p − o_i), the turn of everything beyond joint i about its
//!   axis; σ_θ is in counts, 2π / counts per revolution a count, so
//!   Σ += (2π σ_counts / counts)² d dᵀ. What it leaves out: the harmonics' slope
//!   (1 + Σ h (a_h cos hθ − b_h sin hθ), ~1e-4 off 1 for a calibration's tens of µrad) and
//!   the gravity deflection's change with the pose (g·L ≈ 1e-5): both far below U95's 1e-3.
//! - **Temperature**: ∂p/∂T = Σ_i R_0i κ_i v_i ([`Frames::expansion`]): the links are linear
//!   in T.
//!
//! Before, each column was the hub's chain differenced (stepped by ~1 mrad, by 10 °C): seven
//! chains a point, 10,895 instructions on qemu-m4f; these columns cost a cross product each.

use super::Covariance;
use crate::matrix::{Frames, EXPANSION_STEP_MC};
use crate::rotate::{cross, Vec3};
use crate::scalar::F32;
use crate::table::{Table, FLAG_THERMAL, MAX_JOINTS};

/// mm² → nm².
const NM2_PER_MM2: f64 = 1.0e12;

/// What the hub needs to give every point the reading's own part of Σ_p: built once at
/// boot from the table's budget, the same for either evaluator's chain.
#[derive(Clone, Debug)]
pub struct OwnTerms {
    /// Joints in the table.
    n: usize,
    /// Per joint, (2π σ_counts / counts)² in nm² per mm² of the column (rad² · 10^12).
    joints: [f32; MAX_JOINTS],
    /// (σ_T / [`EXPANSION_STEP_MC`])² · 10^12, where the table has thermal expansion.
    temperature: Option<f32>,
    /// σ_probe² + σ_model² (nm²).
    isotropic: f32,
}

impl OwnTerms {
    /// The budget of a validated table, `None` where the table has none. Its f64 arithmetic
    /// (soft-float on every target) runs once, at boot.
    pub fn new(table: &Table<'_>) -> Option<OwnTerms> {
        let budget = table.budget()?;
        let n = table.joint_count().min(MAX_JOINTS);
        let mut joints = [0.0; MAX_JOINTS];
        for (i, w) in joints.iter_mut().enumerate().take(n) {
            let counts = table.joint(i).map_or(2, |j| j.counts).max(1);
            let sigma = budget.encoder_counts(i) * core::f64::consts::TAU / f64::from(counts);
            *w = (sigma * sigma * NM2_PER_MM2) as f32;
        }
        let thermal = table.flags() & FLAG_THERMAL != 0;
        let t = budget.temperature_c() * 1000.0 / f64::from(EXPANSION_STEP_MC);
        let temperature = (thermal && t > 0.0).then_some((t * t * NM2_PER_MM2) as f32);
        let iso_mm2 =
            budget.probing_mm() * budget.probing_mm() + budget.model_mm() * budget.model_mm();
        Some(OwnTerms {
            n,
            joints,
            temperature,
            isotropic: (iso_mm2 * NM2_PER_MM2) as f32,
        })
    }

    /// The reading's own part of Σ_p (nm²) at the frames of a reading whose tip is `p` (mm).
    pub fn covariance(&self, frames: &Frames, p: Vec3<f32>) -> Covariance {
        let iso = self.isotropic;
        let mut c = Covariance([iso, iso, iso, 0.0, 0.0, 0.0]);
        for i in 0..self.n {
            let w = self.joints[i];
            if w == 0.0 {
                continue;
            }
            let (r, o) = (&frames.rotation[i], &frames.origin[i]);
            let axis = [r[0][2], r[1][2], r[2][2]];
            let lever = [p[0] - o[0], p[1] - o[1], p[2] - o[2]];
            c.add_outer(cross::<F32>(&axis, &lever), w);
        }
        if let Some(w) = self.temperature {
            c.add_outer(frames.expansion, w);
        }
        c
    }
}
