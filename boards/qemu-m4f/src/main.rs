//! quatarm hub on QEMU `mps2-an386` (Cortex-M4F): the f32 chain, fed by a recording over
//! CMSDK UART0, streaming reports back on the same UART.
//!
//! Boot: read the calibration region, validate the table, announce the result. Then replay
//! until the host sends `End`, and exit QEMU with success (any panic exits with failure).
#![no_std]
#![no_main]

mod uart;

use board_common::{calibration, clock, qemu, serve, stack, Link};
use cortex_m_rt::{entry, exception};
use quatarm::stream::Hub;

/// mps2-an386 core clock: 25 MHz.
const CORE_HZ: u32 = 25_000_000;
/// 115200 baud (QEMU does not pace the UART, but the divider must be valid).
const BAUDDIV: u32 = CORE_HZ / 115_200;

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
    // SAFETY: UART0 is used by nothing else.
    let mut link = Uart0(unsafe { uart::Uart::new(uart::Uart::UART0, BAUDDIV) });
    let cal = calibration::load::<quatarm::F32>(board_common::table_region::bytes());
    let mut hub = Hub::new(cal.state(), cal.joints(), quatarm::stream::Precision::F32);
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
