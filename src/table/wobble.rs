//! The axis wobble in the table (`spec/arm-model.md`, `axis_wobble`): the tilt of a joint's
//! bearing varying with its reading, δα_k + A(θ), δβ_k + B(θ), A and B sums of harmonics.
//!
//! The chains do not re-form the tilt per point. With the fixed tilt and zero offset in M'_k,
//! the varied rotation is exactly M'_k R(f1, A(θ)) R(f2, B(θ)) (the reference's
//! `a_wobble_is_the_fixed_tilt_then_two_turns_about_fixed_axes`), with two fixed, orthogonal
//! unit axes of the joint's frame, f1 = R(u, −Δθ) R(e2, −β) e1 and f2 = R(u, −Δθ) e2, which the
//! host computes in f64 and stores here: a point needs only the two angles, and two small
//! turns ([`crate::wobble`]).
//!
//! ```text
//! offset  size  field                              (little-endian, before the CRC)
//! ------  ----  ---------------------------------------------------------------
//!      0     2  count W of joints with a wobble (1..=N)
//!      2     2  reserved, 0
//!      4 W·216  one record per joint, ascending joint:
//!                 +0    1  joint k (1-based)
//!                 +1    1  term count T (1..=4)
//!                 +2    6  reserved, 0
//!                 +8   24  f1 (unit, f64 ×3, the joint's frame as the calibration file has it)
//!                 +32  24  f2 (unit, orthogonal to f1)
//!                 +56 160  4 term slots of 40 bytes, the first T used (the rest 0):
//!                            +0 2 order h (1..=64), +2 6 reserved 0,
//!                            +8 8 α sin, +16 8 α cos, +24 8 β sin, +32 8 β cos (rad)
//! ```
//!
//! The block sits after every other block (the budget and the parameter covariance), so that
//! their offsets do not move, and says its own size in its first field, like the parameter
//! block. A firmware without the `wobble` feature does not know its flag and refuses a table
//! that has one: without it, the coordinates would be off by the wobble's lever.

use super::{abs, limits, rd_f64s, rd_u16, within, Field, TableError};
use super::{MAX_HARMONIC_ORDER, MAX_JOINTS};

/// Term slots per joint.
pub const MAX_TERMS: usize = 4;
/// Length of one joint record.
pub const RECORD_LEN: usize = 216;
/// Length of one term slot.
pub const TERM_LEN: usize = 40;
const HEAD_LEN: usize = 4;

mod off {
    pub const JOINT: usize = 0;
    pub const TERMS: usize = 1;
    pub const RESERVED: usize = 2;
    pub const F1: usize = 8;
    pub const F2: usize = 32;
    pub const SLOTS: usize = 56;
    // Term slot.
    pub const ORDER: usize = 0;
    pub const T_RESERVED: usize = 2;
    pub const ALPHA: usize = 8;
    pub const BETA: usize = 24;
}

/// Length of the block for `w` joints with a wobble.
pub const fn len(w: usize) -> usize {
    HEAD_LEN + w * RECORD_LEN
}

/// The joint count the block's first field states (0 if it cannot be read).
pub(super) fn stated_count(block: &[u8]) -> usize {
    usize::from(rd_u16(block, 0))
}

/// One wobble term: δα += α·(sin hθ, cos hθ), δβ += β·(sin hθ, cos hθ).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WobbleTerm {
    /// Order h.
    pub order: u16,
    /// Coefficients of sin(hθ) and cos(hθ) in δα (rad).
    pub alpha: [f64; 2],
    /// Coefficients of sin(hθ) and cos(hθ) in δβ (rad).
    pub beta: [f64; 2],
}

/// One joint's wobble: its two fixed axes and its terms (none where `count` is 0).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WobbleData {
    /// f1: the axis A(θ) turns about, in the joint's frame after M'_k.
    pub f1: [f64; 3],
    /// f2: the axis B(θ) turns about.
    pub f2: [f64; 3],
    /// Terms used.
    pub count: u8,
    /// The terms (the first `count`).
    pub terms: [WobbleTerm; MAX_TERMS],
}

/// Writes the block of `joints` (only those with terms) into `out`, exactly [`len`] of their
/// number of bytes.
pub(super) fn encode(joints: &[WobbleData], out: &mut [u8]) {
    let with: usize = joints.iter().filter(|w| w.count > 0).count();
    out[..2].copy_from_slice(&(with as u16).to_le_bytes());
    let records = joints.iter().enumerate().filter(|(_, w)| w.count > 0);
    for ((k, w), r) in records.zip(out[HEAD_LEN..].chunks_exact_mut(RECORD_LEN)) {
        r[off::JOINT] = k as u8 + 1;
        r[off::TERMS] = w.count;
        super::put_f64s(&mut r[off::F1..], &w.f1);
        super::put_f64s(&mut r[off::F2..], &w.f2);
        let used = usize::from(w.count).min(MAX_TERMS);
        for (t, s) in w.terms[..used]
            .iter()
            .zip(r[off::SLOTS..].chunks_exact_mut(TERM_LEN))
        {
            s[off::ORDER..off::ORDER + 2].copy_from_slice(&t.order.to_le_bytes());
            super::put_f64s(&mut s[off::ALPHA..], &t.alpha);
            super::put_f64s(&mut s[off::BETA..], &t.beta);
        }
    }
}

/// A table's wobble block, borrowing its bytes.
#[derive(Clone, Copy, Debug)]
pub struct Wobble<'a> {
    bytes: &'a [u8],
}

impl<'a> Wobble<'a> {
    pub(super) fn new(bytes: &'a [u8]) -> Wobble<'a> {
        Wobble { bytes }
    }

    fn records(&self) -> impl Iterator<Item = &'a [u8]> {
        let w = stated_count(self.bytes);
        self.bytes
            .get(HEAD_LEN..)
            .unwrap_or(&[])
            .chunks_exact(RECORD_LEN)
            .take(w)
    }

    /// Joint `i`'s wobble (0-based; count 0 where it has none).
    pub fn joint(&self, i: usize) -> WobbleData {
        let Some(r) = self.records().find(|r| usize::from(r[off::JOINT]) == i + 1) else {
            return WobbleData::default();
        };
        let mut terms = [WobbleTerm::default(); MAX_TERMS];
        for (t, s) in terms.iter_mut().zip(r[off::SLOTS..].chunks_exact(TERM_LEN)) {
            *t = WobbleTerm {
                order: rd_u16(s, off::ORDER),
                alpha: rd_f64s::<2>(s, off::ALPHA),
                beta: rd_f64s::<2>(s, off::BETA),
            };
        }
        WobbleData {
            f1: rd_f64s::<3>(r, off::F1),
            f2: rd_f64s::<3>(r, off::F2),
            count: r[off::TERMS],
            terms,
        }
    }

    /// Checks every record of a table with `joints` joints: joints ascending within 1..=N,
    /// 1..=4 terms of orders 1..=64, Σ |coefficients| ≤ [`limits::HARMONIC_SUM`] per joint
    /// (the chains' small turns stay second-order exact), unit orthogonal axes, reserved and
    /// unused bytes 0.
    // Called only with the feature (without it the flag is refused first).
    #[cfg_attr(not(feature = "wobble"), allow(dead_code))]
    pub(super) fn check(&self, joints: usize) -> Result<(), TableError> {
        let w = stated_count(self.bytes);
        let whole = TableError::Invalid {
            joint: 0,
            field: Field::Wobble,
        };
        if w == 0 || w > joints.min(MAX_JOINTS) || rd_u16(self.bytes, 2) != 0 {
            return Err(whole);
        }
        let mut last = 0;
        for r in self.records() {
            let k = usize::from(r[off::JOINT]);
            if k <= last || k > joints {
                return Err(whole);
            }
            last = k;
            let invalid = TableError::Invalid {
                joint: k as u8,
                field: Field::Wobble,
            };
            let d = self.joint(k - 1);
            let used = usize::from(d.count);
            if !(1..=MAX_TERMS).contains(&used) || r[off::RESERVED..off::F1].iter().any(|&b| b != 0)
            {
                return Err(invalid);
            }
            let mut sum = 0.0;
            for (t, (n, s)) in d
                .terms
                .iter()
                .zip(r[off::SLOTS..].chunks_exact(TERM_LEN).enumerate())
            {
                if n >= used {
                    if s.iter().any(|&b| b != 0) {
                        return Err(invalid);
                    }
                    continue;
                }
                let coefs = [t.alpha[0], t.alpha[1], t.beta[0], t.beta[1]];
                if t.order == 0
                    || t.order > MAX_HARMONIC_ORDER
                    || s[off::T_RESERVED..off::ALPHA].iter().any(|&b| b != 0)
                    || !coefs.iter().all(|&c| within(c, limits::HARMONIC_SUM))
                {
                    return Err(invalid);
                }
                sum += coefs.iter().map(|&c| abs(c)).sum::<f64>();
            }
            let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
            let unit = |a: [f64; 3]| {
                a.iter().all(|&x| within(x, 1.0 + limits::UNIT_TOLERANCE))
                    && abs(dot(a, a) - 1.0) <= limits::UNIT_TOLERANCE
            };
            if sum > limits::HARMONIC_SUM
                || !unit(d.f1)
                || !unit(d.f2)
                || abs(dot(d.f1, d.f2)) > limits::UNIT_TOLERANCE
            {
                return Err(invalid);
            }
        }
        Ok(())
    }
}

#[cfg(all(test, feature = "wobble"))]
mod tests {
    use super::super::tests::{recrc, sample};
    use super::super::{budget, Table, TableData, FLAG_WOBBLE, MAX_TABLE_LEN};
    use super::*;

    /// Joints 2 and 5 wobble; joint 2's axes turned by a few mrad, as the builder makes them.
    fn wobbling() -> TableData {
        let mut d = sample();
        let (c, s) = (0.003f64.cos(), 0.003f64.sin());
        d.wobble[1] = WobbleData {
            f1: [c, s, 0.0],
            f2: [-s, c, 0.0],
            count: 2,
            terms: [
                WobbleTerm {
                    order: 1,
                    alpha: [4e-5, -2e-5],
                    beta: [1e-5, 3e-5],
                },
                WobbleTerm {
                    order: 3,
                    alpha: [1e-5, 0.0],
                    beta: [0.0, -1e-5],
                },
                WobbleTerm::default(),
                WobbleTerm::default(),
            ],
        };
        d.wobble[4] = WobbleData {
            f1: [1.0, 0.0, 0.0],
            f2: [0.0, 1.0, 0.0],
            count: 1,
            terms: [
                WobbleTerm {
                    order: 64,
                    alpha: [0.0, 1e-4],
                    beta: [-1e-4, 0.0],
                },
                WobbleTerm::default(),
                WobbleTerm::default(),
                WobbleTerm::default(),
            ],
        };
        d
    }

    fn encoded(budget: Option<&budget::BudgetData>) -> ([u8; MAX_TABLE_LEN], usize) {
        let mut buf = [0u8; MAX_TABLE_LEN];
        let n = wobbling().encode_with(budget, &mut buf).unwrap();
        (buf, n)
    }

    #[test]
    fn the_block_round_trips_after_the_budget() {
        for b in [None, Some(budget::BudgetData::default())] {
            let (buf, n) = encoded(b.as_ref());
            let extra = if b.is_some() { budget::LEN } else { 0 };
            assert_eq!(n, super::super::table_len(6) + extra + len(2));
            assert!(super::super::is_table_len(n));
            let t = Table::parse(&buf[..n]).unwrap();
            assert_ne!(t.flags() & FLAG_WOBBLE, 0);
            let mut want = wobbling();
            want.flags |= FLAG_WOBBLE;
            if b.is_some() {
                want.flags |= super::super::FLAG_BUDGET;
            }
            assert_eq!(t.data(), want);
            assert_eq!(t.joint_wobble(0).count, 0);
            assert_eq!(t.budget().is_some(), b.is_some());
        }
        // Without any wobble, no block and no flag.
        let mut buf = [0u8; MAX_TABLE_LEN];
        let n = sample().encode(&mut buf).unwrap();
        assert_eq!(Table::parse(&buf[..n]).unwrap().flags() & FLAG_WOBBLE, 0);
    }

    /// Every value check, each on one field of a valid block, names the joint (or the block).
    #[test]
    fn bad_blocks_are_refused_naming_the_joint() {
        let (good, n) = encoded(None);
        let at = n - crate::table::TAIL_LEN - len(2);
        let rec = at + HEAD_LEN;
        let slot = rec + off::SLOTS;
        let f64_at = |b: &mut [u8], o: usize, v: f64| b[o..o + 8].copy_from_slice(&v.to_le_bytes());
        type Edit = fn(&mut [u8], usize, usize, usize);
        let cases: [(&str, Edit, u8); 12] = [
            ("count 0", |b, at, _, _| b[at] = 0, 0),
            ("count past the joints", |b, at, _, _| b[at] = 7, 0),
            ("joint 0", |b, _, rec, _| b[rec] = 0, 0),
            (
                "joints not ascending",
                |b, _, rec, _| b[rec + RECORD_LEN] = 2,
                0,
            ),
            ("no terms", |b, _, rec, _| b[rec + 1] = 0, 2),
            ("five terms", |b, _, rec, _| b[rec + 1] = 5, 2),
            ("order 0", |b, _, _, slot| b[slot] = 0, 2),
            ("order 65", |b, _, _, slot| b[slot] = 65, 2),
            ("reserved", |b, _, rec, _| b[rec + 3] = 1, 2),
            ("unused slot", |b, _, _, slot| b[slot + 2 * TERM_LEN] = 1, 2),
            (
                "f1 not unit",
                |b, _, rec, _| b[rec + off::F1 + 7] ^= 0x01,
                2,
            ),
            ("header reserved", |b, at, _, _| b[at + 2] = 1, 0),
        ];
        for (what, edit, joint) in cases {
            let mut bad = good;
            edit(&mut bad[..n], at, rec, slot);
            recrc(&mut bad[..n]);
            let Err(e) = Table::parse(&bad[..n]) else {
                panic!("{what}: accepted");
            };
            assert!(
                matches!(e, TableError::Invalid { joint: j, field: Field::Wobble } if j == joint)
                    || (joint == 0
                        && matches!(e, TableError::BadLength(_) | TableError::Truncated { .. })),
                "{what}: {e:?}"
            );
        }
        // Too large a sum, a NaN, axes that are not orthogonal.
        for (what, o, v) in [
            ("sum", slot + off::ALPHA, 9.5e-4),
            ("NaN", slot + off::BETA + 8, f64::NAN),
            ("f2 = f1", rec + off::F2, 0.003f64.cos()),
        ] {
            let mut bad = good;
            f64_at(&mut bad, o, v);
            if what == "f2 = f1" {
                f64_at(&mut bad, o + 8, 0.003f64.sin());
            }
            recrc(&mut bad[..n]);
            assert_eq!(
                Table::parse(&bad[..n]).err(),
                Some(TableError::Invalid {
                    joint: 2,
                    field: Field::Wobble
                }),
                "{what}"
            );
        }
        // The flag cleared on a table with the block: a length that disagrees.
        let mut bad = good;
        bad[7] &= !FLAG_WOBBLE;
        recrc(&mut bad[..n]);
        assert!(Table::parse(&bad[..n]).is_err());
    }
}
