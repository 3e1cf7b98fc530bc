//! The settings of a calibration ([`Options`]): what to fit, the solver's budget, the
//! structure checks' tolerances, what pulls the fit besides the data, and the pruning policy.
//! Plain data with the defaults `armcal calibrate` uses; read by every other file of the fit.

use crate::fit::lm;
use crate::fit::priors::{Prior, Ridge};
use crate::params::{Param, Terms};

/// Settings of a calibration.
#[derive(Clone, Debug)]
pub struct Options {
    /// What to fit.
    pub terms: Terms,
    /// Solver settings.
    pub lm: lm::Options,
    /// Singular values below this fraction of the largest (unit-norm columns) are
    /// dependencies.
    pub structural_tol: f64,
    /// Apply the statistical identifiability test after the fit.
    pub weak_check: bool,
    /// A direction is held when its standard uncertainty exceeds this fraction of the
    /// plausible sizes of its unknowns ([`plausible`](crate::params::ParamExt::plausible)).
    pub weak_threshold: f64,
    /// Compare identifiability with a well-spread design (degenerate pose sets, equation
    /// count). Off, the data's own rank is trusted.
    pub design_check: bool,
    /// Proceed on a degenerate pose set, holding what it cannot determine (instead of an
    /// error).
    pub allow_degenerate: bool,
    /// A Gaussian prior on the geometric errors (`None`: plain least squares).
    pub prior: Option<Prior>,
    /// Unknowns to hold at their start values whatever the data say.
    pub hold: Vec<Param>,
    /// Backward elimination of extended effects: while some fitted effect is not significant
    /// at this many standard uncertainties (a harmonic's sin and cos tested together, at the
    /// same tail probability), hold the least significant one and refit. 0: keep every effect
    /// requested. Geometric unknowns are never eliminated this way.
    pub significance: f64,
    /// A ridge penalty on the geometric errors (MUKCa's regulariser); with it, unknowns the
    /// data cannot separate stay fitted and the penalty shares their effect out among them.
    pub ridge: Option<Ridge>,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            terms: Terms::geometric(),
            lm: lm::Options::default(),
            structural_tol: 1e-8,
            weak_check: true,
            weak_threshold: 1.0,
            design_check: true,
            allow_degenerate: false,
            prior: None,
            hold: Vec::new(),
            significance: 0.0,
            ridge: None,
        }
    }
}
