//! The replay source: recorded readings arriving as [`ToDevice`] frames on the UART's receive
//! side, in place of the hub's own encoders.
//!
//! The QEMU boards have no encoders and use it for everything; a real board can use it for a
//! hardware-in-the-loop run (a recording in, the stream out, compared with the host). A frame
//! that fails its checks is not dropped silently: it becomes [`Event::InputError`], for which
//! the hub sends a report with `INPUT_ERROR` and no coordinates, so the output keeps one report
//! per incoming reading and a host can line them up.

use core::marker::PhantomData;

use serde::de::DeserializeOwned;

use super::message::UPDATE_INDEX;
use super::{
    decode_message, FrameError, FrameReader, Mode, Reading, ToDeviceOf, Unread, MAX_FRAME,
};
use crate::update::session::Step;

/// What one incoming frame asks of the hub; `S` the update step as the hub reads it ([`Step`],
/// or [`Unread`] on a hub without an update port).
#[derive(Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event<S = Step> {
    /// A reading to evaluate.
    Reading(Reading),
    /// A frame that failed COBS, CRC or decoding: one slot without coordinates.
    InputError(FrameError),
    /// Switch the output format.
    SetMode(Mode),
    /// The recording is over.
    End,
    /// A step of a calibration update.
    Update(S),
    /// Mount the probe of this id.
    SelectProbe(u8),
}

/// How a hub reads update steps: whole ([`Step`]), or not at all ([`Unread`]).
pub trait StepReading: DeserializeOwned {
    /// What an update frame gives without being decoded; `None` where it is decoded.
    const UNREAD: Option<Self>;
}

impl StepReading for Step {
    const UNREAD: Option<Step> = None;
}

impl StepReading for Unread {
    const UNREAD: Option<Unread> = Some(Unread);
}

/// Turns received bytes into [`Event`]s.
pub struct Replay<S = Step> {
    reader: FrameReader<MAX_FRAME>,
    steps: PhantomData<S>,
}

impl Default for Replay {
    fn default() -> Self {
        Self::new()
    }
}

impl Replay {
    /// A replay source at the start of a recording (the first byte starts a frame).
    pub const fn new() -> Replay {
        Replay {
            reader: FrameReader::new(),
            steps: PhantomData,
        }
    }
}

impl Replay<Unread> {
    /// A replay source for a hub without an update port: an update step is known by its
    /// frame's variant index alone and never decoded, so that the hub's image holds no
    /// decoder for steps it only refuses (720 bytes of the qemu-m0 image, measured).
    pub const fn without_update() -> Replay<Unread> {
        Replay {
            reader: FrameReader::new(),
            steps: PhantomData,
        }
    }
}

impl<S: StepReading> Replay<S> {
    /// Feeds one received byte; returns an event when it closes a frame.
    pub fn push(&mut self, byte: u8) -> Option<Event<S>> {
        let message = match self.reader.push_message(byte)? {
            Ok(m) => m,
            Err(e) => return Some(Event::InputError(e)),
        };
        if let (Some(unread), Some(&UPDATE_INDEX)) = (S::UNREAD, message.first()) {
            return Some(Event::Update(unread));
        }
        Some(match decode_message::<ToDeviceOf<S>>(message) {
            Ok(ToDeviceOf::Reading(reading)) => Event::Reading(reading),
            Ok(ToDeviceOf::SetMode(m)) => Event::SetMode(m),
            Ok(ToDeviceOf::End) => Event::End,
            Ok(ToDeviceOf::Update(step)) => Event::Update(step),
            Ok(ToDeviceOf::SelectProbe(id)) => Event::SelectProbe(id),
            Err(e) => Event::InputError(e),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stream::{encode, Counts, ToDevice};

    fn frame(msg: &ToDevice) -> Vec<u8> {
        let mut out = [0u8; MAX_FRAME];
        let n = encode(msg, &mut out).unwrap();
        out[..n].to_vec()
    }

    fn events(bytes: &[u8]) -> Vec<Event> {
        let mut r = Replay::new();
        bytes.iter().filter_map(|&b| r.push(b)).collect()
    }

    fn reading(seq: u32) -> Reading {
        Reading {
            seq,
            counts: Counts::new(&[seq, 2, 3, 4, 5, 6]).unwrap(),
            temp_mc: 21_500,
            faults: 0,
        }
    }

    #[test]
    fn a_recording_replays_in_order() {
        let mut bytes = Vec::new();
        bytes.extend(frame(&ToDevice::SetMode(Mode::Text)));
        for seq in 0..3 {
            bytes.extend(frame(&ToDevice::Reading(reading(seq))));
        }
        bytes.extend(frame(&ToDevice::SelectProbe(200)));
        bytes.extend(frame(&ToDevice::End));
        assert_eq!(
            events(&bytes),
            vec![
                Event::SetMode(Mode::Text),
                Event::Reading(reading(0)),
                Event::Reading(reading(1)),
                Event::Reading(reading(2)),
                Event::SelectProbe(200),
                Event::End
            ]
        );
    }

    #[test]
    fn a_flipped_bit_costs_exactly_its_own_slot() {
        let mut bytes = Vec::new();
        for seq in 0..3 {
            let mut f = frame(&ToDevice::Reading(reading(seq)));
            if seq == 1 {
                // Flip a bit that does not make a 0x00 (which would split the frame in two).
                let i = f.iter().position(|&b| b & 0x04 != 0 && b != 0x04).unwrap();
                f[i] ^= 0x04;
            }
            bytes.extend(f);
        }
        let got = events(&bytes);
        assert_eq!(got.len(), 3);
        assert_eq!(got[0], Event::Reading(reading(0)));
        assert!(matches!(got[1], Event::InputError(_)), "{:?}", got[1]);
        assert_eq!(got[2], Event::Reading(reading(2)));
    }

    /// A hub without an update port knows an update step by its variant index alone: every
    /// step is `Update(Unread)`, a damaged one still an input error, and every other message
    /// gives the event a full replay gives.
    #[test]
    fn without_an_update_port_steps_are_known_by_their_index() {
        use crate::update::session::Step;
        let table = crate::update::fixtures::table(100.0);
        let steps: Vec<Step> = Step::sequence(&table).chain([Step::Abort]).collect();
        let mut bytes = Vec::new();
        let mut want = Vec::new();
        for step in &steps {
            bytes.extend(frame(&ToDevice::Update(step.clone())));
            want.push(Event::Update(Unread));
        }
        let others = [
            ToDevice::Reading(reading(3)),
            ToDevice::SelectProbe(9),
            ToDevice::SetMode(Mode::Text),
            ToDevice::End,
        ];
        for m in &others {
            bytes.extend(frame(m));
        }
        let mut damaged = frame(&ToDevice::Update(Step::Commit));
        damaged[1] ^= 0x10;
        bytes.extend(&damaged);
        let mut lean = Replay::without_update();
        let got: Vec<Event<Unread>> = bytes.iter().filter_map(|&b| lean.push(b)).collect();
        assert_eq!(&got[..steps.len()], &want[..]);
        let full = events(&bytes);
        assert_eq!(
            full[..steps.len()],
            steps.iter().cloned().map(Event::Update).collect::<Vec<_>>()[..]
        );
        for (a, b) in got[steps.len()..].iter().zip(&full[steps.len()..]) {
            match (a, b) {
                (Event::Reading(x), Event::Reading(y)) => assert_eq!(x, y),
                (Event::SelectProbe(x), Event::SelectProbe(y)) => assert_eq!(x, y),
                (Event::SetMode(x), Event::SetMode(y)) => assert_eq!(x, y),
                (Event::End, Event::End) => {}
                (Event::InputError(x), Event::InputError(y)) => assert_eq!(x, y),
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(got.len(), full.len());
        assert!(matches!(
            got.last(),
            Some(Event::InputError(FrameError::Crc))
        ));
    }

    /// A frame built by hand: a `Reading` whose count sequence claims `n` counts.
    fn hand_made_reading(n: u8) -> Vec<u8> {
        // variant 0 (Reading), seq 1, n counts of 1, temp 0, faults 0.
        let mut body = vec![0u8, 1, n];
        body.extend(vec![1u8; usize::from(n)]);
        body.extend([0, 0]);
        body.extend(crate::stream::CRC.checksum(&body).to_le_bytes());
        let mut enc = vec![0u8; 64];
        let len = cobs::encode(&body, &mut enc);
        enc.truncate(len);
        enc.push(0);
        enc
    }

    #[test]
    fn more_than_seven_counts_is_refused() {
        match events(&hand_made_reading(7)).as_slice() {
            [Event::Reading(r)] => assert_eq!(r.counts.as_slice(), &[1; 7]),
            other => panic!("{other:?}"),
        }
        assert_eq!(
            events(&hand_made_reading(8)),
            vec![Event::InputError(FrameError::Decode)]
        );
    }
}
