//! Benchmark image of qemu-m0: the fixed-point quaternion and matrix chains timed on the
//! readings that arrive over the UART (see `board_common::bench`). Run under `-icount shift=0`.
#![no_std]
#![no_main]

#[path = "../uart.rs"]
mod uart;

use board_common::{bench, clock, qemu, table_region, Link};
use cortex_m_rt::{entry, exception};

struct Uart0(uart::Uart);

impl Link for Uart0 {
    fn read(&mut self) -> u8 {
        self.0.read()
    }
    fn write(&mut self, bytes: &[u8]) {
        self.0.write(bytes)
    }
}

#[entry]
fn main() -> ! {
    let Some(cp) = cortex_m::Peripherals::take() else {
        qemu::exit_failure()
    };
    clock::start(cp.SYST);
    // SAFETY: the only UART of the image.
    let mut link = Uart0(unsafe { uart::Uart::take() });
    bench::run::<_, quatarm::Fixed>(&mut link, table_region::bytes());
    qemu::exit_success()
}

#[exception]
fn SysTick() {
    clock::on_wrap();
}
