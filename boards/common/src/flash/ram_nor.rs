//! A NOR flash over RAM, for QEMU's mps2 boards, whose "flash" at address 0 is RAM: erase
//! sets whole erase units to 0xFF, a write can only clear bits (the stored byte becomes
//! `old & new`), and both check alignment and bounds as a real part's driver does. So the
//! update code runs against the same rules on the emulator as on a chip, instead of against
//! a RAM that would forgive a write without an erase.

use embedded_storage::nor_flash::{
    check_erase, check_read, check_write, ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash,
};

/// `ERASE` bytes per erase unit over a region of RAM.
pub struct RamNor<const ERASE: usize> {
    base: *mut u8,
    len: usize,
}

impl<const ERASE: usize> RamNor<ERASE> {
    /// The region of `len` bytes at `base`.
    ///
    /// # Safety
    /// `base..base + len` must be RAM that nothing else reads or writes while the driver
    /// lives (on mps2: the calibration regions `memory.x` reserves, outside the image).
    pub unsafe fn new(base: usize, len: usize) -> Self {
        RamNor {
            base: base as *mut u8,
            len,
        }
    }
}

impl<const ERASE: usize> ErrorType for RamNor<ERASE> {
    type Error = NorFlashErrorKind;
}

impl<const ERASE: usize> ReadNorFlash for RamNor<ERASE> {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        check_read(self, offset, bytes.len())?;
        for (i, b) in bytes.iter_mut().enumerate() {
            // SAFETY: inside the region (checked above), which this driver owns.
            *b = unsafe { self.base.add(offset as usize + i).read_volatile() };
        }
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.len
    }
}

impl<const ERASE: usize> NorFlash for RamNor<ERASE> {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = ERASE;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        check_erase(self, from, to)?;
        for i in from..to {
            // SAFETY: inside the region (checked above).
            unsafe { self.base.add(i as usize).write_volatile(0xff) };
        }
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        check_write(self, offset, bytes.len())?;
        for (i, &b) in bytes.iter().enumerate() {
            // SAFETY: inside the region (checked above).
            unsafe {
                let p = self.base.add(offset as usize + i);
                p.write_volatile(p.read_volatile() & b);
            }
        }
        Ok(())
    }
}
