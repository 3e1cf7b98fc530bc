//! The calibration flash's driver: the Pico's QSPI flash (W25Q16JV, 4 KiB sectors, 256-byte
//! pages), erased and programmed by the RP2040's boot ROM routines, as the chip routine of
//! `board_common`'s `Window` over the four calibration sectors.
//!
//! **Why the ROM routines through rp2040-hal 0.12, not the `rp2040-flash` crate.** Its newest
//! release (0.6.0) depends on rp2040-hal 0.11, so the image would link two HALs, and it does
//! not link: both define the ROM's float intrinsics (`__addsf3` "multiply defined", and the
//! LTO step then fails; tried with this board's lock file, rustup 1.95). What it does is
//! small and is done here the way the Pico SDK does it (`flash_range_erase`,
//! `flash_range_program` in `hardware_flash`): the ROM functions' addresses looked up from
//! flash first, then one function in RAM (`.data.ram_func`, which cortex-m-rt copies to RAM
//! with `.data`) that calls only them, through those pointers: connect the flash, leave XIP,
//! erase or program, flush the XIP cache, and enter XIP again through a RAM copy of the
//! second-stage boot loader (so that the flash is read in the fast QSPI mode boot2 set up,
//! not the ROM's slow serial one). Nothing may read the flash meanwhile, the code included:
//! interrupts are off for the whole operation (an interrupt handler lives in flash), core 1
//! is never started (it waits in the boot ROM), and no DMA reads flash. `rp2040-hal`'s
//! `rom_data` builds with rustc 1.85 (the board's lock file, `rust-version`).
//!
//! The write unit is the 256-byte page (the state record is one page of its copy's sector),
//! the erase unit the 4 KiB sector. A sector erase keeps interrupts off for its time
//! (typically 45 ms, at most 400 ms: W25Q16JV datasheet), less than SysTick's wrap at
//! 125 MHz (134 ms) in the typical case, so the µs clock loses at most the wraps of a slow
//! erase.

use board_common::flash::window::Raw;
use embedded_storage::nor_flash::NorFlashErrorKind;
use rp2040_hal::rom_data;

/// Where XIP maps the flash, and the ROM routines' offset 0.
const XIP_BASE: usize = 0x1000_0000;
/// The Pico's 2 MiB.
const FLASH_LEN: usize = 2 * 1024 * 1024;
/// The first sector: boot2 and the vector table, never erased here.
const FIRST_SECTOR_END: usize = XIP_BASE + 4096;
/// A page, the program unit.
const PAGE: usize = 256;
/// The Pico SDK's block erase: 64 KiB blocks with command 0xD8 where a range allows, else
/// 4 KiB sector erases (the ROM picks).
const BLOCK_SIZE: u32 = 1 << 16;
const BLOCK_ERASE_CMD: u8 = 0xd8;

/// The ROM routines one operation calls, looked up before XIP goes off.
#[repr(C)]
struct Rom {
    connect_internal_flash: unsafe extern "C" fn(),
    flash_exit_xip: unsafe extern "C" fn(),
    flash_range_erase: unsafe extern "C" fn(u32, usize, u32, u8),
    flash_range_program: unsafe extern "C" fn(u32, *const u8, usize),
    flash_flush_cache: unsafe extern "C" fn(),
    /// boot2's copy in RAM, entered as a function (its address + 1, Thumb).
    enter_xip: unsafe extern "C" fn(),
}

/// One flash operation: erase `len` bytes at `offset` (from the start of flash) if `erase`,
/// then program `len` bytes from `data` there if `data` is not null. Lives in RAM and calls
/// nothing but the ROM pointers in `rom` (no flash access while XIP is off: see the
/// module's doc; the disassembly shows only `blx` through registers).
///
/// # Safety
/// Interrupts off; `rom` valid; `offset`, `len` aligned and inside the flash; `data`, if not
/// null, `len` readable bytes in RAM; `rom` in RAM.
#[inline(never)]
#[link_section = ".data.ram_func"]
unsafe fn operate(rom: &Rom, offset: u32, len: usize, erase: bool, data: *const u8) {
    (rom.connect_internal_flash)();
    (rom.flash_exit_xip)();
    if erase {
        (rom.flash_range_erase)(offset, len, BLOCK_SIZE, BLOCK_ERASE_CMD);
    }
    if !data.is_null() {
        (rom.flash_range_program)(offset, data, len);
    }
    (rom.flash_flush_cache)();
    (rom.enter_xip)();
}

/// Runs one operation with interrupts off, XIP re-entered through a RAM copy of boot2.
fn run(offset: usize, len: usize, erase: bool, data: *const u8) {
    // boot2, the first 256 bytes of flash, copied while XIP still works (word-aligned).
    let mut boot2 = [0u32; 64];
    // SAFETY: XIP is on; the first 256 bytes of flash are mapped and readable.
    unsafe {
        core::ptr::copy_nonoverlapping(XIP_BASE as *const u32, boot2.as_mut_ptr(), 64);
    }
    // SAFETY: a Thumb function's address is its start + 1; boot2 returns to its caller.
    let enter_xip = unsafe {
        core::mem::transmute::<*const u8, unsafe extern "C" fn()>(
            (boot2.as_ptr() as *const u8).wrapping_add(1),
        )
    };
    let rom = Rom {
        connect_internal_flash: rom_data::connect_internal_flash::ptr(),
        flash_exit_xip: rom_data::flash_exit_xip::ptr(),
        flash_range_erase: rom_data::flash_range_erase::ptr(),
        flash_range_program: rom_data::flash_range_program::ptr(),
        flash_flush_cache: rom_data::flash_flush_cache::ptr(),
        enter_xip,
    };
    cortex_m::interrupt::free(|_| {
        // SAFETY: interrupts off, `rom` and `data` on the stack (RAM), range checked by the
        // callers.
        unsafe { operate(&rom, offset as u32, len, erase, data) }
    });
}

/// The QSPI flash, past its first sector.
pub struct Qspi {
    _only: (),
}

impl Qspi {
    /// The driver.
    ///
    /// # Safety
    /// One at a time; core 1 not started and no DMA from flash while it is used (see the
    /// module's doc).
    pub unsafe fn new() -> Self {
        Qspi { _only: () }
    }
}

/// Whether `from..to` lies in the flash past its first sector.
fn inside(from: usize, to: usize) -> bool {
    from >= FIRST_SECTOR_END && from <= to && to <= XIP_BASE + FLASH_LEN
}

impl Raw for Qspi {
    const WRITE_SIZE: usize = PAGE;
    const ERASE_SIZE: usize = 4096;

    fn erase(&mut self, from: usize, to: usize) -> Result<(), NorFlashErrorKind> {
        if !inside(from, to) {
            return Err(NorFlashErrorKind::OutOfBounds);
        }
        run(from - XIP_BASE, to - from, true, core::ptr::null());
        Ok(())
    }

    fn program(&mut self, addr: usize, bytes: &[u8]) -> Result<(), NorFlashErrorKind> {
        if !inside(addr, addr + bytes.len()) {
            return Err(NorFlashErrorKind::OutOfBounds);
        }
        for (i, page) in bytes.chunks(PAGE).enumerate() {
            // The ROM reads the bytes while XIP is off: a copy in RAM, whatever `bytes` is.
            let mut buf = [0xffu8; PAGE];
            buf[..page.len()].copy_from_slice(page);
            run(addr - XIP_BASE + i * PAGE, PAGE, false, buf.as_ptr());
        }
        Ok(())
    }
}
