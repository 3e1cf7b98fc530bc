//! armcal: the logic behind the host tool, shared with the tests.
//!
//! Modules are added by the work that needs them; each has one job.

pub mod accuracy;
pub mod stream_decode;
pub mod tablebuild;
pub mod eval;
