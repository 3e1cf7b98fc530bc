//! armcal: the logic behind the host tool, shared with the tests.
//!
//! The `armcal` binary (`src/main.rs`, one file per subcommand in `src/commands/`) is a thin
//! layer over this library: calibrating an arm from measured data ([`fit`]), diagnosing what a residual pattern points to ([`diagnose`]),
//! simulating measurements ([`sim`]) and evaluating readings with the f64 reference or the
//! firmware's chains ([`eval`], [`accuracy`]). Building the firmware's binary table
//! ([`tablebuild`]) and decoding a hub's stream ([`stream_decode`]) are `quatarm-wire`'s,
//! re-exported here; sending a table to a hub over its UART is [`table_send`]. The arm model itself is `quatarm-ref`'s; the chains are `quatarm`'s.
//!
//! # Example
//!
//! A calibration file becomes the table a hub loads, and the firmware's chain evaluated from
//! that table agrees with the f64 reference on the same arm:
//!
//! ```
//! use quatarm::{Chain, Table, F32};
//! use quatarm_ref::forward::{forward, REFERENCE_TEMP_C};
//!
//! let file = r#"
//! name = "default-6"
//! encoder_counts = 1048576
//! [[joint]]
//! axis = "z"
//! link = [0.0, 0.0, 200.0]
//! [[joint]]
//! axis = "x"
//! link = [0.0, 0.0, 300.0]
//! [[joint]]
//! axis = "z"
//! link = [0.0, 0.0, 300.0]
//! [[joint]]
//! axis = "x"
//! link = [0.0, 0.0, 250.0]
//! [[joint]]
//! axis = "z"
//! link = [0.0, 0.0, 250.0]
//! [[joint]]
//! axis = "x"
//! link = [0.0, 0.0, 80.0]
//! [probe]
//! vector = [0.0, 0.0, 120.0]
//! "#;
//! let arm = quatarm_ref::calfile::parse(file)?.arm;
//! let bytes = armcal::tablebuild::build(&arm)?;
//! let chain = Chain::<F32>::new(&Table::parse(&bytes)?)?;
//!
//! // Joint 2 an eighth of a turn (2^17 of its 2^20 counts), at 20 °C.
//! let counts = [0, 1 << 17, 0, 0, 0, 0];
//! let point = chain.eval(&counts, 20_000)?;
//! let theta = counts.map(|c| f64::from(c) * std::f64::consts::TAU / f64::from(1u32 << 20));
//! let want = forward(&arm, &theta, REFERENCE_TEMP_C).p;
//! let got = point.xyz_f64();
//! let err_um = (0..3).map(|i| (got[i] - want[i]).powi(2)).sum::<f64>().sqrt() * 1e3;
//! assert!(err_um < 1.0, "{err_um} µm");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![deny(missing_docs)]

pub mod acceptance;
pub mod accuracy;
pub mod eval;
pub mod fit;
pub(crate) mod geometry;
/// The table builder and stream decoder live in `quatarm-wire`, which the QEMU tests and
/// `cargo xtask demo` use without the rest of the host tool.
pub use quatarm_wire::{stream_decode, tablebuild};
pub mod uncertainty;

pub mod data;
pub mod diagnose;
pub mod effects;
pub mod html;
pub mod kinds;
pub mod limits;
pub mod load;
pub mod mukca;
pub mod output;
pub mod params;
pub mod plausible;
pub mod progress;
pub mod rng;
pub mod sim;
pub mod stats;
pub mod table_send;
