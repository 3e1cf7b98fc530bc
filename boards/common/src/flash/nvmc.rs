//! The nRF51's flash through its NVMC (non-volatile memory controller), as QEMU's `microbit`
//! models it and the chip has it: 1 KiB pages erased by `ERASEPAGE`, 32-bit words written
//! while `CONFIG` enables writes, each operation finished when `READY` reads 1. The flash is
//! memory-mapped from address 0, so reads are plain loads.
//!
//! The driver covers one span of the flash (the calibration regions), offsets from its start.

use embedded_storage::nor_flash::{
    check_erase, check_read, check_write, ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash,
};

const NVMC: usize = 0x4001_E000;
const READY: usize = NVMC + 0x400;
const CONFIG: usize = NVMC + 0x504;
const ERASEPAGE: usize = NVMC + 0x508;
const CONFIG_READ: u32 = 0;
const CONFIG_WRITE: u32 = 1;
const CONFIG_ERASE: u32 = 2;

/// The NVMC over the flash span `base..base + len`.
pub struct Nvmc {
    base: usize,
    len: usize,
}

impl Nvmc {
    /// The span of `len` bytes at flash address `base` (page-aligned).
    ///
    /// # Safety
    /// Nothing else may use the NVMC, and the span must hold no code or data of the image.
    pub unsafe fn new(base: usize, len: usize) -> Nvmc {
        Nvmc { base, len }
    }

    fn configure(mode: u32) {
        // SAFETY: the NVMC's CONFIG register, owned by this driver.
        unsafe { (CONFIG as *mut u32).write_volatile(mode) };
        Self::wait();
    }

    fn wait() {
        // SAFETY: reading READY has no side effect.
        while unsafe { (READY as *const u32).read_volatile() } & 1 == 0 {}
    }
}

impl ErrorType for Nvmc {
    type Error = NorFlashErrorKind;
}

impl ReadNorFlash for Nvmc {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        check_read(self, offset, bytes.len())?;
        for (i, b) in bytes.iter_mut().enumerate() {
            // SAFETY: inside the span (checked above), memory-mapped flash.
            *b = unsafe { ((self.base + offset as usize + i) as *const u8).read_volatile() };
        }
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.len
    }
}

impl NorFlash for Nvmc {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = 1024;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        check_erase(self, from, to)?;
        Self::configure(CONFIG_ERASE);
        for page in (from..to).step_by(Self::ERASE_SIZE) {
            // SAFETY: a page address inside the span; erase is enabled.
            unsafe { (ERASEPAGE as *mut u32).write_volatile((self.base + page as usize) as u32) };
            Self::wait();
        }
        Self::configure(CONFIG_READ);
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        check_write(self, offset, bytes.len())?;
        Self::configure(CONFIG_WRITE);
        for (i, w) in bytes.chunks_exact(4).enumerate() {
            let word = u32::from_le_bytes([w[0], w[1], w[2], w[3]]);
            let at = self.base + offset as usize + 4 * i;
            // SAFETY: a word-aligned address inside the span (checked above); writes enabled.
            unsafe { (at as *mut u32).write_volatile(word) };
            Self::wait();
        }
        Self::configure(CONFIG_READ);
        Ok(())
    }
}
