//! The calibration flash's driver: sectors 6 and 7 (128 KiB each, the update's two slots with
//! the state record in their trailers) through stm32f4xx-hal 0.23's `UnlockedFlash`, as the
//! chip routine of `board_common`'s `Window`.
//!
//! Why not the HAL's `NorFlash` implementation directly: it spans the whole 512 KiB with an
//! `ERASE_SIZE` of 128 KiB over sectors of 16, 64 and 128 KiB (an erase from any offset
//! erases whatever sector holds it, unchecked), so a wrong offset could erase the firmware,
//! and its `read` indexes a slice and panics past the end. The window here holds only the two
//! 128 KiB sectors (offset 0 = sector 6), where its 128 KiB erase unit is the chip's; it
//! refuses anything below sector 6, where the firmware's sectors 0-5 end (`memory.x`).
//! Around each HAL call it also does what the HAL leaves out, as ST's own HAL does:
//! - clears the status register's error flags first: they stay set until cleared, and the
//!   HAL reads any as the failure of the operation it just started;
//! - resets the ART accelerator's instruction and data caches after (ST's
//!   `FLASH_FlushCaches`), so that no read returns a cached line of the bytes before.
//!
//! The write unit is 4 bytes (the HAL programs bytes, at ×8 parallelism, any supply
//! voltage): the record is then 24 bytes at the end of its slot, and a word is what the
//! power-loss test cuts (`quatarm::update` `power_loss`). A 128 KiB erase stalls every flash
//! access of the core until it ends: the update's `Begin` takes seconds
//! (`board_common::live`).

use board_common::flash::window::Raw;
use embedded_storage::nor_flash::{NorFlashError, NorFlashErrorKind};
use stm32f4xx_hal::flash::FlashExt;
use stm32f4xx_hal::pac::FLASH;

/// Where the flash is mapped, and the HAL's offset 0.
const FLASH_START: usize = 0x0800_0000;
/// Sector 6, the first sector after the firmware's (sectors 0-5, 256 KiB, `memory.x`): the
/// lowest address the driver erases or programs.
const SECTOR_6: usize = 0x0804_0000;
/// The end of the STM32F446RE's 512 KiB.
const FLASH_END: usize = 0x0808_0000;
/// A 128 KiB sector.
const SECTOR_LEN: usize = 128 * 1024;

/// The flash controller, for sectors 6 and 7 only.
pub struct Sectors {
    flash: FLASH,
}

impl Sectors {
    /// Takes the flash controller (the clock set-up has set its wait states already).
    pub fn new(flash: FLASH) -> Self {
        Sectors { flash }
    }

    /// Clears the error flags a previous operation may have left (write 1 to clear).
    fn clear_errors(&mut self) {
        self.flash.sr().write(|w| {
            w.operr().clear();
            w.wrperr().clear();
            w.pgaerr().clear();
            w.pgperr().clear();
            w.pgserr().clear();
            w.rderr().clear()
        });
    }

    /// Resets the instruction and data caches, each disabled while it is reset and enabled
    /// again if it was (RM0390, "Flash memory interface", as ST's `FLASH_FlushCaches`).
    fn flush_caches(&mut self) {
        let acr = self.flash.acr();
        if acr.read().icen().bit_is_set() {
            acr.modify(|_, w| w.icen().clear_bit());
            acr.modify(|_, w| w.icrst().set_bit());
            acr.modify(|_, w| w.icrst().clear_bit());
            acr.modify(|_, w| w.icen().set_bit());
        }
        if acr.read().dcen().bit_is_set() {
            acr.modify(|_, w| w.dcen().clear_bit());
            acr.modify(|_, w| w.dcrst().set_bit());
            acr.modify(|_, w| w.dcrst().clear_bit());
            acr.modify(|_, w| w.dcen().set_bit());
        }
    }
}

impl Raw for Sectors {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = SECTOR_LEN;

    fn erase(&mut self, from: usize, to: usize) -> Result<(), NorFlashErrorKind> {
        if from < SECTOR_6 || to > FLASH_END {
            return Err(NorFlashErrorKind::OutOfBounds);
        }
        for at in (from..to).step_by(SECTOR_LEN) {
            // Sectors 6, 7 from 0x0804_0000 on; `at` is sector-aligned (the window's
            // check, with its base on a sector boundary).
            let sector = (6 + (at - SECTOR_6) / SECTOR_LEN) as u8;
            self.clear_errors();
            let result = self.flash.unlocked().erase(sector);
            self.flush_caches();
            result.map_err(|e| e.kind())?;
        }
        Ok(())
    }

    fn program(&mut self, addr: usize, bytes: &[u8]) -> Result<(), NorFlashErrorKind> {
        if addr < SECTOR_6 || addr + bytes.len() > FLASH_END {
            return Err(NorFlashErrorKind::OutOfBounds);
        }
        self.clear_errors();
        let result = self
            .flash
            .unlocked()
            .program(addr - FLASH_START, bytes.iter());
        self.flush_caches();
        result.map_err(|e| e.kind())
    }
}
