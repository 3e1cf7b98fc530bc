//! What the QEMU boards share: the hub's and the benchmark's whole runs (the boards differ
//! only in their UART and core clock), and leaving QEMU: semihosting's exit call becomes the
//! QEMU process's exit code, so a test run fails loudly on a panic instead of hanging.

use cortex_m_semihosting::debug::{self, EXIT_FAILURE, EXIT_SUCCESS};

use embedded_storage::nor_flash::NorFlash;
use quatarm::stream::{Replay, TableState};
use quatarm::table::MAX_TABLE_LEN;
use quatarm::update::{Accept, Layout, Refusal};

use crate::calibration::{Calibration, HubEvaluator};
use crate::flash::{Boot, Port};
use crate::{bench, clock, serve, stack, table_region, Link, Served};

/// The whole run of a QEMU hub image: boot on the live table, replay the recording that
/// arrives on the link and carry out update steps until the host's `End` (booting again on
/// the new table after each committed update, as after a reset), log the stack's peak and the
/// statics' size, exit with success.
///
/// The core clock is a constant parameter, not an argument: the ticks-to-µs division of every
/// report then compiles to a multiplication (a runtime u64 division costs hundreds of
/// instructions on the M0, and flash).
///
/// `open_link` sets up the board's UART; it runs after the clock has started, so that report
/// times count from the same point on every board. `flash` is the driver of the calibration
/// flash, laid out as `layout` (`slots::Map::window`, as the real boards give `live::run`).
/// `accept` is what the hub requires of a table (its joints, its maker's key). `ram_start`
/// is where `memory.x` puts RAM.
pub fn hub_main<P: HubEvaluator, const CORE_HZ: u32, L: Link, F: NorFlash>(
    ram_start: usize,
    accept: Accept,
    open_link: impl FnOnce() -> L,
    (flash, layout): (F, Layout),
) -> ! {
    stack::paint();
    let mut link = start(open_link);
    // The live table (which the calibration borrows) and the update's scratch, apart.
    let mut live = [0u8; MAX_TABLE_LEN];
    let mut scratch = [0u8; MAX_TABLE_LEN];
    let mut port = Port::new(flash, layout, accept, &mut scratch);
    loop {
        let mut boot = Boot::empty();
        port.boot::<P>(&mut live, &mut boot);
        let served = serve(
            &mut link,
            boot.hub(),
            &mut boot.calibration,
            Replay::new(),
            || clock::now_us(CORE_HZ),
            |step| port.step(step),
        );
        if served == Served::Ended {
            break;
        }
    }
    log_memory(ram_start);
    exit_success()
}

/// The whole run of a QEMU hub image without an update port: as [`hub_main`], on the table
/// of slot 0 (`CALTABLE`) as a debug probe flashed it; update steps are answered
/// `NotSupported`, known by their frames' variant index without being decoded. For the
/// qemu-m0 hub, whose 32 KiB budget the updater does not fit (37,228 bytes with it, rustup
/// 1.95; README, "On the targets").
pub fn hub_main_without_update<P: HubEvaluator, const CORE_HZ: u32, L: Link>(
    ram_start: usize,
    open_link: impl FnOnce() -> L,
) -> ! {
    stack::paint();
    let mut link = start(open_link);
    let mut cal = Calibration::<P>::refused(TableState::Missing);
    cal.load_in(table_region::bytes());
    let hub = cal.hub();
    serve(
        &mut link,
        hub,
        &mut cal,
        Replay::without_update(),
        || clock::now_us(CORE_HZ),
        |_| Err(Refusal::NotSupported),
    );
    log_memory(ram_start);
    exit_success()
}

/// What every QEMU image does first: SysTick started as the µs clock, then the board's link
/// opened (after the clock, so that report times count from the same point on every board).
fn start<L: Link>(open_link: impl FnOnce() -> L) -> L {
    let Some(cp) = cortex_m::Peripherals::take() else {
        exit_failure()
    };
    clock::start(cp.SYST);
    open_link()
}

/// The stack's peak and the statics' size, for the end-to-end tests' report.
fn log_memory(ram_start: usize) {
    defmt::info!(
        "stack peak {=u32} bytes, statics {=u32} bytes",
        stack::peak() as u32,
        stack::statics(ram_start) as u32
    );
}

/// The whole run of a QEMU benchmark image ([`bench::run`] in precision `P`), then exit with
/// success. `open_link` as for [`hub_main`].
/// `key` is the public key the table in the region is checked against (its check is timed).
pub fn bench_main<P: HubEvaluator, L: Link>(
    key: &[u8; quatarm::signature::KEY_LEN],
    open_link: impl FnOnce() -> L,
) -> ! {
    let mut link = start(open_link);
    bench::run::<_, P>(&mut link, table_region::bytes(), key);
    exit_success()
}

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
