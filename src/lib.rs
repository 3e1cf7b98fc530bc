//! quatarm: the `no_std` quaternion kinematic chain of an articulated-arm CMM, its binary
//! calibration table and the UART stream between an encoder hub and a host.
//!
//! A hub reads one absolute encoder count per joint and the arm's temperature, and sends the
//! corrected position of the probe ball and the probe's direction. This crate is everything
//! between those two ends that does not touch a bus:
//!
//! - [`table`]: the calibration table, a flat binary layout (CRC-checked, every value range
//!   checked) that stays in its own flash region; a new calibration needs no firmware build.
//! - [`Chain`]: the calibrated arm as joint quaternions, evaluated per reading, generic over
//!   the number format: [`F32`] for cores with an FPU, [`Fixed`] (32-bit fixed point) for
//!   cores without. Encoder harmonics, gravity compliance and thermal expansion are part of
//!   the model ([`model`], [`physics`]). [`MatrixChain`] is the same model as 3×4 matrices,
//!   for comparison.
//! - [`uncertainty`]: every point's covariance and U95, from the budget the table carries.
//! - [`update`]: a new table written into the inactive one of two flash slots and made live by
//!   a state record, safe against a power cut at any moment.
//! - [`stream`]: the framed messages both ways (postcard, CRC-32, COBS), the hub's report
//!   logic, the decoder of its receive side and the hub's loop ([`stream::HubLoop`],
//!   [`stream::Live`]): bytes in, bytes to send out; a board only moves them.
//! - [`encoder::AbsoluteEncoder`] and [`temperature::TemperatureSensor`]: what a hub needs of
//!   its parts. The drivers for real parts are the crate `quatarm-drivers`, so that the chain
//!   alone does not pull in embedded-hal.
//!
//! Nothing here panics on input or allocates: bad bytes, readings or tables are error values
//! ([`TableError`], [`ChainError`], [`stream::FrameError`]) naming what is wrong.
//!
//! # Example
//!
//! A table for a nominal planar arm (every joint about its z axis, links of 100 mm along x,
//! a 50 mm probe along z), then one pose: joint 1 a quarter turn, the others at zero.
//!
//! ```
//! use quatarm::table::{quat_to_matrix, JointData, ProbeData, TableData, MAX_TABLE_LEN};
//! use quatarm::{Chain, Table, F32};
//!
//! let mut data = TableData { joint_count: 6, ..TableData::default() };
//! let identity = [1.0, 0.0, 0.0, 0.0];
//! for joint in &mut data.joints[..6] {
//!     *joint = JointData {
//!         axis: 2,
//!         counts: 1 << 14,
//!         rotation: identity,
//!         matrix: quat_to_matrix(&identity),
//!         link: [100.0, 0.0, 0.0],
//!         ..JointData::default()
//!     };
//! }
//! data.probe = ProbeData {
//!     vector: [0.0, 0.0, 50.0],
//!     direction: [0.0, 0.0, 1.0],
//!     ..ProbeData::default()
//! };
//! data.flags = data.content_flags();
//!
//! let mut bytes = [0u8; MAX_TABLE_LEN];
//! let len = data.encode(&mut bytes)?;
//! let table = Table::parse(&bytes[..len])?;
//! let chain = Chain::<F32>::new(&table)?;
//!
//! // Joint 1 at a quarter of its 2^14 counts, the arm at 20 °C (20,000 m°C): the whole arm,
//! // its first link included, turns to +y; the probe still points up.
//! let point = chain.eval(&[1 << 12, 0, 0, 0, 0, 0], 20_000)?;
//! let close = |got: [f64; 3], want: [f64; 3]| {
//!     got.iter().zip(want).all(|(g, w)| (g - w).abs() < 1e-6)
//! };
//! assert!(close(point.xyz_f64(), [0.0, 600.0, 50.0]), "{:?}", point.xyz_f64());
//! assert!(close(point.dir_f64(), [0.0, 0.0, 1.0]), "{:?}", point.dir_f64());
//! // What the stream carries: integer nanometres.
//! assert_eq!(point.xyz_nm(), [0, 600_000_000, 50_000_000]);
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]

// The mock flash of the update's fuzz target lives on the heap.
#[cfg(all(feature = "mock-flash", not(test)))]
extern crate std;

pub(crate) mod angle;
pub mod chain;
pub mod encoder;
pub mod lean;
pub mod lean_wobble;
pub mod matrix;
pub mod model;
pub mod physics;
pub(crate) mod rotate;
pub mod scalar;
pub mod signature;
pub mod stream;
pub mod table;
pub mod temperature;
pub mod uncertainty;
pub mod update;
pub mod wobble;

pub use chain::{Chain, ChainF32, ChainFixed, Evaluator};
pub use matrix::{MatrixChain, MatrixChainF32, MatrixChainFixed};
pub use model::{ChainError, Point};
pub use physics::Physics;
pub use scalar::{Arithmetic, Fixed, F32};
pub use table::{Table, TableError};
