//! Benchmark image of qemu-m4f: the f32 quaternion and matrix chains timed on the readings
//! that arrive over UART0 (see `board_common::bench`). Run under `-icount shift=0`.
#![no_std]
#![no_main]

#[path = "../uart.rs"]
mod uart;

use board_common::maker_key::TEST_MAKER_KEY;
use board_common::qemu;
use cortex_m_rt::entry;

#[entry]
fn main() -> ! {
    qemu::bench_main::<quatarm::F32, _>(&TEST_MAKER_KEY, || {
        // SAFETY: UART0 is used by nothing else.
        unsafe { uart::Uart::new(uart::Uart::UART0, 217) }
    })
}
