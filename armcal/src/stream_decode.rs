//! Reading a hub's stream on the host: frames to messages, with the counts a person needs to
//! trust it (sequence gaps, damaged frames). `armcal decode`, `cargo xtask demo` and the QEMU
//! end-to-end tests all read streams through this one decoder.

use quatarm::stream::{FrameError, FrameReader, Hello, Report, ToHost, MAX_FRAME};

/// One item of a decoded stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Item {
    /// A boot or mode-change announcement.
    Hello(Hello),
    /// A report.
    Report(Report),
    /// A frame that failed its checks.
    Damaged(FrameError),
}

/// What a decoder has seen so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Reports decoded.
    pub reports: u64,
    /// Reports that carried coordinates.
    pub points: u64,
    /// Reports missing between consecutive sequence numbers (a restart, seq back to 0 after a
    /// `Hello`, is not a gap).
    pub lost: u64,
    /// Frames whose CRC did not match.
    pub crc_errors: u64,
    /// Frames refused for another reason (COBS, length, undecodable after a good CRC).
    pub other_errors: u64,
    /// Bytes skipped before the first delimiter (joining a running stream).
    pub skipped_bytes: u64,
}

impl Stats {
    /// Every damaged frame, whatever the check that caught it.
    pub fn damaged(&self) -> u64 {
        self.crc_errors + self.other_errors
    }
}

/// A stream decoder: feed bytes, get items.
pub struct Decoder {
    reader: FrameReader<MAX_FRAME>,
    next_seq: Option<u32>,
    stats: Stats,
}

impl Decoder {
    /// A decoder for a stream captured from its start (a QEMU run, a file written from boot).
    pub fn from_start() -> Decoder {
        Decoder {
            reader: FrameReader::new(),
            next_seq: None,
            stats: Stats::default(),
        }
    }

    /// A decoder for a stream joined while running (a serial port opened on a live hub): bytes
    /// before the first delimiter are skipped, not counted as damage.
    pub fn joining() -> Decoder {
        Decoder {
            reader: FrameReader::joining(),
            ..Decoder::from_start()
        }
    }

    /// The counts so far.
    pub fn stats(&self) -> Stats {
        Stats {
            skipped_bytes: self.reader.skipped() as u64,
            ..self.stats
        }
    }

    /// Feeds one byte.
    pub fn push(&mut self, byte: u8) -> Option<Item> {
        let item = match self.reader.push::<ToHost>(byte)? {
            Ok(ToHost::Hello(h)) => {
                // A hub that (re)boots numbers from 0 again.
                self.next_seq = None;
                Item::Hello(h)
            }
            Ok(ToHost::Report(r)) => {
                if let Some(expected) = self.next_seq {
                    self.stats.lost += u64::from(r.seq.wrapping_sub(expected));
                }
                self.next_seq = Some(r.seq.wrapping_add(1));
                self.stats.reports += 1;
                self.stats.points += u64::from(r.point.is_some());
                Item::Report(r)
            }
            Err(e) => {
                match e {
                    FrameError::Crc => self.stats.crc_errors += 1,
                    _ => self.stats.other_errors += 1,
                }
                Item::Damaged(e)
            }
        };
        Some(item)
    }

    /// Feeds a buffer; returns the items it completed.
    pub fn push_all(&mut self, bytes: &[u8]) -> Vec<Item> {
        bytes.iter().filter_map(|&b| self.push(b)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use quatarm::stream::{encode, Coordinates, Status};

    fn frame(seq: u32) -> Vec<u8> {
        let msg = ToHost::Report(Report {
            seq,
            time_us: u64::from(seq) * 1000,
            status: Status(Status::TABLE_VALID),
            point: Some(Coordinates {
                xyz_nm: [1, 2, 3],
                dir_e9: [0, 0, 1_000_000_000],
            }),
        });
        let mut out = [0u8; MAX_FRAME];
        let n = encode(&msg, &mut out).unwrap();
        out[..n].to_vec()
    }

    #[test]
    fn gaps_and_damage_are_counted() {
        let mut bytes = Vec::new();
        for seq in [0, 1, 2, 5, 6] {
            bytes.extend(frame(seq));
        }
        let mut bad = frame(7);
        bad[3] ^= 0x20;
        bytes.extend(bad);
        bytes.extend(frame(8));
        let mut d = Decoder::from_start();
        let items = d.push_all(&bytes);
        assert_eq!(items.len(), 7);
        let s = d.stats();
        assert_eq!(
            (s.reports, s.points, s.lost),
            (6, 6, 3),
            "5 and 6 after 2: two lost; 8 after 6: one"
        );
        assert_eq!(s.damaged(), 1);
    }

    #[test]
    fn joining_mid_frame_is_not_damage() {
        let mut bytes = frame(0);
        bytes.extend(frame(1));
        let mut d = Decoder::joining();
        let items = d.push_all(&bytes[4..]);
        assert_eq!(items.len(), 1);
        assert_eq!(d.stats().damaged(), 0);
        assert_eq!(d.stats().skipped_bytes as usize, frame(0).len() - 5);
    }
}
