//! The calibration flash of a board: where `memory.x` puts the two table slots and the state
//! record's copies ([`slots`]), the boot and the update port through them ([`port`]), and the
//! drivers: [`window`], a `NorFlash` over memory-mapped flash that every board's driver is a
//! chip routine of (the NUCLEO's over stm32f4xx-hal's `UnlockedFlash`, the Pico's over the
//! RP2040's ROM routines, both in their board's crate), and [`ram_nor`], the mps2 board's over
//! its code RAM. The qemu-m0 hub has no update port: with the updater its image is 37,228
//! bytes, over its 32 KiB budget.
//!
//! Every driver implements `embedded-storage`'s `NorFlash`, the trait `quatarm::update` is
//! written against and every embassy / `*-hal` flash driver implements.

pub mod port;
pub mod ram_nor;
pub mod slots;
pub mod window;

pub use port::Port;
pub use slots::{boot, Boot};
