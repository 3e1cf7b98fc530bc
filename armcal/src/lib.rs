//! armcal: the logic behind the host tool, shared with the tests.
//!
//! Modules are added by the work that needs them; each has one job.

pub mod accuracy;
pub mod eval;
pub mod stream_decode;
pub mod tablebuild;
pub mod uncertainty;

pub mod calib;
pub mod data;
pub mod diagnose;
pub mod effects;
pub mod holdout;
pub mod ident;
pub mod jacobian;
pub mod kinds;
pub mod limits;
pub mod lm;
pub mod load;
pub mod mukca;
pub mod output;
pub mod params;
pub mod progress;
pub mod report;
pub mod residuals;
pub mod sim;
pub mod stats;
