//! A fitted calibration ([`Fit`]) made from the accepted pass: the data's own singular values
//! (without what a ridge shares out), the standard uncertainties, correlations and covariance
//! of what was kept, the calibrated arm and its instrument frame.

use crate::fit::ident::{self, Identifiability};
use crate::fit::lm;
use crate::fit::priors::PriorConflict;
use crate::fit::problem::State;
use crate::fit::residuals::Rigid;
use crate::fit::structure::Structure;
use crate::params::Param;
use nalgebra::DMatrix;
use quatarm_ref::arm::{Arm, Frame};
use std::time::{Duration, Instant};

/// A fitted calibration.
#[derive(Clone, Debug)]
pub struct Fit {
    /// The arm the fit started from (with an entry for each fitted harmonic).
    pub start: Arm,
    /// The calibrated arm; its `reference_frame` is the instrument frame for `point` data.
    pub arm: Arm,
    /// Every unknown considered.
    pub params: Vec<Param>,
    /// The fitted increment of each (0 where held); frame entries are 0 (see `frame`).
    pub values: Vec<f64>,
    /// Standard uncertainty of each fitted unknown (`None` where held).
    pub uncertainty: Vec<Option<f64>>,
    /// What was fitted and what was held, and why.
    pub ident: Identifiability,
    /// The instrument frame, for `point` data.
    pub frame: Option<Rigid>,
    /// Residual standard deviation per equation (mm).
    pub sigma_mm: f64,
    /// Equations the data give.
    pub equations: usize,
    /// Solver iterations over all passes.
    pub iterations: usize,
    /// How the solver stopped.
    pub solver: lm::Termination,
    /// RMS of the equations before and after (mm).
    pub rms_before_mm: f64,
    /// RMS of the equations after (mm).
    pub rms_after_mm: f64,
    /// Time the fit took.
    pub elapsed: Duration,
    /// Correlation matrix of the fitted unknowns (kept order).
    pub correlation: DMatrix<f64>,
    /// σ̂² (JᵀJ)⁻¹ of the accepted pass, with the unknowns (indices into `params`) its rows
    /// are in: the frame's among them, so that a sub-block is the covariance of the arm's
    /// unknowns marginal over the frame (`spat` points are already eliminated by the
    /// variable projection, which is the same marginalisation). `None` when JᵀJ is singular.
    pub covariance: Option<(Vec<usize>, DMatrix<f64>)>,
    /// Per-unknown priors the data contradicted, dropped for this fit.
    pub prior_conflicts: Vec<PriorConflict>,
}

impl Fit {
    /// The fitted value of an identifiable combination: unknown `k` (kept) stands for itself
    /// plus coefficient × each held unknown it absorbs. Given the true increments of every
    /// unknown, returns what `values[k]` should equal.
    pub fn combination(&self, k: usize, truth: &dyn Fn(usize) -> f64) -> f64 {
        let mut v = truth(k);
        for f in &self.ident.fixed {
            for &(by, c) in &f.absorbed_by {
                if by == k {
                    v += c * truth(f.index);
                }
            }
        }
        v
    }

    /// The calibrated instrument frame as the file stores it.
    pub fn reference_frame(&self) -> Option<Frame> {
        self.frame
            .map(|f| crate::geometry::frame_from(&f.rot, &f.trans))
    }
}

/// The accepted pass.
pub(crate) struct Fitted {
    pub(crate) state: State,
    pub(crate) arm: Arm,
    pub(crate) jtj: DMatrix<f64>,
    pub(crate) sigma: f64,
    pub(crate) data_cost: f64,
    pub(crate) solver: lm::Termination,
}

/// The fit of the accepted model: the data's own singular values, the uncertainties and
/// correlations of what was kept, the calibrated arm and frame.
pub(crate) fn finish(
    s: Structure,
    f: Fitted,
    iterations: usize,
    rms_before: f64,
    t0: Instant,
) -> Fit {
    let Structure {
        layout,
        all,
        base,
        eqs,
        mut id,
        r_skel,
        mut shared,
        shared_fixed: _,
    } = s;
    // The rows of `f.jtj`: the kept unknowns of the accepted pass, before the reordering below.
    let jtj_order = id.kept.clone();
    // Singular values and condition number are the data's own: of the unknowns they
    // determine, without those the ridge shares out.
    shared.retain(|i| id.kept.contains(i));
    id.kept.retain(|i| !shared.contains(i));
    ident::refresh(&r_skel, &mut id);
    id.kept.extend(&shared);
    id.kept.sort_unstable();
    let cov = ident::covariance(&f.jtj, f.sigma);
    let mut uncertainty = vec![None; all.len()];
    let k = id.kept.len();
    let mut correlation = DMatrix::identity(k, k);
    if let Some(c) = &cov {
        for (pos, &i) in id.kept.iter().enumerate() {
            uncertainty[i] = Some(c[(pos, pos)].sqrt());
        }
        for a in 0..k {
            for b in 0..k {
                correlation[(a, b)] = c[(a, b)] / (c[(a, a)] * c[(b, b)]).sqrt();
            }
        }
    }
    let mut arm = f.arm;
    let frame = (!layout.points.is_empty()).then_some(f.state.frame);
    arm.reference_frame = frame.map(|f| crate::geometry::frame_from(&f.rot, &f.trans));
    let mut values = f.state.x.clone();
    for (i, p) in all.iter().enumerate() {
        if p.is_frame() {
            values[i] = 0.0;
        }
    }
    Fit {
        start: base,
        arm,
        params: all,
        values,
        uncertainty,
        ident: id,
        frame,
        sigma_mm: f.sigma,
        equations: eqs,
        iterations,
        solver: f.solver,
        rms_before_mm: rms_before,
        rms_after_mm: (2.0 * f.data_cost / eqs as f64).sqrt(),
        elapsed: t0.elapsed(),
        correlation,
        covariance: cov.map(|c| (jtj_order, c)),
        prior_conflicts: Vec::new(),
    }
}
