//! The loop of a real hub: its own encoders sampled at a fixed period with the arm's
//! temperature, a replay taking over whenever the host sends recorded readings
//! (hardware-in-the-loop runs) until its `End`, and calibration updates over the same link
//! (`docs/update.md`), after each of which the hub boots again on the new table.
//!
//! The temperature sensor is polled every [`TEMP_PERIOD_US`], not at every sample: the arm's
//! structure changes temperature over minutes, the sensor converts once a second, and an I2C
//! poll costs a few hundred µs of the 1 ms sample period. Between polls every sample uses the
//! last poll's outcome; a failed poll gives `TEMP_SENSOR_FAULT` and no coordinates until a
//! poll succeeds again (`Hub::report_sample`).
//!
//! An update step that erases or programs flash stops the sampling while it runs (one loop,
//! no interrupts doing the work): the NUCLEO's `Begin` erases a 128 KiB sector, which stalls
//! every flash access of the core for the erase (seconds: the datasheet's t_ERASE128KB), so
//! no reports come then; and the µs clock (SysTick, whose handler is in flash) misses the
//! wraps of that time, so report times after it are behind by it. The host's `armcal table
//! send` waits for each answer (5 s by default, `--timeout`).

use embedded_storage::nor_flash::NorFlash;
use quatarm::encoder::{read_joints, AbsoluteEncoder};
use quatarm::signature::KEY_LEN;
use quatarm::stream::{Event, Hub, Replay, ToHost, UpdateAnswer, MAX_OUTPUT};
use quatarm::table::MAX_TABLE_LEN;
use quatarm::temperature::TemperatureSensor;
use quatarm::update::session::Step;
use quatarm::update::{Accept, Layout};

use crate::calibration::{Calibration, HubEvaluator, JOINTS};
use crate::clock;
use crate::flash::Port;
use crate::serve::answer_update;

/// How often the temperature sensor is polled.
pub const TEMP_PERIOD_US: u64 = 250_000;

/// Polls in a row that may find no new conversion of a sensor converting once a second
/// before its reading counts as stale: two seconds' worth (see `Tmp117::new`).
pub const TEMP_STALE_POLLS: u16 = (2_000_000 / TEMP_PERIOD_US) as u16;

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
/// joints and the encoders' resolution, signed under the arm maker's `key`; then
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
    key: [u8; KEY_LEN],
) -> ! {
    let resolution = encoders.each_ref().map(|e| e.counts_per_rev());
    let accept = Accept::joints(JOINTS)
        .signed_by(key)
        .for_encoders(&resolution);
    // The live table (which the calibration borrows) and the update's scratch, apart
    // (`flash::port`).
    let mut live = [0u8; MAX_TABLE_LEN];
    let mut scratch = [0u8; MAX_TABLE_LEN];
    let mut port = Port::new(flash, layout, accept, &mut scratch);
    loop {
        let mut boot = port.boot::<P>(&mut live);
        let mut hub = boot.hub();
        serve_live(
            link,
            &mut hub,
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
    hub: &mut Hub,
    encoders: &mut [E],
    period_us: u64,
    mut now_us: impl FnMut() -> u64,
    thermometer: &mut T,
    cal: &mut Calibration<'_, P>,
    mut update: impl FnMut(&Step) -> UpdateAnswer,
) {
    let mut out = [0u8; MAX_OUTPUT];
    link.write(&[0]);
    link.write(hub.render(&hub.hello(), &mut out));
    defmt::info!(
        "hub up: table {}, {=u8} joints, {}, {=usize} encoders",
        hub.table(),
        hub.joints(),
        hub.precision(),
        encoders.len()
    );
    let mut replay = Replay::new();
    let mut replaying = false;
    let mut next = now_us();
    let mut next_temp = next;
    let mut temp_mc: Option<i32> = None;
    let mut temp_ok = true; // only changes of the sensor's state are logged
    let mut counts = [0u32; quatarm::table::MAX_JOINTS];
    let joints = encoders.len().min(counts.len());
    loop {
        let eval = |counts: &[u32], temp_mc| cal.eval(counts, temp_mc);
        let report = if let Some(byte) = link.try_read() {
            match replay.push(byte) {
                Some(Event::Reading(r)) => {
                    replaying = true;
                    hub.report(now_us(), Ok(&r), eval)
                }
                Some(Event::InputError(e)) => {
                    defmt::warn!("damaged input frame: {}", e);
                    hub.report(now_us(), Err(e), eval)
                }
                Some(Event::SetMode(m)) => {
                    hub.set_mode(m);
                    link.write(hub.render(&hub.hello(), &mut out));
                    continue;
                }
                Some(Event::End) => {
                    replaying = false;
                    next = now_us();
                    continue;
                }
                Some(Event::Update(step)) => {
                    if answer_update(hub, &mut out, update(&step), |b| link.write(b)) {
                        return;
                    }
                    continue;
                }
                Some(Event::SelectProbe(id)) => {
                    let answer = hub.select(id, |k| cal.mount(k));
                    link.write(hub.render(&ToHost::Probe(answer), &mut out));
                    continue;
                }
                None => continue,
            }
        } else if !replaying && now_us() >= next {
            next += period_us;
            if now_us() >= next_temp {
                next_temp += TEMP_PERIOD_US;
                temp_mc = thermometer.read_mc().ok();
                match (temp_mc, temp_ok) {
                    (None, true) => defmt::warn!("temperature sensor: no valid reading"),
                    (Some(t), false) => defmt::info!("temperature sensor back: {=i32} mC", t),
                    _ => {}
                }
                temp_ok = temp_mc.is_some();
            }
            let faults = read_joints(&mut encoders[..joints], &mut counts[..joints]);
            hub.report_sample(now_us(), &counts[..joints], faults, temp_mc, eval)
        } else {
            continue;
        };
        link.write(hub.render(&ToHost::Report(report), &mut out));
    }
}
