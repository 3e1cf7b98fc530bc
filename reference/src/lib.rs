//! f64 reference of the quatarm arm model (`spec/arm-model.md`).
//!
//! This crate is the yardstick the firmware chains are measured against, so it is written
//! apart from them on purpose: it shares no code with `quatarm`, works in f64 with `nalgebra`
//! rotation matrices instead of quaternions, and evaluates gravity compliance exactly (the
//! chain re-evaluated with the deflected angles) rather than to first order.
//!
//! - [`arm`]: the arm description (nominal geometry, the 39 geometric parameters, the extended
//!   effects), as the calibration file holds it.
//! - [`calfile`]: reading and writing the calibration file (`spec/calibration-file.md`).
//! - [`forward`]: forward kinematics, base frame, from joint angles and a temperature.
//! - [`dh`]: the classic formulation (Sładek et al.): Denavit–Hartenberg arms with 4×4
//!   matrices, published robot tables, and their conversion into the spec's model.
//! - [`uncertainty`]: the calibration file's `[uncertainty]` budget (`spec/uncertainty.md`).
//! - [`orientation`]: axis–angle of a rotation matrix and the probe-direction error (eq. 22).
#![deny(missing_docs)]

pub mod arm;
pub mod calfile;
pub mod dh;
pub mod forward;
pub mod orientation;
pub mod uncertainty;

pub use arm::{Arm, Axis, Frame, Harmonic, Joint, Probe};
pub use forward::Pose;
