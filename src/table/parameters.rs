//! The calibration's parameter covariance in the table (`spec/uncertainty.md`, J_π C J_πᵀ):
//! every identified parameter as the way it moves the tip, and C as its Cholesky factor.
//!
//! The hub does not know what a tilt or a harmonic is: the host writes, for each parameter,
//! which motion it is — a turn about a joint's axis (weighed by 1, sin hθ, cos hθ or the
//! gravity lever), a turn about a fixed axis through the joint (a tilt, weighed by 1, sin hθ
//! or cos hθ), a shift along a fixed vector of a frame (a link or probe error, a thermal
//! expansion), or the shift of one probe of several, which moves the tip only while that
//! probe is mounted — and the hub evaluates that column from the joints' frames at the
//! reading ([`crate::uncertainty`]).
//! The columns are the host's analytic Jacobian (`armcal::jacobian`), term for term.
//!
//! Why this form and not a low-rank factor of C projected on the workspace: on the shipped
//! 52-parameter budget the parameter part is spread so evenly over the parameters that
//! 29 factors still leave 3.5–9.6 % of it out (`docs/spec-reading.md`, "The hub's U95"); the
//! exact factor of C costs 4 · P(P+1)/2 bytes, 5.5 KB for P = 52, and 3 · P(P+1)/2
//! multiply-adds a point. Its numbers are f32, the table's only ones: U95 needs 1e-3, and in
//! f64 the 52-parameter block (11 KB) would not leave a 16 KiB slot room for 64 parameters.
//!
//! ```text
//! offset   size        field                     (little-endian, after the budget)
//! ------   ----        ---------------------------------------------------------------
//!      0      2        parameter count P (1..=64)
//!      2      2        flags: bit 0 the pose part follows L ([`super::pose`]); the others 0
//!      4   P·24        one column record per parameter, in C's order:
//!                        +0  1  kind (`Kind`: 0 turn, 1 turn·sin hθ, 2 turn·cos hθ,
//!                               3 turn·gravity lever, 4 tilt, 5 shift, 6 tilt·sin hθ,
//!                               7 tilt·cos hθ, 8 shift of probe ID)
//!                        +1  1  joint k (0-based)
//!                        +2  2  harmonic order h (kinds 1, 2, 6 and 7), the probe's id
//!                               (kind 8, one of the table's); else 0
//!                        +4 12  vector u (f32 ×3; kinds 4 to 8; else 0)
//!                        +16 4  w0 (f32; kinds 5 and 8; else 0)
//!                        +20 4  w1 (f32, per °C; kinds 5 and 8; else 0)
//! 4+P·24  4·P(P+1)/2   L, lower triangular, C = L Lᵀ, row by row: L00, L10, L11, L20, …
//!                      (f32, the parameters' units: rad, mm, rad/mm, 1/°C)
//!   …    12+4·P·r      the pose part, where flag bit 0 is set ([`super::pose`]: its layout)
//! ```
//!
//! What each kind's column is, at a reading with tip p, joint origins o_k, axes a_k, frames
//! R_k (after joint k's turn; R_(−1) = I), θ_k the raw reading (rad), ΔT from 20 °C:
//!
//! | kind | column ∂p/∂π |
//! |------|--------------|
//! | 0 turn | a_k × (p − o_k) |
//! | 1, 2 | sin hθ_k (cos hθ_k) · a_k × (p − o_k) |
//! | 3 gravity | (a_k · ((p − o_k) × ẑ)) · a_k × (p − o_k) |
//! | 4 tilt | (R_(k−1) u) × (p − o_k), u in the frame before joint k |
//! | 5 shift | (w0 + w1 ΔT) · R_k u, u in the frame after joint k (the probe's is the last) |
//! | 6, 7 wobble | sin hθ_k (cos hθ_k) · (R_(k−1) u) × (p − o_k): the tilt's column, u the fixed tilt's axis (the wobble moves it by ~1e-4 of itself, far below U95's 1e-3) |
//! | 8 shift of probe ID | kind 5's column while the probe of that id is mounted, else 0 |
//!
//! The host writes a probe's error and expansion as kind 5 on an arm of one probe (so its
//! tables are as before) and as kind 8 on an arm of several: a parameter of a probe not
//! mounted does not move the tip.
//!
//! Vectors are in the calibration file's frames (each joint's axis its own x, y or z), as the
//! host's reference has them; the hub relabels them into its chain's z-axis frames.

use super::pose::{self, Pose, PoseData};
use super::{Field, TableError, MAX_JOINTS};

/// Most parameters a table carries: 64 fill a 16 KiB slot to 11.9 KB with 7 joints.
pub const MAX_PARAMETERS: usize = 64;
/// Length of one column record.
pub const COLUMN_LEN: usize = 24;
const HEAD_LEN: usize = 4;

/// The block's flag: the pose part follows L ([`super::pose`]).
pub const FLAG_POSE: u16 = 1 << 0;

/// The block's flags this firmware reads: the Pico's profile (`fixed-u95`, J·L in integers)
/// does not take the pose part, and refuses its flag.
const FLAGS_KNOWN: u16 = if cfg!(feature = "fixed-u95") {
    0
} else {
    FLAG_POSE
};

/// Length of the block for `p` parameters, without the pose part.
pub const fn len(p: usize) -> usize {
    HEAD_LEN + p * COLUMN_LEN + 4 * factor_len(p)
}

/// Entries of the lower triangle of a `p` × `p` matrix.
pub const fn factor_len(p: usize) -> usize {
    p * (p + 1) / 2
}

/// Largest magnitude of a vector component, weight or factor entry: far beyond any real
/// parameter's (a link error's factor entry is ~1e-3 mm, a unit vector's 1), small enough
/// that no product of them leaves f32.
pub const LIMIT: f32 = 1.0e6;

/// How a parameter moves the tip (the block's kind byte).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Kind {
    /// An angle added to joint k: a zero offset.
    Turn,
    /// An angle sin(hθ_k) added to joint k: a harmonic's sin coefficient.
    TurnSin,
    /// An angle cos(hθ_k) added to joint k: a harmonic's cos coefficient.
    TurnCos,
    /// The gravity deflection of joint k per unit compliance: the parameter `gravity`
    /// (`quatarm_params::Param::Gravity`), a turn weighed by its lever.
    Gravity,
    /// A turn about the fixed axis u of the frame before joint k, through its origin.
    Tilt,
    /// A shift by (w0 + w1 ΔT) u in the frame after joint k.
    Shift,
    /// A turn sin(hθ_k) about the fixed axis u of the frame before joint k: an axis wobble's
    /// sin coefficient.
    TiltSin,
    /// A turn cos(hθ_k) about the fixed axis u: an axis wobble's cos coefficient.
    TiltCos,
    /// A [`Kind::Shift`] of the probe whose id is the record's `order`: it moves the tip only
    /// while that probe is mounted (an arm of several probes).
    ProbeShift,
}

impl Kind {
    fn from_byte(b: u8) -> Option<Kind> {
        Some(match b {
            0 => Kind::Turn,
            1 => Kind::TurnSin,
            2 => Kind::TurnCos,
            3 => Kind::Gravity,
            4 => Kind::Tilt,
            5 => Kind::Shift,
            6 => Kind::TiltSin,
            7 => Kind::TiltCos,
            8 => Kind::ProbeShift,
            _ => return None,
        })
    }

    /// The kind byte.
    pub fn byte(self) -> u8 {
        self as u8
    }
}

/// One parameter's column record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Column {
    /// How it moves the tip.
    pub kind: Kind,
    /// The joint whose frame it acts in (0-based).
    pub joint: u8,
    /// The harmonic's order (kinds [`Kind::TurnSin`], [`Kind::TurnCos`], [`Kind::TiltSin`],
    /// [`Kind::TiltCos`]), the probe's id ([`Kind::ProbeShift`]); else 0.
    pub order: u16,
    /// The axis or shift vector (kinds [`Kind::Tilt`] to [`Kind::ProbeShift`]; else 0).
    pub vector: [f32; 3],
    /// The shift's weight at 20 °C ([`Kind::Shift`], [`Kind::ProbeShift`]; else 0).
    pub w0: f32,
    /// The shift's weight per °C ([`Kind::Shift`], [`Kind::ProbeShift`]; else 0).
    pub w1: f32,
}

impl Column {
    /// A column of `kind` at `joint` with everything else 0.
    pub fn new(kind: Kind, joint: u8) -> Column {
        Column {
            kind,
            joint,
            order: 0,
            vector: [0.0; 3],
            w0: 0.0,
            w1: 0.0,
        }
    }

    fn encode(&self, out: &mut [u8]) {
        out[0] = self.kind.byte();
        out[1] = self.joint;
        out[2..4].copy_from_slice(&self.order.to_le_bytes());
        for (chunk, x) in out[4..].chunks_exact_mut(4).zip(
            self.vector
                .iter()
                .chain(core::iter::once(&self.w0))
                .chain(core::iter::once(&self.w1)),
        ) {
            chunk.copy_from_slice(&x.to_le_bytes());
        }
    }
}

/// The block to write ([`super::TableData::encode_full`]): columns and factor of the same
/// length P; the factor's strict upper triangle is not written.
#[derive(Clone, Copy, Debug)]
pub struct ParameterData<'a> {
    /// One column per parameter.
    pub columns: &'a [Column],
    /// The factor L, row by row, [`factor_len`]`(P)` entries.
    pub factor: &'a [f32],
    /// The budget's pose part, where it has one ([`super::pose`]).
    pub pose: Option<PoseData<'a>>,
}

impl ParameterData<'_> {
    /// The block's length in bytes, its pose part's included; `None` if P is 0, above
    /// [`MAX_PARAMETERS`], the factor's length is not P's, or the pose part is malformed
    /// ([`PoseData::part_len`]).
    pub fn block_len(&self) -> Option<usize> {
        let p = self.columns.len();
        if !(1..=MAX_PARAMETERS).contains(&p) || self.factor.len() != factor_len(p) {
            return None;
        }
        let part = match &self.pose {
            Some(pose) => pose.part_len(p)?,
            None => 0,
        };
        Some(len(p) + part)
    }

    /// Writes the block into `out` (exactly [`Self::block_len`] bytes).
    pub(super) fn encode(&self, out: &mut [u8]) {
        let p = self.columns.len();
        out[0..2].copy_from_slice(&(p as u16).to_le_bytes());
        let flags = if self.pose.is_some() { FLAG_POSE } else { 0 };
        out[2..4].copy_from_slice(&flags.to_le_bytes());
        if let Some(pose) = &self.pose {
            pose.encode(&mut out[len(p)..]);
        }
        for (c, rec) in self
            .columns
            .iter()
            .zip(out[HEAD_LEN..HEAD_LEN + p * COLUMN_LEN].chunks_exact_mut(COLUMN_LEN))
        {
            c.encode(rec);
        }
        let at = HEAD_LEN + p * COLUMN_LEN;
        for (chunk, x) in out[at..].chunks_exact_mut(4).zip(self.factor) {
            chunk.copy_from_slice(&x.to_le_bytes());
        }
    }
}

/// A table's parameter block, borrowing its bytes (length checked by the table).
#[derive(Clone, Copy, Debug)]
pub struct Parameters<'a> {
    bytes: &'a [u8],
}

fn rd_f32(b: &[u8], at: usize) -> f32 {
    f32::from_bits(super::rd_u32(b, at))
}

/// The parameter count the block at `bytes` states (0 if it cannot be read).
pub(super) fn stated_count(bytes: &[u8]) -> usize {
    usize::from(super::rd_u16(bytes, 0))
}

/// The length the block at `bytes` states: its count's, and its pose part's where its flag
/// is set. The count is clamped to one past [`MAX_PARAMETERS`] (which the check refuses), so
/// that no stated count overflows a 32-bit length.
pub(super) fn stated_len(bytes: &[u8]) -> usize {
    let p = stated_count(bytes).min(MAX_PARAMETERS + 1);
    let base = len(p);
    if stated_flags(bytes) & FLAG_POSE == 0 {
        return base;
    }
    base + pose::stated_len(bytes.get(base..).unwrap_or(&[]), p)
}

/// The block's flags field.
fn stated_flags(bytes: &[u8]) -> u16 {
    super::rd_u16(bytes, 2)
}

impl<'a> Parameters<'a> {
    pub(super) fn new(bytes: &'a [u8]) -> Parameters<'a> {
        Parameters { bytes }
    }

    /// Number of parameters P.
    pub fn count(&self) -> usize {
        stated_count(self.bytes)
    }

    /// Parameter `i`'s column record; `None` past the last or for an unknown kind.
    pub fn column(&self, i: usize) -> Option<Column> {
        if i >= self.count() {
            return None;
        }
        let r = self
            .bytes
            .get(HEAD_LEN + i * COLUMN_LEN..HEAD_LEN + (i + 1) * COLUMN_LEN)?;
        Some(Column {
            kind: Kind::from_byte(r[0])?,
            joint: r[1],
            order: super::rd_u16(r, 2),
            vector: [rd_f32(r, 4), rd_f32(r, 8), rd_f32(r, 12)],
            w0: rd_f32(r, 16),
            w1: rd_f32(r, 20),
        })
    }

    /// L whole, row after row, as raw little-endian bytes: row `i` starts at byte
    /// 4 · [`factor_len`]`(i)` (empty if the block is shorter than its count states).
    pub fn factor(&self) -> &'a [u8] {
        let at = HEAD_LEN + self.count() * COLUMN_LEN;
        self.bytes
            .get(at..at + 4 * factor_len(self.count()))
            .unwrap_or(&[])
    }

    /// The budget's pose part, where the block has one ([`super::pose`]).
    pub fn pose(&self) -> Option<Pose<'a>> {
        if stated_flags(self.bytes) & FLAG_POSE == 0 {
            return None;
        }
        let p = self.count();
        self.bytes.get(len(p)..).map(|b| Pose::new(b, p))
    }

    /// L's row `i` (its first i + 1 entries), as raw little-endian bytes.
    pub fn factor_row(&self, i: usize) -> &'a [u8] {
        let at = HEAD_LEN + self.count() * COLUMN_LEN + 4 * factor_len(i);
        self.bytes.get(at..at + 4 * (i + 1)).unwrap_or(&[])
    }

    /// Every record well formed (a probe's shift naming one of the table's probes: `probe`
    /// tells an id of the table's) and every number finite and within [`LIMIT`] (what the
    /// boot applies to a table that has the block).
    #[cfg_attr(not(feature = "parameters"), allow(dead_code))] // refused by its flag there
    pub(super) fn check(
        &self,
        joints: usize,
        probe: impl Fn(u8) -> bool,
    ) -> Result<(), TableError> {
        let bad = TableError::Invalid {
            joint: 0,
            field: Field::Budget,
        };
        let p = self.count();
        if !(1..=MAX_PARAMETERS).contains(&p) {
            return Err(bad);
        }
        // A flag this firmware does not read: refused as the header's unknown flags are.
        if stated_flags(self.bytes) & !FLAGS_KNOWN != 0 {
            return Err(TableError::Invalid {
                joint: 0,
                field: Field::Flags,
            });
        }
        let ok = |x: f32| x.is_finite() && x.abs() <= LIMIT;
        for i in 0..p {
            let c = self.column(i).ok_or(bad)?;
            let harmonic = matches!(
                c.kind,
                Kind::TurnSin | Kind::TurnCos | Kind::TiltSin | Kind::TiltCos
            );
            let shift = matches!(c.kind, Kind::Shift | Kind::ProbeShift);
            let vector = shift || matches!(c.kind, Kind::Tilt | Kind::TiltSin | Kind::TiltCos);
            let order_ok = match c.kind {
                Kind::ProbeShift => u8::try_from(c.order).is_ok_and(&probe),
                _ => (c.order != 0) == harmonic && c.order <= super::MAX_HARMONIC_ORDER,
            };
            let weights = shift;
            let well_formed = usize::from(c.joint) < joints.min(MAX_JOINTS)
                && order_ok
                && c.vector
                    .iter()
                    .all(|&x| ok(x) && (vector || x.to_bits() == 0))
                && [c.w0, c.w1]
                    .iter()
                    .all(|&x| ok(x) && (weights || x.to_bits() == 0));
            if !well_formed {
                return Err(TableError::Invalid {
                    joint: c.joint.saturating_add(1),
                    field: Field::Budget,
                });
            }
        }
        for i in 0..p {
            let row = self.factor_row(i);
            if row.len() != 4 * (i + 1) || !(0..=i).all(|k| ok(rd_f32(row, 4 * k))) {
                return Err(bad);
            }
        }
        match self.pose() {
            Some(pose) => pose.check(joints),
            None => Ok(()),
        }
    }
}

#[cfg(all(test, feature = "parameters"))]
mod tests {
    use super::*;
    use crate::table::budget::BudgetData;
    use crate::table::tests::{recrc, sample};
    use crate::table::{Table, FLAG_PARAMETERS, MAX_TABLE_LEN};

    /// The kind bytes are the contract with the tables already written: a rename of a kind
    /// (gravity's, once spelt as a turn, is `Gravity`) keeps its byte, and no byte moves.
    #[test]
    fn kind_bytes_are_fixed() {
        let kinds = [
            (Kind::Turn, 0),
            (Kind::TurnSin, 1),
            (Kind::TurnCos, 2),
            (Kind::Gravity, 3),
            (Kind::Tilt, 4),
            (Kind::Shift, 5),
            (Kind::TiltSin, 6),
            (Kind::TiltCos, 7),
            (Kind::ProbeShift, 8),
        ];
        for (kind, byte) in kinds {
            assert_eq!(kind.byte(), byte, "{kind:?}");
            assert_eq!(Kind::from_byte(byte), Some(kind));
        }
        assert_eq!(Kind::from_byte(9), None);
        assert_eq!(Kind::from_byte(0xff), None);
    }

    fn columns() -> [Column; 3] {
        [
            Column::new(Kind::Turn, 1),
            Column {
                order: 2,
                ..Column::new(Kind::TurnCos, 3)
            },
            Column {
                vector: [0.0, 0.0, 1.0],
                w0: 1.0,
                w1: 2.3e-5,
                ..Column::new(Kind::Shift, 5)
            },
        ]
    }

    const FACTOR: [f32; 6] = [1e-5, 2e-6, 3e-5, -1e-6, 0.0, 4e-3];

    fn encoded() -> ([u8; MAX_TABLE_LEN], usize) {
        let mut buf = [0u8; MAX_TABLE_LEN];
        let cols = columns();
        let block = ParameterData {
            columns: &cols,
            factor: &FACTOR,
            pose: None,
        };
        let n = sample()
            .encode_full(Some(&BudgetData::default()), Some(&block), &mut buf)
            .unwrap();
        (buf, n)
    }

    /// The block's start in a 6-joint table.
    const AT: usize = 48 + 6 * 248 + 64 + 80;

    #[test]
    fn a_block_round_trips() {
        let (buf, n) = encoded();
        assert_eq!(n, 48 + 6 * 248 + 64 + 80 + len(3) + crate::table::TAIL_LEN);
        assert!(crate::table::is_table_len(n));
        let t = Table::parse(&buf[..n]).unwrap();
        let p = t.parameters().unwrap();
        assert_eq!(p.count(), 3);
        for (i, c) in columns().iter().enumerate() {
            assert_eq!(p.column(i).as_ref(), Some(c));
        }
        let row2: Vec<f32> = p
            .factor_row(2)
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        assert_eq!(row2, FACTOR[3..]);
    }

    /// A probe's shift names one of the table's probes by id: one of the sample's (its only
    /// probe, id 0) is taken and reads back; another id is refused.
    #[test]
    fn a_probes_shift_names_a_probe_of_the_table() {
        let mut cols = columns();
        cols[2].kind = Kind::ProbeShift;
        let block = ParameterData {
            columns: &cols,
            factor: &FACTOR,
            pose: None,
        };
        let mut buf = [0u8; MAX_TABLE_LEN];
        let n = sample()
            .encode_full(Some(&BudgetData::default()), Some(&block), &mut buf)
            .unwrap();
        let t = Table::parse(&buf[..n]).unwrap();
        assert_eq!(t.parameters().unwrap().column(2), Some(cols[2]));
        let order = AT + 4 + 2 * COLUMN_LEN + 2;
        buf[order] = 1;
        recrc(&mut buf[..n]);
        assert_eq!(
            Table::parse(&buf[..n]).unwrap_err(),
            TableError::Invalid {
                joint: 6,
                field: Field::Budget
            }
        );
    }

    /// Every malformed record or value is refused, naming the budget (and the joint where
    /// there is one); so is the block's flag without a budget.
    #[test]
    fn a_bad_block_is_refused() {
        let (good, n) = encoded();
        let rec = |i: usize| AT + 4 + i * COLUMN_LEN;
        let cases: [(&str, usize, &[u8]); 5] = [
            ("unknown kind", rec(0), &[9]),
            ("joint past the table", rec(0) + 1, &[6]),
            ("harmonic without order", rec(1) + 2, &[0, 0]),
            ("turn with a vector", rec(0) + 4, &1.0f32.to_le_bytes()),
            (
                "NaN in the factor",
                AT + 4 + 3 * COLUMN_LEN,
                &f32::NAN.to_le_bytes(),
            ),
        ];
        for (what, at, bytes) in cases {
            let mut b = good;
            b[at..at + bytes.len()].copy_from_slice(bytes);
            recrc(&mut b[..n]);
            match Table::parse(&b[..n]) {
                Err(TableError::Invalid {
                    field: Field::Budget,
                    ..
                }) => {}
                other => panic!("{what}: {other:?}"),
            }
        }
        // A block flag this firmware does not know: refused by it, not read as a length.
        let mut b = good;
        b[AT + 2] = 2;
        recrc(&mut b[..n]);
        assert_eq!(
            Table::parse(&b[..n]).unwrap_err(),
            TableError::Invalid {
                joint: 0,
                field: Field::Flags
            }
        );
        // The pose flag on a block without the part: its length disagrees.
        let mut b = good;
        b[AT + 2] = 1;
        recrc(&mut b[..n]);
        assert!(matches!(
            Table::parse(&b[..n]),
            Err(TableError::BadLength(_))
        ));
        let mut b = [0u8; MAX_TABLE_LEN];
        let m = sample().encode(&mut b).unwrap();
        b[7] |= FLAG_PARAMETERS;
        recrc(&mut b[..m]);
        assert!(Table::parse(&b[..m]).is_err());
    }
}
