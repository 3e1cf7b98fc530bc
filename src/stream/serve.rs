//! The hub's loop without its peripherals: received bytes in, bytes to send out.
//!
//! Every board runs the same conversation with its host: a lone delimiter and a `Hello` at
//! boot, then for each incoming frame a report, a mode switch, a probe selection, an update
//! step or the end of a replay ([`Event`]). [`HubLoop`] holds that dispatch once, so that it
//! is tested here on the host and a board's loop only moves bytes between its UART and the
//! [`Reply`] it is given (`board_common::serve`, `board_common::live`). The board supplies
//! what touches its hardware as arguments: the µs clock, the chain ([`Measure`]) and the
//! update port (a closure carrying out one step on its flash).
//!
//! With the `defmt` feature the loop logs what the boards logged before it moved here (the
//! hub's start, damaged frames, the end of a replay, a committed update); the QEMU end-to-end
//! tests read those lines.

use super::{Coordinates, Event, Hub, Replay, StepReading, ToHost, UpdateAnswer, MAX_OUTPUT};
use crate::update::session::Step;
use crate::update::Accepted;

/// What the loop asks of the board's calibration: run the chain, mount a probe.
pub trait Measure {
    /// Why the chain gave no point (any error gives `CHAIN_ERROR`).
    type Error;
    /// The point of one reading: encoder `counts` (joint 1 first) at `temp_mc` m°C.
    fn eval(&self, counts: &[u32], temp_mc: i32) -> Result<Coordinates, Self::Error>;
    /// Converts the table's probe `k` (its index in the table) into the chain's numbers;
    /// `false` where it cannot, and the probe before stays ([`Hub::select`]).
    fn mount(&mut self, k: usize) -> bool;
}

/// What the board does once it has sent a [`Reply`]'s bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Then {
    /// Keep going.
    Continue,
    /// The host ended its replay: a replay hub stops, a live hub samples its encoders again.
    Ended,
    /// An update committed a new table: boot again on it (a new chain, a new `Hello`), as a
    /// reset would.
    Boot,
}

/// The loop's answer to one event: bytes to send (often none), then what to do.
#[derive(Debug, PartialEq, Eq)]
pub struct Reply<'a> {
    /// Bytes for the link, in order; empty when the event asks for no answer.
    pub send: &'a [u8],
    /// What follows.
    pub then: Then,
}

/// The hub's loop: a [`Hub`] and the decoder of its receive side, dispatching each decoded
/// frame; `S` is how update steps are read ([`StepReading`]).
pub struct HubLoop<S = Step> {
    hub: Hub,
    replay: Replay<S>,
    /// A rendered message; one byte more than [`MAX_OUTPUT`] for the greeting's lone
    /// delimiter in front of the `Hello` (which has its own).
    out: [u8; MAX_OUTPUT + 1],
    /// A replay is under way: a reading arrived since the start or the last `End`.
    replaying: bool,
    /// Reports and damaged frames of the replay under way, for the log at its end.
    reports: u32,
    input_errors: u32,
}

impl<S: StepReading> HubLoop<S> {
    /// The loop of `hub`, decoding what arrives with `replay` ([`Replay::new`], or
    /// [`Replay::without_update`] on a hub without an update port).
    pub fn new(hub: Hub, replay: Replay<S>) -> HubLoop<S> {
        HubLoop {
            hub,
            replay,
            out: [0; MAX_OUTPUT + 1],
            replaying: false,
            reports: 0,
            input_errors: 0,
        }
    }

    /// The hub whose state the loop keeps.
    pub fn hub(&self) -> &Hub {
        &self.hub
    }

    /// Whether the host is replaying readings (one arrived since the start or the last
    /// `End`): a live hub does not sample its own encoders meanwhile.
    pub fn replaying(&self) -> bool {
        self.replaying
    }

    /// What the hub sends first: a lone delimiter, so that whoever listens is in sync from
    /// the first frame on, then the `Hello`.
    pub fn greeting(&mut self) -> &[u8] {
        #[cfg(feature = "defmt")]
        defmt::info!(
            "hub up: table {}, {=u8} joints, {}, probe {=u8}",
            self.hub.table(),
            self.hub.joints(),
            self.hub.precision(),
            self.hub.probe()
        );
        let (first, rest) = self.out.split_at_mut(1);
        first[0] = 0;
        let n = self.hub.render(&self.hub.hello(), rest).len();
        &self.out[..n + 1]
    }

    /// Feeds one received byte. Nothing to send until it closes a frame; then the answer to
    /// the frame's event ([`HubLoop::handle`]). `now_us` is read only when a report is made.
    pub fn receive<M: Measure>(
        &mut self,
        byte: u8,
        now_us: impl FnOnce() -> u64,
        chain: &mut M,
        update: impl FnOnce(&S) -> UpdateAnswer,
    ) -> Reply<'_> {
        match self.replay.push(byte) {
            Some(event) => self.handle(event, now_us, chain, update),
            None => Reply {
                send: &[],
                then: Then::Continue,
            },
        }
    }

    /// The answer to one event: a reading or a damaged frame gives a report stamped
    /// `now_us()` (`chain` evaluating it where [`Hub::report`] allows), a mode switch a
    /// `Hello` in the new mode, a probe selection its answer (`chain` mounting the probe), an
    /// update step the answer of `update`, which carries it out (and [`Then::Boot`] once it
    /// committed), `End` nothing and [`Then::Ended`].
    pub fn handle<M: Measure>(
        &mut self,
        event: Event<S>,
        now_us: impl FnOnce() -> u64,
        chain: &mut M,
        update: impl FnOnce(&S) -> UpdateAnswer,
    ) -> Reply<'_> {
        let eval = |counts: &[u32], temp_mc| chain.eval(counts, temp_mc);
        let report = match event {
            Event::Reading(r) => {
                self.replaying = true;
                self.hub.report(now_us(), Ok(&r), eval)
            }
            Event::InputError(e) => {
                self.input_errors = self.input_errors.wrapping_add(1);
                #[cfg(feature = "defmt")]
                defmt::warn!("damaged input frame: {}", e);
                self.hub.report(now_us(), Err(e), eval)
            }
            Event::SetMode(m) => {
                self.hub.set_mode(m);
                return self.send(&self.hub.hello(), Then::Continue);
            }
            Event::SelectProbe(id) => {
                let answer = self.hub.select(id, |k| chain.mount(k));
                return self.send(&ToHost::Probe(answer), Then::Continue);
            }
            Event::Update(step) => return self.answer_update(update(&step)),
            Event::End => return self.end(),
        };
        self.reports = self.reports.wrapping_add(1);
        self.send(&ToHost::Report(report), Then::Continue)
    }

    /// The report for one sample of the hub's own sensors ([`Hub::report_sample`]), rendered.
    pub fn sample<M: Measure>(
        &mut self,
        time_us: u64,
        counts: &[u32],
        faults: u8,
        temp_mc: Option<i32>,
        chain: &M,
    ) -> Reply<'_> {
        let report = self
            .hub
            .report_sample(time_us, counts, faults, temp_mc, |c, t| chain.eval(c, t));
        self.send(&ToHost::Report(report), Then::Continue)
    }

    /// The answer to an update step, a frame in either output mode; [`Then::Boot`] once it
    /// committed a new table.
    fn answer_update(&mut self, answer: UpdateAnswer) -> Reply<'_> {
        let then = match answer {
            Ok(Accepted::Committed { slot, seq }) => {
                #[cfg(feature = "defmt")]
                defmt::info!("update committed: slot {=u8}, record {=u32}", slot, seq);
                #[cfg(not(feature = "defmt"))]
                let _ = (slot, seq);
                Then::Boot
            }
            _ => Then::Continue,
        };
        self.send(&ToHost::Update(answer), then)
    }

    /// The host's `End`: the replay's counts logged and started again.
    fn end(&mut self) -> Reply<'_> {
        #[cfg(feature = "defmt")]
        defmt::info!(
            "replay done: {=u32} reports, {=u32} damaged input frames",
            self.reports,
            self.input_errors
        );
        self.replaying = false;
        self.reports = 0;
        self.input_errors = 0;
        Reply {
            send: &[],
            then: Then::Ended,
        }
    }

    /// `msg` rendered in the current mode.
    fn send(&mut self, msg: &ToHost, then: Then) -> Reply<'_> {
        Reply {
            send: self.hub.render(msg, &mut self.out),
            then,
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::stream::{
        encode, Counts, FrameReader, Mode, NumberFormat, ProbeRefusal, Reading, Report, Status,
        TableState, ToDevice, Unread, CSV_HEADER, MAX_FRAME,
    };
    use crate::update::session::Step;
    use crate::update::Refusal;

    /// A chain that gives one point per reading (its first count as x) and mounts the probes
    /// it is told it has.
    pub(in crate::stream) struct Fake {
        pub probes: usize,
        pub mounted: Option<usize>,
    }

    impl Measure for Fake {
        type Error = ();
        fn eval(&self, counts: &[u32], temp_mc: i32) -> Result<Coordinates, ()> {
            Ok(Coordinates {
                xyz_nm: [counts[0] as i32, temp_mc, 0],
                dir_e9: [0, 0, 1_000_000_000],
                u95_nm: None,
            })
        }
        fn mount(&mut self, k: usize) -> bool {
            self.mounted = Some(k);
            k < self.probes
        }
    }

    pub(in crate::stream) fn fake() -> Fake {
        Fake {
            probes: 2,
            mounted: None,
        }
    }

    pub(in crate::stream) fn valid_hub() -> Hub {
        Hub::new(TableState::Valid, 6, NumberFormat::F32).with_probes([3, 8])
    }

    pub(in crate::stream) fn reading(first: u32) -> Reading {
        Reading {
            seq: 0,
            counts: Counts::new(&[first, 2, 3, 4, 5, 6]).unwrap(),
            temp_mc: 20_000,
            faults: 0,
        }
    }

    pub(in crate::stream) fn frame(msg: &ToDevice) -> Vec<u8> {
        let mut out = [0u8; MAX_FRAME];
        let n = encode(msg, &mut out).unwrap();
        out[..n].to_vec()
    }

    /// Every message in `bytes` as the host decodes it.
    pub(in crate::stream) fn decoded(bytes: &[u8]) -> Vec<ToHost> {
        let mut reader = FrameReader::<MAX_FRAME>::new();
        bytes
            .iter()
            .filter_map(|&b| reader.push::<ToHost>(b))
            .map(|m| m.expect("the hub sent a damaged frame"))
            .collect()
    }

    /// Feeds `bytes` to `hub`; the bytes it sent, and the `Then` of every non-`Continue`
    /// reply. `update` answers every step.
    fn run<S: StepReading>(
        hub: &mut HubLoop<S>,
        chain: &mut Fake,
        bytes: &[u8],
        update: impl Fn(&S) -> UpdateAnswer,
    ) -> (Vec<u8>, Vec<Then>) {
        let (mut sent, mut thens) = (Vec::new(), Vec::new());
        for (t, &b) in bytes.iter().enumerate() {
            let reply = hub.receive(b, || t as u64, chain, &update);
            sent.extend_from_slice(reply.send);
            if reply.then != Then::Continue {
                thens.push(reply.then);
            }
        }
        (sent, thens)
    }

    fn no_update(_: &Step) -> UpdateAnswer {
        panic!("no update step was sent")
    }

    #[test]
    fn the_greeting_is_a_lone_delimiter_then_the_hello() {
        let mut hub = HubLoop::new(valid_hub(), Replay::new());
        let hello = hub.hub().hello();
        let bytes = hub.greeting().to_vec();
        assert_eq!(
            &bytes[..2],
            &[0, 0],
            "a lone delimiter, then the Hello's own"
        );
        assert_eq!(decoded(&bytes), vec![hello]);
    }

    #[test]
    fn readings_and_damaged_frames_each_give_one_numbered_report() {
        let mut hub = HubLoop::new(valid_hub(), Replay::new());
        let mut chain = fake();
        let mut input = frame(&ToDevice::Reading(reading(11)));
        let mut damaged = frame(&ToDevice::Reading(reading(12)));
        damaged[3] ^= 0x40; // a flipped bit: the CRC fails
        input.extend(&damaged);
        input.extend(frame(&ToDevice::Reading(reading(13))));
        assert!(!hub.replaying());
        let (sent, thens) = run(&mut hub, &mut chain, &input, no_update);
        assert!(thens.is_empty());
        assert!(hub.replaying(), "a reading starts a replay");
        let reports: Vec<Report> = decoded(&sent)
            .into_iter()
            .map(|m| match m {
                ToHost::Report(r) => r,
                other => panic!("{other:?}"),
            })
            .collect();
        assert_eq!(reports.len(), 3);
        assert_eq!(reports.iter().map(|r| r.seq).collect::<Vec<_>>(), [0, 1, 2]);
        assert_eq!(reports[0].point.unwrap().xyz_nm[0], 11);
        assert_eq!(reports[0].probe, 3, "the first probe is mounted at boot");
        assert!(reports[1].point.is_none() && reports[1].status.has(Status::INPUT_ERROR));
        assert_eq!(reports[2].point.unwrap().xyz_nm, [13, 20_000, 0]);
        // Stamped by the clock when the frame closed (the test's clock: the byte's index).
        assert_eq!(reports[2].time_us, input.len() as u64 - 1);
    }

    #[test]
    fn end_ends_the_replay_and_sends_nothing() {
        let mut hub = HubLoop::new(valid_hub(), Replay::new());
        let mut input = frame(&ToDevice::Reading(reading(1)));
        input.extend(frame(&ToDevice::End));
        let (sent, thens) = run(&mut hub, &mut fake(), &input, no_update);
        assert_eq!(decoded(&sent).len(), 1, "the reading's report only");
        assert_eq!(thens, [Then::Ended]);
        assert!(!hub.replaying());
    }

    #[test]
    fn a_mode_switch_answers_with_a_hello_in_the_new_mode() {
        let mut hub = HubLoop::new(valid_hub(), Replay::new());
        let mut input = frame(&ToDevice::SetMode(Mode::Text));
        input.extend(frame(&ToDevice::Reading(reading(1))));
        let (sent, _) = run(&mut hub, &mut fake(), &input, no_update);
        let text = core::str::from_utf8(&sent).unwrap();
        assert!(text.starts_with(CSV_HEADER), "{text}");
        assert!(text[CSV_HEADER.len()..].starts_with("0,"), "{text}");
        assert_eq!(hub.hub().mode(), Mode::Text);
    }

    #[test]
    fn a_probe_selection_is_mounted_and_answered() {
        let mut hub = HubLoop::new(valid_hub(), Replay::new());
        let mut chain = fake();
        let mut input = frame(&ToDevice::SelectProbe(8));
        input.extend(frame(&ToDevice::SelectProbe(5)));
        input.extend(frame(&ToDevice::Reading(reading(1))));
        let (sent, _) = run(&mut hub, &mut chain, &input, no_update);
        let got = decoded(&sent);
        assert_eq!(got[0], ToHost::Probe(Ok(8)));
        assert_eq!(got[1], ToHost::Probe(Err(ProbeRefusal::Unknown)));
        assert_eq!(chain.mounted, Some(1), "id 8 is the table's second probe");
        match got[2] {
            ToHost::Report(r) => assert_eq!(r.probe, 8),
            ref other => panic!("{other:?}"),
        }
    }

    #[test]
    fn update_steps_are_carried_out_and_a_commit_boots() {
        let mut hub = HubLoop::new(valid_hub(), Replay::new());
        let steps = [Step::Abort, Step::Commit];
        let mut input = Vec::new();
        for s in &steps {
            input.extend(frame(&ToDevice::Update(s.clone())));
        }
        let answer = |s: &Step| match s {
            Step::Commit => Ok(Accepted::Committed { slot: 1, seq: 7 }),
            _ => Err(Refusal::NotBegun),
        };
        let (sent, thens) = run(&mut hub, &mut fake(), &input, answer);
        assert_eq!(
            decoded(&sent),
            [
                ToHost::Update(Err(Refusal::NotBegun)),
                ToHost::Update(Ok(Accepted::Committed { slot: 1, seq: 7 }))
            ]
        );
        assert_eq!(thens, [Then::Boot]);
    }

    #[test]
    fn an_update_answer_is_a_frame_in_text_mode_too() {
        let mut hub = HubLoop::new(valid_hub(), Replay::new());
        let mut input = frame(&ToDevice::SetMode(Mode::Text));
        input.extend(frame(&ToDevice::Update(Step::Abort)));
        let (sent, _) = run(&mut hub, &mut fake(), &input, |_| Ok(Accepted::Aborted));
        let answer = &sent[CSV_HEADER.len()..];
        assert_eq!(answer[0], 0, "behind a lone delimiter");
        assert_eq!(decoded(answer), [ToHost::Update(Ok(Accepted::Aborted))]);
    }

    /// A hub without an update port refuses each step without decoding it, and keeps
    /// answering readings.
    #[test]
    fn without_an_update_port_every_step_is_refused() {
        let mut hub = HubLoop::new(valid_hub(), Replay::without_update());
        let mut input = frame(&ToDevice::Update(Step::Commit));
        input.extend(frame(&ToDevice::Reading(reading(1))));
        let refuse = |_: &Unread| Err(Refusal::NotSupported);
        let (sent, thens) = run(&mut hub, &mut fake(), &input, refuse);
        let got = decoded(&sent);
        assert_eq!(got[0], ToHost::Update(Err(Refusal::NotSupported)));
        assert!(matches!(got[1], ToHost::Report(r) if r.point.is_some()));
        assert!(thens.is_empty());
    }

    #[test]
    fn without_a_table_readings_give_reports_without_coordinates() {
        let hub = Hub::new(TableState::Corrupt, 6, NumberFormat::Fixed);
        let mut hub = HubLoop::new(hub, Replay::new());
        let mut chain = fake();
        let input = frame(&ToDevice::Reading(reading(1)));
        let (sent, _) = run(&mut hub, &mut chain, &input, no_update);
        match decoded(&sent)[..] {
            [ToHost::Report(r)] => {
                assert_eq!((r.point, r.status.table()), (None, TableState::Corrupt))
            }
            ref other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_sample_is_reported_at_its_time() {
        let mut hub = HubLoop::<Step>::new(valid_hub(), Replay::new());
        let reply = hub.sample(42, &[9, 2, 3, 4, 5, 6], 0, Some(21_000), &fake());
        assert_eq!(reply.then, Then::Continue);
        match decoded(reply.send)[..] {
            [ToHost::Report(r)] => {
                assert_eq!((r.time_us, r.point.unwrap().xyz_nm), (42, [9, 21_000, 0]))
            }
            ref other => panic!("{other:?}"),
        }
        let reply = hub.sample(43, &[9, 2, 3, 4, 5, 6], 0, None, &fake());
        match decoded(reply.send)[..] {
            [ToHost::Report(r)] => assert!(r.status.has(Status::TEMP_SENSOR_FAULT)),
            ref other => panic!("{other:?}"),
        }
    }
}
