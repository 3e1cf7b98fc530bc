//! An arm's other probes in the table: up to seven beside the first (ball styli of different
//! lengths and diameters, an extension), one mounted at a time.
//!
//! The first probe keeps its place (the probe record after the joints) and its id is the
//! header's byte 44, so a table of one probe of id 0 is byte for byte what it was before there
//! were several. The others follow every other block (after the wobble's), where flag bit 7
//! is set:
//!
//! ```text
//! offset  size  field                              (little-endian, before the CRC)
//! ------  ----  ---------------------------------------------------------------
//!      0     1  count P of the other probes (1..=7)
//!      1     3  reserved, 0
//!      4  P·72  one record per probe, in the calibration file's order:
//!                 +0   1  id (distinct from every other probe's, the first's included)
//!                 +1   7  reserved, 0
//!                 +8  64  the probe record, as the first probe's: vector v_p + Δv_p
//!                         (mm, f64 ×3), its unit direction (f64 ×3), thermal expansion
//!                         κ_p (1/°C, f64), stylus ball diameter (mm, f64; 0 unknown)
//! ```
//!
//! Every probe's values are checked as the first probe's are, and every id must differ from
//! the others' ([`super::Table::parse`]). The hub mounts the first probe at boot and another
//! when the host selects it by id (`ToDevice::SelectProbe`, `docs/protocol.md`): its chain
//! then ends at that probe's ball. The block is 4 + 72·P bytes, 508 for seven others: the
//! largest table without a parameter block is 2,448 bytes ([`super::MAX_PLAIN_TABLE_LEN`]),
//! which the 4 KiB slots of the fixed-point boards hold.
//!
//! Every board reads it, the Cortex-M0 hub too (no feature): its 32 KiB image holds it with
//! 180 bytes to spare (rustup 1.95, `cargo xtask bench-target`: 32,588 bytes, 32,712 before
//! the probes, the room found elsewhere; README, "Several probes"). The f32 images grew by
//! ~8 KB (the checks and a probe's conversion in soft f64).

use super::{Field, ProbeData, TableError, PROBE_LEN};

/// Most probes a table holds, the first included.
pub const MAX_PROBES: usize = 8;
/// Length of one record of the block.
pub const RECORD_LEN: usize = 8 + PROBE_LEN;
const HEAD_LEN: usize = 4;
/// Where a record's probe data starts.
const DATA: usize = 8;

/// Length of the block for `p` probes beside the first.
pub const fn len(p: usize) -> usize {
    HEAD_LEN + p * RECORD_LEN
}

/// The probe count the block's first byte states (0 if it cannot be read).
pub(super) fn stated_count(block: &[u8]) -> usize {
    block.first().map_or(0, |&p| usize::from(p))
}

/// Writes the block of `probes` into `out`, exactly [`len`] of their number of bytes.
pub(super) fn encode(probes: &[ProbeData], out: &mut [u8]) {
    out[0] = probes.len() as u8;
    for (p, r) in probes
        .iter()
        .zip(out[HEAD_LEN..].chunks_exact_mut(RECORD_LEN))
    {
        r[0] = p.id;
        super::put_probe(&mut r[DATA..], p);
    }
}

/// A table's block of other probes, borrowing its bytes (length checked by the table).
#[derive(Clone, Copy, Debug)]
pub struct Probes<'a> {
    bytes: &'a [u8],
}

impl<'a> Probes<'a> {
    pub(super) fn new(bytes: &'a [u8]) -> Probes<'a> {
        Probes { bytes }
    }

    /// Number of probes in the block (the first probe not counted).
    pub fn count(&self) -> usize {
        stated_count(self.bytes)
    }

    /// The `k`-th probe of the block (0-based); `None` past the last.
    pub fn probe(&self, k: usize) -> Option<ProbeData> {
        if k >= self.count() {
            return None;
        }
        let r = self
            .bytes
            .get(HEAD_LEN + k * RECORD_LEN..HEAD_LEN + (k + 1) * RECORD_LEN)?;
        Some(super::read_probe(r[0], &r[DATA..]))
    }

    /// The `k`-th probe's id (0-based); `None` past the last.
    pub fn id(&self, k: usize) -> Option<u8> {
        if k >= self.count() {
            return None;
        }
        self.bytes.get(HEAD_LEN + k * RECORD_LEN).copied()
    }

    /// Checks the block's own fields: 1..=7 probes, reserved bytes 0. (The table checks
    /// every probe's values and ids, the first's with the others'.)
    pub(super) fn check(&self) -> Result<(), TableError> {
        let p = self.count();
        if !(1..MAX_PROBES).contains(&p) {
            return Err(TableError::Invalid {
                joint: 0,
                field: Field::Probe,
            });
        }
        // The records by index, not `chunks_exact`, whose remainder is a division by 72 (a
        // runtime call on the Cortex-M0); the table's length gave the block all p records.
        let reserved = (0..p).flat_map(|k| {
            let at = HEAD_LEN + k * RECORD_LEN;
            self.bytes.get(at + 1..at + DATA).unwrap_or(&[])
        });
        if reserved.chain(&self.bytes[1..HEAD_LEN]).any(|&b| b != 0) {
            return Err(TableError::Invalid {
                joint: 0,
                field: Field::Reserved,
            });
        }
        Ok(())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::super::tests::{recrc, sample};
    use super::super::{budget, is_table_len, table_len, Table, TableData};
    use super::super::{FLAG_BUDGET, FLAG_PROBES, FLAG_THERMAL, MAX_TABLE_LEN};
    use super::*;

    /// The sample arm with a first probe of id 4 and two others: a 40 mm extension (id 9,
    /// thermal) and a stylus turned off the axis (id 0).
    pub(crate) fn several() -> TableData {
        let mut d = sample();
        d.probe.id = 4;
        d.more_probes[0] = ProbeData {
            id: 9,
            vector: [0.0, 0.0, 160.0],
            direction: [0.0, 0.0, 1.0],
            thermal: 2.3e-5,
            ball_diameter: 3.0,
        };
        let (c, s) = (0.6, 0.8);
        d.more_probes[1] = ProbeData {
            id: 0,
            vector: [0.0, 50.0 * c, 50.0 * s],
            direction: [0.0, c, s],
            thermal: 0.0,
            ball_diameter: 2.0,
        };
        d.more_probe_count = 2;
        d.flags = d.content_flags() | super::super::FLAG_GEOMETRIC;
        d
    }

    fn encoded(budget: Option<&budget::BudgetData>) -> ([u8; MAX_TABLE_LEN], usize) {
        let mut buf = [0u8; MAX_TABLE_LEN];
        let n = several().encode_with(budget, &mut buf).unwrap();
        (buf, n)
    }

    #[test]
    fn the_block_round_trips_after_every_other() {
        for b in [None, Some(budget::BudgetData::default())] {
            let (buf, n) = encoded(b.as_ref());
            let extra = if b.is_some() { budget::LEN } else { 0 };
            assert_eq!(n, table_len(6) + extra + len(2));
            assert!(is_table_len(n));
            let t = Table::parse(&buf[..n]).unwrap();
            let mut want = several();
            want.flags |= FLAG_PROBES | if b.is_some() { FLAG_BUDGET } else { 0 };
            assert_eq!(t.data(), want);
            assert_eq!(t.probe_count(), 3);
            assert_eq!(t.probe().id, 4);
            assert_eq!(buf[44], 4, "the first probe's id in the header");
            assert_eq!(t.probe_at(1), Some(want.more_probes[0]));
            assert_eq!(t.probe_at(2), Some(want.more_probes[1]));
            assert_eq!(t.probe_at(3), None);
            assert_eq!(t.budget().is_some(), b.is_some());
            // The extension's expansion is a thermal term of the arm's.
            assert_ne!(t.flags() & FLAG_THERMAL, 0);
        }
        // One probe: no block, no flag, and the same bytes as before there were several.
        let mut buf = [0u8; MAX_TABLE_LEN];
        let n = sample().encode(&mut buf).unwrap();
        let t = Table::parse(&buf[..n]).unwrap();
        assert_eq!(
            (t.flags() & FLAG_PROBES, t.probe_count(), n),
            (0, 1, table_len(6))
        );
        assert!(t.other_probes().is_none());
        assert_eq!(buf[44..48], [0; 4]);
    }

    /// The sample's probe has no thermal expansion; another probe's sets the thermal flag,
    /// which a table without it then lacks.
    #[test]
    fn another_probes_expansion_needs_the_thermal_flag() {
        let mut d = sample();
        for j in &mut d.joints {
            j.thermal = 0.0;
        }
        d.more_probes[0] = several().more_probes[0];
        d.more_probes[0].id = 1;
        d.more_probe_count = 1;
        d.flags = d.content_flags();
        assert_ne!(d.flags & FLAG_THERMAL, 0);
        let mut buf = [0u8; MAX_TABLE_LEN];
        let n = d.encode(&mut buf).unwrap();
        assert!(Table::parse(&buf[..n]).is_ok());
        buf[7] &= !FLAG_THERMAL;
        recrc(&mut buf[..n]);
        assert_eq!(
            Table::parse(&buf[..n]).unwrap_err(),
            TableError::Invalid {
                joint: 0,
                field: Field::Flags
            }
        );
    }

    /// Every check of the block, each on one field of a valid table, refuses it.
    #[test]
    fn bad_blocks_are_refused() {
        let (good, n) = encoded(None);
        let at = n - crate::table::TAIL_LEN - len(2);
        let rec = at + HEAD_LEN;
        let data = rec + DATA;
        let f64_at = |b: &mut [u8], o: usize, v: f64| b[o..o + 8].copy_from_slice(&v.to_le_bytes());
        let probe = TableError::Invalid {
            joint: 0,
            field: Field::Probe,
        };
        let reserved = TableError::Invalid {
            joint: 0,
            field: Field::Reserved,
        };
        type Edit = fn(&mut [u8], usize, usize, usize);
        let cases: [(&str, Edit, Option<TableError>); 14] = [
            ("count 0", |b, at, _, _| b[at] = 0, None),
            ("count past the records", |b, at, _, _| b[at] = 3, None),
            (
                "block reserved",
                |b, at, _, _| b[at + 2] = 1,
                Some(reserved),
            ),
            (
                "record reserved",
                |b, _, rec, _| b[rec + 5] = 1,
                Some(reserved),
            ),
            (
                "id of the first probe",
                |b, _, rec, _| b[rec] = 4,
                Some(probe),
            ),
            (
                "two ids alike",
                |b, _, rec, _| b[rec + RECORD_LEN] = 9,
                Some(probe),
            ),
            ("header reserved", |b, _, _, _| b[46] = 1, Some(reserved)),
            (
                "vector NaN",
                |b, _, _, d| b[d..d + 8].copy_from_slice(&f64::NAN.to_le_bytes()),
                Some(probe),
            ),
            (
                "vector too long",
                |b, _, _, d| b[d + 16..d + 24].copy_from_slice(&6000.0f64.to_le_bytes()),
                Some(probe),
            ),
            (
                "direction not along the vector",
                |b, _, _, d| {
                    b[d + 24..d + 32].copy_from_slice(&1.0f64.to_le_bytes());
                    b[d + 40..d + 48].copy_from_slice(&0.0f64.to_le_bytes());
                },
                Some(probe),
            ),
            (
                "direction not unit",
                |b, _, _, d| b[d + 40..d + 48].copy_from_slice(&1.001f64.to_le_bytes()),
                Some(probe),
            ),
            (
                "thermal too large",
                |b, _, _, d| b[d + 48..d + 56].copy_from_slice(&1e-3f64.to_le_bytes()),
                Some(probe),
            ),
            (
                "ball negative",
                |b, _, _, d| b[d + 56..d + 64].copy_from_slice(&(-1.0f64).to_le_bytes()),
                Some(probe),
            ),
            ("flag cleared", |b, _, _, _| b[7] &= !FLAG_PROBES, None),
        ];
        for (what, edit, want) in cases {
            let mut bad = good;
            edit(&mut bad[..n], at, rec, data);
            recrc(&mut bad[..n]);
            let Err(e) = Table::parse(&bad[..n]) else {
                panic!("{what}: accepted");
            };
            match want {
                Some(w) => assert_eq!(e, w, "{what}"),
                // Counts and flags that disagree with the bytes: a length that does not add up.
                None => assert!(
                    matches!(e, TableError::BadLength(_) | TableError::Truncated { .. }),
                    "{what}: {e:?}"
                ),
            }
        }
        // A direction pointing against the vector, in the second record.
        let mut bad = good;
        let d2 = data + RECORD_LEN;
        for k in 0..3 {
            let v = f64::from_le_bytes(bad[d2 + 24 + 8 * k..d2 + 32 + 8 * k].try_into().unwrap());
            f64_at(&mut bad, d2 + 24 + 8 * k, -v);
        }
        recrc(&mut bad[..n]);
        assert_eq!(Table::parse(&bad[..n]).unwrap_err(), probe);
        // Eight other probes: more than a table holds, refused by the encoder too.
        let mut d = several();
        d.more_probe_count = 8;
        let mut buf = [0u8; MAX_TABLE_LEN];
        assert_eq!(d.encode(&mut buf).unwrap_err(), probe);
    }

    /// Seven others, the most: the largest table without a parameter block has them.
    #[test]
    fn seven_others_fit_and_an_eighth_count_is_refused() {
        let mut d = several();
        for (k, p) in d.more_probes.iter_mut().enumerate() {
            *p = ProbeData {
                id: 10 + k as u8,
                ..several().more_probes[0]
            };
        }
        d.more_probe_count = 7;
        let mut buf = [0u8; MAX_TABLE_LEN];
        let n = d.encode(&mut buf).unwrap();
        assert_eq!(n, table_len(6) + len(7));
        let t = Table::parse(&buf[..n]).unwrap();
        assert_eq!(t.probe_count(), MAX_PROBES);
        assert_eq!(t.probe_at(7).map(|p| p.id), Some(16));
        // A count of 8 with eight records' bytes (a length that adds up): refused by value.
        let mut big = [0u8; MAX_TABLE_LEN + RECORD_LEN];
        let tail = crate::table::TAIL_LEN;
        big[..n - tail].copy_from_slice(&buf[..n - tail]);
        let at = n - tail - len(7);
        big[at] = 8;
        let rec8 = at + len(7);
        big[rec8..rec8 + RECORD_LEN].copy_from_slice(&buf[at + HEAD_LEN..at + len(1)]);
        big[rec8] = 30;
        let m = n + RECORD_LEN;
        big[m - tail..m - 4].copy_from_slice(&buf[n - tail..n - 4]);
        big[40..44].copy_from_slice(&(m as u32).to_le_bytes());
        recrc(&mut big[..m]);
        assert_eq!(
            Table::parse(&big[..m]).unwrap_err(),
            TableError::Invalid {
                joint: 0,
                field: Field::Probe
            }
        );
    }
}
