//! Benchmark image of qemu-m0: the fixed-point quaternion and matrix chains timed on the
//! readings that arrive over the UART (see `board_common::bench`). Run under `-icount shift=0`.
#![no_std]
#![no_main]

#[path = "../uart.rs"]
mod uart;

use board_common::maker_key::TEST_MAKER_KEY;
use board_common::qemu;
use cortex_m_rt::entry;

#[entry]
fn main() -> ! {
    qemu::bench_main::<quatarm::Fixed, _>(&TEST_MAKER_KEY, || {
        // SAFETY: the only UART of the image.
        unsafe { uart::Uart::take() }
    })
}
