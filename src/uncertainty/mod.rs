//! The uncertainty of every point the hub streams (`spec/uncertainty.md`): Σ_p and U95.
//!
//! Σ_p = J_π C J_πᵀ + J_θ diag(σ_θ²) J_θᵀ + J_T σ_T² J_Tᵀ + (σ_probe² + σ_model²) I₃, in two
//! parts from the table: the reading's own terms ([`own`], from the budget: the firmware's own
//! chain differenced), and the calibration's parameter part ([`parameters`], from the
//! parameter block: analytic columns on the matrix chain's frames, with C's Cholesky factor).
//! [`radius::u95`] gives the radius of the 95 % sphere.
//!
//! Measured against the host's first order (`cargo test -p armcal --test hub_u95 --
//! --nocapture`): the numbers are in the README, "The uncertainty of every point".

pub mod own;
pub mod parameters;
pub mod radius;

mod grid;

use crate::chain::{Chain, Evaluator};
use crate::model::{ChainError, Point};
use crate::table::Table;

pub use own::OwnTerms;
pub use parameters::ParameterPart;

/// Σ_p, in nm²: xx, yy, zz, xy, xz, yz (the order of `armcal eval --uncertainty`'s columns).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Covariance(pub [f32; 6]);

impl Covariance {
    /// Σ += w d dᵀ.
    fn add_outer(&mut self, d: [f32; 3], w: f32) {
        let c = &mut self.0;
        c[0] += w * d[0] * d[0];
        c[1] += w * d[1] * d[1];
        c[2] += w * d[2] * d[2];
        c[3] += w * d[0] * d[1];
        c[4] += w * d[0] * d[2];
        c[5] += w * d[1] * d[2];
    }

    /// U95 (nm): the radius of the sphere about the point that holds the true point with
    /// 95 % probability.
    pub fn u95_nm(&self) -> f32 {
        radius::u95(self)
    }
}

/// Everything a hub needs for a point's Σ_p, built once at boot from a table with a budget;
/// it borrows the table's parameter block.
#[derive(Clone, Debug)]
pub struct Uncertainty<'a, P: Evaluator> {
    own: OwnTerms,
    parameters: Option<ParameterPart<'a, P>>,
}

impl<'a, P: Evaluator> Uncertainty<'a, P> {
    /// The uncertainty of a validated table's points; `None` where the table has no budget
    /// (then the hub streams no U95).
    pub fn new(table: &Table<'a>) -> Result<Option<Uncertainty<'a, P>>, ChainError> {
        let Some(own) = OwnTerms::new(table) else {
            return Ok(None);
        };
        Ok(Some(Uncertainty {
            own,
            parameters: ParameterPart::new(table)?,
        }))
    }

    /// Follows the hub's chain to the table's probe `k` (its index in the table): the
    /// reading's own terms take the chain they are given, the parameter part its own matrix
    /// chain and the probe's columns. Nothing changes on an error.
    pub fn mount(&mut self, table: &Table<'a>, k: usize) -> Result<(), ChainError> {
        match &mut self.parameters {
            Some(part) => part.mount(table, k),
            None => Ok(()),
        }
    }

    /// Whether the calibration's parameter part is in (the table has a parameter block, and
    /// the `parameters` feature reads it).
    pub fn has_parameters(&self) -> bool {
        self.parameters.is_some()
    }

    /// Σ_p of a reading (`counts`, `temp_mc`) whose point `chain` gave.
    pub fn covariance(
        &self,
        chain: &Chain<P>,
        counts: &[u32],
        temp_mc: i32,
        point: &Point<P>,
    ) -> Result<Covariance, ChainError> {
        let mut sigma = self.own.covariance(chain, counts, temp_mc, point)?;
        if let Some(part) = &self.parameters {
            part.add_to(counts, temp_mc, &mut sigma)?;
        }
        Ok(sigma)
    }

    /// U95 of a reading, in whole nanometres (rounded up: never below the computed radius).
    pub fn u95_nm(
        &self,
        chain: &Chain<P>,
        counts: &[u32],
        temp_mc: i32,
        point: &Point<P>,
    ) -> Result<u32, ChainError> {
        let u = self
            .covariance(chain, counts, temp_mc, point)?
            .u95_nm()
            .max(0.0);
        // f32 → u32 saturates; a U95 beyond 4.29 m is not a measurement anyway.
        Ok(micromath::F32Ext::ceil(u) as u32)
    }
}
