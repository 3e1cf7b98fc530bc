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
//!
//! # Example
//!
//! The spec's nominal arm `default-6` stands straight up at θ = 0 (links of 200, 300, 300,
//! 250, 250 and 80 mm and a 120 mm probe, all along z). A quarter turn of joint 2, a hinge
//! about x, lays everything above its first link down along −y:
//!
//! ```
//! use std::f64::consts::FRAC_PI_2;
//! use quatarm_ref::forward::{forward, REFERENCE_TEMP_C};
//! use quatarm_ref::Arm;
//!
//! let arm = Arm::default6();
//! let up = forward(&arm, &[0.0; 6], REFERENCE_TEMP_C);
//! assert!((up.p - nalgebra::Vector3::new(0.0, 0.0, 1500.0)).norm() < 1e-9);
//!
//! let pose = forward(&arm, &[0.0, FRAC_PI_2, 0.0, 0.0, 0.0, 0.0], REFERENCE_TEMP_C);
//! assert!((pose.p - nalgebra::Vector3::new(0.0, -1300.0, 200.0)).norm() < 1e-9);
//! assert!((pose.n - nalgebra::Vector3::new(0.0, -1.0, 0.0)).norm() < 1e-12);
//! ```
#![deny(missing_docs)]

pub mod arm;
pub mod calfile;
pub mod dh;
pub mod forward;
pub mod orientation;
pub mod release;
pub mod uncertainty;

pub use arm::{Arm, Axis, Frame, Harmonic, Joint, Probe};
pub use forward::Pose;
