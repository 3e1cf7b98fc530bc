//! Calibration: from measured data to an arm's fitted unknowns and what the data could not
//! determine.
//!
//! [`calib`] is the loop of a calibration, each of its steps a file: the settings
//! ([`options`]); what the data can fix before any fit ([`structure`], which compares the data
//! with a well-spread [`design`] of the same kinds); the least-squares [`problem`], solved by
//! Levenberg–Marquardt ([`lm`]) on the Jacobian of the model's unknowns ([`jacobian`]) and
//! analysed for identifiability ([`ident`]); what pulls the fit besides the data ([`priors`]);
//! the pruning policy between passes ([`prune`]); the fitted result ([`finish`]); and the
//! refusals ([`error`]). [`residuals`] are what the fit leaves, [`holdout`] what it leaves on
//! rows it did not see, [`probes`] how several probes share one arm, [`fleet_prior`] the prior
//! a fleet of arms gives, and [`report`] the calibration's report in words and JSON. This
//! layer stands on the model (`params`, `effects`), the data and the leaf modules only; the
//! uncertainty, the diagnosis, the acceptance tests and the simulation stand on it (the
//! simulation builds on the design's pose and group generators).

pub mod calib;
pub mod design;
pub mod error;
pub mod finish;
pub mod fleet_prior;
pub mod holdout;
pub mod ident;
pub mod jacobian;
pub mod lm;
pub mod options;
pub mod priors;
pub mod probes;
pub mod problem;
pub mod prune;
pub mod report;
pub mod residuals;
pub mod structure;
