//! What every quatarm board shares, so that a board's `main.rs` is only its hardware.
//!
//! - [`calibration`]: the table validated at boot and the chain built from it.
//! - [`clock`]: microseconds since boot from SysTick.
//! - [`table_region`]: the calibration table's flash region, as `memory.x` reserves it.
//! - [`serve`]: the replay loop: bytes in, [`quatarm::stream::Hub`] reports out.
//! - [`qemu`] (feature `qemu`): exit codes through semihosting, and the panic handler.
#![no_std]
#![deny(missing_docs)]

pub mod calibration;
pub mod clock;
#[cfg(feature = "qemu")]
pub mod qemu;
mod serve;
pub mod table_region;

pub use serve::{serve, Link, Served};
