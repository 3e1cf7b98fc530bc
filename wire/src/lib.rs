//! The host side of the two formats the hub shares with the host: the binary calibration
//! table it boots from ([`tablebuild`]: an arm in, the bytes `quatarm::table` reads out) and
//! the UART stream it writes ([`stream_decode`]: bytes in, `Hello`s, reports and counted
//! damage out); and signing a table with the arm maker's key ([`tablesign`]).
//!
//! `armcal` re-exports both (`armcal table build`, `armcal decode`); `cargo xtask demo` and the
//! QEMU tests use them directly, so a first run compiles the firmware's formats and the f64
//! reference, not the host tool's solver, plots or benchmarks.
//!
//! ```
//! use quatarm_wire::{stream_decode::Decoder, tablebuild};
//! let text = include_str!("../../data/default-6.toml");
//! let arm = quatarm_ref::calfile::parse(text).expect("the shipped nominal arm").arm;
//! let bytes = tablebuild::build(&arm).expect("a nominal arm fits a table");
//! assert!(quatarm::table::Table::parse(&bytes).is_ok());
//! // A frame delimiter alone is no frame: nothing decoded, nothing counted as damage.
//! let mut decoder = Decoder::from_start();
//! assert!(decoder.push(0).is_none());
//! assert_eq!(decoder.stats().damaged(), 0);
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod budget;
pub mod stream_decode;
pub mod tablebuild;
pub mod tablesign;
