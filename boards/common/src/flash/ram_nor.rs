//! A NOR flash over RAM, for QEMU's mps2 boards, whose "flash" at address 0 is RAM: erase
//! sets whole erase units to 0xFF, a write can only clear bits (the stored byte becomes
//! `old & new`), and both check alignment and bounds as a real part's driver does (the
//! [`Window`] every board's driver shares). So the update code runs against the same rules on
//! the emulator as on a chip, instead of against a RAM that would forgive a write without an
//! erase.

use embedded_storage::nor_flash::NorFlashErrorKind;

use super::window::{Raw, Window};

/// `ERASE` bytes per erase unit over a region of RAM.
pub type RamNor<const ERASE: usize> = Window<Ram<ERASE>>;

/// RAM treated as NOR flash, 4-byte write units, `ERASE`-byte erase units.
pub struct Ram<const ERASE: usize>;

impl<const ERASE: usize> Raw for Ram<ERASE> {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = ERASE;

    fn erase(&mut self, from: usize, to: usize) -> Result<(), NorFlashErrorKind> {
        for a in from..to {
            // SAFETY: inside the window (checked by it), which this driver owns.
            unsafe { (a as *mut u8).write_volatile(0xff) };
        }
        Ok(())
    }

    fn program(&mut self, addr: usize, bytes: &[u8]) -> Result<(), NorFlashErrorKind> {
        for (i, &b) in bytes.iter().enumerate() {
            // SAFETY: inside the window (checked by it).
            unsafe {
                let p = (addr + i) as *mut u8;
                p.write_volatile(p.read_volatile() & b);
            }
        }
        Ok(())
    }
}
