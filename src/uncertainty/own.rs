//! The reading's own terms of Σ_p: the encoder, the temperature sensor, the probing and the
//! model, each Jacobian taken from the firmware's own chain by differences.
//!
//! - **Joints**: the chain at the reading with joint i stepped by k_i counts (≈ 1 mrad), less
//!   the point, is k_i counts of J_θ's column i; σ_θ is in counts already, so
//!   Σ += (σ_counts / k_i)² d dᵀ. A milliradian moves the tip by up to 1.5 mm: far above the
//!   chain's rounding (0.1 µm, 1e-4), far below where the chain bends (second-order terms
//!   ~5e-4 of the step).
//! - **Temperature**: the chain at T ± 10 °C (thermal expansion is linear in T).
//!
//! Every difference is of integer nanometres (`Point::xyz_nm`), so the f32 and the fixed-point
//! chain feed the same f32 arithmetic here.

use super::Covariance;
use crate::chain::{Chain, Evaluator};
use crate::model::{ChainError, Point};
use crate::table::{Table, FLAG_THERMAL, MAX_JOINTS};
use heapless::Vec;

/// One joint's reading term: the step k (counts), its joint's counts per revolution, and
/// (σ_counts / k)².
#[derive(Clone, Copy, Debug, Default)]
struct JointTerm {
    step: u32,
    counts: u32,
    weight: f32,
}

/// The temperature step of the thermal term (m°C).
const TEMPERATURE_STEP_MC: i32 = 10_000;
/// The joint step: about a milliradian, counts per revolution / 2π·1000.
const STEPS_PER_TURN: u32 = 6283;

/// What the hub needs to give every point the reading's own part of Σ_p: built once at
/// boot from the table's budget, the same for either evaluator's chain.
#[derive(Clone, Debug)]
pub struct OwnTerms {
    joints: Vec<JointTerm, MAX_JOINTS>,
    /// (σ_T / step)², where the table has thermal expansion.
    temperature: Option<f32>,
    /// σ_probe² + σ_model² (nm²).
    isotropic: f32,
}

impl OwnTerms {
    /// The budget of a validated table, `None` where the table has none. Its f64 arithmetic
    /// (soft-float on every target) runs once, at boot.
    pub fn new(table: &Table<'_>) -> Option<OwnTerms> {
        let budget = table.budget()?;
        let n = table.joint_count();
        let mut joints = Vec::new();
        for i in 0..n {
            let counts = table.joint(i).map_or(2, |j| j.counts);
            let step = (counts / STEPS_PER_TURN).max(1);
            let sigma = budget.encoder_counts(i) / f64::from(step);
            let _ = joints.push(JointTerm {
                step,
                counts,
                weight: (sigma * sigma) as f32,
            });
        }
        let thermal = table.flags() & FLAG_THERMAL != 0;
        let t = budget.temperature_c() * 1000.0 / f64::from(TEMPERATURE_STEP_MC);
        let temperature = (thermal && t > 0.0).then_some((t * t) as f32);
        let iso_mm2 =
            budget.probing_mm() * budget.probing_mm() + budget.model_mm() * budget.model_mm();
        Some(OwnTerms {
            joints,
            temperature,
            isotropic: (iso_mm2 * 1.0e12) as f32,
        })
    }

    /// The reading's own part of Σ_p (`counts`, `temp_mc`; `chain` gave `point` for it).
    pub fn covariance<P: Evaluator>(
        &self,
        chain: &Chain<P>,
        counts: &[u32],
        temp_mc: i32,
        point: &Point<P>,
    ) -> Result<Covariance, ChainError> {
        let p = point.xyz_nm();
        let diff = |q: Point<P>| {
            let q = q.xyz_nm();
            [0, 1, 2].map(|k| q[k].wrapping_sub(p[k]) as f32)
        };
        let iso = self.isotropic;
        let mut c = Covariance([iso, iso, iso, 0.0, 0.0, 0.0]);
        let mut stepped = [0u32; MAX_JOINTS];
        let n = counts.len().min(MAX_JOINTS);
        stepped[..n].copy_from_slice(&counts[..n]);
        for (i, j) in self.joints.iter().enumerate().take(n) {
            if j.weight == 0.0 {
                continue;
            }
            // c0 is below counts per revolution by the chain's check (the point was
            // evaluated) and the step is at most a sixth of a turn, so one subtraction wraps
            // it (no division: software on the Cortex-M0).
            let c0 = stepped[i];
            let s = c0 + j.step;
            stepped[i] = if s >= j.counts { s - j.counts } else { s };
            c.add_outer(diff(chain.eval(&stepped[..n], temp_mc)?), j.weight);
            stepped[i] = c0;
        }
        if let Some(w) = self.temperature {
            let up = chain.eval(counts, temp_mc.saturating_add(TEMPERATURE_STEP_MC));
            let q = match up {
                Err(ChainError::Temperature) => {
                    chain.eval(counts, temp_mc.saturating_sub(TEMPERATURE_STEP_MC))?
                }
                other => other?,
            };
            c.add_outer(diff(q), w);
        }
        Ok(c)
    }
}
