//! The live hub's clock: its own encoders sampled at a fixed period with the arm's
//! temperature, unless the host is replaying readings ([`HubLoop::replaying`]), until that
//! replay's `End`.
//!
//! The temperature sensor is polled every [`TEMP_PERIOD_US`], not at every sample: the arm's
//! structure changes temperature over minutes, the sensor converts once a second, and an I2C
//! poll costs a few hundred µs of the 1 ms sample period. Between polls every sample uses the
//! last poll's outcome; a failed poll gives `TEMP_SENSOR_FAULT` and no coordinates until a
//! poll succeeds again ([`Hub::report_sample`](super::Hub::report_sample)).

use super::{HubLoop, Measure, Reply, StepReading, Then, UpdateAnswer};
use crate::encoder::{read_joints, AbsoluteEncoder};
use crate::table::MAX_JOINTS;
use crate::temperature::TemperatureSensor;
use crate::update::session::Step;

/// How often the temperature sensor is polled.
pub const TEMP_PERIOD_US: u64 = 250_000;

/// Polls in a row that may find no new conversion of a sensor converting once a second
/// before its reading counts as stale: two seconds' worth (`quatarm_drivers::Tmp117::new`).
pub const TEMP_STALE_POLLS: u16 = (2_000_000 / TEMP_PERIOD_US) as u16;

/// A [`HubLoop`] that also samples the hub's own sensors when one is due ([`Live::tick`]).
pub struct Live<S = Step> {
    hub: HubLoop<S>,
    period_us: u64,
    /// When the next sample is due, µs.
    next: u64,
    /// When the thermometer is polled next, µs.
    next_temp: u64,
    /// The last poll's temperature, m°C; `None` after a failed poll.
    temp_mc: Option<i32>,
    /// The sensor's state when last logged: only its changes are.
    #[cfg(feature = "defmt")]
    temp_ok: bool,
}

impl<S: StepReading> Live<S> {
    /// The live loop of `hub` (whose greeting has been sent), a sample every `period_us`, the
    /// first and the first temperature poll at `now_us` (on the clock `tick` is given).
    pub fn new(hub: HubLoop<S>, period_us: u64, now_us: u64) -> Live<S> {
        Live {
            hub,
            period_us,
            next: now_us,
            next_temp: now_us,
            temp_mc: None,
            #[cfg(feature = "defmt")]
            temp_ok: true,
        }
    }

    /// The loop inside.
    pub fn hub(&self) -> &HubLoop<S> {
        &self.hub
    }

    /// Feeds one received byte ([`HubLoop::receive`]); the end of a replay restarts the
    /// sampling at `now_us()`.
    pub fn receive<M: Measure>(
        &mut self,
        byte: u8,
        mut now_us: impl FnMut() -> u64,
        chain: &mut M,
        update: impl FnOnce(&S) -> UpdateAnswer,
    ) -> Reply<'_> {
        let reply = self.hub.receive(byte, &mut now_us, chain, update);
        if reply.then == Then::Ended {
            self.next = now_us();
        }
        reply
    }

    /// The report of a sample if one is due at `now_us()` and no replay is under way: the
    /// thermometer polled first when its poll is due, then every encoder (joint 1 first; a
    /// failed read is its joint's fault bit, [`read_joints`]). `None`: nothing to send yet.
    pub fn tick<M: Measure, E: AbsoluteEncoder, T: TemperatureSensor>(
        &mut self,
        mut now_us: impl FnMut() -> u64,
        encoders: &mut [E],
        thermometer: &mut T,
        chain: &M,
    ) -> Option<Reply<'_>> {
        if self.hub.replaying() || now_us() < self.next {
            return None;
        }
        self.next += self.period_us;
        if now_us() >= self.next_temp {
            self.next_temp += TEMP_PERIOD_US;
            self.poll(thermometer);
        }
        let mut counts = [0u32; MAX_JOINTS];
        let joints = encoders.len().min(MAX_JOINTS);
        let faults = read_joints(&mut encoders[..joints], &mut counts[..joints]);
        let temp_mc = self.temp_mc;
        Some(
            self.hub
                .sample(now_us(), &counts[..joints], faults, temp_mc, chain),
        )
    }

    /// Reads the thermometer; its failure is logged once, as is its return.
    fn poll<T: TemperatureSensor>(&mut self, thermometer: &mut T) {
        self.temp_mc = thermometer.read_mc().ok();
        #[cfg(feature = "defmt")]
        {
            match (self.temp_mc, self.temp_ok) {
                (None, true) => defmt::warn!("temperature sensor: no valid reading"),
                (Some(t), false) => defmt::info!("temperature sensor back: {=i32} mC", t),
                _ => {}
            }
            self.temp_ok = self.temp_mc.is_some();
        }
    }
}

#[cfg(test)]
mod tests {
    use core::cell::Cell;

    use super::*;
    use crate::stream::serve::tests::{decoded, fake, frame, reading, valid_hub};
    use crate::stream::{Replay, Report, Status, ToDevice, ToHost};

    struct Encoder(Result<u32, ()>);

    impl AbsoluteEncoder for Encoder {
        type Error = ();
        fn counts_per_rev(&self) -> u32 {
            1 << 14
        }
        fn read_count(&mut self) -> Result<u32, ()> {
            self.0
        }
    }

    /// A thermometer that answers from a list and counts its polls.
    struct Thermometer {
        answers: Vec<Result<i32, ()>>,
        polls: usize,
    }

    impl TemperatureSensor for Thermometer {
        type Error = ();
        fn read_mc(&mut self) -> Result<i32, ()> {
            self.polls += 1;
            self.answers[(self.polls - 1).min(self.answers.len() - 1)]
        }
    }

    fn encoders() -> [Encoder; 6] {
        [1, 2, 3, 4, 5, 6].map(|c| Encoder(Ok(c)))
    }

    fn report(reply: Option<Reply<'_>>) -> Report {
        let reply = reply.expect("a sample was due");
        match decoded(reply.send)[..] {
            [ToHost::Report(r)] => r,
            ref other => panic!("{other:?}"),
        }
    }

    #[test]
    fn samples_come_at_the_period_and_the_temperature_at_its_own() {
        let clock = Cell::new(1_000);
        let now = || clock.get();
        let mut live = Live::new(
            HubLoop::<Step>::new(valid_hub(), Replay::new()),
            1_000,
            now(),
        );
        let mut enc = encoders();
        let mut thermo = Thermometer {
            answers: vec![Ok(21_000), Err(()), Ok(22_000)],
            polls: 0,
        };
        let chain = fake();
        let r = report(live.tick(now, &mut enc, &mut thermo, &chain));
        assert_eq!(
            (r.time_us, r.point.unwrap().xyz_nm),
            (1_000, [1, 21_000, 0])
        );
        assert!(live.tick(now, &mut enc, &mut thermo, &chain).is_none());
        clock.set(1_999);
        assert!(live.tick(now, &mut enc, &mut thermo, &chain).is_none());
        // One sample per period, on the old temperature until its next poll.
        for k in 1..250 {
            clock.set(1_000 + 1_000 * k);
            let r = report(live.tick(now, &mut enc, &mut thermo, &chain));
            assert_eq!((r.seq, r.point.unwrap().xyz_nm[1]), (k as u32, 21_000));
        }
        assert_eq!(thermo.polls, 1);
        // The second poll fails: no coordinates until one succeeds.
        clock.set(251_000);
        let r = report(live.tick(now, &mut enc, &mut thermo, &chain));
        assert!(r.point.is_none() && r.status.has(Status::TEMP_SENSOR_FAULT));
        clock.set(501_000);
        for _ in 0..249 {
            // Late: the samples missed catch up one per tick, the poll once.
            let _ = report(live.tick(now, &mut enc, &mut thermo, &chain));
        }
        assert_eq!(thermo.polls, 3);
        let r = report(live.tick(now, &mut enc, &mut thermo, &chain));
        assert_eq!(r.point.unwrap().xyz_nm[1], 22_000);
    }

    #[test]
    fn a_failed_encoder_is_its_joints_fault() {
        let clock = Cell::new(0);
        let mut live = Live::new(HubLoop::<Step>::new(valid_hub(), Replay::new()), 1_000, 0);
        let mut enc = encoders();
        enc[2] = Encoder(Err(()));
        enc[4] = Encoder(Ok(1 << 14)); // out of range: a fault too, never a guess
        let mut thermo = Thermometer {
            answers: vec![Ok(20_000)],
            polls: 0,
        };
        let r = report(live.tick(|| clock.get(), &mut enc, &mut thermo, &fake()));
        assert_eq!((r.point, r.status.encoder_faults()), (None, 0b1_0100));
    }

    /// A replay takes over from the encoders until its `End`; sampling restarts at the end,
    /// not in a burst of the samples the replay held back.
    #[test]
    fn a_replay_holds_the_sampling_until_its_end() {
        let clock = Cell::new(0);
        let now = || clock.get();
        let mut live = Live::new(HubLoop::<Step>::new(valid_hub(), Replay::new()), 1_000, 0);
        let (mut enc, mut chain) = (encoders(), fake());
        let mut thermo = Thermometer {
            answers: vec![Ok(20_000)],
            polls: 0,
        };
        let _ = report(live.tick(now, &mut enc, &mut thermo, &chain));
        let mut sent = Vec::new();
        for b in frame(&ToDevice::Reading(reading(77))) {
            sent.extend(live.receive(b, now, &mut chain, |_| unreachable!()).send);
        }
        assert_eq!(decoded(&sent).len(), 1);
        clock.set(10_000);
        assert!(live.tick(now, &mut enc, &mut thermo, &chain).is_none());
        for b in frame(&ToDevice::End) {
            let reply = live.receive(b, now, &mut chain, |_| unreachable!());
            assert!(reply.send.is_empty());
        }
        let r = report(live.tick(now, &mut enc, &mut thermo, &chain));
        assert_eq!((r.time_us, r.seq), (10_000, 2));
        assert!(live.tick(now, &mut enc, &mut thermo, &chain).is_none());
    }
}
