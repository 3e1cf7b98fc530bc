//! quatarm hub on QEMU `microbit` (nRF51822, Cortex-M0, no FPU): the fixed-point chain, fed by
//! a recording over the nRF51 UART, streaming reports back on it.
//!
//! Kept small for its 32 KiB / 8 KiB budget (enforced by `memory.x`): no `core::fmt` anywhere
//! in the image, a panic handler that only exits QEMU with failure.
//!
//! The minimal profile (no feature of `board-common`). What it leaves out for its 32 KiB:
//! the axis wobble and the parameter block (a table with either is refused, `Malformed`),
//! every point's U95 (its reports carry none, whatever budget the table has), the update
//! port (update steps are answered `NotSupported`) and the table's signature check (the
//! table is loaded into `CALTABLE` beside the image). The Raspberry Pi Pico runs the same
//! core's instructions with all of them; this crate's feature `pico-profile` builds that
//! profile here for its benchmark (`docs/results/boards.md`, "Board profiles").
#![no_std]
#![no_main]

mod uart;

use board_common::qemu;
use cortex_m_rt::entry;

/// microbit core clock: 16 MHz.
const CORE_HZ: u32 = 16_000_000;

/// Start of RAM in `memory.x`.
const RAM_START: usize = 0x2000_0000;

#[entry]
fn main() -> ! {
    qemu::hub_main_without_update::<quatarm::Fixed, CORE_HZ, _>(RAM_START, || {
        // SAFETY: the only UART of the image.
        unsafe { uart::Uart::take() }
    })
}
