//! Frames: postcard bytes, a CRC-32 over them, COBS around both, one `0x00` after.
//!
//! Two steps rather than one stacked postcard flavor, so that the CRC provably covers the
//! message bytes (not their COBS encoding) and each step can be tested on its own.

use serde::de::DeserializeOwned;
use serde::Serialize;

/// CRC-32/ISCSI (Castagnoli): of the common 32-bit polynomials it keeps the largest Hamming
/// distance for frames of this length (HD 6 up to 5,243 bits), so any 5 flipped bits are seen.
pub const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISCSI);

/// Largest message, postcard bytes plus the 4 CRC bytes, that a frame carries.
pub const MAX_PAYLOAD: usize = 64;

/// Largest frame on the wire: COBS adds one byte per 254 (and one), then the delimiter.
pub const MAX_FRAME: usize = MAX_PAYLOAD + MAX_PAYLOAD / 254 + 1 + 1;

const CRC_LEN: usize = 4;

/// Why a frame was refused. Each kind is counted apart by `armcal decode`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FrameError {
    /// The bytes between two delimiters are not valid COBS.
    Cobs,
    /// Too few bytes for a message and its CRC.
    TooShort,
    /// The CRC does not match: the frame was damaged on the way.
    Crc,
    /// The CRC matched but the bytes are not a message of this protocol version.
    Decode,
    /// More bytes than [`MAX_FRAME`] before a delimiter: a lost delimiter or line noise.
    Overflow,
    /// (encoding) The message or the output buffer is too small for the frame.
    BufferTooSmall,
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            FrameError::Cobs => "invalid COBS encoding",
            FrameError::TooShort => "frame too short for a message and its CRC",
            FrameError::Crc => "CRC mismatch",
            FrameError::Decode => "CRC good but not a message of this protocol version",
            FrameError::Overflow => "frame longer than the protocol allows",
            FrameError::BufferTooSmall => "buffer too small for the frame",
        })
    }
}

impl core::error::Error for FrameError {}

/// Writes `msg` as one complete frame, delimiter included, into `out`; returns its length.
pub fn encode<T: Serialize>(msg: &T, out: &mut [u8]) -> Result<usize, FrameError> {
    let mut raw = [0u8; MAX_PAYLOAD];
    let n = postcard::to_slice(msg, &mut raw[..MAX_PAYLOAD - CRC_LEN])
        .map_err(|_| FrameError::BufferTooSmall)?
        .len();
    let crc = CRC.checksum(&raw[..n]);
    raw[n..n + CRC_LEN].copy_from_slice(&crc.to_le_bytes());
    let len = cobs::try_encode(&raw[..n + CRC_LEN], out).map_err(|_| FrameError::BufferTooSmall)?;
    let end = out.get_mut(len).ok_or(FrameError::BufferTooSmall)?;
    *end = 0;
    Ok(len + 1)
}

/// Decodes one frame, given the bytes between two delimiters (without them). The buffer is
/// COBS-decoded in place. A message must use every byte: trailing bytes are a `Decode` error.
pub fn decode<T: DeserializeOwned>(frame: &mut [u8]) -> Result<T, FrameError> {
    decode_message(check(frame)?)
}

/// Decodes a message from its bytes (a frame's, as [`FrameReader::push_message`] gives
/// them), which it must use every one of: trailing bytes are a `Decode` error.
pub fn decode_message<T: DeserializeOwned>(body: &[u8]) -> Result<T, FrameError> {
    match postcard::take_from_bytes::<T>(body) {
        Ok((msg, [])) => Ok(msg),
        _ => Err(FrameError::Decode),
    }
}

/// The message bytes of one frame (COBS-decoded in place, the CRC checked and cut off),
/// given the bytes between two delimiters.
fn check(frame: &mut [u8]) -> Result<&[u8], FrameError> {
    if frame.len() > MAX_FRAME - 1 {
        return Err(FrameError::Overflow);
    }
    if frame.contains(&0) {
        return Err(FrameError::Cobs);
    }
    let n = cobs::decode_in_place(frame).map_err(|_| FrameError::Cobs)?;
    if n <= CRC_LEN {
        return Err(FrameError::TooShort);
    }
    let (body, crc) = frame[..n].split_at(n - CRC_LEN);
    let sent = u32::from_le_bytes([crc[0], crc[1], crc[2], crc[3]]);
    if CRC.checksum(body) != sent {
        return Err(FrameError::Crc);
    }
    Ok(body)
}

/// Collects bytes from a UART (one at a time, as an interrupt or a poll loop gets them) or a
/// host reader, and hands out each frame as its delimiter arrives.
///
/// A reader made with [`FrameReader::joining`] drops everything up to the first delimiter, so
/// a host that opens a port mid-frame does not count the tail it caught as an error. An
/// empty frame (two delimiters in a row) is idle line, not an error.
pub struct FrameReader<const N: usize = MAX_FRAME> {
    buf: [u8; N],
    len: usize,
    overflowed: bool,
    hunting: bool,
    skipped: usize,
}

impl<const N: usize> Default for FrameReader<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> FrameReader<N> {
    /// A reader that takes the first byte as the start of a frame (a link that starts with
    /// the sender, as QEMU's UART does).
    pub const fn new() -> Self {
        FrameReader {
            buf: [0; N],
            len: 0,
            overflowed: false,
            hunting: false,
            skipped: 0,
        }
    }

    /// A reader for a link already running: bytes before the first delimiter are skipped.
    pub const fn joining() -> Self {
        let mut r = Self::new();
        r.hunting = true;
        r
    }

    /// Bytes skipped while looking for the first delimiter.
    pub fn skipped(&self) -> usize {
        self.skipped
    }

    /// Feeds one byte; returns a decoded message, or why the frame was refused, when `byte`
    /// closes a frame.
    pub fn push<T: DeserializeOwned>(&mut self, byte: u8) -> Option<Result<T, FrameError>> {
        self.push_message(byte).map(|r| r.and_then(decode_message))
    }

    /// Feeds one byte; returns the message bytes of a frame that passed its checks (COBS,
    /// length, CRC; the CRC cut off), or why it was refused, when `byte` closes a frame. For a
    /// reader that looks at a message before it decodes it (`super::Replay::without_update`).
    pub fn push_message(&mut self, byte: u8) -> Option<Result<&[u8], FrameError>> {
        if self.hunting {
            if byte == 0 {
                self.hunting = false;
            } else {
                self.skipped += 1;
            }
            return None;
        }
        if byte != 0 {
            match self.buf.get_mut(self.len) {
                Some(slot) => {
                    *slot = byte;
                    self.len += 1;
                }
                None => self.overflowed = true,
            }
            return None;
        }
        let (len, overflowed) = (self.len, self.overflowed);
        self.len = 0;
        self.overflowed = false;
        if overflowed {
            return Some(Err(FrameError::Overflow));
        }
        if len == 0 {
            return None;
        }
        Some(check(&mut self.buf[..len]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stream::{Coordinates, Counts, Reading, Report, Status, ToDevice, ToHost};
    use proptest::prelude::*;

    fn report(seq: u32) -> ToHost {
        ToHost::Report(Report {
            seq,
            time_us: 1_234_567_890_123,
            status: Status(Status::TABLE_VALID),
            point: Some(Coordinates {
                xyz_nm: [i32::MAX, i32::MIN, -1_234_567_890],
                dir_e9: [-1_000_000_000, 1, 999_999_999],
                u95_nm: Some(u32::MAX),
            }),
            probe: u8::MAX,
        })
    }

    fn frame_of(msg: &ToHost) -> Vec<u8> {
        let mut out = [0u8; MAX_FRAME];
        let n = encode(msg, &mut out).unwrap();
        out[..n].to_vec()
    }

    /// The sizes `docs/protocol.md` states: 12 bytes for the shortest report, 63 for the
    /// longest (58 without its U95, as the fixed-point hubs send it); a probe id above 127
    /// takes no more, postcard writing a `u8` as one raw byte.
    #[test]
    fn report_sizes_are_as_documented() {
        let short = ToHost::Report(Report {
            seq: 0,
            time_us: 0,
            status: Status(0),
            point: None,
            probe: 0,
        });
        assert_eq!(frame_of(&short).len(), 12);
        let long = ToHost::Report(Report {
            seq: u32::MAX,
            time_us: u64::MAX,
            status: Status(u16::MAX),
            point: Some(Coordinates {
                xyz_nm: [i32::MIN; 3],
                dir_e9: [i32::MIN; 3],
                u95_nm: Some(u32::MAX),
            }),
            probe: 255,
        });
        assert_eq!(frame_of(&long).len(), 63);
        let ToHost::Report(r) = long else {
            unreachable!()
        };
        let without = ToHost::Report(Report {
            point: r.point.map(|p| Coordinates { u95_nm: None, ..p }),
            ..r
        });
        assert_eq!(frame_of(&without).len(), 58);
    }

    /// Coordinates of protocol 2 (ending after `dir_e9`) decode, with no U95; protocol 3's
    /// round-trip with it. And a report of protocol 4 is refused by a reader of protocol 3's
    /// layout, which finds its probe byte left over (`Report`'s docs: why it is last).
    #[test]
    fn older_coordinates_decode_and_an_older_reader_refuses_a_protocol_4_report() {
        let c = Coordinates {
            xyz_nm: [1, -2, 3],
            dir_e9: [0, 0, 1_000_000_000],
            u95_nm: Some(4_321),
        };
        let mut buf = [0u8; MAX_PAYLOAD];
        let bytes = postcard::to_slice(&c, &mut buf).unwrap().to_vec();
        // Protocol 3 ends with the option's tag 1 and the varint 4321 (2 bytes).
        assert_eq!(&bytes[bytes.len() - 3..], [1, 0xe1, 0x21]);
        let v2 = &bytes[..bytes.len() - 3];
        let got: Coordinates = postcard::from_bytes(v2).unwrap();
        assert_eq!(got, Coordinates { u95_nm: None, ..c });
        assert_eq!(postcard::from_bytes::<Coordinates>(&bytes).unwrap(), c);
        #[derive(serde::Deserialize)]
        #[allow(dead_code)] // read only to be refused
        struct ReportV3 {
            seq: u32,
            time_us: u64,
            status: Status,
            point: Option<Coordinates>,
        }
        for probe in [0, 1, 2, 255] {
            for point in [None, Some(c), Some(Coordinates { u95_nm: None, ..c })] {
                let v4 = Report {
                    seq: 5,
                    time_us: 77,
                    status: Status(Status::TABLE_VALID),
                    point,
                    probe,
                };
                let bytes = postcard::to_slice(&v4, &mut buf).unwrap();
                assert!(
                    !matches!(postcard::take_from_bytes::<ReportV3>(bytes), Ok((_, []))),
                    "{v4:?}"
                );
                assert_eq!(postcard::from_bytes::<Report>(bytes).unwrap(), v4);
            }
        }
        // Where the id is not: right after the status, probe 1 before a point without U95
        // whose direction ends at -1e-9 reads whole as an older report, with its coordinates
        // shifted by one field (the reason the id is last).
        let after_status = (
            5u32,
            77u64,
            Status(Status::TABLE_VALID),
            1u8,
            Some(Coordinates {
                xyz_nm: [10, 20, 30],
                dir_e9: [0, 1_000_000_000, -1],
                u95_nm: None,
            }),
        );
        let bytes = postcard::to_slice(&after_status, &mut buf).unwrap();
        match postcard::take_from_bytes::<ReportV3>(bytes) {
            Ok((misread, [])) => assert_eq!(
                misread.point.map(|c| c.xyz_nm),
                Some([-1, 10, 20]),
                "read whole, and wrong"
            ),
            other => panic!("{:?}", other.map(|_| ())),
        }
    }

    fn read_all(reader: &mut FrameReader, bytes: &[u8]) -> Vec<Result<ToHost, FrameError>> {
        bytes.iter().filter_map(|&b| reader.push(b)).collect()
    }

    #[test]
    fn worst_case_messages_fit_a_frame() {
        // The largest report: every varint at its longest.
        let frame = frame_of(&report(u32::MAX));
        assert!(frame.len() <= MAX_FRAME, "{} > {MAX_FRAME}", frame.len());
        assert_eq!(frame.iter().filter(|&&b| b == 0).count(), 1);
        assert_eq!(*frame.last().unwrap(), 0);
        let reading = ToDevice::Reading(Reading {
            seq: u32::MAX,
            counts: Counts::new(&[u32::MAX; 7]).unwrap(),
            temp_mc: i32::MIN,
            faults: 0xFF,
        });
        let mut out = [0u8; MAX_FRAME];
        let n = encode(&reading, &mut out).unwrap();
        let mut r = FrameReader::<MAX_FRAME>::new();
        let got: Vec<_> = out[..n]
            .iter()
            .filter_map(|&b| r.push::<ToDevice>(b))
            .collect();
        assert_eq!(got, vec![Ok(reading)]);
    }

    #[test]
    fn overflow_starts_past_65_bytes_before_a_delimiter() {
        // docs/protocol.md: a good frame is at most MAX_FRAME bytes with its 0x00, so 65
        // bytes before a delimiter are judged on their content and 66 are an overflow.
        let mut r = FrameReader::<MAX_FRAME>::new();
        let mut at_limit = vec![1u8; MAX_FRAME - 1];
        at_limit.push(0);
        let got = read_all(&mut r, &at_limit);
        assert_eq!(got.len(), 1);
        assert_ne!(got[0], Err(FrameError::Overflow));
        let mut past = vec![1u8; MAX_FRAME];
        past.push(0);
        assert_eq!(read_all(&mut r, &past), vec![Err(FrameError::Overflow)]);
    }

    #[test]
    fn crc_is_over_the_postcard_bytes() {
        let msg = report(7);
        let mut frame = frame_of(&msg);
        let n = frame.len() - 1;
        let len = cobs::decode_in_place(&mut frame[..n]).unwrap();
        let body = postcard::to_slice(&msg, &mut [0u8; 64]).unwrap().to_vec();
        assert_eq!(&frame[..len - 4], &body[..]);
        assert_eq!(frame[len - 4..len], CRC.checksum(&body).to_le_bytes());
    }

    #[test]
    fn a_reader_joining_mid_frame_resynchronises() {
        let mut stream = Vec::new();
        for seq in 0..3 {
            stream.extend(frame_of(&report(seq)));
        }
        // Start 5 bytes into the first frame.
        let mut r = FrameReader::<MAX_FRAME>::joining();
        let got = read_all(&mut r, &stream[5..]);
        assert_eq!(got, vec![Ok(report(1)), Ok(report(2))]);
        assert_eq!(r.skipped(), frame_of(&report(0)).len() - 5 - 1);
    }

    #[test]
    fn idle_delimiters_are_not_errors() {
        let mut stream = vec![0, 0];
        stream.extend(frame_of(&report(1)));
        stream.extend([0, 0, 0]);
        let got = read_all(&mut FrameReader::<MAX_FRAME>::new(), &stream);
        assert_eq!(got, vec![Ok(report(1))]);
    }

    #[test]
    fn a_lost_delimiter_costs_two_frames_then_the_stream_recovers() {
        let mut stream = Vec::new();
        for seq in 0..4 {
            let mut f = frame_of(&report(seq));
            if seq == 1 {
                f.pop(); // the delimiter of frame 1 is lost
            }
            stream.extend(f);
        }
        let got = read_all(&mut FrameReader::<MAX_FRAME>::new(), &stream);
        assert_eq!(got.len(), 3);
        assert_eq!(got[0], Ok(report(0)));
        assert!(got[1].is_err());
        assert_eq!(got[2], Ok(report(3)));
    }

    #[test]
    fn overflow_is_reported_and_the_next_frame_is_fine() {
        let mut stream = vec![0x55u8; 3 * MAX_FRAME];
        stream.push(0);
        stream.extend(frame_of(&report(9)));
        let got = read_all(&mut FrameReader::<MAX_FRAME>::new(), &stream);
        assert_eq!(got, vec![Err(FrameError::Overflow), Ok(report(9))]);
    }

    #[test]
    fn trailing_bytes_after_a_message_are_refused() {
        // A valid CRC over a message with one byte too many: not this protocol.
        let body = postcard::to_slice(&report(3), &mut [0u8; 64])
            .unwrap()
            .to_vec();
        let mut raw = body.clone();
        raw.push(0x42);
        raw.extend(CRC.checksum(&raw).to_le_bytes());
        let mut enc = vec![0u8; 80];
        let n = cobs::encode(&raw, &mut enc);
        assert_eq!(decode::<ToHost>(&mut enc[..n]), Err(FrameError::Decode));
    }

    proptest! {
        /// Any single flipped bit in a frame is caught, never decoded as another message.
        #[test]
        fn every_single_bit_flip_is_caught(seq in any::<u32>(), bit in 0usize..(8 * 60)) {
            let frame = frame_of(&report(seq));
            let bit = bit % (8 * (frame.len() - 1));
            let mut bad = frame.clone();
            bad[bit / 8] ^= 1 << (bit % 8);
            let got = read_all(&mut FrameReader::<MAX_FRAME>::new(), &bad);
            prop_assert!(!got.is_empty());
            prop_assert!(got.iter().all(|r| r.is_err()), "{got:?}");
        }

        /// Random line noise never panics the reader and never yields a message that was
        /// not sent (a CRC-32 collision is possible in principle, at 2^-32 per frame).
        #[test]
        fn noise_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
            let mut r = FrameReader::<MAX_FRAME>::joining();
            for b in bytes {
                let _ = r.push::<ToHost>(b);
            }
        }

        #[test]
        fn reports_round_trip(seq in any::<u32>(), t in any::<u64>(), s in any::<u16>(),
                              xyz in any::<[i32; 3]>(), dir in any::<[i32; 3]>(), some in any::<bool>(),
                              u95 in any::<Option<u32>>(), probe in any::<u8>()) {
            let msg = ToHost::Report(Report {
                seq, time_us: t, status: Status(s),
                point: some.then_some(Coordinates { xyz_nm: xyz, dir_e9: dir, u95_nm: u95 }),
                probe,
            });
            let frame = frame_of(&msg);
            prop_assert_eq!(read_all(&mut FrameReader::<MAX_FRAME>::new(), &frame), vec![Ok(msg)]);
        }
    }
}
