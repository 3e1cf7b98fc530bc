//! The replay loop every board runs: read bytes, evaluate readings, send reports, carry out
//! calibration update steps and probe selections.

use quatarm::stream::{Event, Hub, Replay, StepReading, ToHost, UpdateAnswer, MAX_OUTPUT};
use quatarm::update::Accepted;

use crate::calibration::{Calibration, HubEvaluator};

/// A byte link to the host (a UART).
pub trait Link {
    /// Waits for one received byte.
    fn read(&mut self) -> u8;
    /// Sends all of `bytes`.
    fn write(&mut self, bytes: &[u8]);
}

/// How a replay ended.
pub enum Served {
    /// The host sent `End`.
    Ended {
        /// Reports sent.
        reports: u32,
    },
    /// An update committed a new table: the caller boots on it (a new chain, a new `Hello`).
    Updated,
}

/// Announces the hub, then answers every incoming frame of `replay` until the host sends `End`
/// or an update commits. `now_us` stamps each report; `cal` evaluates the readings that may
/// give coordinates (see [`Hub::report`]) and mounts the probes the host selects; `update`
/// carries out one update step (`quatarm::update::Updater::step` on the board's flash; a hub
/// without an update port reads no step, [`Replay::without_update`], and refuses each).
/// Readings keep being answered while an update is under way, on the old table, until the
/// commit.
pub fn serve<L: Link, P: HubEvaluator, S: StepReading>(
    link: &mut L,
    hub: &mut Hub,
    cal: &mut Calibration<'_, P>,
    mut replay: Replay<S>,
    mut now_us: impl FnMut() -> u64,
    mut update: impl FnMut(&S) -> UpdateAnswer,
) -> Served {
    let mut out = [0u8; MAX_OUTPUT];
    // A lone delimiter first: whoever listens is in sync from the first frame on.
    link.write(&[0]);
    link.write(hub.render(&hub.hello(), &mut out));
    defmt::info!(
        "hub up: table {}, {=u8} joints, {}, probe {=u8}",
        hub.table(),
        hub.joints(),
        hub.precision(),
        hub.probe()
    );
    let mut reports = 0u32;
    let mut input_errors = 0u32;
    loop {
        let Some(event) = replay.push(link.read()) else {
            continue;
        };
        let eval = |counts: &[u32], temp_mc| cal.eval(counts, temp_mc);
        let report = match event {
            Event::Reading(r) => hub.report(now_us(), Ok(&r), eval),
            Event::InputError(e) => {
                input_errors += 1;
                defmt::warn!("damaged input frame: {}", e);
                hub.report(now_us(), Err(e), eval)
            }
            Event::SetMode(m) => {
                hub.set_mode(m);
                link.write(hub.render(&hub.hello(), &mut out));
                continue;
            }
            Event::Update(step) => {
                if answer_update(hub, &mut out, update(&step), |b| link.write(b)) {
                    return Served::Updated;
                }
                continue;
            }
            Event::SelectProbe(id) => {
                let answer = hub.select(id, |k| cal.mount(k));
                link.write(hub.render(&ToHost::Probe(answer), &mut out));
                continue;
            }
            Event::End => {
                defmt::info!(
                    "replay done: {=u32} reports, {=u32} damaged input frames",
                    reports,
                    input_errors
                );
                return Served::Ended { reports };
            }
        };
        link.write(hub.render(&ToHost::Report(report), &mut out));
        reports = reports.wrapping_add(1);
    }
}

/// Sends the answer to an update step (a frame in either output mode); whether it committed a
/// new table, which the caller then boots on (a new chain, a new `Hello`), as a reset would.
/// The one answer of both loops, the replay's and the live hub's.
#[inline(always)] // one caller in an image (`serve` or `serve_live`): a call would only add bytes
pub(crate) fn answer_update(
    hub: &Hub,
    out: &mut [u8; MAX_OUTPUT],
    answer: UpdateAnswer,
    write: impl FnOnce(&[u8]),
) -> bool {
    write(hub.render(&ToHost::Update(answer), out));
    match answer {
        Ok(Accepted::Committed { slot, seq }) => {
            defmt::info!("update committed: slot {=u8}, record {=u32}", slot, seq);
            true
        }
        _ => false,
    }
}
