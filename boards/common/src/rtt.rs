//! What the real boards share apart from their loop: the defmt log over RTT, which a debug
//! probe reads apart from the data stream, and the panic handler.

use defmt_rtt as _;

/// No message (no `core::fmt`), just a stop a debug probe sees: the stream falls silent, which
/// a host notices as missing reports.
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    defmt::error!("panic");
    cortex_m::asm::udf()
}
