//! The replay loop every board runs: read bytes, evaluate readings, send reports.

use quatarm::stream::{Coordinates, Event, Hub, Replay, ToHost, MAX_OUTPUT};

/// A byte link to the host (a UART).
pub trait Link {
    /// Waits for one received byte.
    fn read(&mut self) -> u8;
    /// Sends all of `bytes`.
    fn write(&mut self, bytes: &[u8]);
}

/// How a replay ended.
pub struct Served {
    /// Reports sent.
    pub reports: u32,
}

/// Announces the hub, then answers every incoming frame until the host sends `End`.
/// `now_us` stamps each report; `eval` runs the chain (it is called only for readings that may
/// give coordinates, see [`Hub::report`]).
pub fn serve<L: Link, E>(
    link: &mut L,
    hub: &mut Hub,
    mut now_us: impl FnMut() -> u64,
    mut eval: impl FnMut(&[u32], i32) -> Result<Coordinates, E>,
) -> Served {
    let mut out = [0u8; MAX_OUTPUT];
    // A lone delimiter first: whoever listens is in sync from the first frame on.
    link.write(&[0]);
    link.write(hub.render(&hub.hello(), &mut out));
    defmt::info!(
        "hub up: table {}, {=u8} joints, {}",
        hub.table(),
        hub.joints(),
        hub.precision()
    );
    let mut replay = Replay::new();
    let mut reports = 0u32;
    let mut input_errors = 0u32;
    loop {
        let Some(event) = replay.push(link.read()) else {
            continue;
        };
        let report = match event {
            Event::Reading(r) => hub.report(now_us(), Ok(&r), &mut eval),
            Event::InputError(e) => {
                input_errors += 1;
                defmt::warn!("damaged input frame: {}", e);
                hub.report(now_us(), Err(e), &mut eval)
            }
            Event::SetMode(m) => {
                hub.set_mode(m);
                link.write(hub.render(&hub.hello(), &mut out));
                continue;
            }
            Event::End => {
                defmt::info!(
                    "replay done: {=u32} reports, {=u32} damaged input frames",
                    reports,
                    input_errors
                );
                return Served { reports };
            }
        };
        link.write(hub.render(&ToHost::Report(report), &mut out));
        reports = reports.wrapping_add(1);
    }
}
