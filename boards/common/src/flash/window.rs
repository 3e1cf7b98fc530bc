//! A `NorFlash` over a window of memory-mapped flash (or, on QEMU's mps2, RAM): reads straight
//! from the memory map, erase and program by the chip's own routine ([`Raw`]). What every
//! board's driver would otherwise repeat is here once: offsets counted from the window's
//! start, alignment and bounds checked before the chip is touched (the HALs' routines check
//! neither: stm32f4xx-hal's erase takes whatever sector holds its `from`, and the RP2040's ROM
//! routines take any address), and nothing outside the window reachable, so a wrong layout
//! can never erase the firmware.

use embedded_storage::nor_flash::{
    check_erase, check_read, check_write, ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash,
};

/// A chip's erase and program, on absolute addresses that [`Window`] has checked: inside it,
/// `from`, `to` and `addr` aligned to the units, `bytes` whole write units.
pub trait Raw {
    /// Bytes of one program operation (and its alignment).
    const WRITE_SIZE: usize;
    /// Bytes of one erase unit (and its alignment).
    const ERASE_SIZE: usize;
    /// Erases the erase units from `from` to `to`.
    fn erase(&mut self, from: usize, to: usize) -> Result<(), NorFlashErrorKind>;
    /// Programs `bytes` at `addr`.
    fn program(&mut self, addr: usize, bytes: &[u8]) -> Result<(), NorFlashErrorKind>;
}

/// `len` bytes of flash from `base`, offset 0 at `base`.
pub struct Window<R: Raw> {
    raw: R,
    base: usize,
    len: usize,
}

impl<R: Raw> Window<R> {
    /// The window of `len` bytes at `base` (an erase-unit boundary: alignment is checked on
    /// offsets, so `base` must be aligned for it to mean the chip's).
    ///
    /// # Safety
    /// `base..base + len` must be memory-mapped flash that `raw` erases and programs (or RAM
    /// that it treats so), readable at those addresses whenever no operation of `raw` runs,
    /// and that nothing else writes while the window lives: outside the firmware image (the
    /// calibration regions `memory.x` reserves).
    pub unsafe fn new(raw: R, base: usize, len: usize) -> Self {
        Window { raw, base, len }
    }
}

impl<R: Raw> ErrorType for Window<R> {
    type Error = NorFlashErrorKind;
}

impl<R: Raw> ReadNorFlash for Window<R> {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        check_read(self, offset, bytes.len())?;
        let from = (self.base + offset as usize) as *const u8;
        for (i, b) in bytes.iter_mut().enumerate() {
            // SAFETY: inside the window (checked above), readable memory (`new`'s contract).
            // Volatile: the bytes change under the program's feet when `raw` writes them.
            *b = unsafe { from.add(i).read_volatile() };
        }
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.len
    }
}

impl<R: Raw> NorFlash for Window<R> {
    const WRITE_SIZE: usize = R::WRITE_SIZE;
    const ERASE_SIZE: usize = R::ERASE_SIZE;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        check_erase(self, from, to)?;
        self.raw
            .erase(self.base + from as usize, self.base + to as usize)
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        check_write(self, offset, bytes.len())?;
        self.raw.program(self.base + offset as usize, bytes)
    }
}
