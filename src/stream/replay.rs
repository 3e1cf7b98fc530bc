//! The replay source: recorded readings arriving as [`ToDevice`] frames on the UART's receive
//! side, in place of the hub's own encoders.
//!
//! The QEMU boards have no encoders and use it for everything; a real board can use it for a
//! hardware-in-the-loop run (a recording in, the stream out, compared with the host). A frame
//! that fails its checks is not dropped silently: it becomes [`Event::InputError`], for which
//! the hub sends a report with `INPUT_ERROR` and no coordinates, so the output keeps one report
//! per incoming reading and a host can line them up.

use super::{FrameError, FrameReader, Mode, Reading, ToDevice, MAX_FRAME};
use crate::update::session::Step;

/// What one incoming frame asks of the hub.
#[derive(Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// A reading to evaluate.
    Reading(Reading),
    /// A frame that failed COBS, CRC or decoding: one slot without coordinates.
    InputError(FrameError),
    /// Switch the output format.
    SetMode(Mode),
    /// The recording is over.
    End,
    /// A step of a calibration update.
    Update(Step),
}

/// Turns received bytes into [`Event`]s.
#[derive(Default)]
pub struct Replay {
    reader: FrameReader<MAX_FRAME>,
}

impl Replay {
    /// A replay source at the start of a recording (the first byte starts a frame).
    pub const fn new() -> Replay {
        Replay {
            reader: FrameReader::new(),
        }
    }

    /// Feeds one received byte; returns an event when it closes a frame.
    pub fn push(&mut self, byte: u8) -> Option<Event> {
        self.reader.push::<ToDevice>(byte).map(|r| match r {
            Ok(ToDevice::Reading(reading)) => Event::Reading(reading),
            Ok(ToDevice::SetMode(m)) => Event::SetMode(m),
            Ok(ToDevice::End) => Event::End,
            Ok(ToDevice::Update(step)) => Event::Update(step),
            Err(e) => Event::InputError(e),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stream::{encode, Counts};

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
        bytes.extend(frame(&ToDevice::End));
        assert_eq!(
            events(&bytes),
            vec![
                Event::SetMode(Mode::Text),
                Event::Reading(reading(0)),
                Event::Reading(reading(1)),
                Event::Reading(reading(2)),
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
