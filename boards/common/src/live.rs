//! The loop of a real hub: its own encoders sampled at a fixed period, and a replay taking
//! over whenever the host sends recorded readings (hardware-in-the-loop runs) until its `End`.

use quatarm::encoder::{read_joints, AbsoluteEncoder, Event, Replay};
use quatarm::stream::{Coordinates, Counts, Hub, Reading, ToHost, MAX_OUTPUT};

/// A byte link that can be polled without blocking (a UART with a receive flag).
pub trait PollLink {
    /// A received byte, if one is waiting.
    fn try_read(&mut self) -> Option<u8>;
    /// Sends all of `bytes`.
    fn write(&mut self, bytes: &[u8]);
}

/// Runs the hub for ever: a report every `period_us` from `encoders` (joint 1 first) and
/// `temp_mc`, or one per replayed reading while a replay is under way.
pub fn serve_live<L: PollLink, E: AbsoluteEncoder, X>(
    link: &mut L,
    hub: &mut Hub,
    encoders: &mut [E],
    period_us: u64,
    mut now_us: impl FnMut() -> u64,
    mut temp_mc: impl FnMut() -> i32,
    mut eval: impl FnMut(&[u32], i32) -> Result<Coordinates, X>,
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
    let mut counts = [0u32; 7];
    let joints = encoders.len().min(counts.len());
    loop {
        let report = if let Some(byte) = link.try_read() {
            match replay.push(byte) {
                Some(Event::Reading(r)) => {
                    replaying = true;
                    hub.report(now_us(), Ok(&r), &mut eval)
                }
                Some(Event::InputError(e)) => {
                    defmt::warn!("damaged input frame: {}", e);
                    hub.report(now_us(), Err(e), &mut eval)
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
                None => continue,
            }
        } else if !replaying && now_us() >= next {
            next += period_us;
            let faults = read_joints(&mut encoders[..joints], &mut counts[..joints]);
            let Some(c) = Counts::new(&counts[..joints]) else {
                continue;
            };
            let reading = Reading {
                seq: 0,
                counts: c,
                temp_mc: temp_mc(),
                faults,
            };
            hub.report(now_us(), Ok(&reading), &mut eval)
        } else {
            continue;
        };
        link.write(hub.render(&ToHost::Report(report), &mut out));
    }
}
