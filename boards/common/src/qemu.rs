//! Leaving QEMU: semihosting's exit call becomes the QEMU process's exit code, so a test run
//! fails loudly on a panic instead of hanging.

use cortex_m_semihosting::debug::{self, EXIT_FAILURE, EXIT_SUCCESS};

/// Ends the QEMU run with success.
pub fn exit_success() -> ! {
    debug::exit(EXIT_SUCCESS);
    #[allow(clippy::empty_loop)]
    loop {}
}

/// Ends the QEMU run with failure.
pub fn exit_failure() -> ! {
    debug::exit(EXIT_FAILURE);
    #[allow(clippy::empty_loop)]
    loop {}
}

/// The panic handler of the QEMU boards: no message (no `core::fmt` in the image), just a
/// failing exit code.
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    exit_failure()
}

/// A hard fault (a stack overflow into the statics' guard, a bad access) ends the run with
/// failure instead of looping forever.
#[cortex_m_rt::exception]
unsafe fn HardFault(_: &cortex_m_rt::ExceptionFrame) -> ! {
    exit_failure()
}
