//! The replay loop every QEMU board runs: bytes from the link into [`HubLoop`], its replies
//! back out, until the host's `End` or a committed update. What the hub does with each frame
//! is `quatarm::stream::HubLoop`'s, tested on the host; this loop only moves bytes.

use quatarm::stream::{Hub, HubLoop, Replay, StepReading, Then, UpdateAnswer};

use crate::calibration::{Calibration, HubEvaluator};

/// A byte link to the host (a UART).
pub trait Link {
    /// Waits for one received byte.
    fn read(&mut self) -> u8;
    /// Sends all of `bytes`.
    fn write(&mut self, bytes: &[u8]);
}

/// How a replay ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Served {
    /// The host sent `End`.
    Ended,
    /// An update committed a new table: the caller boots on it (a new chain, a new `Hello`).
    Updated,
}

/// Announces `hub`, then answers every incoming frame of `replay` until the host sends `End`
/// or an update commits. `now_us` stamps each report; `cal` evaluates the readings that may
/// give coordinates (see [`Hub::report`]) and mounts the probes the host selects; `update`
/// carries out one update step (`quatarm::update::Updater::step` on the board's flash; a hub
/// without an update port reads no step, [`Replay::without_update`], and refuses each).
/// Readings keep being answered while an update is under way, on the old table, until the
/// commit.
pub fn serve<L: Link, P: HubEvaluator, S: StepReading>(
    link: &mut L,
    hub: Hub,
    cal: &mut Calibration<'_, P>,
    replay: Replay<S>,
    mut now_us: impl FnMut() -> u64,
    mut update: impl FnMut(&S) -> UpdateAnswer,
) -> Served {
    let mut hub = HubLoop::new(hub, replay);
    link.write(hub.greeting());
    loop {
        let reply = hub.receive(link.read(), &mut now_us, cal, &mut update);
        link.write(reply.send);
        match reply.then {
            Then::Continue => {}
            Then::Ended => return Served::Ended,
            Then::Boot => return Served::Updated,
        }
    }
}
