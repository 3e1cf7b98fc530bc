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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flash::ram_nor::Ram;

    const UNIT: usize = 256;
    const GUARD: u8 = 0x5a;

    /// Runs `f` on a window of four erase units in the middle of a buffer whose first and
    /// last unit lie outside it; returns the whole buffer.
    fn with_window(f: impl FnOnce(&mut Window<Ram<UNIT>>)) -> [u8; 6 * UNIT] {
        let mut mem = [GUARD; 6 * UNIT];
        let base = mem.as_mut_ptr() as usize + UNIT;
        // SAFETY: the window lies inside `mem`, which nothing else touches while it lives.
        let mut w = unsafe { Window::new(Ram::<UNIT>, base, 4 * UNIT) };
        f(&mut w);
        mem
    }

    fn outside_untouched(mem: &[u8; 6 * UNIT]) -> bool {
        mem[..UNIT]
            .iter()
            .chain(&mem[5 * UNIT..])
            .all(|&b| b == GUARD)
    }

    #[test]
    fn erase_write_and_read_count_from_the_windows_start() {
        let mem = with_window(|w| {
            assert_eq!(w.capacity(), 4 * UNIT);
            w.erase(UNIT as u32, 2 * UNIT as u32).unwrap();
            w.write(UNIT as u32 + 8, &[0x0f, 0xf0, 0x12, 0x34]).unwrap();
            let mut got = [0u8; 6];
            w.read(UNIT as u32 + 6, &mut got).unwrap();
            assert_eq!(got, [0xff, 0xff, 0x0f, 0xf0, 0x12, 0x34]);
            // NOR: a write only clears bits.
            w.write(UNIT as u32 + 8, &[0xf0, 0xff, 0xff, 0x00]).unwrap();
            w.read(UNIT as u32 + 8, &mut got[..4]).unwrap();
            assert_eq!(got[..4], [0x00, 0xf0, 0x12, 0x00]);
        });
        // Offset UNIT of the window is unit 2 of the buffer: only it was erased.
        assert!(mem[2 * UNIT..3 * UNIT]
            .iter()
            .enumerate()
            .all(|(i, &b)| (8..12).contains(&i) || b == 0xff));
        assert!(mem[UNIT..2 * UNIT].iter().all(|&b| b == GUARD));
        assert!(mem[3 * UNIT..5 * UNIT].iter().all(|&b| b == GUARD));
        assert!(outside_untouched(&mem));
    }

    #[test]
    fn misaligned_or_outside_operations_are_refused_before_the_chip() {
        use NorFlashErrorKind::{NotAligned, OutOfBounds};
        let mem = with_window(|w| {
            let top = 4 * UNIT as u32;
            assert_eq!(w.erase(1, UNIT as u32), Err(NotAligned));
            assert_eq!(w.erase(0, UNIT as u32 + 4), Err(NotAligned));
            assert_eq!(
                w.erase(top - UNIT as u32, top + UNIT as u32),
                Err(OutOfBounds)
            );
            assert_eq!(w.write(2, &[0; 4]), Err(NotAligned));
            assert_eq!(w.write(0, &[0; 3]), Err(NotAligned));
            assert_eq!(w.write(top, &[0; 4]), Err(OutOfBounds));
            assert_eq!(w.write(top - 4, &[0; 8]), Err(OutOfBounds));
            assert_eq!(w.read(top - 1, &mut [0; 2]), Err(OutOfBounds));
        });
        // Nothing was written, inside the window or out.
        assert!(mem.iter().all(|&b| b == GUARD));
    }
}
