//! Calibration: from measured data to an arm's fitted unknowns and what the data could not
//! determine.
//!
//! The problem and its options ([`calib`]) are solved by Levenberg–Marquardt ([`lm`]) on the
//! Jacobian of the model's unknowns ([`jacobian`]), after the structure checks of [`ident`];
//! [`residuals`] are what the fit leaves, [`holdout`] what it leaves on rows it did not see,
//! [`probes`] how several probes share one arm, [`fleet_prior`] the prior a fleet of arms
//! gives, and [`report`] the calibration's report in words and JSON. This layer stands on the
//! model (`params`, `effects`), the data and the leaf modules only; the uncertainty, the
//! diagnosis, the acceptance tests and the simulation stand on it.

pub mod calib;
pub mod error;
pub mod finish;
pub mod fleet_prior;
pub mod holdout;
pub mod ident;
pub mod jacobian;
pub mod lm;
pub mod options;
pub mod priors;
pub mod problem;
pub mod probes;
pub mod prune;
pub mod report;
pub mod residuals;
pub mod structure;
