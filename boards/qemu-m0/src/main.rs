//! quatarm hub on QEMU `microbit` (nRF51822, Cortex-M0, no FPU): the fixed-point chain, fed by
//! a recording over the nRF51 UART, streaming reports back on it.
//!
//! Kept small for its 32 KiB / 8 KiB budget (enforced by `memory.x`): no `core::fmt` anywhere
//! in the image, a panic handler that only exits QEMU with failure.
#![no_std]
#![no_main]

mod uart;

use board_common::{calibration, clock, qemu, serve, stack, Link};
use cortex_m_rt::{entry, exception};
use quatarm::stream::{Hub, Precision};

/// microbit core clock: 16 MHz.
const CORE_HZ: u32 = 16_000_000;

/// Start of RAM in `memory.x`.
const RAM_START: usize = 0x2000_0000;

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
    stack::paint();
    let Some(cp) = cortex_m::Peripherals::take() else {
        qemu::exit_failure()
    };
    clock::start(cp.SYST);
    // SAFETY: the only UART of the image.
    let mut link = Uart0(unsafe { uart::Uart::take() });
    let cal = calibration::load::<quatarm::Fixed>(board_common::table_region::bytes());
    let mut hub = Hub::new(cal.state(), cal.joints(), Precision::Fixed);
    serve(
        &mut link,
        &mut hub,
        || clock::now_us(CORE_HZ),
        |counts, temp_mc| cal.eval(counts, temp_mc),
    );
    defmt::info!(
        "stack peak {=u32} bytes, statics {=u32} bytes",
        stack::peak() as u32,
        stack::statics(RAM_START) as u32
    );
    qemu::exit_success()
}

#[exception]
fn SysTick() {
    clock::on_wrap();
}
