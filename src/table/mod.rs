//! The binary calibration table: what a board keeps in a flash region of its own.
//!
//! The host builds it from a calibration file (`armcal table build`) with everything that is
//! constant precomputed in f64: the misalignment quaternion with the zero offset folded in,
//! M'_i = R(e1, δα) · R(e2, δβ) · R(u, Δθ), the same rotation as a 3×3 matrix (for the matrix
//! chain), the link vectors with their errors, the probe vector and its unit direction. Real
//! numbers are stored as little-endian IEEE-754 f64: the one format from which both the f32 and
//! the fixed-point evaluator take their full accuracy (each rounds once, when the chain is
//! built at boot; nothing in the per-point path touches f64).
//!
//! ```text
//! offset  size  field                                   (all little-endian)
//! ------  ----  ---------------------------------------------------------------
//!      0     4  magic "QATB"
//!      4     2  format version (3)
//!      6     1  joint count N (6 or 7)
//!      7     1  flags: bit0 geometric errors, bit1 encoder harmonics,
//!               bit2 gravity compliance, bit3 thermal expansion, bit4 uncertainty budget,
//!               bit5 parameter covariance (only with bit4), bit6 axis wobble, bit7 more
//!               probes
//!      8    32  arm serial, UTF-8, NUL-padded
//!     40     4  total length in bytes, CRC included (= 48 + N·248 + 64 + 4, plus the
//!               uncertainty budget's length where flag bit4 is set, the parameter
//!               block's where bit5 is, the wobble block's where bit6 is, the probes
//!               block's where bit7 is)
//!     44     1  the first probe's id (0 for an arm of one probe without an id)
//!     45     3  reserved, 0
//!     48 N·248  joint records, base first:
//!                 +0    1  axis: 0 = x, 1 = y, 2 = z
//!                 +1    1  harmonic count H (0..=4)
//!                 +2    2  reserved, 0
//!                 +4    4  counts per revolution (2..=2^31 − 1)
//!                 +8   32  M'_i quaternion w, x, y, z (f64)
//!                 +40  72  M'_i as a 3×3 matrix, row-major (f64)
//!                 +112 24  link vector v_i + Δv_i (mm, f64 ×3)
//!                 +136  8  thermal expansion κ_i (1/°C, f64)
//!                 +144  8  gravity compliance g_i (rad/mm, f64)
//!                 +152 96  4 harmonic slots of 24 bytes, the first H used:
//!                            +0 2 order h (1..=64), +2 6 reserved 0,
//!                            +8 8 sin coefficient (rad), +16 8 cos coefficient (rad)
//! 48+N·248   64  probe: vector v_p + Δv_p (mm, f64 ×3), its unit direction (f64 ×3),
//!               thermal expansion κ_p (1/°C, f64), stylus ball diameter (mm, f64; 0 unknown)
//! 48+N·248+64    the uncertainty budget, where flag bit4 is set ([`budget`]: its layout)
//!   … +80        the parameter covariance, where flag bit5 is set ([`parameters`]: its
//!                layout; its parameter count is its first field), and after its factor
//!                the budget's pose part where the block's own flag says so ([`pose`])
//!   …            the axis wobble, where flag bit6 is set ([`wobble`]: its layout; its joint
//!                count is its first field)
//!   …            the arm's other probes, where flag bit7 is set ([`probes`]: its layout;
//!                its probe count is its first field)
//!  len−12    4  calibration number (version 4 only): monotonic per arm, the hub's
//!               anti-rollback counter ([`Release`]; `docs/update.md`)
//!  len−8     4  calibration date (version 4 only) as the decimal number YYYYMMDD, 0 unknown
//!  len−4     4  CRC-32 (ISO-HDLC, as zlib) of every byte before it
//! ```
//!
//! A version-3 table (no number, no date) is still read, as number 0 and no date: it can go
//! live only on a hub whose live number is 0, so it never replaces a numbered calibration.
//!
//! [`Table::parse`] is a checked constructor in the manner of smoltcp's `new_checked`: it
//! validates length, magic, version, CRC, joint count and every value's range once; after it
//! the accessors cannot fail and nothing panics on any input. Erased flash (all 0xFF) and
//! zeroed flash are reported as [`TableError::Blank`], not as corruption.

use core::fmt;

pub mod budget;
pub mod joint_leverage;
pub mod parameters;
pub mod pose;
pub mod probes;
pub mod wobble;

/// The table's magic bytes.
pub const MAGIC: [u8; 4] = *b"QATB";
/// The format version this firmware reads and writes. Version 2 widened the serial from 16
/// to 32 bytes (the MUKCa Panda `panda_1_with_sensor` has 19), which moved every field after
/// it; a version-1 table is refused ([`TableError::UnsupportedVersion`]) rather than read, since
/// the Cortex-M0 image has no flash for a second layout: rebuild it with `armcal table build`.
///
/// Version 3 added the stylus ball diameter to the probe record (the sphere tests of
/// `spec/acceptance-tests.md` compensate it) and the optional uncertainty budget
/// ([`budget`]); a version-2 table is refused like a version-1 one.
///
/// Version 4 added the calibration number and date before the CRC ([`Release`]), inside what
/// the signature covers; every block before them kept its place, so version 3 is still read
/// (as number 0, no date: [`OLD_VERSION`]).
pub const VERSION: u16 = 4;
/// The older format version still read: a version-4 table without the release fields.
pub const OLD_VERSION: u16 = 3;
/// Bytes of the release fields (calibration number, date) of a version-4 table.
pub const RELEASE_LEN: usize = 8;
/// Most joints a table holds.
pub const MAX_JOINTS: usize = 7;
/// Fewest joints a table holds.
pub const MIN_JOINTS: usize = 6;
/// Harmonic slots per joint.
pub const MAX_HARMONICS: usize = 4;
/// Highest harmonic order.
pub const MAX_HARMONIC_ORDER: u16 = 64;
/// Length of the serial field (bytes of UTF-8).
pub const SERIAL_LEN: usize = 32;

/// Header length.
pub const HEADER_LEN: usize = 48;
/// Length of one joint record.
pub const JOINT_LEN: usize = 248;
/// Length of the probe record.
pub const PROBE_LEN: usize = 64;
/// Length of one harmonic slot.
pub const HARMONIC_LEN: usize = 24;
const CRC_LEN: usize = 4;
/// What follows the last block: the release fields and the CRC (of a version-4 table).
pub(crate) const TAIL_LEN: usize = RELEASE_LEN + CRC_LEN;

mod off {
    pub const MAGIC: usize = 0;
    pub const VERSION: usize = 4;
    pub const JOINTS: usize = 6;
    pub const FLAGS: usize = 7;
    pub const SERIAL: usize = 8;
    pub const LENGTH: usize = 40;
    pub const PROBE_ID: usize = 44;
    pub const RESERVED: usize = 45;
    // Joint record.
    pub const AXIS: usize = 0;
    pub const HARMONICS: usize = 1;
    pub const J_RESERVED: usize = 2;
    pub const COUNTS: usize = 4;
    pub const QUAT: usize = 8;
    pub const MATRIX: usize = 40;
    pub const LINK: usize = 112;
    pub const THERMAL: usize = 136;
    pub const GRAVITY: usize = 144;
    pub const SLOTS: usize = 152;
    // Harmonic slot.
    pub const H_ORDER: usize = 0;
    pub const H_RESERVED: usize = 2;
    pub const H_SIN: usize = 8;
    pub const H_COS: usize = 16;
    // Probe record.
    pub const P_VECTOR: usize = 0;
    pub const P_DIR: usize = 24;
    pub const P_THERMAL: usize = 48;
    pub const P_BALL: usize = 56;
}

/// Flag: some geometric error (zero offset, tilt, link or probe error) is non-zero.
pub const FLAG_GEOMETRIC: u8 = 1 << 0;
/// Flag: some joint has encoder harmonics.
pub const FLAG_HARMONICS: u8 = 1 << 1;
/// Flag: some joint has gravity compliance.
pub const FLAG_GRAVITY: u8 = 1 << 2;
/// Flag: some link or the probe has thermal expansion.
pub const FLAG_THERMAL: u8 = 1 << 3;
/// Flag: the table carries an uncertainty budget ([`budget`]).
pub const FLAG_BUDGET: u8 = 1 << 4;
/// Flag: the table carries the calibration's parameter covariance ([`parameters`]), after
/// the budget (so only with [`FLAG_BUDGET`]).
pub const FLAG_PARAMETERS: u8 = 1 << 5;
/// Flag: some joint has an axis wobble ([`wobble`]: its block, after every other).
pub const FLAG_WOBBLE: u8 = 1 << 6;
/// Flag: the arm has more than one probe ([`probes`]: the others' block, after every other).
pub const FLAG_PROBES: u8 = 1 << 7;
/// Without the `parameters` or `wobble` feature, that block's flag is unknown, so refused.
const FLAGS_KNOWN: u8 = 0x1f
    | FLAG_PROBES
    | if cfg!(feature = "parameters") {
        FLAG_PARAMETERS
    } else {
        0
    }
    | if cfg!(feature = "wobble") {
        FLAG_WOBBLE
    } else {
        0
    };

/// Limits of the values a table may hold. They keep every evaluator inside its range and its
/// small-angle formulas inside their accuracy; a real arm is far inside them.
pub mod limits {
    /// |component| of a link or probe vector (mm).
    pub const LENGTH_MM: f64 = 5000.0;
    /// |κ| (1/°C).
    pub const THERMAL: f64 = 4.0e-4;
    /// |g| (rad/mm). A hub-class arm deflects 2–4e-8; the light robots of the MUKCa data fit
    /// up to ~2e-6. At the limit, on three hinges of a 1.5 m arm (deflections of ~5 mrad), the
    /// quaternion chain's small-angle turns and second-order compositions stay within the
    /// fixed-point bounds (0.034 µm, 6.6e-8; `host-tests` `chain_accuracy`); at 5e-6 they
    /// would not (0.09 µm, 2.5e-7).
    pub const GRAVITY: f64 = 3.0e-6;
    /// Σ |sin| + |cos| of a joint's harmonics (rad): the small-angle rotation stays
    /// second-order exact.
    pub const HARMONIC_SUM: f64 = 1.0e-3;
    /// How far a stored rotation may be from unit length / orthonormal.
    pub const UNIT_TOLERANCE: f64 = 1.0e-9;
    /// The arm's reach: Σ |components| of the links and the probe (mm), a bound on every
    /// coordinate the chain can produce. Every board streams XYZ as i32 nanometres, whose
    /// range is ±2147.483647 mm; thermal expansion at the accepted temperatures (|κ| ≤ 4e-4
    /// over 100 °C) stretches the arm by at most 4 %, to 2146.6 mm here. A longer arm would be
    /// clipped in the stream: the host's table builder refuses it, and on the board
    /// `Chain::new` refuses any table whose reach with that margin leaves its evaluator's
    /// range ([`crate::ChainError::Reach`]; f32 1650 mm, its rounding's; fixed point 2000 mm,
    /// its I12F20's). (The check lives there rather than in [`super::Table::parse`] because the
    /// chain sums the reach anyway, and the Cortex-M0 image has no flash for a second sum.)
    pub const REACH_MM: f64 = 2064.0;
    /// Stylus ball diameter (mm): larger than any stylus an arm carries.
    pub const BALL_MM: f64 = 100.0;
}

/// Why a table cannot be used. The firmware streams no coordinates while it has one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum TableError {
    /// The region is erased (all 0xFF) or zeroed: no table was ever flashed.
    Blank,
    /// Fewer bytes than the header says, or than any table needs.
    Truncated {
        /// Bytes the table needs.
        needed: u32,
        /// Bytes available.
        available: u32,
    },
    /// The first four bytes are not "QATB": not a quatarm table.
    BadMagic,
    /// A format version this firmware does not read.
    UnsupportedVersion(u16),
    /// A joint count outside 6..=7.
    BadJointCount(u8),
    /// The table is for another number of joints than this firmware drives.
    WrongJointCount {
        /// Joints the firmware drives.
        expected: u8,
        /// Joints in the table.
        found: u8,
    },
    /// The length field disagrees with the joint count.
    BadLength(u32),
    /// The CRC does not match: the table is corrupt.
    Crc {
        /// CRC stored in the table.
        stored: u32,
        /// CRC of the bytes.
        computed: u32,
    },
    /// A value out of its range; `joint` is 1-based, 0 for the header or the probe.
    Invalid {
        /// The joint (1..=N), or 0 for the header and probe.
        joint: u8,
        /// Which field.
        field: Field,
    },
}

/// A field of the table, named in [`TableError::Invalid`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Field {
    /// Header flags (unknown bits, or disagreeing with the contents).
    Flags,
    /// A reserved field is not zero.
    Reserved,
    /// Serial number not UTF-8.
    Serial,
    /// Axis not 0, 1 or 2.
    Axis,
    /// Counts per revolution outside 2..=2^31 − 1.
    Counts,
    /// Harmonic count above 4.
    HarmonicCount,
    /// Harmonic order 0 or above 64.
    HarmonicOrder,
    /// Harmonic coefficients not finite or too large.
    Harmonic,
    /// Rotation quaternion not unit, or matrix not its rotation.
    Rotation,
    /// Link vector not finite or too long.
    Link,
    /// Thermal coefficient not finite or too large.
    Thermal,
    /// Gravity coefficient not finite or too large.
    Gravity,
    /// Probe vector or direction invalid.
    Probe,
    /// The uncertainty budget: a standard uncertainty out of range, a factor's scale, or a
    /// factor table that is not a table of the same arm.
    Budget,
    /// The axis wobble block: its joints, terms, coefficients or axes.
    Wobble,
}

impl fmt::Display for Field {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Field::Flags => "flags",
            Field::Reserved => "reserved field",
            Field::Serial => "serial",
            Field::Axis => "axis",
            Field::Counts => "counts per revolution",
            Field::HarmonicCount => "harmonic count",
            Field::HarmonicOrder => "harmonic order",
            Field::Harmonic => "harmonic coefficients",
            Field::Rotation => "rotation",
            Field::Link => "link vector",
            Field::Thermal => "thermal coefficient",
            Field::Gravity => "gravity coefficient",
            Field::Probe => "probe",
            Field::Budget => "uncertainty budget",
            Field::Wobble => "axis wobble",
        })
    }
}

impl fmt::Display for TableError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            TableError::Blank => f.write_str("no calibration table (blank flash)"),
            TableError::Truncated { needed, available } => {
                write!(
                    f,
                    "calibration table truncated: {available} of {needed} bytes"
                )
            }
            TableError::BadMagic => f.write_str("not a calibration table (bad magic)"),
            TableError::UnsupportedVersion(v) => {
                write!(
                    f,
                    "calibration table format version {v}, this firmware reads {OLD_VERSION} and {VERSION} \
                     (rebuild the table from its calibration file: armcal table build)"
                )
            }
            TableError::BadJointCount(n) => write!(f, "calibration table has {n} joints"),
            TableError::WrongJointCount { expected, found } => write!(
                f,
                "calibration table is for {found} joints, this firmware drives {expected}"
            ),
            TableError::BadLength(l) => write!(f, "calibration table length field {l} is wrong"),
            TableError::Crc { stored, computed } => write!(
                f,
                "calibration table corrupt: CRC {computed:08x}, stored {stored:08x}"
            ),
            TableError::Invalid { joint: 0, field } => {
                write!(f, "calibration table: invalid {field}")
            }
            TableError::Invalid { joint, field } => {
                write!(f, "calibration table: joint {joint}: invalid {field}")
            }
        }
    }
}

impl core::error::Error for TableError {}

/// The CRC of the table: CRC-32/ISO-HDLC (the zlib and Ethernet CRC).
pub const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// Table length for `joints` joints, without an uncertainty budget.
pub const fn table_len(joints: usize) -> usize {
    core_len(joints) + TAIL_LEN
}

/// Whether a table can be `len` bytes long: 6 or 7 joints, with or without the budget, with
/// or without a parameter block after it, a wobble block, a block of other probes (what an
/// update must be told before any byte of it arrives).
/// A version-3 table is [`RELEASE_LEN`] bytes shorter than the same version-4 one.
pub fn is_table_len(len: usize) -> bool {
    is_v4_len(len) || is_v4_len(len + RELEASE_LEN)
}

fn is_v4_len(len: usize) -> bool {
    (MIN_JOINTS..=MAX_JOINTS).any(|n| {
        // The wobble block, of any joint count the arm has, or none.
        let wobbles = if cfg!(feature = "wobble") { n } else { 0 };
        (0..=wobbles).any(|w| {
            // The other probes' block, of 1 to 7 probes, or none.
            (0..probes::MAX_PROBES).any(|p| {
                let wobble = if w > 0 { wobble::len(w) } else { 0 };
                let others = if p > 0 { probes::len(p) } else { 0 };
                let Some(rest) = len.checked_sub(table_len(n) + wobble + others) else {
                    return false;
                };
                // Then the budget, and the parameter block after it, or neither.
                rest == 0
                    || rest == budget::LEN
                    || rest
                        .checked_sub(budget::LEN)
                        .is_some_and(|b| is_block_len(b, n))
            })
        })
    })
}

// Out of line: inlined into the loops above, its 64 lengths were unrolled into 5 KB.
#[cfg(feature = "parameters")]
#[inline(never)]
fn is_block_len(len: usize, joints: usize) -> bool {
    (1..=parameters::MAX_PARAMETERS).any(|p| {
        // The block alone, or with a pose part of 1 to MAX_FACTORS columns, with or without
        // the joint leverage of the table's joints.
        len.checked_sub(parameters::len(p)).is_some_and(|rest| {
            let column = 4 * p;
            let is_pose = |d: usize| {
                d.checked_sub(pose::HEAD_LEN).is_some_and(|d| {
                    d % column == 0 && (1..=pose::MAX_FACTORS).contains(&(d / column))
                })
            };
            rest == 0
                || is_pose(rest)
                || rest
                    .checked_sub(joint_leverage::len(joints))
                    .is_some_and(is_pose)
        })
    })
}

#[cfg(not(feature = "parameters"))]
fn is_block_len(_: usize, _: usize) -> bool {
    false
}

/// The bytes after the last block: the release fields (version 4) and the CRC.
const fn tail_len(version: u16) -> usize {
    if version == OLD_VERSION {
        CRC_LEN
    } else {
        TAIL_LEN
    }
}

/// Where the budget starts: the header, the joints and the probe.
const fn core_len(joints: usize) -> usize {
    HEADER_LEN + joints * JOINT_LEN + PROBE_LEN
}

/// Largest table length: 7 joints with a budget and 8 probes, `parameters::MAX_PARAMETERS`
/// parameters where the `parameters` feature reads them and every joint's wobble where the
/// `wobble` feature does (12,308 bytes with the first, 13,824 with both; without either,
/// [`MAX_PLAIN_TABLE_LEN`]). A block with the budget's pose part ([`pose`]) must fit too:
/// the hubs keep two buffers of this length in RAM and 16 KiB slots, so the part is not
/// added to it. A 6-joint table of 52 parameters with D's 16 columns is 11.8 KB; the host's
/// builder refuses a table longer than this.
pub const MAX_TABLE_LEN: usize = MAX_PLAIN_TABLE_LEN
    + if cfg!(feature = "parameters") {
        parameters::len(parameters::MAX_PARAMETERS)
    } else {
        0
    }
    + if cfg!(feature = "wobble") {
        wobble::len(MAX_JOINTS)
    } else {
        0
    };

/// Largest table without a parameter block or a wobble: 7 joints with a budget and 8 probes
/// (2,448 bytes). A board whose flash slots are smaller than [`MAX_TABLE_LEN`] but at least
/// this (the fixed-point boards' 4 KiB) takes every table but those with many parameters,
/// and its update refuses those by their length.
pub const MAX_PLAIN_TABLE_LEN: usize =
    table_len(MAX_JOINTS) + budget::LEN + probes::len(probes::MAX_PROBES - 1);

/// One encoder-harmonic term: e += sin·sin(hθ) + cos·cos(hθ).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Harmonic {
    /// Order h.
    pub order: u16,
    /// Coefficient of sin(hθ) (rad).
    pub sin: f64,
    /// Coefficient of cos(hθ) (rad).
    pub cos: f64,
}

/// One joint's precomputed constants.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JointData {
    /// Axis: 0 = x, 1 = y, 2 = z.
    pub axis: u8,
    /// Counts per revolution.
    pub counts: u32,
    /// M'_i = R(e1, δα) R(e2, δβ) R(u, Δθ) as a unit quaternion (w, x, y, z).
    pub rotation: [f64; 4],
    /// The same rotation as a matrix, row-major.
    pub matrix: [[f64; 3]; 3],
    /// Link vector with its error (mm).
    pub link: [f64; 3],
    /// Thermal expansion κ (1/°C).
    pub thermal: f64,
    /// Gravity compliance g (rad/mm).
    pub gravity: f64,
    /// Number of harmonics used.
    pub harmonic_count: u8,
    /// Harmonic terms (the first `harmonic_count`).
    pub harmonics: [Harmonic; MAX_HARMONICS],
}

/// A probe's precomputed constants.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ProbeData {
    /// Its id: what the hub's reports carry and the host selects it by (the first probe's is
    /// the header's byte 44; 0 for an arm of one probe without an id).
    pub id: u8,
    /// Probe vector with its error (mm).
    pub vector: [f64; 3],
    /// Its unit direction.
    pub direction: [f64; 3],
    /// Thermal expansion κ_p (1/°C).
    pub thermal: f64,
    /// Stylus ball diameter (mm; 0 where the calibration gives none): the chain gives the
    /// ball's centre, the sphere tests compensate the diameter.
    pub ball_diameter: f64,
}

/// The contents of a table, as plain values: what the encoder writes and [`Table::data`]
/// reads back.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TableData {
    /// Arm serial (UTF-8, NUL-padded).
    pub serial: [u8; SERIAL_LEN],
    /// Flags (`FLAG_*`).
    pub flags: u8,
    /// Number of joints.
    pub joint_count: u8,
    /// Joints, base first (the first `joint_count` used).
    pub joints: [JointData; MAX_JOINTS],
    /// The first probe: the one the hub mounts at boot.
    pub probe: ProbeData,
    /// The arm's other probes (the first `more_probe_count`; the block is written where there
    /// is one), ids distinct from each other and from the first's.
    pub more_probes: [ProbeData; probes::MAX_PROBES - 1],
    /// How many of `more_probes` the arm has (0..=7).
    pub more_probe_count: u8,
    /// Each joint's axis wobble (count 0: none; the block is written where some joint has
    /// one).
    pub wobble: [wobble::WobbleData; MAX_JOINTS],
    /// The calibration's number and date (version 4; zeros read from a version-3 table).
    pub release: Release,
}

/// Which calibration of the arm a table is: what the hub's anti-rollback compares
/// (`docs/update.md`, "Anti-rollback"). Both fields are inside the CRC and the signature.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Release {
    /// The calibration number, monotonic per arm (the maker's certificate number): a hub
    /// refuses a table whose number is below the live one's. 0 for a version-3 table.
    pub number: u32,
    /// The calibration date as the decimal number YYYYMMDD (20261204); 0 unknown. Only the
    /// host reads it (the hub has no calendar).
    pub date: u32,
}

impl Release {
    /// Whether `date` is 0 or a plausible YYYYMMDD (month 1–12, day 1–31, year 1900–9999).
    pub fn date_is_valid(date: u32) -> bool {
        let (y, m, d) = (date / 10_000, date / 100 % 100, date % 100);
        date == 0 || ((1900..=9999).contains(&y) && (1..=12).contains(&m) && (1..=31).contains(&d))
    }
}

impl JointData {
    /// The effect flags this joint calls for.
    pub fn content_flags(&self) -> u8 {
        let mut flags = 0;
        if self.harmonic_count > 0 {
            flags |= FLAG_HARMONICS;
        }
        if self.gravity != 0.0 {
            flags |= FLAG_GRAVITY;
        }
        if self.thermal != 0.0 {
            flags |= FLAG_THERMAL;
        }
        flags
    }
}

impl ProbeData {
    /// The effect flags the probe calls for.
    pub fn content_flags(&self) -> u8 {
        if self.thermal != 0.0 {
            FLAG_THERMAL
        } else {
            0
        }
    }
}

impl TableData {
    /// The flags that the contents call for (geometric errors are the builder's to set).
    pub fn content_flags(&self) -> u8 {
        let joints = &self.joints[..usize::from(self.joint_count).min(MAX_JOINTS)];
        let probes = self.other_probes().iter().map(ProbeData::content_flags);
        joints
            .iter()
            .map(JointData::content_flags)
            .chain(probes)
            .fold(self.probe.content_flags(), |f, c| f | c)
    }

    /// The other probes the arm has (the first `more_probe_count` of `more_probes`).
    pub fn other_probes(&self) -> &[ProbeData] {
        let n = usize::from(self.more_probe_count).min(self.more_probes.len());
        &self.more_probes[..n]
    }

    /// Writes the table into `out`, without an uncertainty budget; returns its length. Fails
    /// only if `out` is too short or the joint count is outside 6..=7.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, TableError> {
        self.encode_with(None, out)
    }

    /// Writes the table into `out` with `budget` (flag bit4 follows it, whatever
    /// `self.flags` says); returns its length. Fails only if `out` is too short, the joint
    /// count is outside 6..=7.
    pub fn encode_with(
        &self,
        budget: Option<&budget::BudgetData>,
        out: &mut [u8],
    ) -> Result<usize, TableError> {
        self.encode_full(budget, None, out)
    }

    /// Writes the table into `out` with `budget` and, after it, `parameters` (flag bits 4 and
    /// 5 follow them, bits 6 and 7 the wobble and the other probes); returns its length.
    /// Fails if `out` is too short, the joint count is outside 6..=7, there are parameters
    /// without a budget or a block of a wrong size ([`parameters::ParameterData::block_len`]),
    /// or more than 7 other probes.
    pub fn encode_full(
        &self,
        budget: Option<&budget::BudgetData>,
        parameters: Option<&parameters::ParameterData<'_>>,
        out: &mut [u8],
    ) -> Result<usize, TableError> {
        let at = self.layout(budget.is_some(), parameters)?;
        let (n, len) = (at.joints, at.len);
        if out.len() < len {
            return Err(TableError::Truncated {
                needed: len as u32,
                available: out.len() as u32,
            });
        }
        let out = &mut out[..len];
        out.fill(0);
        self.encode_header(&at, out);
        for (i, j) in self.joints[..n].iter().enumerate() {
            encode_joint(
                j,
                &mut out[HEADER_LEN + i * JOINT_LEN..HEADER_LEN + (i + 1) * JOINT_LEN],
            );
        }
        put_probe(
            &mut out[HEADER_LEN + n * JOINT_LEN..core_len(n)],
            &self.probe,
        );
        if let Some(b) = budget {
            b.encode(&mut out[core_len(n)..core_len(n) + budget::LEN]);
        }
        let probes_at = len - TAIL_LEN - at.probes;
        let end = probes_at - at.wobble;
        if let Some(p) = parameters {
            p.encode(&mut out[core_len(n) + budget::LEN..end]);
        }
        if at.wobble > 0 {
            wobble::encode(&self.wobble[..n], &mut out[end..probes_at]);
        }
        if at.probes > 0 {
            probes::encode(self.other_probes(), &mut out[probes_at..len - TAIL_LEN]);
        }
        out[len - TAIL_LEN..len - CRC_LEN - 4].copy_from_slice(&self.release.number.to_le_bytes());
        out[len - CRC_LEN - 4..len - CRC_LEN].copy_from_slice(&self.release.date.to_le_bytes());
        let crc = CRC.checksum(&out[..len - CRC_LEN]);
        out[len - CRC_LEN..].copy_from_slice(&crc.to_le_bytes());
        Ok(len)
    }

    /// The lengths of the table's blocks and of the whole, with a budget (`budget`) and
    /// `parameters`; fails as [`TableData::encode_full`] does, but for `out`'s length.
    fn layout(
        &self,
        budget: bool,
        parameters: Option<&parameters::ParameterData<'_>>,
    ) -> Result<Layout, TableError> {
        let n = usize::from(self.joint_count);
        if !(MIN_JOINTS..=MAX_JOINTS).contains(&n) {
            return Err(TableError::BadJointCount(self.joint_count));
        }
        let invalid = TableError::Invalid {
            joint: 0,
            field: Field::Budget,
        };
        let block = match parameters {
            None => 0,
            Some(_) if !budget => return Err(invalid),
            Some(p) => p.block_len().ok_or(invalid)?,
        };
        let extra = if budget { budget::LEN } else { 0 };
        let wobbling = self.wobble[..n].iter().filter(|w| w.count > 0).count();
        let wobble_len = if wobbling > 0 {
            wobble::len(wobbling)
        } else {
            0
        };
        if usize::from(self.more_probe_count) > self.more_probes.len() {
            return Err(TableError::Invalid {
                joint: 0,
                field: Field::Probe,
            });
        }
        let others = self.other_probes();
        let probes_len = if others.is_empty() {
            0
        } else {
            probes::len(others.len())
        };
        Ok(Layout {
            joints: n,
            budget: extra,
            parameters: block,
            wobble: wobble_len,
            probes: probes_len,
            len: table_len(n) + extra + block + wobble_len + probes_len,
        })
    }

    /// Writes the header of a table laid out as `at` into `out` (zeroed): the flags of its
    /// blocks set from what it holds, whatever `self.flags` says of them.
    fn encode_header(&self, at: &Layout, out: &mut [u8]) {
        let flag = |len: usize, f: u8| if len > 0 { f } else { 0 };
        out[off::MAGIC..off::MAGIC + 4].copy_from_slice(&MAGIC);
        out[off::VERSION..off::VERSION + 2].copy_from_slice(&VERSION.to_le_bytes());
        out[off::JOINTS] = self.joint_count;
        out[off::FLAGS] = (self.flags
            & !(FLAG_BUDGET | FLAG_PARAMETERS | FLAG_WOBBLE | FLAG_PROBES))
            | flag(at.budget, FLAG_BUDGET)
            | flag(at.parameters, FLAG_PARAMETERS)
            | flag(at.wobble, FLAG_WOBBLE)
            | flag(at.probes, FLAG_PROBES);
        out[off::SERIAL..off::SERIAL + SERIAL_LEN].copy_from_slice(&self.serial);
        out[off::LENGTH..off::LENGTH + 4].copy_from_slice(&(at.len as u32).to_le_bytes());
        out[off::PROBE_ID] = self.probe.id;
    }
}

/// The lengths of an encoded table's blocks (0 where it has none) and of the whole.
struct Layout {
    /// The joint count.
    joints: usize,
    /// The budget block.
    budget: usize,
    /// The parameters block.
    parameters: usize,
    /// The wobble block.
    wobble: usize,
    /// The other probes' block.
    probes: usize,
    /// The whole table.
    len: usize,
}

/// Writes joint `j`'s record into `r` (its [`JOINT_LEN`] bytes, zeroed).
fn encode_joint(j: &JointData, r: &mut [u8]) {
    r[off::AXIS] = j.axis;
    r[off::HARMONICS] = j.harmonic_count;
    r[off::COUNTS..off::COUNTS + 4].copy_from_slice(&j.counts.to_le_bytes());
    put_f64s(&mut r[off::QUAT..], &j.rotation);
    for (row, m) in j.matrix.iter().enumerate() {
        put_f64s(&mut r[off::MATRIX + 24 * row..], m);
    }
    put_f64s(&mut r[off::LINK..], &j.link);
    put_f64s(&mut r[off::THERMAL..], &[j.thermal]);
    put_f64s(&mut r[off::GRAVITY..], &[j.gravity]);
    for (k, h) in j.harmonics.iter().enumerate() {
        let s = &mut r[off::SLOTS + k * HARMONIC_LEN..off::SLOTS + (k + 1) * HARMONIC_LEN];
        s[off::H_ORDER..off::H_ORDER + 2].copy_from_slice(&h.order.to_le_bytes());
        put_f64s(&mut s[off::H_SIN..], &[h.sin]);
        put_f64s(&mut s[off::H_COS..], &[h.cos]);
    }
}

fn put_f64s(out: &mut [u8], v: &[f64]) {
    for (chunk, x) in out.chunks_exact_mut(8).zip(v) {
        chunk.copy_from_slice(&x.to_le_bytes());
    }
}

/// Writes a probe record (its 64 bytes; the id is kept elsewhere).
fn put_probe(out: &mut [u8], p: &ProbeData) {
    put_f64s(&mut out[off::P_VECTOR..], &p.vector);
    put_f64s(&mut out[off::P_DIR..], &p.direction);
    put_f64s(&mut out[off::P_THERMAL..], &[p.thermal]);
    put_f64s(&mut out[off::P_BALL..], &[p.ball_diameter]);
}

/// Reads a probe record (its 64 bytes) of the probe with id `id`.
fn read_probe(id: u8, r: &[u8]) -> ProbeData {
    ProbeData {
        id,
        vector: rd_f64s::<3>(r, off::P_VECTOR),
        direction: rd_f64s::<3>(r, off::P_DIR),
        thermal: rd_f64(r, off::P_THERMAL),
        ball_diameter: rd_f64(r, off::P_BALL),
    }
}

/// The error for a bad value of joint `joint` (1-based; 0 for the table's own fields).
fn invalid(joint: usize, field: Field) -> TableError {
    TableError::Invalid {
        joint: joint as u8,
        field,
    }
}

/// Checks joint `no`'s harmonic slots (its record `r`): reserved bytes zero, the unused
/// slots empty, the used ones of an order in range with finite terms whose sum of
/// magnitudes is within [`limits::HARMONIC_SUM`].
fn check_harmonics(no: usize, r: &[u8], j: &JointData) -> Result<(), TableError> {
    let mut sum = 0.0;
    for (k, h) in j.harmonics.iter().enumerate() {
        let s = &r[off::SLOTS + k * HARMONIC_LEN..off::SLOTS + (k + 1) * HARMONIC_LEN];
        if s[off::H_RESERVED..off::H_SIN].iter().any(|&x| x != 0) {
            return Err(invalid(no, Field::Reserved));
        }
        if k >= usize::from(j.harmonic_count) {
            if h.order != 0 || h.sin.to_bits() != 0 || h.cos.to_bits() != 0 {
                return Err(invalid(no, Field::Reserved));
            }
            continue;
        }
        if h.order == 0 || h.order > MAX_HARMONIC_ORDER {
            return Err(invalid(no, Field::HarmonicOrder));
        }
        if !(h.sin.is_finite() && h.cos.is_finite()) {
            return Err(invalid(no, Field::Harmonic));
        }
        sum += abs(h.sin) + abs(h.cos);
    }
    // NaN cannot reach here (checked above); `>` is the whole test.
    if sum > limits::HARMONIC_SUM {
        return Err(invalid(no, Field::Harmonic));
    }
    Ok(())
}

/// Checks a probe's values: vector and thermal coefficient in range, a unit direction along
/// the vector, a ball diameter in 0..=100 mm. The same check for every probe of a table.
fn check_probe(p: &ProbeData) -> Result<(), TableError> {
    let invalid = TableError::Invalid {
        joint: 0,
        field: Field::Probe,
    };
    let ok = p.vector.iter().all(|&x| within(x, limits::LENGTH_MM))
        && p.direction
            .iter()
            .all(|&x| within(x, 1.0 + limits::UNIT_TOLERANCE))
        && within(p.thermal, limits::THERMAL)
        && within(p.ball_diameter, limits::BALL_MM)
        && p.ball_diameter >= 0.0;
    if !ok {
        return Err(invalid);
    }
    let [dx, dy, dz] = p.direction;
    if abs(dx * dx + dy * dy + dz * dz - 1.0) > limits::UNIT_TOLERANCE {
        return Err(invalid);
    }
    // The direction must be that of the vector: their cross product vanishes relative to
    // the vector's length, and they point the same way.
    let [vx, vy, vz] = p.vector;
    let len2 = vx * vx + vy * vy + vz * vz;
    let dot = vx * dx + vy * dy + vz * dz;
    let cx = vy * dz - vz * dy;
    let cy = vz * dx - vx * dz;
    let cz = vx * dy - vy * dx;
    let parallel = len2 > 0.0 && dot > 0.0 && (cx * cx + cy * cy + cz * cz) <= 1e-18 * len2;
    if !parallel {
        return Err(invalid);
    }
    Ok(())
}

/// A validated calibration table, borrowing its bytes (which may stay in flash).
#[derive(Clone, Copy, Debug)]
pub struct Table<'a> {
    bytes: &'a [u8],
}

// Out of line: inlined at each of its uses (the header's fields, the CRC, the release
// fields) it cost the Cortex-M0 image, 32 KiB in all, more than a call does.
#[inline(never)]
fn rd_u32(b: &[u8], at: usize) -> u32 {
    let mut a = [0u8; 4];
    if let Some(s) = b.get(at..at + 4) {
        a.copy_from_slice(s);
    }
    u32::from_le_bytes(a)
}

fn rd_u16(b: &[u8], at: usize) -> u16 {
    let mut a = [0u8; 2];
    if let Some(s) = b.get(at..at + 2) {
        a.copy_from_slice(s);
    }
    u16::from_le_bytes(a)
}

fn rd_f64(b: &[u8], at: usize) -> f64 {
    let mut a = [0u8; 8];
    if let Some(s) = b.get(at..at + 8) {
        a.copy_from_slice(s);
    }
    f64::from_le_bytes(a)
}

fn rd_f64s<const K: usize>(b: &[u8], at: usize) -> [f64; K] {
    let mut v = [0.0; K];
    for (i, x) in v.iter_mut().enumerate() {
        *x = rd_f64(b, at + 8 * i);
    }
    v
}

fn abs(x: f64) -> f64 {
    if x < 0.0 {
        -x
    } else {
        x
    }
}

fn within(x: f64, limit: f64) -> bool {
    x.is_finite() && abs(x) <= limit
}

impl<'a> Table<'a> {
    /// Validates `bytes` as a table for any supported joint count (bytes after the table's
    /// length are ignored, so a whole flash region may be passed).
    pub fn parse(bytes: &'a [u8]) -> Result<Table<'a>, TableError> {
        Self::check(bytes, None)
    }

    /// Validates `bytes` as a table for exactly `joints` joints, the number the firmware
    /// drives.
    pub fn parse_for(bytes: &'a [u8], joints: usize) -> Result<Table<'a>, TableError> {
        Self::check(bytes, Some(joints))
    }

    fn check(bytes: &'a [u8], expected: Option<usize>) -> Result<Table<'a>, TableError> {
        let head = &bytes[..bytes.len().min(HEADER_LEN)];
        if !head.is_empty() && (head.iter().all(|&b| b == 0xff) || head.iter().all(|&b| b == 0)) {
            return Err(TableError::Blank);
        }
        if bytes.len() < HEADER_LEN {
            return Err(TableError::Truncated {
                needed: HEADER_LEN as u32,
                available: bytes.len() as u32,
            });
        }
        if bytes[off::MAGIC..off::MAGIC + 4] != MAGIC {
            return Err(TableError::BadMagic);
        }
        let version = rd_u16(bytes, off::VERSION);
        if version != VERSION && version != OLD_VERSION {
            return Err(TableError::UnsupportedVersion(version));
        }
        // The release fields and the CRC after the last block; a version-3 table has no
        // release fields.
        let tail = tail_len(version);
        let n8 = bytes[off::JOINTS];
        let n = usize::from(n8);
        if !(MIN_JOINTS..=MAX_JOINTS).contains(&n) {
            return Err(TableError::BadJointCount(n8));
        }
        let flags = bytes[off::FLAGS];
        let mut len = core_len(n) + tail;
        if flags & FLAG_BUDGET != 0 {
            len += budget::LEN;
            if flags & FLAG_PARAMETERS != 0 {
                // Without the feature, refused before its length is known, as the wobble's.
                if !cfg!(feature = "parameters") {
                    return Err(TableError::Invalid {
                        joint: 0,
                        field: Field::Flags,
                    });
                }
                // The block states its own size; a count that cannot be read counts as 0 and
                // fails the length check below or the block's own.
                let at = core_len(n) + budget::LEN;
                len += parameters::stated_len(bytes.get(at..).unwrap_or(&[]));
            }
        }
        if flags & FLAG_WOBBLE != 0 {
            // Without the feature, refused here, before its length is known: as a flag this
            // firmware does not read (`Malformed` on the stream), not as a corrupt table.
            if !cfg!(feature = "wobble") {
                return Err(TableError::Invalid {
                    joint: 0,
                    field: Field::Flags,
                });
            }
            let at = len - tail;
            len += wobble::len(wobble::stated_count(bytes.get(at..).unwrap_or(&[])));
        }
        if flags & FLAG_PROBES != 0 {
            let at = len - tail;
            len += probes::len(probes::stated_count(bytes.get(at..).unwrap_or(&[])));
        }
        let stated = rd_u32(bytes, off::LENGTH);
        if stated as usize != len {
            return Err(TableError::BadLength(stated));
        }
        if bytes.len() < len {
            return Err(TableError::Truncated {
                needed: len as u32,
                available: bytes.len() as u32,
            });
        }
        let bytes = &bytes[..len];
        let stored = rd_u32(bytes, len - CRC_LEN);
        let computed = CRC.checksum(&bytes[..len - CRC_LEN]);
        if stored != computed {
            return Err(TableError::Crc { stored, computed });
        }
        if let Some(e) = expected {
            if e != n {
                return Err(TableError::WrongJointCount {
                    expected: e.min(255) as u8,
                    found: n8,
                });
            }
        }
        let table = Table { bytes };
        table.check_values()?;
        Ok(table)
    }

    /// Checks every value of a table whose length and CRC are right: the header, each joint
    /// ([`Table::check_joint`]), each probe, the flags against the contents, and the blocks.
    fn check_values(&self) -> Result<(), TableError> {
        let b = self.bytes;
        if b[off::RESERVED..off::RESERVED + 3].iter().any(|&x| x != 0) {
            return Err(invalid(0, Field::Reserved));
        }
        if core::str::from_utf8(self.serial()).is_err() {
            return Err(invalid(0, Field::Serial));
        }
        let mut content = 0;
        for i in 0..self.joint_count() {
            content |= self.check_joint(i)?;
        }
        content |= self.check_probes()?;
        self.check_flags(content)?;
        if let Some(budget) = self.budget() {
            budget.check(self)?;
        }
        #[cfg(feature = "parameters")]
        if let Some(p) = self.parameters() {
            let of_table = |id| (0..self.probe_count()).any(|k| self.probe_id(k) == Some(id));
            p.check(self.joint_count(), of_table)?;
        }
        #[cfg(feature = "wobble")]
        if let Some(w) = self.wobble() {
            w.check(self.joint_count())?;
        }
        Ok(())
    }

    /// Checks joint `i`'s record; returns the content flags its values call for. One joint at
    /// a time, not `self.data()`: on a target without an FPU every f64 here is soft-float,
    /// and a whole TableData on the boot stack would cost kilobytes.
    fn check_joint(&self, i: usize) -> Result<u8, TableError> {
        let no = i + 1;
        let (Some(r), Some(j)) = (
            self.bytes
                .get(HEADER_LEN + i * JOINT_LEN..HEADER_LEN + (i + 1) * JOINT_LEN),
            self.joint(i),
        ) else {
            return Err(invalid(no, Field::Reserved));
        };
        if rd_u16(r, off::J_RESERVED) != 0 {
            return Err(invalid(no, Field::Reserved));
        }
        if j.axis > 2 {
            return Err(invalid(no, Field::Axis));
        }
        if !(2..=i32::MAX as u32).contains(&j.counts) {
            return Err(invalid(no, Field::Counts));
        }
        if usize::from(j.harmonic_count) > MAX_HARMONICS {
            return Err(invalid(no, Field::HarmonicCount));
        }
        check_rotation(&j.rotation, &j.matrix).map_err(|_| invalid(no, Field::Rotation))?;
        if !j.link.iter().all(|&x| within(x, limits::LENGTH_MM)) {
            return Err(invalid(no, Field::Link));
        }
        if !within(j.thermal, limits::THERMAL) {
            return Err(invalid(no, Field::Thermal));
        }
        if !within(j.gravity, limits::GRAVITY) {
            return Err(invalid(no, Field::Gravity));
        }
        check_harmonics(no, r, &j)?;
        Ok(j.content_flags())
    }

    /// Checks every probe's values, the first's and the others', and that their ids are all
    /// distinct; returns the content flags their values call for.
    fn check_probes(&self) -> Result<u8, TableError> {
        if let Some(others) = self.other_probes() {
            others.check()?;
        }
        let mut content = 0;
        for k in 0..self.probe_count() {
            let p = self.probe_at(k).ok_or(invalid(0, Field::Probe))?;
            check_probe(&p)?;
            if (0..k).any(|j| self.probe_id(j) == Some(p.id)) {
                return Err(invalid(0, Field::Probe));
            }
            content |= p.content_flags();
        }
        Ok(content)
    }

    /// Checks the flags: every bit known, the content bits those the values call for
    /// (`content`), and parameters only with a budget.
    // With every feature every flag is known (`!FLAGS_KNOWN` is 0, the test always passes);
    // without one, its block's flag is refused by it.
    #[allow(clippy::bad_bit_mask)]
    fn check_flags(&self, content: u8) -> Result<(), TableError> {
        let flags = self.bytes[off::FLAGS];
        let blocks = FLAG_GEOMETRIC | FLAG_BUDGET | FLAG_PARAMETERS | FLAG_WOBBLE | FLAG_PROBES;
        if flags & !FLAGS_KNOWN != 0
            || flags & !blocks != content
            || (flags & FLAG_PARAMETERS != 0 && flags & FLAG_BUDGET == 0)
        {
            return Err(invalid(0, Field::Flags));
        }
        Ok(())
    }

    /// The uncertainty budget, where the table has one.
    pub fn budget(&self) -> Option<budget::Budget<'a>> {
        if self.flags() & FLAG_BUDGET == 0 {
            return None;
        }
        let n = self.joint_count();
        self.bytes
            .get(core_len(n)..core_len(n) + budget::LEN)
            .map(budget::Budget::new)
    }

    /// The calibration's parameter covariance, where the table has it (never without the
    /// `parameters` feature, which refuses a table with the block).
    pub fn parameters(&self) -> Option<parameters::Parameters<'a>> {
        // Without the feature a table with the block was refused: nothing to read (and no
        // code for it in the 32 KiB image).
        if !cfg!(feature = "parameters") || self.flags() & FLAG_PARAMETERS == 0 {
            return None;
        }
        let at = core_len(self.joint_count()) + budget::LEN;
        let len = parameters::stated_len(self.bytes.get(at..).unwrap_or(&[]));
        self.bytes
            .get(at..at + len)
            .map(parameters::Parameters::new)
    }

    /// Where the wobble block starts, or would: after the probe, the budget and the
    /// parameter block. (A block whose feature is off is refused by its flag before this is
    /// asked: its length need not be known.)
    fn wobble_at(&self) -> usize {
        let mut at = core_len(self.joint_count());
        if self.flags() & FLAG_BUDGET != 0 {
            at += budget::LEN;
        }
        if cfg!(feature = "parameters") && self.flags() & FLAG_PARAMETERS != 0 {
            at += parameters::stated_len(self.bytes.get(at..).unwrap_or(&[]));
        }
        at
    }

    /// Where the other probes' block starts, or would: after the wobble's.
    fn probes_at(&self) -> usize {
        let at = self.wobble_at();
        if !cfg!(feature = "wobble") || self.flags() & FLAG_WOBBLE == 0 {
            return at;
        }
        at + wobble::len(wobble::stated_count(self.bytes.get(at..).unwrap_or(&[])))
    }

    /// The axis wobble block, where the table has one (never without the `wobble` feature,
    /// which refuses a table with the block).
    pub fn wobble(&self) -> Option<wobble::Wobble<'a>> {
        if self.flags() & FLAG_WOBBLE == 0 {
            return None;
        }
        self.bytes
            .get(self.wobble_at()..self.probes_at())
            .map(wobble::Wobble::new)
    }

    /// The block of the arm's other probes, where it has more than one.
    pub fn other_probes(&self) -> Option<probes::Probes<'a>> {
        if self.flags() & FLAG_PROBES == 0 {
            return None;
        }
        let end = self.bytes.len() - self.tail();
        self.bytes
            .get(self.probes_at()..end)
            .map(probes::Probes::new)
    }

    /// How many probes the arm has, the first included (1..=8).
    pub fn probe_count(&self) -> usize {
        1 + self.other_probes().map_or(0, |p| p.count())
    }

    /// Probe `k`'s id (0 the first, as [`Table::probe_at`]); `None` past the last.
    pub fn probe_id(&self, k: usize) -> Option<u8> {
        match k {
            0 => Some(self.bytes[off::PROBE_ID]),
            _ => self.other_probes()?.id(k - 1),
        }
    }

    /// Probe `k`: 0 the first (the one the hub mounts at boot), then the others in the
    /// table's order; `None` past the last.
    pub fn probe_at(&self, k: usize) -> Option<ProbeData> {
        match k {
            0 => Some(self.probe()),
            _ => self.other_probes()?.probe(k - 1),
        }
    }

    /// Joint `i`'s axis wobble (0-based; count 0 where it has none).
    pub fn joint_wobble(&self, i: usize) -> wobble::WobbleData {
        self.wobble().map(|w| w.joint(i)).unwrap_or_default()
    }

    /// The table's bytes (exactly its length).
    pub fn bytes(&self) -> &'a [u8] {
        self.bytes
    }

    /// Number of joints.
    pub fn joint_count(&self) -> usize {
        usize::from(self.bytes[off::JOINTS])
    }

    /// Flags (`FLAG_*`).
    pub fn flags(&self) -> u8 {
        self.bytes[off::FLAGS]
    }

    /// The arm's serial, without its NUL padding.
    pub fn serial(&self) -> &'a [u8] {
        let s = &self.bytes[off::SERIAL..off::SERIAL + SERIAL_LEN];
        let end = s.iter().position(|&b| b == 0).unwrap_or(SERIAL_LEN);
        &s[..end]
    }

    /// The format version (4, or 3 read without release fields).
    pub fn version(&self) -> u16 {
        rd_u16(self.bytes, off::VERSION)
    }

    fn tail(&self) -> usize {
        tail_len(self.version())
    }

    /// The calibration number and date (zeros for a version-3 table).
    pub fn release(&self) -> Release {
        if self.version() == OLD_VERSION {
            return Release::default();
        }
        let at = self.bytes.len() - TAIL_LEN;
        Release {
            number: rd_u32(self.bytes, at),
            date: rd_u32(self.bytes, at + 4),
        }
    }

    /// The CRC stored in the table.
    pub fn crc(&self) -> u32 {
        rd_u32(self.bytes, self.bytes.len() - CRC_LEN)
    }

    /// Joint `i`'s axis, link vector and thermal expansion (what mounting a probe on the
    /// last joint needs): read alone rather than as a whole [`JointData`], whose ~300 bytes
    /// the Cortex-M0 hub's stack has no room for where a probe is mounted at boot.
    pub fn joint_link(&self, i: usize) -> Option<(u8, [f64; 3], f64)> {
        if i >= self.joint_count() {
            return None;
        }
        let r = self
            .bytes
            .get(HEADER_LEN + i * JOINT_LEN..HEADER_LEN + (i + 1) * JOINT_LEN)?;
        Some((
            r[off::AXIS],
            rd_f64s::<3>(r, off::LINK),
            rd_f64(r, off::THERMAL),
        ))
    }

    /// Joint `i` (0-based); `None` past the last joint.
    pub fn joint(&self, i: usize) -> Option<JointData> {
        if i >= self.joint_count() {
            return None;
        }
        let r = self
            .bytes
            .get(HEADER_LEN + i * JOINT_LEN..HEADER_LEN + (i + 1) * JOINT_LEN)?;
        let mut harmonics = [Harmonic::default(); MAX_HARMONICS];
        for (k, h) in harmonics.iter_mut().enumerate() {
            let s = off::SLOTS + k * HARMONIC_LEN;
            *h = Harmonic {
                order: rd_u16(r, s + off::H_ORDER),
                sin: rd_f64(r, s + off::H_SIN),
                cos: rd_f64(r, s + off::H_COS),
            };
        }
        Some(JointData {
            axis: r[off::AXIS],
            counts: rd_u32(r, off::COUNTS),
            rotation: rd_f64s::<4>(r, off::QUAT),
            matrix: [
                rd_f64s::<3>(r, off::MATRIX),
                rd_f64s::<3>(r, off::MATRIX + 24),
                rd_f64s::<3>(r, off::MATRIX + 48),
            ],
            link: rd_f64s::<3>(r, off::LINK),
            thermal: rd_f64(r, off::THERMAL),
            gravity: rd_f64(r, off::GRAVITY),
            harmonic_count: r[off::HARMONICS],
            harmonics,
        })
    }

    /// The first probe (the one the hub mounts at boot).
    pub fn probe(&self) -> ProbeData {
        let at = HEADER_LEN + self.joint_count() * JOINT_LEN;
        read_probe(
            self.bytes[off::PROBE_ID],
            self.bytes.get(at..).unwrap_or(&[]),
        )
    }

    /// Everything, as plain values.
    pub fn data(&self) -> TableData {
        let mut serial = [0u8; SERIAL_LEN];
        serial.copy_from_slice(&self.bytes[off::SERIAL..off::SERIAL + SERIAL_LEN]);
        let mut joints = [JointData::default(); MAX_JOINTS];
        for (i, j) in joints.iter_mut().enumerate().take(self.joint_count()) {
            if let Some(d) = self.joint(i) {
                *j = d;
            }
        }
        let mut more_probes = [ProbeData::default(); probes::MAX_PROBES - 1];
        let mut more_probe_count = 0;
        for (k, p) in more_probes.iter_mut().enumerate() {
            if let Some(d) = self.probe_at(k + 1) {
                *p = d;
                more_probe_count += 1;
            }
        }
        TableData {
            serial,
            flags: self.flags(),
            joint_count: self.bytes[off::JOINTS],
            joints,
            probe: self.probe(),
            more_probes,
            more_probe_count,
            wobble: core::array::from_fn(|i| {
                if cfg!(feature = "wobble") && i < self.joint_count() {
                    self.joint_wobble(i)
                } else {
                    wobble::WobbleData::default()
                }
            }),
            release: self.release(),
        }
    }
}

/// Checks a unit quaternion and its matrix: |q| = 1, and the matrix is q's rotation.
fn check_rotation(q: &[f64; 4], m: &[[f64; 3]; 3]) -> Result<(), ()> {
    if !q
        .iter()
        .chain(m.iter().flatten())
        .all(|&x| within(x, 1.0 + limits::UNIT_TOLERANCE))
    {
        return Err(());
    }
    let [w, x, y, z] = *q;
    if abs(w * w + x * x + y * y + z * z - 1.0) > limits::UNIT_TOLERANCE {
        return Err(());
    }
    let want = quat_to_matrix(q);
    for r in 0..3 {
        for c in 0..3 {
            if abs(want[r][c] - m[r][c]) > 1e-9 {
                return Err(());
            }
        }
    }
    Ok(())
}

/// The rotation matrix of a unit quaternion (w, x, y, z).
pub fn quat_to_matrix(q: &[f64; 4]) -> [[f64; 3]; 3] {
    let [w, x, y, z] = *q;
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) fn sample() -> TableData {
        let mut d = TableData {
            joint_count: 6,
            ..TableData::default()
        };
        d.serial[..7].copy_from_slice(b"SN-0001");
        let axes = [2u8, 0, 2, 0, 2, 0];
        let links = [200.0, 300.0, 300.0, 250.0, 250.0, 80.0];
        for i in 0..6 {
            let h = 1e-3 * (i as f64 + 1.0);
            let q = [(1.0f64 - h * h).sqrt(), h, 0.0, 0.0];
            d.joints[i] = JointData {
                axis: axes[i],
                counts: 1 << 20,
                rotation: q,
                matrix: quat_to_matrix(&q),
                link: [0.1, -0.2, links[i]],
                thermal: 2.3e-5,
                gravity: if i % 2 == 1 { 3e-8 } else { 0.0 },
                harmonic_count: 2,
                harmonics: [
                    Harmonic {
                        order: 1,
                        sin: 1e-4,
                        cos: -5e-5,
                    },
                    Harmonic {
                        order: 2,
                        sin: 2e-5,
                        cos: 1e-5,
                    },
                    Harmonic::default(),
                    Harmonic::default(),
                ],
            };
        }
        d.probe = ProbeData {
            id: 0,
            vector: [0.0, 0.0, 120.0],
            direction: [0.0, 0.0, 1.0],
            thermal: 0.0,
            ball_diameter: 6.0,
        };
        d.flags = d.content_flags() | FLAG_GEOMETRIC;
        d
    }

    fn encoded() -> ([u8; MAX_TABLE_LEN], usize) {
        let mut buf = [0u8; MAX_TABLE_LEN];
        let n = sample().encode(&mut buf).unwrap();
        (buf, n)
    }

    pub(crate) fn recrc(b: &mut [u8]) {
        let n = b.len();
        let c = CRC.checksum(&b[..n - 4]);
        b[n - 4..].copy_from_slice(&c.to_le_bytes());
    }

    #[test]
    fn round_trip() {
        let (buf, n) = encoded();
        assert_eq!(n, table_len(6));
        let t = Table::parse(&buf).unwrap();
        assert_eq!(t.data(), sample());
        assert_eq!(t.serial(), b"SN-0001");
        assert_eq!(t.bytes().len(), n);
        assert!(Table::parse_for(&buf[..n], 6).is_ok());
    }

    /// The serial's full 32 bytes (a MUKCa serial has 19; version 1 held 16) come back whole,
    /// with nothing after them disturbed.
    #[test]
    fn full_width_serial_round_trip() {
        let mut d = sample();
        d.serial
            .copy_from_slice(b"panda_1_with_sensor-0123456789ab");
        let mut b = [0u8; MAX_TABLE_LEN];
        let n = d.encode(&mut b).unwrap();
        assert_eq!(n, HEADER_LEN + 6 * JOINT_LEN + PROBE_LEN + TAIL_LEN);
        let t = Table::parse(&b[..n]).unwrap();
        assert_eq!(t.serial(), b"panda_1_with_sensor-0123456789ab");
        assert_eq!(t.data(), d);
    }

    #[test]
    fn budget_round_trips_and_bad_values_are_refused() {
        let b = budget::BudgetData {
            encoder_counts: [0.29, 0.29, 0.5, 0.29, 0.29, 1.0, 0.0],
            probing_mm: 0.002,
            model_mm: 0.001,
            temperature_c: 0.2,
        };
        let mut buf = [0u8; MAX_TABLE_LEN];
        let n = sample().encode_with(Some(&b), &mut buf).unwrap();
        assert_eq!(n, table_len(6) + budget::LEN);
        let t = Table::parse(&buf[..n]).unwrap();
        let got = t.budget().unwrap();
        assert_eq!(got.encoder_counts(2), 0.5);
        assert_eq!(got.encoder_counts(6), 0.0);
        assert_eq!(
            (got.probing_mm(), got.model_mm(), got.temperature_c()),
            (0.002, 0.001, 0.2)
        );
        assert_eq!(t.probe().ball_diameter, 6.0);
        // Without the budget: no budget, and the flag is clear.
        let (plain, m) = encoded();
        assert!(Table::parse(&plain[..m]).unwrap().budget().is_none());
        // A negative, a NaN, an encoder term on a joint the arm does not have.
        for (at, v) in [
            (core_len(6) + 56, -0.001),
            (core_len(6) + 72, f64::NAN),
            (core_len(6) + 48, 0.1),
        ] {
            let mut bad = buf;
            bad[at..at + 8].copy_from_slice(&v.to_le_bytes());
            recrc(&mut bad[..n]);
            assert!(
                matches!(
                    Table::parse(&bad[..n]),
                    Err(TableError::Invalid {
                        field: Field::Budget,
                        ..
                    })
                ),
                "{at} {v}"
            );
        }
        // The flag set on a table without the budget's bytes: a length that disagrees.
        let mut flagged = plain;
        flagged[off::FLAGS] |= FLAG_BUDGET;
        recrc(&mut flagged[..m]);
        assert!(Table::parse(&flagged[..m]).is_err());
    }

    #[test]
    fn rejections() {
        let (buf, n) = encoded();
        assert_eq!(Table::parse(&[0xff; 64]).unwrap_err(), TableError::Blank);
        assert_eq!(Table::parse(&[0; 2048]).unwrap_err(), TableError::Blank);
        assert!(matches!(
            Table::parse(&[]).unwrap_err(),
            TableError::Truncated { .. }
        ));
        assert!(matches!(
            Table::parse(&buf[..n - 1]).unwrap_err(),
            TableError::Truncated { .. }
        ));
        assert_eq!(
            Table::parse_for(&buf, 7).unwrap_err(),
            TableError::WrongJointCount {
                expected: 7,
                found: 6
            }
        );
        let mut b = buf;
        b[0] = b'X';
        assert_eq!(Table::parse(&b).unwrap_err(), TableError::BadMagic);
        // Versions 1 (the 16-byte serial) and 2 (no ball diameter, no budget) and any unknown
        // version are refused by number, with a CRC that matches, before any field is read.
        for v in [1u8, 2, 5, 0xff] {
            let mut b = buf;
            b[4] = v;
            recrc(&mut b[..n]);
            let e = Table::parse(&b).unwrap_err();
            assert_eq!(e, TableError::UnsupportedVersion(u16::from(v)));
            let msg = std::format!("{e}");
            assert!(
                msg.contains(&std::format!("version {v},"))
                    && msg.contains("reads 3 and 4")
                    && msg.contains("armcal table build"),
                "{msg}"
            );
        }
        let mut b = buf;
        b[6] = 5;
        assert_eq!(Table::parse(&b).unwrap_err(), TableError::BadJointCount(5));
        let mut b = buf;
        b[off::LENGTH] += 1;
        assert!(matches!(
            Table::parse(&b).unwrap_err(),
            TableError::BadLength(_)
        ));
        let mut b = buf;
        b[100] ^= 0x10;
        assert!(matches!(
            Table::parse(&b).unwrap_err(),
            TableError::Crc { .. }
        ));
        // Values out of range, with a correct CRC.
        let cases: [(usize, u8, Field); 5] = [
            (HEADER_LEN + off::AXIS, 3, Field::Axis),
            (HEADER_LEN + off::HARMONICS, 5, Field::HarmonicCount),
            (HEADER_LEN + off::COUNTS + 3, 0x80, Field::Counts),
            (HEADER_LEN + off::QUAT + 7, 0x40, Field::Rotation),
            (
                HEADER_LEN + off::SLOTS + off::H_ORDER,
                0,
                Field::HarmonicOrder,
            ),
        ];
        for (at, v, field) in cases {
            let mut b = buf;
            b[at] = v;
            recrc(&mut b[..n]);
            assert_eq!(
                Table::parse(&b).unwrap_err(),
                TableError::Invalid { joint: 1, field },
                "{field}"
            );
        }
        let mut d = sample();
        d.joints[2].gravity = f64::NAN;
        let mut b = [0u8; MAX_TABLE_LEN];
        d.encode(&mut b).unwrap();
        assert_eq!(
            Table::parse(&b).unwrap_err(),
            TableError::Invalid {
                joint: 3,
                field: Field::Gravity
            }
        );
        let mut d = sample();
        d.probe.direction = [0.0, 1.0, 0.0];
        d.encode(&mut b).unwrap();
        assert_eq!(
            Table::parse(&b).unwrap_err(),
            TableError::Invalid {
                joint: 0,
                field: Field::Probe
            }
        );
        let mut d = sample();
        d.flags = 0;
        d.encode(&mut b).unwrap();
        assert_eq!(
            Table::parse(&b).unwrap_err(),
            TableError::Invalid {
                joint: 0,
                field: Field::Flags
            }
        );
        let mut d = sample();
        d.joints[5].harmonics[0].sin = 2e-3;
        d.encode(&mut b).unwrap();
        assert_eq!(
            Table::parse(&b).unwrap_err(),
            TableError::Invalid {
                joint: 6,
                field: Field::Harmonic
            }
        );
    }

    /// `v4` (a version-4 table) as the version-3 table of the same contents: without the
    /// release fields, version 3, its length and CRC rewritten. Returns its length in `out`.
    pub(crate) fn as_version_3(v4: &[u8], out: &mut [u8]) -> usize {
        let n = v4.len() - RELEASE_LEN;
        out[..n - CRC_LEN].copy_from_slice(&v4[..n - CRC_LEN]);
        out[off::VERSION..off::VERSION + 2].copy_from_slice(&OLD_VERSION.to_le_bytes());
        out[off::LENGTH..off::LENGTH + 4].copy_from_slice(&(n as u32).to_le_bytes());
        recrc(&mut out[..n]);
        n
    }

    /// The number and date round-trip, are covered by the CRC, and a version-3 table (no
    /// release fields) is read with its blocks in place, as number 0 and no date.
    #[test]
    fn release_round_trips_and_version_3_reads_as_number_0() {
        let mut d = probes::tests::several();
        d.release = Release {
            number: 7,
            date: 20261204,
        };
        let mut b = [0u8; MAX_TABLE_LEN];
        let n = d.encode(&mut b).unwrap();
        let t = Table::parse(&b[..n]).unwrap();
        assert_eq!(t.version(), VERSION);
        assert_eq!(t.release(), d.release);
        assert_eq!(t.data().release, d.release);
        for at in n - TAIL_LEN..n - CRC_LEN {
            let mut c = b;
            c[at] ^= 1;
            assert!(matches!(Table::parse(&c[..n]), Err(TableError::Crc { .. })));
        }
        let mut old = [0u8; MAX_TABLE_LEN];
        let m = as_version_3(&b[..n], &mut old);
        assert_eq!(m, n - RELEASE_LEN);
        assert!(is_table_len(m) && is_table_len(n));
        let t3 = Table::parse(&old[..m]).unwrap();
        assert_eq!(t3.version(), OLD_VERSION);
        assert_eq!(t3.release(), Release::default());
        assert_eq!(t3.probe_count(), 1 + usize::from(d.more_probe_count));
        assert_eq!(
            t3.data(),
            TableData {
                release: Release::default(),
                ..t.data()
            }
        );
        // Version 2, and 5, are refused.
        for v in [2u16, 5] {
            let mut c = b;
            c[off::VERSION..off::VERSION + 2].copy_from_slice(&v.to_le_bytes());
            recrc(&mut c[..n]);
            assert_eq!(
                Table::parse(&c[..n]).unwrap_err(),
                TableError::UnsupportedVersion(v)
            );
        }
        assert!(Release::date_is_valid(20261204) && Release::date_is_valid(0));
        assert!(!Release::date_is_valid(20261304) && !Release::date_is_valid(2026120));
    }

    #[test]
    fn encode_needs_room() {
        let mut small = [0u8; 100];
        assert!(matches!(
            sample().encode(&mut small),
            Err(TableError::Truncated { .. })
        ));
    }

    proptest::proptest! {
        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..2000)) {
            let _ = Table::parse(&bytes);
        }

        #[test]
        fn flipped_bytes_are_refused(at in 0usize..table_len(6), bit in 0u8..8) {
            let (mut b, n) = encoded();
            b[at] ^= 1 << bit;
            proptest::prop_assert!(Table::parse(&b[..n]).is_err());
        }
    }
}
