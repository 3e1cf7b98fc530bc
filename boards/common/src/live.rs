//! The loop of a real hub: its own encoders sampled at a fixed period with the arm's
//! temperature, a replay taking over whenever the host sends recorded readings
//! (hardware-in-the-loop runs) until its `End`, and calibration updates over the same link
//! (`docs/update.md`), after each of which the hub boots again on the new table.
//!
//! When it samples and polls the thermometer, and what it answers to each frame, is
//! `quatarm::stream::Live`'s, tested on the host; this loop only moves bytes.
//!
//! An update step that erases or programs flash stops the sampling while it runs (one loop,
//! no interrupts doing the work): the NUCLEO's `Begin` erases a 128 KiB sector, which stalls
//! every flash access of the core for the erase (seconds: the datasheet's t_ERASE128KB), so
//! no reports come then; and the µs clock (SysTick, whose handler is in flash) misses the
//! wraps of that time, so report times after it are behind by it. The host's `armcal table
//! send` waits for each answer (5 s by default, `--timeout`).

use embedded_storage::nor_flash::NorFlash;
use quatarm::encoder::AbsoluteEncoder;
use quatarm::stream::{Hub, HubLoop, Live, Replay, Then, UpdateAnswer};
use quatarm::table::MAX_TABLE_LEN;
use quatarm::temperature::TemperatureSensor;
use quatarm::update::session::Step;
use quatarm::update::{Accept, Keys, Layout};

use crate::calibration::{Calibration, HubEvaluator, JOINTS};
use crate::clock;
use crate::flash::{Boot, Port};

pub use quatarm::stream::{TEMP_PERIOD_US, TEMP_STALE_POLLS};

/// A byte link that can be polled without blocking (a UART with a receive flag).
pub trait PollLink {
    /// A received byte, if one is waiting.
    fn try_read(&mut self) -> Option<u8>;
    /// Sends all of `bytes`.
    fn write(&mut self, bytes: &[u8]);
}

/// The whole run of a real hub once its board has set up the link, the encoders (joint 1
/// first, one per joint of the table), the thermometer and its calibration flash (`flash`,
/// laid out as `layout`: `slots::Map::window`): boot on the live table, one for this many
/// joints and the encoders' resolution, signed under the arm maker's `keys` (its current key
/// and, where the image holds one, the next: [`crate::maker_keys!`]); then
/// [`serve_live`] in precision `P` with a report every `period_us`, timed by a core clock of
/// `CORE_HZ` (a constant parameter so that the ticks-to-µs divisions, several per sample,
/// compile to multiplications), until an update commits; then boot again on the new table,
/// as a reset would.
pub fn run<P: HubEvaluator, const CORE_HZ: u32, F: NorFlash>(
    link: &mut impl PollLink,
    encoders: &mut [impl AbsoluteEncoder; JOINTS],
    thermometer: &mut impl TemperatureSensor,
    period_us: u64,
    (flash, layout): (F, Layout),
    keys: Keys,
) -> ! {
    let resolution = encoders.each_ref().map(|e| e.counts_per_rev());
    let accept = Accept::joints(JOINTS)
        .signed_by_keys(keys)
        .for_encoders(&resolution);
    // The live table (which the calibration borrows) and the update's scratch, apart
    // (`flash::port`).
    let mut live = [0u8; MAX_TABLE_LEN];
    let mut scratch = [0u8; MAX_TABLE_LEN];
    let mut port = Port::new(flash, layout, accept, &mut scratch);
    loop {
        let mut boot = Boot::empty();
        port.boot::<P>(&mut live, &mut boot);
        serve_live(
            link,
            boot.hub(),
            encoders,
            period_us,
            || clock::now_us(CORE_HZ),
            thermometer,
            &mut boot.calibration,
            |step| port.step(step),
        );
    }
}

/// Runs the hub: a report every `period_us` from `encoders` (joint 1 first) and
/// `thermometer`, or one per replayed reading while a replay is under way; `cal` evaluates
/// them and mounts the probes the host selects; update steps carried out by `update`
/// (`Port::step`). Returns when an update has committed a new table, for the caller to boot
/// on.
#[allow(clippy::too_many_arguments)] // the loop's whole world; one caller
pub fn serve_live<L: PollLink, E: AbsoluteEncoder, T: TemperatureSensor, P: HubEvaluator>(
    link: &mut L,
    hub: Hub,
    encoders: &mut [E],
    period_us: u64,
    mut now_us: impl FnMut() -> u64,
    thermometer: &mut T,
    cal: &mut Calibration<'_, P>,
    mut update: impl FnMut(&Step) -> UpdateAnswer,
) {
    let mut hub = HubLoop::new(hub, Replay::new());
    link.write(hub.greeting());
    // Sampling starts once the greeting is out.
    let mut live = Live::new(hub, period_us, now_us());
    loop {
        let reply = match link.try_read() {
            Some(byte) => live.receive(byte, &mut now_us, cal, &mut update),
            None => match live.tick(&mut now_us, encoders, thermometer, cal) {
                Some(reply) => reply,
                None => continue,
            },
        };
        link.write(reply.send);
        if reply.then == Then::Boot {
            return;
        }
    }
}
