//! The budget's pose part in the table (issue 27; `quatarm_ref::uncertainty::PoseLeverage`,
//! the contract): what lets the hub widen a reading's parameter part where the calibration's
//! design gave the parameters little hold.
//!
//! The parameter covariance C of the parameter block ([`super::parameters`]) is read as
//! C = C_fit + P, P = D Dᵀ + b · C_fit the pose part: D's r columns the between-group spread
//! of the parameters, b the shrink, so that C_fit = (C − D Dᵀ)/(1 + b). At a reading whose
//! Jacobian is J, with ℓ = tr(J C_fit Jᵀ)/m (m the calibration rows' mean of it), the
//! parameter part is J C Jᵀ + (max(1, ℓ) − 1) · J P Jᵀ ([`crate::uncertainty::pose`]: how the
//! hub forms it from the J·L pass it makes anyway and one J·D product).
//!
//! It extends the parameter block rather than taking a header flag (the header's eight are
//! all used): bit 0 of the block's second field, reserved and 0 before, says it follows L.
//! A hub from before it refuses such a table whatever its blocks — its length counts no pose
//! part (`BadLength`), and a length made to agree would still fail its reserved field — so
//! nothing misreads it; a table without it is byte for byte what it was. A hub that takes the
//! parameter block but not this part (the Pico's profile, feature `fixed-u95`) refuses the
//! bit as an unknown flag ([`super::Field::Flags`]); qemu-m0 refuses the parameter block
//! itself by its flag, as before.
//!
//! ```text
//! offset  size   field                     (little-endian, right after the factor L)
//! ------  ----   ---------------------------------------------------------------
//!      0     2   factor count r (1..=MAX_FACTORS)
//!      2     2   flags: bit 0 the joint leverage follows D ([`super::joint_leverage`]);
//!                the others 0 (the whole field was reserved, 0, before)
//!      4     4   shrink b (f32, 0..=LIMIT)
//!      8     4   leverage mean m (f32, mm², > 0 and ≤ LIMIT)
//!     12 4·P·r   D row by parameter, in C's order: row i holds D_i0 … D_i(r−1)
//!                (f32, the parameters' units, each within LIMIT)
//!      …   …     the joint leverage, where flag bit 0 is set (its layout there)
//! ```
//!
//! A hub from before the joint leverage refuses a table with it (its length counts no joint
//! part, and its check wants the flags' field 0), so it never applies max(1, ℓ) alone where
//! the budget says max(1, ℓ, ℓJ).
//!
//! Its numbers are f32 like the rest of the block: U95 needs 1e-3. D is stored by parameter
//! (as L is, row by row) so that the hub's J·D runs over the rows with J's column once each.

use super::joint_leverage::{self, JointLeverage, JointLeverageData};
use super::parameters::LIMIT;
use super::{rd_u16, rd_u32, Field, TableError};

/// Most columns D has: the host's budget has one per held-out group at most, and the hub's
/// J·D costs 3 · P multiply-adds a column (`docs/results/speed.md`). The host's writer
/// (`quatarm_wire::budget`) refuses more; the same constant for both.
pub const MAX_FACTORS: usize = 16;

/// Length of the part's head (r, reserved, b, m).
pub const HEAD_LEN: usize = 12;

/// The part's flag: the joint leverage follows D ([`super::joint_leverage`]).
pub const FLAG_JOINTS: u16 = 1 << 0;

/// Length of the part for `p` parameters and `r` columns of D, without the joint leverage.
pub const fn len(p: usize, r: usize) -> usize {
    HEAD_LEN + 4 * p * r
}

/// The length the part at `bytes` states for `p` parameters: D's, and the joint leverage's
/// where its flag is set (its r clamped to one past [`MAX_FACTORS`], which the check
/// refuses, so that no stated count overflows a length).
pub(super) fn stated_len(bytes: &[u8], p: usize) -> usize {
    let base = len(p, usize::from(rd_u16(bytes, 0)).min(MAX_FACTORS + 1));
    if rd_u16(bytes, 2) & FLAG_JOINTS == 0 {
        return base;
    }
    base + joint_leverage::stated_len(bytes.get(base..).unwrap_or(&[]))
}

/// The part to write ([`super::parameters::ParameterData::pose`]).
#[derive(Clone, Copy, Debug)]
pub struct PoseData<'a> {
    /// D row by parameter: P · r entries, row i's r first.
    pub factor: &'a [f32],
    /// r, D's columns.
    pub count: usize,
    /// b.
    pub shrink: f32,
    /// m (mm²).
    pub leverage_mean: f32,
    /// The joint leverage, where the budget has it.
    pub joints: Option<JointLeverageData<'a>>,
}

impl PoseData<'_> {
    /// The part's length for `p` parameters; `None` if r is 0 or above [`MAX_FACTORS`], D
    /// does not hold p · r entries, or the joint leverage is malformed
    /// ([`JointLeverageData::part_len`]).
    pub fn part_len(&self, p: usize) -> Option<usize> {
        let r = self.count;
        if !((1..=MAX_FACTORS).contains(&r) && self.factor.len() == p * r) {
            return None;
        }
        let joints = match &self.joints {
            Some(j) => j.part_len()?,
            None => 0,
        };
        Some(len(p, r) + joints)
    }

    /// Writes the part into `out` (exactly [`Self::part_len`] bytes).
    pub(super) fn encode(&self, out: &mut [u8]) {
        out[0..2].copy_from_slice(&(self.count as u16).to_le_bytes());
        let flags = if self.joints.is_some() {
            FLAG_JOINTS
        } else {
            0
        };
        out[2..4].copy_from_slice(&flags.to_le_bytes());
        if let Some(j) = &self.joints {
            j.encode(&mut out[HEAD_LEN + 4 * self.factor.len()..]);
        }
        out[4..8].copy_from_slice(&self.shrink.to_le_bytes());
        out[8..12].copy_from_slice(&self.leverage_mean.to_le_bytes());
        for (chunk, x) in out[HEAD_LEN..].chunks_exact_mut(4).zip(self.factor) {
            chunk.copy_from_slice(&x.to_le_bytes());
        }
    }
}

/// A table's pose part, borrowing its bytes (length checked by the table).
#[derive(Clone, Copy, Debug)]
pub struct Pose<'a> {
    bytes: &'a [u8],
    /// P, the parameter block's count.
    parameters: usize,
}

fn rd_f32(b: &[u8], at: usize) -> f32 {
    f32::from_bits(rd_u32(b, at))
}

impl<'a> Pose<'a> {
    pub(super) fn new(bytes: &'a [u8], parameters: usize) -> Pose<'a> {
        Pose { bytes, parameters }
    }

    /// r, D's columns.
    pub fn count(&self) -> usize {
        usize::from(rd_u16(self.bytes, 0))
    }

    /// b.
    pub fn shrink(&self) -> f32 {
        rd_f32(self.bytes, 4)
    }

    /// m (mm²).
    pub fn leverage_mean(&self) -> f32 {
        rd_f32(self.bytes, 8)
    }

    /// D whole, row by parameter (row i at byte 4 · r · i), as raw little-endian bytes
    /// (empty if the part is shorter than its count states).
    pub fn factor(&self) -> &'a [u8] {
        let n = 4 * self.parameters * self.count();
        self.bytes.get(HEAD_LEN..HEAD_LEN + n).unwrap_or(&[])
    }

    /// The joint leverage, where the part has it ([`super::joint_leverage`]).
    pub fn joints(&self) -> Option<JointLeverage<'a>> {
        if rd_u16(self.bytes, 2) & FLAG_JOINTS == 0 {
            return None;
        }
        self.bytes
            .get(len(self.parameters, self.count())..)
            .map(JointLeverage::new)
    }

    /// D's entry (i, j).
    pub fn entry(&self, i: usize, j: usize) -> Option<f32> {
        let r = self.count();
        if i >= self.parameters || j >= r {
            return None;
        }
        let at = HEAD_LEN + 4 * (i * r + j);
        self.bytes.get(at..at + 4).map(|_| rd_f32(self.bytes, at))
    }

    /// Everything well formed: r within 1..=[`MAX_FACTORS`], no flag but
    /// [`FLAG_JOINTS`], b finite and within 0..=[`LIMIT`], m finite, > 0 and within
    /// [`LIMIT`], every entry of D finite and within [`LIMIT`], and the joint leverage where
    /// flagged ([`JointLeverage`]'s check, for the table's `joints`): what the boot applies
    /// to a table that has the part.
    pub(super) fn check(&self, joints: usize) -> Result<(), TableError> {
        let bad = TableError::Invalid {
            joint: 0,
            field: Field::Budget,
        };
        let r = self.count();
        let (b, m) = (self.shrink(), self.leverage_mean());
        let ok = (1..=MAX_FACTORS).contains(&r)
            && rd_u16(self.bytes, 2) & !FLAG_JOINTS == 0
            && b.is_finite()
            && (0.0..=LIMIT).contains(&b)
            && m.is_finite()
            && m > 0.0
            && m <= LIMIT;
        if !ok || self.factor().len() != 4 * self.parameters * r {
            return Err(bad);
        }
        let within = |c: &[u8]| {
            let x = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            x.is_finite() && x.abs() <= LIMIT
        };
        if !self.factor().chunks_exact(4).all(within) {
            return Err(bad);
        }
        match self.joints() {
            Some(j) => j.check(joints),
            None => Ok(()),
        }
    }
}

#[cfg(all(test, feature = "parameters", not(feature = "fixed-u95")))]
pub(crate) mod tests {
    use super::*;
    use crate::table::budget::BudgetData;
    use crate::table::parameters::{self, Column, Kind, ParameterData};
    use crate::table::tests::{recrc, sample};
    use crate::table::{is_table_len, Table, MAX_TABLE_LEN, TAIL_LEN};

    const COLUMNS: [Column; 3] = [
        Column {
            kind: Kind::Turn,
            joint: 1,
            order: 0,
            vector: [0.0; 3],
            w0: 0.0,
            w1: 0.0,
        },
        Column {
            kind: Kind::Turn,
            joint: 3,
            order: 0,
            vector: [0.0; 3],
            w0: 0.0,
            w1: 0.0,
        },
        Column {
            kind: Kind::Shift,
            joint: 5,
            order: 0,
            vector: [0.0, 0.0, 1.0],
            w0: 1.0,
            w1: 0.0,
        },
    ];
    const FACTOR: [f32; 6] = [1e-5, 2e-6, 3e-5, -1e-6, 0.0, 4e-3];
    /// D: 3 parameters × 2 columns, row by parameter.
    const D: [f32; 6] = [4e-6, -1e-6, 0.0, 2e-5, 1e-3, 5e-4];

    /// The sample table with a budget and a 3-parameter block with a pose part of r = 2.
    pub(crate) fn encoded() -> ([u8; MAX_TABLE_LEN], usize) {
        let mut buf = [0u8; MAX_TABLE_LEN];
        let block = ParameterData {
            columns: &COLUMNS,
            factor: &FACTOR,
            pose: Some(PoseData {
                factor: &D,
                count: 2,
                shrink: 0.25,
                leverage_mean: 2.5e-6,
                joints: None,
            }),
        };
        let n = sample()
            .encode_full(Some(&BudgetData::default()), Some(&block), &mut buf)
            .unwrap();
        (buf, n)
    }

    /// Where the pose part starts in the 6-joint sample.
    const AT: usize = 48 + 6 * 248 + 64 + 80 + parameters::len(3);

    /// μ of the 6-joint sample's joint leverage (rad).
    const MEAN: [f32; 6] = [0.5, 1.0, 3.0, 6.0, 0.1, 2.0];
    /// W's upper triangle (1/rad²): diagonal 4, 2, 1, 0 (a joint that did not move), 8, 0.5
    /// and a few couplings.
    const WEIGHT: [f32; 21] = [
        4.0, 0.5, 0.0, 0.0, -0.3, 0.0, //
        2.0, 0.2, 0.0, 0.0, 0.0, //
        1.0, 0.0, 0.1, 0.0, //
        0.0, 0.0, 0.0, //
        8.0, -1.0, //
        0.5,
    ];

    /// The sample table with the pose part of [`encoded`] and a joint leverage after D.
    pub(crate) fn encoded_with_joints() -> ([u8; MAX_TABLE_LEN], usize) {
        let mut buf = [0u8; MAX_TABLE_LEN];
        let block = ParameterData {
            columns: &COLUMNS,
            factor: &FACTOR,
            pose: Some(PoseData {
                factor: &D,
                count: 2,
                shrink: 0.25,
                leverage_mean: 2.5e-6,
                joints: Some(JointLeverageData {
                    mean: &MEAN,
                    weight: &WEIGHT,
                }),
            }),
        };
        let n = sample()
            .encode_full(Some(&BudgetData::default()), Some(&block), &mut buf)
            .unwrap();
        (buf, n)
    }

    /// The table `good[..n]` with `bytes` written at `at` (`what`) and its CRC made to match
    /// is refused as a bad budget or a length that disagrees.
    fn assert_refused(good: &[u8; MAX_TABLE_LEN], n: usize, what: &str, at: usize, bytes: &[u8]) {
        let mut b = *good;
        b[at..at + bytes.len()].copy_from_slice(bytes);
        recrc(&mut b[..n]);
        match Table::parse(&b[..n]) {
            Err(TableError::Invalid {
                field: Field::Budget,
                ..
            })
            | Err(TableError::BadLength(_)) => {}
            other => panic!("{what}: {other:?}"),
        }
    }

    /// Where the joint leverage starts in [`encoded_with_joints`].
    const JOINTS_AT: usize = AT + len(3, 2);

    #[test]
    fn the_joint_leverage_round_trips() {
        let (buf, n) = encoded_with_joints();
        assert_eq!(n, JOINTS_AT + joint_leverage::len(6) + TAIL_LEN);
        assert!(is_table_len(n));
        let t = Table::parse(&buf[..n]).unwrap();
        let pose = t.parameters().unwrap().pose().unwrap();
        assert_eq!((pose.count(), pose.entry(2, 1)), (2, Some(D[5])));
        let j = pose.joints().unwrap();
        assert_eq!(j.count(), 6);
        for (i, m) in MEAN.iter().enumerate() {
            assert_eq!(j.mean(i), Some(*m));
        }
        assert_eq!(j.mean(6), None);
        let mut at = 0;
        for a in 0..6 {
            for b in a..6 {
                assert_eq!(j.weight(a, b), Some(WEIGHT[at]), "({a}, {b})");
                assert_eq!(j.weight(b, a), Some(WEIGHT[at]), "({b}, {a})");
                at += 1;
            }
        }
        assert_eq!(j.weight(0, 6), None);
        // Without it: the table of `encoded`, its flag clear.
        let (plain, m) = encoded();
        assert_eq!(m, n - joint_leverage::len(6));
        // Only the table's length field and the pose part's flags differ before the part.
        for i in 0..JOINTS_AT {
            if !((40..44).contains(&i) || i == AT + 2) {
                assert_eq!(buf[i], plain[i], "byte {i}");
            }
        }
        assert_eq!(buf[AT + 2], FLAG_JOINTS as u8);
        assert!(Table::parse(&plain[..m])
            .unwrap()
            .parameters()
            .unwrap()
            .pose()
            .unwrap()
            .joints()
            .is_none());
    }

    /// A corrupted joint leverage is refused, its CRC made to match: a count other than the
    /// table's joints, the reserved field, a mean not finite or past its limit, a weight not
    /// finite or past its limit, a negative diagonal; and a truncated one (the table's length
    /// then disagrees with what the part states). So is a table with the part read as a hub
    /// from before it reads it (its flag cleared: the length disagrees).
    #[test]
    fn a_bad_joint_leverage_is_refused() {
        let (good, n) = encoded_with_joints();
        let f = |x: f32| x.to_le_bytes();
        let mean = |i: usize| JOINTS_AT + joint_leverage::HEAD_LEN + 4 * i;
        let weight = |k: usize| mean(6) + 4 * k;
        let cases: [(&str, usize, std::vec::Vec<u8>); 11] = [
            ("k = 7 on a 6-joint table", JOINTS_AT, std::vec![7, 0]),
            ("k = 5 on a 6-joint table", JOINTS_AT, std::vec![5, 0]),
            ("reserved", JOINTS_AT + 2, std::vec![1, 0]),
            ("NaN mean", mean(3), f(f32::NAN).to_vec()),
            ("mean past the limit", mean(0), f(64.5).to_vec()),
            ("negative mean past the limit", mean(5), f(-100.0).to_vec()),
            ("infinite weight", weight(4), f(f32::NEG_INFINITY).to_vec()),
            ("weight past the limit", weight(1), f(2e12).to_vec()),
            ("negative diagonal", weight(6), f(-1e-3).to_vec()),
            ("an unknown flag of the pose part", AT + 2, std::vec![3, 0]),
            (
                "the flag cleared (a hub from before)",
                AT + 2,
                std::vec![0, 0],
            ),
        ];
        for (what, at, bytes) in cases {
            assert_refused(&good, n, what, at, &bytes);
        }
        // Truncated: the last weight cut off, the length field and CRC made to agree.
        let short = n - 4;
        let mut b = good;
        b.copy_within(n - TAIL_LEN..n, short - TAIL_LEN);
        b[40..44].copy_from_slice(&(short as u32).to_le_bytes());
        recrc(&mut b[..short]);
        assert!(matches!(
            Table::parse(&b[..short]),
            Err(TableError::BadLength(_))
        ));
        // The writer refuses what the reader would: μ of 5 joints or 8, W of the wrong length.
        for (m, w) in [(&MEAN[..5], &WEIGHT[..15]), (&MEAN[..], &WEIGHT[..20])] {
            let part = JointLeverageData { mean: m, weight: w };
            assert!(part.part_len().is_none(), "{} means", m.len());
        }
    }

    #[test]
    fn the_pose_part_round_trips() {
        let (buf, n) = encoded();
        assert_eq!(n, AT + len(3, 2) + TAIL_LEN);
        assert!(is_table_len(n));
        let t = Table::parse(&buf[..n]).unwrap();
        let p = t.parameters().unwrap();
        assert_eq!(p.count(), 3);
        assert_eq!(p.column(2), Some(COLUMNS[2]));
        let pose = p.pose().unwrap();
        assert_eq!(
            (pose.count(), pose.shrink(), pose.leverage_mean()),
            (2, 0.25, 2.5e-6)
        );
        for i in 0..3 {
            for j in 0..2 {
                assert_eq!(pose.entry(i, j), Some(D[2 * i + j]), "({i}, {j})");
            }
        }
        assert_eq!(pose.entry(3, 0), None);
        assert_eq!(pose.entry(0, 2), None);
        // Without the part: the same block reads as before, with no pose.
        let mut plain = [0u8; MAX_TABLE_LEN];
        let block = ParameterData {
            columns: &COLUMNS,
            factor: &FACTOR,
            pose: None,
        };
        let m = sample()
            .encode_full(Some(&BudgetData::default()), Some(&block), &mut plain)
            .unwrap();
        assert_eq!(m, n - len(3, 2));
        assert!(Table::parse(&plain[..m])
            .unwrap()
            .parameters()
            .unwrap()
            .pose()
            .is_none());
    }

    /// Each malformed value is refused as the budget's, with a CRC that matches.
    #[test]
    fn a_bad_pose_part_is_refused() {
        let (good, n) = encoded();
        let f = |x: f32| x.to_le_bytes();
        let cases: [(&str, usize, [u8; 4]); 9] = [
            (
                "r = 0 (its length then disagrees, or is refused)",
                AT,
                [0, 0, 0, 0],
            ),
            ("reserved", AT + 2, [1, 0, 0, 0]),
            ("negative shrink", AT + 4, f(-0.5)),
            ("NaN shrink", AT + 4, f(f32::NAN)),
            ("shrink past the limit", AT + 4, f(2e6)),
            ("zero mean", AT + 8, f(0.0)),
            ("negative mean", AT + 8, f(-1e-6)),
            ("infinite entry of D", AT + HEAD_LEN + 8, f(f32::INFINITY)),
            ("entry of D past the limit", AT + HEAD_LEN + 20, f(-3e6)),
        ];
        for (what, at, bytes) in cases {
            let k = if what == "reserved" { 2 } else { 4 };
            assert_refused(&good, n, what, at, &bytes[..k]);
        }
        // r past the cap, with a length that agrees: refused by the check, not read.
        let r = MAX_FACTORS + 1;
        let d = [0.0f32; 3 * (MAX_FACTORS + 1)];
        let mut buf = [0u8; MAX_TABLE_LEN];
        let block = ParameterData {
            columns: &COLUMNS,
            factor: &FACTOR,
            pose: Some(PoseData {
                factor: &d[..3 * MAX_FACTORS],
                count: MAX_FACTORS,
                shrink: 0.0,
                leverage_mean: 1e-6,
                joints: None,
            }),
        };
        let m = sample()
            .encode_full(Some(&BudgetData::default()), Some(&block), &mut buf)
            .unwrap();
        assert!(Table::parse(&buf[..m]).is_ok(), "r = MAX_FACTORS is taken");
        // Grow it by one column of D: count, length field, CRC.
        let grown = m + 4 * 3;
        buf.copy_within(m - TAIL_LEN..m, grown - TAIL_LEN);
        buf[AT..AT + 2].copy_from_slice(&(r as u16).to_le_bytes());
        buf[40..44].copy_from_slice(&(grown as u32).to_le_bytes());
        recrc(&mut buf[..grown]);
        assert_eq!(
            Table::parse(&buf[..grown]).unwrap_err(),
            TableError::Invalid {
                joint: 0,
                field: Field::Budget
            }
        );
        // The writer refuses what the reader would.
        for (count, factor) in [(0, &D[..0]), (2, &D[..5]), (r, &d[..])] {
            let block = ParameterData {
                columns: &COLUMNS,
                factor: &FACTOR,
                pose: Some(PoseData {
                    factor,
                    count,
                    shrink: 0.0,
                    leverage_mean: 1e-6,
                    joints: None,
                }),
            };
            assert!(block.block_len().is_none(), "r = {count}");
        }
    }

    /// The fuzz corpus's seed with a pose part (the shipped 52-parameter budget, a
    /// version-3 table, r = 3) is a table the parser takes, its part read back.
    #[test]
    fn the_fuzz_seed_with_a_pose_part_is_a_table() {
        let seed = include_bytes!("../../fuzz/corpus/table_parse/seed-default-6-full-pose.bin");
        let t = Table::parse(seed).unwrap();
        let pose = t.parameters().unwrap().pose().unwrap();
        assert_eq!((t.parameters().unwrap().count(), pose.count()), (52, 3));
        assert_eq!((pose.shrink(), pose.leverage_mean()), (0.2, 1e-6));
    }

    proptest::proptest! {
        /// Any bit flipped in a table with a pose part is refused (the CRC, or a check).
        #[test]
        fn flipped_bytes_of_a_pose_table_are_refused(at in 0usize..2000, bit in 0u8..8) {
            let (mut b, n) = encoded();
            let at = at % n;
            b[at] ^= 1 << bit;
            proptest::prop_assert!(Table::parse(&b[..n]).is_err());
        }

        /// Any bit flipped in a table with a joint leverage is refused.
        #[test]
        fn flipped_bytes_of_a_joint_leverage_table_are_refused(at in 0usize..2200, bit in 0u8..8) {
            let (mut b, n) = encoded_with_joints();
            let at = at % n;
            b[at] ^= 1 << bit;
            proptest::prop_assert!(Table::parse(&b[..n]).is_err());
        }

        /// A joint leverage whose bytes are random, its CRC made to match, is refused or read
        /// within its limits; never a panic.
        #[test]
        fn a_random_joint_leverage_is_refused_or_within_limits(
            bytes in proptest::collection::vec(proptest::num::u8::ANY, joint_leverage::len(6))
        ) {
            let (mut b, n) = encoded_with_joints();
            b[JOINTS_AT..JOINTS_AT + joint_leverage::len(6)].copy_from_slice(&bytes);
            recrc(&mut b[..n]);
            if let Ok(t) = Table::parse(&b[..n]) {
                let j = t.parameters().unwrap().pose().unwrap().joints().unwrap();
                proptest::prop_assert_eq!(j.count(), 6);
                for i in 0..6 {
                    let m = j.mean(i).unwrap();
                    proptest::prop_assert!(m.is_finite() && m.abs() <= joint_leverage::MEAN_LIMIT);
                    proptest::prop_assert!(j.weight(i, i).unwrap() >= 0.0);
                    for k in 0..6 {
                        let w = j.weight(i, k).unwrap();
                        proptest::prop_assert!(w.is_finite() && w.abs() <= joint_leverage::WEIGHT_LIMIT);
                    }
                }
            }
        }

        /// A pose part whose bytes are random, its CRC made to match, is refused or read
        /// within its limits; never a panic.
        #[test]
        fn a_random_pose_part_is_refused_or_within_limits(
            bytes in proptest::collection::vec(proptest::num::u8::ANY, len(3, 2))
        ) {
            let (mut b, n) = encoded();
            b[AT..AT + len(3, 2)].copy_from_slice(&bytes);
            recrc(&mut b[..n]);
            if let Ok(t) = Table::parse(&b[..n]) {
                let pose = t.parameters().unwrap().pose().unwrap();
                proptest::prop_assert!(pose.count() == 2 && pose.leverage_mean() > 0.0);
                proptest::prop_assert!((0.0..=LIMIT).contains(&pose.shrink()));
            }
        }
    }
}
