//! The calibration flash of a board: where `memory.x` puts the two table slots and the two
//! copies of the update's state record ([`slots`]), and the flash drivers the QEMU boards
//! update them through ([`ram_nor`] for mps2's code RAM, [`nvmc`] for the nRF51's NVMC).
//!
//! Every driver implements `embedded-storage`'s `NorFlash`, the trait `quatarm::update` is
//! written against and every embassy / `*-hal` flash driver implements, so a real board
//! passes its HAL's driver (stm32f4xx-hal's `LockedFlash`, rp2040-flash) unchanged.

pub mod nvmc;
pub mod ram_nor;
pub mod slots;

pub use slots::{boot, Boot};
