//! Microseconds since boot, from SysTick counting the core clock and an exception counting its
//! wraps. The only time source every Cortex-M has (the DWT cycle counter is missing on the M0
//! and under QEMU).

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::{syst::SystClkSource, SYST};

static WRAPS: AtomicU32 = AtomicU32::new(0);
const RELOAD: u32 = 0x00FF_FFFF;

/// Starts SysTick free-running on the core clock, interrupting at every wrap (the handler is
/// this module's: a board defines no `SysTick` of its own).
pub fn start(mut syst: SYST) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(RELOAD);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

/// Counts a wrap. The clock owns SysTick, so its handler lives here rather than in each board.
#[cortex_m_rt::exception]
fn SysTick() {
    // Only this handler writes WRAPS, so load + store is enough (the M0 has no atomic add).
    WRAPS.store(
        WRAPS.load(Ordering::Relaxed).wrapping_add(1),
        Ordering::Relaxed,
    );
}

/// Core-clock ticks since `start`.
pub fn ticks() -> u64 {
    loop {
        let before = WRAPS.load(Ordering::Relaxed);
        let val = SYST::get_current();
        let after = WRAPS.load(Ordering::Relaxed);
        if before == after {
            return (u64::from(before) << 24) + u64::from(RELOAD - val);
        }
    }
}

/// Microseconds since `start`, for a core clock of `hz` (a whole number of MHz).
pub fn now_us(hz: u32) -> u64 {
    ticks() / u64::from(hz / 1_000_000)
}
