//! The uncertainty of every point the hub streams (`spec/uncertainty.md`): Σ_p and U95.
//!
//! Σ_p = J_π C J_πᵀ + J_θ diag(σ_θ²) J_θᵀ + J_T σ_T² J_Tᵀ + (σ_probe² + σ_model²) I₃, in two
//! parts from the table: the reading's own terms ([`own`], from the budget) and the
//! calibration's parameter part ([`parameters`], from the parameter block, with C's Cholesky
//! factor; widened at a reading of high leverage where the block has the budget's pose part,
//! [`pose`]). Both take their Jacobian columns analytically from one pass of the matrix chain
//! that keeps its frames ([`MatrixChain::eval_frames`]): the joints' axes and origins, cos θ
//! and sin θ of the readings, the links' expansion. [`radius::u95`] gives the radius of the
//! 95 % sphere.
//!
//! Measured against the host's first order (`cargo test -p armcal --test hub_u95 --
//! --nocapture`), and its cost on qemu-m4f (`cargo xtask bench-target`): the numbers are in
//! `docs/results/speed.md`.

#[cfg(feature = "fixed-u95")]
pub mod fixed_product;
pub mod joints;
pub mod own;
pub mod parameters;
pub mod pose;
pub mod radius;

mod grid;

use crate::chain::Evaluator;
use crate::matrix::{Frames, MatrixChain};
use crate::model::ChainError;
use crate::table::Table;
use core::cell::RefCell;

pub use own::OwnTerms;
pub use parameters::ParameterPart;
pub use pose::PosePart;

/// Σ_p, in nm²: xx, yy, zz, xy, xz, yz (the order of `armcal eval --uncertainty`'s columns).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Covariance(pub [f32; 6]);

impl Covariance {
    /// Σ += other.
    fn add(&mut self, other: &Covariance) {
        for (s, x) in self.0.iter_mut().zip(other.0) {
            *s += x;
        }
    }

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
    /// The matrix chain whose frames give every column (mounted with the hub's probe).
    chain: MatrixChain<P>,
    own: OwnTerms,
    parameters: Option<ParameterPart<'a>>,
    /// The frames of the last reading, reused: `eval_frames` writes every joint of the
    /// table at each reading (and the expansion), the entries past them stay the zeros they
    /// start as. A fresh `Frames::default()` a point was a 404-byte `memset` call (with
    /// Debian's `core` a loop of 5 instructions a word; `docs/results/speed.md`).
    frames: RefCell<Frames>,
}

impl<'a, P: Evaluator> Uncertainty<'a, P> {
    /// The uncertainty of a validated table's points; `None` where the table has no budget
    /// (then the hub streams no U95).
    pub fn new(table: &Table<'a>) -> Result<Option<Uncertainty<'a, P>>, ChainError> {
        let mut out = None;
        Self::build_in(&mut out, table)?;
        Ok(out)
    }

    /// [`Uncertainty::new`] in place: `out` becomes the uncertainty of the table's points,
    /// `None` where the table has no budget and on an error. A hub builds it at boot straight
    /// into the place it runs from (4,104 bytes on the f32 hubs, most of it the matrix chain,
    /// built in place too: [`MatrixChain::build_in`]), as its chain ([`crate::Chain::build_in`]).
    pub fn build_in(
        out: &mut Option<Uncertainty<'a, P>>,
        table: &Table<'a>,
    ) -> Result<(), ChainError> {
        *out = None;
        let Some(own) = OwnTerms::new(table) else {
            return Ok(());
        };
        let u = out.insert(Uncertainty {
            chain: MatrixChain::default(),
            own,
            parameters: None,
            frames: RefCell::new(Frames::default()),
        });
        let built = match u.chain.build_in(table) {
            Ok(()) => ParameterPart::new(table).map(|p| u.parameters = p),
            Err(e) => Err(e),
        };
        if built.is_err() {
            *out = None;
        }
        built
    }

    /// Follows the hub's chain to the table's probe `k` (its index in the table): the frames'
    /// chain mounts it, and the parameter part takes that probe's columns. Nothing changes on
    /// an error.
    pub fn mount(&mut self, table: &Table<'a>, k: usize) -> Result<(), ChainError> {
        // The parameter part refuses only a `k` past the table's probes, which the chain
        // refuses too, with the same error: checked first, the chain mounts in place (its
        // model changes nothing on an error, `Model::mount`) and the part cannot fail after
        // it. (A copy of the chain to restore took 1,900 bytes of the f32 hubs' stack.)
        if self.parameters.is_some() && table.probe_id(k).is_none() {
            return Err(ChainError::Range { joint: 0 });
        }
        self.chain.mount(table, k)?;
        if let Some(part) = &mut self.parameters {
            part.mount(table, k)?;
        }
        Ok(())
    }

    /// Whether the calibration's parameter part is in (the table has a parameter block, and
    /// the `parameters` feature reads it).
    pub fn has_parameters(&self) -> bool {
        self.parameters.is_some()
    }

    /// Σ_p of a reading (`counts`, `temp_mc`): one pass of the matrix chain for the frames,
    /// then the columns. An error is the chain's (a reading it refuses).
    pub fn covariance(&self, counts: &[u32], temp_mc: i32) -> Result<Covariance, ChainError> {
        // Never borrowed elsewhere (nothing here re-enters); were it, a fresh one.
        let mut kept = self.frames.try_borrow_mut();
        let mut spare = None;
        let frames: &mut Frames = match kept.as_deref_mut() {
            Ok(f) => f,
            Err(_) => spare.insert(Frames::default()),
        };
        let tip = self.chain.eval_frames(counts, temp_mc, frames)?;
        let p = tip.xyz.map(P::l_to_f32);
        let mut sigma = self.own.covariance(frames, p);
        if let Some(part) = &self.parameters {
            part.add_to(frames, p, temp_mc, counts, &mut sigma);
        }
        Ok(sigma)
    }

    /// U95 of a reading, in whole nanometres (rounded up: never below the computed radius).
    pub fn u95_nm(&self, counts: &[u32], temp_mc: i32) -> Result<u32, ChainError> {
        let u = self.covariance(counts, temp_mc)?.u95_nm().max(0.0);
        // f32 → u32 saturates; a U95 beyond 4.29 m is not a measurement anyway.
        Ok(micromath::F32Ext::ceil(u) as u32)
    }
}
