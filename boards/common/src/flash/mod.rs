//! The calibration flash of a board: where `memory.x` puts the two table slots and the two
//! copies of the update's state record ([`slots`]), and the flash driver the mps2 board
//! updates them through ([`ram_nor`], over its code RAM). The qemu-m0 hub has no update
//! port: with the updater its image is 37,228 bytes, over its 32 KiB budget.
//!
//! Every driver implements `embedded-storage`'s `NorFlash`, the trait `quatarm::update` is
//! written against and every embassy / `*-hal` flash driver implements, so a real board
//! passes its HAL's driver (stm32f4xx-hal's `LockedFlash`, rp2040-flash) unchanged.

pub mod ram_nor;
pub mod slots;

pub use slots::{boot, Boot};
