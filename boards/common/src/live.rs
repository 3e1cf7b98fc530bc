//! The loop of a real hub: its own encoders sampled at a fixed period with the arm's
//! temperature, and a replay taking over whenever the host sends recorded readings
//! (hardware-in-the-loop runs) until its `End`.
//!
//! The temperature sensor is polled every [`TEMP_PERIOD_US`], not at every sample: the arm's
//! structure changes temperature over minutes, the sensor converts once a second, and an I2C
//! poll costs a few hundred µs of the 1 ms sample period. Between polls every sample uses the
//! last poll's outcome; a failed poll gives `TEMP_SENSOR_FAULT` and no coordinates until a
//! poll succeeds again (`Hub::report_sample`).

use quatarm::encoder::{read_joints, AbsoluteEncoder};
use quatarm::stream::{Event, Hub, Replay, ToHost, UpdateAnswer, MAX_OUTPUT};
use quatarm::temperature::TemperatureSensor;
use quatarm::update::Refusal;

use crate::calibration::{self, Calibration, HubEvaluator, JOINTS};
use crate::{clock, table_region};

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
/// first, one per joint of the table) and the thermometer: the table checked against the encoders' resolution, then
/// [`serve_live`] in precision `P` with a report every `period_us`, timed by a core clock of
/// `CORE_HZ` (a constant parameter so that the ticks-to-µs divisions, several per sample,
/// compile to multiplications).
pub fn run<P: HubEvaluator, const CORE_HZ: u32>(
    link: &mut impl PollLink,
    encoders: &mut [impl AbsoluteEncoder; JOINTS],
    thermometer: &mut impl TemperatureSensor,
    period_us: u64,
) -> ! {
    let resolution = encoders.each_ref().map(|e| e.counts_per_rev());
    let mut cal = calibration::load_for_encoders::<P>(table_region::bytes(), &resolution);
    let mut hub = cal.hub();
    serve_live(
        link,
        &mut hub,
        encoders,
        period_us,
        || clock::now_us(CORE_HZ),
        thermometer,
        &mut cal,
    )
}

/// Runs the hub for ever: a report every `period_us` from `encoders` (joint 1 first) and
/// `thermometer`, or one per replayed reading while a replay is under way; `cal` evaluates
/// them and mounts the probes the host selects.
pub fn serve_live<L: PollLink, E: AbsoluteEncoder, T: TemperatureSensor, P: HubEvaluator>(
    link: &mut L,
    hub: &mut Hub,
    encoders: &mut [E],
    period_us: u64,
    mut now_us: impl FnMut() -> u64,
    thermometer: &mut T,
    cal: &mut Calibration<'_, P>,
) -> ! {
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
                // The real boards' flash drivers are not wired to the updater yet: the
                // table changes with a debug probe, and the host is told so.
                Some(Event::Update(_)) => {
                    let answer: UpdateAnswer = Err(Refusal::NotSupported);
                    link.write(hub.render(&ToHost::Update(answer), &mut out));
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
