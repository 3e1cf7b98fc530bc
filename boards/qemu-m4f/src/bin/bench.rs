//! Benchmark image of qemu-m4f: the f32 quaternion and matrix chains timed on the readings
//! that arrive over UART0 (see `board_common::bench`). Run under `-icount shift=0`.
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
    // SAFETY: UART0 is used by nothing else.
    let mut link = Uart0(unsafe { uart::Uart::new(uart::Uart::UART0, 217) });
    bench::run::<_, quatarm::F32>(&mut link, table_region::bytes());
    qemu::exit_success()
}

#[exception]
fn SysTick() {
    clock::on_wrap();
}
