//! Reading a hub's stream on the host: frames to messages, with the counts a person needs to
//! trust it (sequence gaps, damaged frames, frames that came twice or out of order, reports
//! that break the protocol's rule on coordinates). `armcal decode`, `cargo xtask demo` and the
//! QEMU end-to-end tests all read streams through this one decoder.
//!
//! The decoder's promise is the product's: it never hands out coordinates it cannot vouch
//! for. A report whose status carries a fault but which holds coordinates anyway (a hub never
//! sends one; a broken or foreign hub might) is handed out without them.
//!
//! Reports are read by the protocol the last `Hello` announced: protocols 4 and 5 (whose
//! reports are the same; 5 added the calibration's number and date to `Hello`) end each with
//! the mounted probe's id, protocols 1 to 3 have none (their hubs had one probe, id 0, which the
//! decoder gives them). After a `Hello` of a protocol it does not know, it reads this
//! protocol's; before any `Hello` (a stream joined mid-way, a capture cut after the hub's
//! boot), this protocol's or, failing that, an older one's: a report of either is a byte
//! short of the other's layout or one over, so no frame reads as both.

use quatarm::stream::{
    decode_message, Coordinates, FrameError, FrameReader, Hello, ProbeAnswer, Report, Status,
    ToHost, UpdateAnswer, MAX_FRAME, PROTOCOL_VERSION,
};
use quatarm::table::probes::MAX_PROBES;
use serde::Deserialize;

/// A forward jump of the sequence number up to this size is a gap (lost reports); a larger
/// one is a step backwards modulo 2^32 (at ~1,700 reports/s, 2^31 reports are two weeks).
const MAX_FORWARD_GAP: u32 = 1 << 31;

/// One item of a decoded stream.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Item {
    /// A boot or mode-change announcement.
    Hello(Hello),
    /// A report, in sequence (perhaps after a gap, counted as lost).
    Report(Report),
    /// A report whose sequence number went backwards without a `Hello` (a hub reset whose
    /// announcement was lost, or frames reordered on the way): the numbering restarts from
    /// it; nothing is counted lost.
    Backward {
        /// The report.
        report: Report,
        /// The sequence number that was due.
        expected: u32,
    },
    /// The same report as the one before it, byte for byte (a frame repeated on the way):
    /// not a new reading, so not to be written again.
    Repeated(Report),
    /// A report that breaks a rule of `docs/protocol.md` that its frame's checks cannot see
    /// (the reason is the second field): handed out without coordinates, whatever it carried.
    Inconsistent(Report, Inconsistency),
    /// The hub's answer to a calibration update step (`docs/update.md`).
    Update(UpdateAnswer),
    /// The hub's answer to a probe selection: the id now mounted, or why not.
    Probe(ProbeAnswer),
    /// A frame that failed its checks.
    Damaged(FrameError),
}

impl Item {
    /// The report to write out for this item, if any: every report except a repeated one.
    pub fn report(&self) -> Option<&Report> {
        match self {
            Item::Report(r) | Item::Backward { report: r, .. } | Item::Inconsistent(r, _) => {
                Some(r)
            }
            Item::Hello(_)
            | Item::Repeated(_)
            | Item::Update(_)
            | Item::Probe(_)
            | Item::Damaged(_) => None,
        }
    }
}

/// Why a report is [`Item::Inconsistent`]: each a rule of `docs/protocol.md` ("What a decoder
/// refuses"), the first that applies in this order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Inconsistency {
    /// The status word contradicts itself: bit 0 (valid table) beside a table state other
    /// than 0, state 0 without bit 0, or a reserved state (9 to 15). F5 of
    /// `../shared/repro/round2`.
    Status,
    /// Coordinates beside a status that forbids them (a fault bit, an invalid table).
    Forbidden,
    /// No coordinates although the status has no fault.
    Missing,
    /// A report of a probe the last `Hello` (protocol 4 or 5) does not list (0 where it lists
    /// none).
    UnknownProbe,
    /// A probe direction that is no unit vector (its length off 1 by more than
    /// [`DIRECTION_TOLERANCE_E9`] units of 1e-9; a zero direction among them).
    Direction,
}

/// How far a report's direction may be from unit length, in units of 1e-9 of its length
/// (1e-3). Both chains give it within 1e-6 (`docs/protocol.md`); anything further is not a
/// direction a hub computed.
pub const DIRECTION_TOLERANCE_E9: i64 = 1_000_000;

/// True if `dir_e9` is a unit vector within [`DIRECTION_TOLERANCE_E9`] (exact integer
/// arithmetic: each component is an `i32`, so the squares sum in an `i128` without overflow).
pub fn is_unit_direction(dir_e9: [i32; 3]) -> bool {
    let len2: i128 = dir_e9.iter().map(|&c| i128::from(c) * i128::from(c)).sum();
    let (lo, hi) = (
        i128::from(1_000_000_000 - DIRECTION_TOLERANCE_E9),
        i128::from(1_000_000_000 + DIRECTION_TOLERANCE_E9),
    );
    (lo * lo..=hi * hi).contains(&len2)
}

/// What a decoder has seen so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// `Hello` announcements decoded.
    pub hellos: u64,
    /// Answers to update steps decoded.
    pub updates: u64,
    /// Answers to probe selections decoded.
    pub probe_answers: u64,
    /// Reports decoded (repeated ones not included).
    pub reports: u64,
    /// Reports that carried coordinates, as handed out.
    pub points: u64,
    /// Reports missing between consecutive sequence numbers (a restart, seq back to 0 after a
    /// `Hello`, is not a gap). A damaged report frame shows up here too, as the gap it left.
    pub lost: u64,
    /// Reports whose sequence number went backwards without a `Hello`.
    pub backward: u64,
    /// Reports that repeated the one before them exactly.
    pub repeated: u64,
    /// Reports that broke a rule their frame's checks cannot see (see [`Inconsistency`]).
    pub inconsistent: u64,
    /// Frames whose CRC did not match.
    pub crc_errors: u64,
    /// Frames refused for another reason (COBS, length, undecodable after a good CRC).
    pub other_errors: u64,
    /// Of `other_errors`, frames whose CRC was good but which are not a message of this
    /// protocol version (an unknown `ToHost` variant, a newer hub; or a field no encoder
    /// writes: an option tag other than 0 or 1, a varint beyond its type, bytes left over):
    /// reported apart because they mean "wrong or broken sender", not "bad line".
    pub undecodable: u64,
    /// `Hello`s announcing a `protocol` this decoder does not read (it reads 1 to
    /// [`PROTOCOL_VERSION`], 5: the same messages, protocol 2 adding `Hello::live` and the
    /// update messages, protocol 3 the coordinates' U95, protocol 4 the probes, protocol 5
    /// the calibration's number and date in `Hello`).
    pub foreign_protocol: u64,
    /// Bytes skipped before the first delimiter (joining a running stream).
    pub skipped_bytes: u64,
    /// Bytes after the last delimiter that never closed a frame, at the end of the input
    /// (counted by [`Decoder::finish`]).
    pub unterminated_bytes: u64,
}

impl Stats {
    /// Every damaged frame, whatever the check that caught it; an unterminated tail counts
    /// as one.
    pub fn damaged(&self) -> u64 {
        self.crc_errors + self.other_errors + u64::from(self.unterminated_bytes > 0)
    }

    /// Frames that passed every check.
    pub fn valid_frames(&self) -> u64 {
        self.hellos + self.reports + self.repeated + self.updates + self.probe_answers
    }
}

/// A stream decoder: feed bytes, get items.
pub struct Decoder {
    reader: FrameReader<MAX_FRAME>,
    /// The last report handed out since the last `Hello` (for gaps and repeats).
    last: Option<Report>,
    /// Bytes since the last delimiter (after the first one when joining).
    open: u64,
    /// The protocol the last `Hello` announced, by which reports are read (`None` before the
    /// first).
    protocol: Option<u16>,
    /// The probe ids a report may name: those the last `Hello` of protocol 4 or 5 listed (`[0]`
    /// where it listed none: a hub without a valid table); `None` before one (a stream
    /// joined mid-way, an older protocol), when any id passes.
    probes: Option<heapless::Vec<u8, MAX_PROBES>>,
    stats: Stats,
}

/// A hub→host message of protocols 1 to 3: reports without the probe's id.
#[derive(Deserialize)]
enum Legacy {
    Hello(Hello),
    Report(LegacyReport),
    Update(UpdateAnswer),
}

/// A report of protocols 1 to 3 ([`Report`] without `probe`; its coordinates read as
/// [`Coordinates`] reads those of every protocol).
#[derive(Deserialize)]
struct LegacyReport {
    seq: u32,
    time_us: u64,
    status: Status,
    point: Option<Coordinates>,
}

impl From<Legacy> for ToHost {
    fn from(m: Legacy) -> ToHost {
        match m {
            Legacy::Hello(h) => ToHost::Hello(h),
            Legacy::Update(a) => ToHost::Update(a),
            // The only probe a table had before protocol 4: id 0 (the header's byte 44,
            // reserved and 0 then).
            Legacy::Report(r) => ToHost::Report(Report {
                seq: r.seq,
                time_us: r.time_us,
                status: r.status,
                point: r.point,
                probe: 0,
            }),
        }
    }
}

impl Decoder {
    /// A decoder for a stream captured from its start (a QEMU run, a file written from boot).
    pub fn from_start() -> Decoder {
        Decoder {
            reader: FrameReader::new(),
            last: None,
            open: 0,
            protocol: None,
            probes: None,
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

    /// The counts so far (without the unterminated tail, which only the end of input tells).
    pub fn stats(&self) -> Stats {
        Stats {
            skipped_bytes: self.reader.skipped() as u64,
            ..self.stats
        }
    }

    /// The counts at the end of the input: bytes after the last delimiter are an
    /// unterminated frame (a capture cut mid-frame, line noise, or a text-mode capture,
    /// which has no delimiter at all), not silence.
    pub fn finish(&self) -> Stats {
        let joined_before = self.reader.skipped() as u64;
        Stats {
            unterminated_bytes: self.open.saturating_sub(joined_before),
            ..self.stats()
        }
    }

    /// Feeds one byte.
    pub fn push(&mut self, byte: u8) -> Option<Item> {
        if byte == 0 {
            self.open = 0;
        } else {
            self.open += 1;
        }
        let legacy = |body| decode_message::<Legacy>(body).map(ToHost::from);
        let message = self
            .reader
            .push_message(byte)?
            .and_then(|body| match self.protocol {
                Some(1..=3) => legacy(body),
                Some(_) => decode_message::<ToHost>(body),
                None => decode_message::<ToHost>(body).or_else(|_| legacy(body)),
            });
        let item = match message {
            Ok(ToHost::Hello(h)) => {
                // A hub that (re)boots numbers from 0 again.
                self.last = None;
                self.stats.hellos += 1;
                let known = (1..=PROTOCOL_VERSION).contains(&h.protocol);
                self.stats.foreign_protocol += u64::from(!known);
                self.protocol = Some(if known { h.protocol } else { PROTOCOL_VERSION });
                self.probes = match h.protocol {
                    4 | 5 if h.probes.is_empty() => heapless::Vec::from_slice(&[0]).ok(),
                    4 | 5 => Some(h.probes.clone()),
                    _ => None,
                };
                Item::Hello(h)
            }
            Ok(ToHost::Report(r)) => self.report(r),
            Ok(ToHost::Update(a)) => {
                self.stats.updates += 1;
                Item::Update(a)
            }
            Ok(ToHost::Probe(a)) => {
                self.stats.probe_answers += 1;
                Item::Probe(a)
            }
            Err(e) => {
                match e {
                    FrameError::Crc => self.stats.crc_errors += 1,
                    FrameError::Decode => {
                        self.stats.other_errors += 1;
                        self.stats.undecodable += 1;
                    }
                    _ => self.stats.other_errors += 1,
                }
                Item::Damaged(e)
            }
        };
        Some(item)
    }

    /// Places a decoded report in the sequence and checks it against the coordinates rule.
    fn report(&mut self, mut r: Report) -> Item {
        if self.last == Some(r) {
            self.stats.repeated += 1;
            return Item::Repeated(r);
        }
        let mut backward = None;
        if let Some(prev) = self.last {
            let expected = prev.seq.wrapping_add(1);
            let gap = r.seq.wrapping_sub(expected);
            if gap < MAX_FORWARD_GAP {
                self.stats.lost += u64::from(gap);
            } else {
                self.stats.backward += 1;
                backward = Some(expected);
            }
        }
        self.last = Some(r);
        self.stats.reports += 1;
        if let Some(why) = self.inconsistency(&r) {
            self.stats.inconsistent += 1;
            r.point = None;
            return Item::Inconsistent(r, why);
        }
        self.stats.points += u64::from(r.point.is_some());
        match backward {
            Some(expected) => Item::Backward {
                report: r,
                expected,
            },
            None => Item::Report(r),
        }
    }

    /// The first rule of `docs/protocol.md` the report breaks that its frame's checks cannot
    /// see, if any.
    fn inconsistency(&self, r: &Report) -> Option<Inconsistency> {
        let listed = |probes: &heapless::Vec<u8, MAX_PROBES>| probes.contains(&r.probe);
        Some(if !r.status.is_coherent() {
            Inconsistency::Status
        } else if r.point.is_some() && !r.status.is_measurement() {
            Inconsistency::Forbidden
        } else if r.point.is_none() && r.status.is_measurement() {
            Inconsistency::Missing
        } else if !self.probes.as_ref().is_none_or(listed) {
            Inconsistency::UnknownProbe
        } else if r.point.is_some_and(|p| !is_unit_direction(p.dir_e9)) {
            Inconsistency::Direction
        } else {
            return None;
        })
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

    const POINT: Coordinates = Coordinates {
        xyz_nm: [1, 2, 3],
        dir_e9: [0, 0, 1_000_000_000],
        u95_nm: Some(4_000),
    };

    fn report(seq: u32) -> Report {
        Report {
            seq,
            time_us: u64::from(seq) * 1000,
            status: Status(Status::TABLE_VALID),
            point: Some(POINT),
            probe: 7,
        }
    }

    /// A frame of `msg` as postcard writes it (tuples field by field, as enums and structs).
    fn raw_frame(msg: &impl serde::Serialize) -> Vec<u8> {
        let mut out = [0u8; MAX_FRAME];
        let n = encode(msg, &mut out).unwrap();
        out[..n].to_vec()
    }

    /// A protocol-3 report of `seq` as an older hub sends it: no probe id after the point.
    fn v3_frame(seq: u32, point: Option<Coordinates>) -> Vec<u8> {
        let r = report(seq);
        raw_frame(&(1u8, r.seq, r.time_us, r.status, point))
    }

    /// Captures of protocols 3 and 4 decode by the protocol their `Hello` announced: a
    /// protocol-3 report with the only probe an older hub had, id 0; a protocol-4 one with
    /// its own. A report of one layout under a `Hello` of the other is refused, not misread.
    #[test]
    fn reports_are_read_by_the_protocol_of_the_last_hello() {
        let hello = |protocol: u16| raw_frame(&(0u8, protocol, 0u8, 6u8, 1u16, None::<u8>));
        // Protocol 4's Hello: the mounted probe and the ids after `live` (a tuple: `Hello`
        // itself serialises protocol 5's layout, the number and date after them).
        let v4_hello = raw_frame(&(
            0u8,
            4u16,
            quatarm::stream::NumberFormat::F32,
            6u8,
            Status(Status::TABLE_VALID),
            None::<u8>,
            7u8,
            &[7u8, 2][..],
        ));
        let no_u95 = Coordinates {
            u95_nm: None,
            ..POINT
        };
        let bytes = [
            hello(3),
            v3_frame(0, Some(POINT)),
            v3_frame(1, None),
            frame(2),
            v4_hello,
            frame(0),
            v3_frame(1, Some(POINT)),
            frame_of(Report {
                point: Some(no_u95),
                ..report(2)
            }),
            hello(2),
            v3_frame(0, Some(no_u95)),
        ]
        .concat();
        let mut d = Decoder::from_start();
        let items = d.push_all(&bytes);
        let reports: Vec<(u32, u8, Option<u32>)> = items
            .iter()
            .filter_map(Item::report)
            .map(|r| (r.seq, r.probe, r.point.and_then(|p| p.u95_nm)))
            .collect();
        assert_eq!(
            reports,
            [
                (0, 0, Some(4_000)),
                (1, 0, None),
                (0, 7, Some(4_000)),
                (2, 7, None),
                (0, 0, None)
            ]
        );
        match &items[4] {
            Item::Hello(h) => assert_eq!((h.probe, h.probes.as_slice()), (7, &[7, 2][..])),
            other => panic!("{other:?}"),
        }
        let s = d.finish();
        assert_eq!((s.undecodable, s.foreign_protocol, s.hellos), (2, 0, 3));
        assert!(matches!(items[3], Item::Damaged(FrameError::Decode)));
        assert!(matches!(items[6], Item::Damaged(FrameError::Decode)));
    }

    /// Without a `Hello` (a capture joined mid-stream) both layouts are read, each report by
    /// the one it fits; a probe selection's answer is an item of its own.
    #[test]
    fn without_a_hello_either_layout_is_read_and_probe_answers_are_counted() {
        let bytes = [
            v3_frame(0, Some(POINT)),
            frame(1),
            raw_frame(&ToHost::Probe(Ok(2))),
            raw_frame(&ToHost::Probe(Err(quatarm::stream::ProbeRefusal::Unknown))),
        ]
        .concat();
        let mut d = Decoder::joining();
        let items = d.push_all(&[&[0u8][..], &bytes].concat());
        assert_eq!(items[0].report().map(|r| r.probe), Some(0));
        assert_eq!(items[1].report().map(|r| r.probe), Some(7));
        assert_eq!(items[2], Item::Probe(Ok(2)));
        assert_eq!(
            items[3],
            Item::Probe(Err(quatarm::stream::ProbeRefusal::Unknown))
        );
        let s = d.finish();
        assert_eq!((s.reports, s.probe_answers, s.damaged()), (2, 2, 0));
        assert_eq!(s.valid_frames(), 4);
    }

    fn frame_of(r: Report) -> Vec<u8> {
        let mut out = [0u8; MAX_FRAME];
        let n = encode(&ToHost::Report(r), &mut out).unwrap();
        out[..n].to_vec()
    }

    fn frame(seq: u32) -> Vec<u8> {
        frame_of(report(seq))
    }

    #[test]
    fn a_foreign_protocol_and_an_unknown_variant_are_reported_as_such() {
        // Postcard writes a tuple field by field, as it writes the enum and struct: variant
        // 0 (Hello), protocol 2, precision 0, joints 0, status 0; then variant 9 (unknown).
        let mut out = [0u8; MAX_FRAME];
        let mut bytes = Vec::new();
        let n = encode(&(0u8, PROTOCOL_VERSION + 1, 0u8, 0u8, 0u16), &mut out).unwrap();
        bytes.extend(&out[..n]);
        let n = encode(&(9u8,), &mut out).unwrap();
        bytes.extend(&out[..n]);
        let mut d = Decoder::from_start();
        let items: Vec<_> = bytes.iter().filter_map(|&b| d.push(b)).collect();
        assert!(matches!(items[1], Item::Damaged(FrameError::Decode)));
        let s = d.finish();
        assert_eq!(
            (s.hellos, s.foreign_protocol, s.undecodable, s.crc_errors),
            (1, 1, 1, 0)
        );
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
        let s = d.finish();
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
        assert_eq!(d.finish().damaged(), 0);
        assert_eq!(d.stats().skipped_bytes as usize, frame(0).len() - 5);
    }

    #[test]
    fn a_repeated_frame_is_one_repeat_not_four_billion_lost() {
        // The shape of ../shared/repro/s-dup.bin: report 1 twice.
        let mut bytes = frame(0);
        bytes.extend(frame(1));
        bytes.extend(frame(1));
        bytes.extend(frame(2));
        let mut d = Decoder::from_start();
        let items = d.push_all(&bytes);
        assert_eq!(items[2], Item::Repeated(report(1)));
        assert_eq!(items.iter().filter_map(Item::report).count(), 3);
        let s = d.finish();
        assert_eq!((s.reports, s.repeated, s.lost, s.backward), (3, 1, 0, 0));
    }

    #[test]
    fn a_backward_step_restarts_the_numbering_and_loses_nothing() {
        let mut bytes = Vec::new();
        for seq in [10, 11, 3, 4, 6] {
            bytes.extend(frame(seq));
        }
        let mut d = Decoder::from_start();
        let items = d.push_all(&bytes);
        assert_eq!(
            items[2],
            Item::Backward {
                report: report(3),
                expected: 12
            }
        );
        let s = d.finish();
        assert_eq!((s.reports, s.backward, s.lost, s.repeated), (5, 1, 1, 0));
        // The same sequence number with other content is a step back, not a repeat.
        let mut other = report(11);
        other.time_us += 1;
        let mut d = Decoder::from_start();
        d.push_all(&[frame(11), frame_of(other)].concat());
        assert_eq!((d.stats().backward, d.stats().repeated), (1, 0));
        // Wrapping at 2^32 is a step forward.
        let mut d = Decoder::from_start();
        d.push_all(&[frame(u32::MAX - 1), frame(1)].concat());
        assert_eq!((d.stats().lost, d.stats().backward), (2, 0));
    }

    #[test]
    fn coordinates_beside_a_fault_are_never_handed_out() {
        let mut faulted = report(1);
        faulted.status = Status(Status::TABLE_VALID | Status::OVER_TEMPERATURE);
        let mut no_table = report(2);
        no_table.status = Status(0x0010); // table missing, yet coordinates
        let mut missing = report(3);
        missing.point = None; // no fault, no coordinates
        let bytes = [
            frame(0),
            frame_of(faulted),
            frame_of(no_table),
            frame_of(missing),
        ]
        .concat();
        let mut d = Decoder::from_start();
        let items = d.push_all(&bytes);
        for item in &items[1..] {
            match item {
                Item::Inconsistent(r, _) => assert_eq!(r.point, None),
                other => panic!("{other:?}"),
            }
        }
        let s = d.finish();
        assert_eq!((s.reports, s.points, s.inconsistent), (4, 1, 3));
    }

    #[test]
    fn bytes_that_never_reach_a_delimiter_are_counted() {
        let mut d = Decoder::from_start();
        d.push_all(b"seq,time_us,status\n0,1,0x0001\n");
        let s = d.finish();
        assert_eq!(
            (s.unterminated_bytes, s.damaged(), s.valid_frames()),
            (30, 1, 0)
        );
        // A frame cut at the end of a capture.
        let mut d = Decoder::from_start();
        let f = frame(0);
        d.push_all(&[&f[..], &f[..10]].concat());
        assert_eq!((d.finish().unterminated_bytes, d.finish().reports), (10, 1));
        // Joining: bytes before the first delimiter are skipped, not unterminated.
        let mut d = Decoder::joining();
        d.push_all(&[0x55; 100]);
        let s = d.finish();
        assert_eq!((s.skipped_bytes, s.unterminated_bytes), (100, 0));
        // An idle line of delimiters is nothing at all.
        let mut d = Decoder::from_start();
        d.push_all(&[0; 5]);
        assert_eq!(d.finish(), Stats::default());
    }
}
