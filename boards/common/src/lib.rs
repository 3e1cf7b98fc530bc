//! What every quatarm board shares, so that a board's `main.rs` is only its hardware.
//!
//! - [`bench`]: instructions per point of the quaternion and matrix chains, on target.
//! - [`calibration`]: the table validated at boot and the chain built from it.
//! - [`stack`]: stack high-water mark by painting.
//! - [`clock`]: microseconds since boot from SysTick, whose handler it defines.
//! - [`flash`]: the two table slots and the update's state record, the boot and the update
//!   port through them, the `NorFlash` window every board's flash driver is built on, the
//!   QEMU boards' driver.
//! - [`table_region`]: the calibration table's flash region, as `memory.x` reserves it.
//! - [`maker_key`](mod@maker_key): the public key an image checks tables against (the test key on QEMU, the
//!   maker's on the real boards, [`maker_key!`]).
//! - [`live`]: a real hub's loop: its link's bytes into [`quatarm::stream::Live`] (encoders
//!   at a fixed period, replay when the host sends one, calibration updates) and its replies
//!   out.
//! - [`serve`]: the replay loop: bytes in, [`quatarm::stream::HubLoop`]'s replies out.
//! - [`qemu`] (feature `qemu`): the QEMU images' runs, exit codes through semihosting, the
//!   panic and fault handlers.
//! - `rtt` (feature `rtt`): the real boards' log transport and panic handler.
//!
//! Logs go through defmt, apart from the data stream: semihosting under QEMU (feature
//! `qemu`), RTT on real boards (feature `rtt`).
#![no_std]
#![deny(missing_docs)]

pub mod bench;
pub mod calibration;
pub mod clock;
pub mod flash;
pub mod live;
pub mod maker_key;
#[cfg(feature = "qemu")]
pub mod qemu;
#[cfg(feature = "rtt")]
mod rtt;
mod serve;
pub mod stack;
pub mod table_region;

pub use serve::{serve, Link, Served};

// The defmt transport under QEMU: a channel apart from the data stream.
#[cfg(feature = "qemu")]
use defmt_semihosting as _;
