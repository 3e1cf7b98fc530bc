//! What both chains share: the calibrated model converted to one evaluator's numbers, the
//! per-point joint angles with their encoder harmonics, thermal expansion of the links, the
//! gravity deflection angle, and the output point.
//!
//! The chains differ only in how they represent and apply rotations ([`crate::chain`]:
//! quaternions, tip to base; [`crate::matrix`]: 3×4 matrices, base to tip).

use crate::angle::{CountScale, JointAngle, Multiples};
use crate::rotate::Vec3;
use crate::scalar::{Precision, Scale};
use crate::table::{Table, MAX_HARMONICS, MAX_JOINTS};
use core::fmt;

/// Links have their nominal length at 20 °C (20,000 m°C).
pub const REFERENCE_TEMP_MC: i32 = 20_000;
/// Temperatures the chain accepts: 20 °C ± 100 °C.
pub const TEMP_RANGE_MC: i32 = 100_000;

/// Why a chain cannot be built or cannot evaluate a reading.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ChainError {
    /// The reading has another number of counts than the arm has joints.
    JointCount {
        /// Joints of the arm.
        expected: u8,
        /// Counts given.
        found: u8,
    },
    /// A count is not below its joint's counts per revolution (joint 1-based).
    CountOutOfRange {
        /// The joint (1..=N).
        joint: u8,
    },
    /// The temperature is outside −80 °C..120 °C.
    Temperature,
    /// A table value does not fit this evaluator's number format (joint 1-based, 0 for the
    /// probe or the arm's reach as a whole).
    Range {
        /// The joint (1..=N), or 0.
        joint: u8,
    },
}

impl fmt::Display for ChainError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ChainError::JointCount { expected, found } => {
                write!(f, "{found} encoder counts for a {expected}-joint arm")
            }
            ChainError::CountOutOfRange { joint } => {
                write!(f, "joint {joint}: count not below counts per revolution")
            }
            ChainError::Temperature => f.write_str("temperature outside -80..120 degC"),
            ChainError::Range { joint: 0 } => {
                f.write_str("probe or reach does not fit this evaluator")
            }
            ChainError::Range { joint } => {
                write!(f, "joint {joint}: table value does not fit this evaluator")
            }
        }
    }
}

impl core::error::Error for ChainError {}

/// A probe-ball centre and probe direction in one evaluator's numbers.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Point<P: Precision> {
    /// Probe-ball centre, base frame (mm).
    pub xyz: Vec3<P::L>,
    /// Probe direction, unit vector.
    pub dir: Vec3<P::U>,
}

impl<P: Precision> Point<P> {
    /// XYZ in integer nanometres, exactly rounded from the evaluator's value: the firmware's
    /// output format.
    pub fn xyz_nm(&self) -> [i32; 3] {
        self.xyz.map(P::l_to_nm)
    }

    /// Probe direction in integer units of 1e-9, exactly rounded.
    pub fn dir_e9(&self) -> [i32; 3] {
        self.dir.map(P::u_to_e9)
    }

    /// XYZ (mm) as f64, exact.
    pub fn xyz_f64(&self) -> [f64; 3] {
        self.xyz.map(P::l_to_f64)
    }

    /// Direction as f64, exact.
    pub fn dir_f64(&self) -> [f64; 3] {
        self.dir.map(P::u_to_f64)
    }
}

/// One harmonic term in evaluator numbers.
#[derive(Clone, Copy, Debug, Default)]
pub struct HarmonicTerm<P: Precision> {
    /// Order h.
    pub order: u32,
    /// Coefficient of sin(hθ).
    pub sin: P::U,
    /// Coefficient of cos(hθ).
    pub cos: P::U,
}

/// One joint's constants, except its fixed rotation (the chains keep that in their own form).
#[derive(Clone, Copy, Debug, Default)]
pub struct JointModel<P: Precision> {
    /// Axis 0 = x, 1 = y, 2 = z.
    pub axis: u8,
    /// Count to binary angle.
    pub scale: CountScale,
    /// Link vector with its error (mm).
    pub link: Vec3<P::L>,
    /// Thermal expansion per m°C.
    pub thermal: P::K,
    /// Whether `thermal` is non-zero.
    pub has_thermal: bool,
    /// Gravity compliance.
    pub gravity: P::G,
    /// Whether `gravity` is non-zero.
    pub has_gravity: bool,
    /// Harmonic terms, ascending order.
    pub harmonics: [HarmonicTerm<P>; MAX_HARMONICS],
    /// Number of harmonic terms.
    pub harmonic_count: u8,
}

/// The calibrated model in one evaluator's numbers.
#[derive(Clone, Copy, Debug)]
pub struct Model<P: Precision> {
    /// Number of joints.
    pub n: usize,
    /// Joints, base first.
    pub joints: [JointModel<P>; MAX_JOINTS],
    /// Probe vector with its error (mm).
    pub probe: Vec3<P::L>,
    /// Its unit direction.
    pub dir: Vec3<P::U>,
    /// Probe thermal expansion per m°C.
    pub probe_thermal: P::K,
    /// Whether `probe_thermal` is non-zero.
    pub probe_has_thermal: bool,
}

/// Every joint's state and the probe vector at temperature.
pub type ReadingState<P> = ([JointState<P>; MAX_JOINTS], Vec3<<P as Precision>::L>);

/// The per-point state both chains start from.
#[derive(Clone, Copy, Debug)]
pub struct JointState<P: Precision> {
    /// The raw reading split into quadrant and half angle.
    pub angle: JointAngle<P>,
    /// The encoder-harmonic angle error e (rad).
    pub error: P::U,
    /// The link at the reading's temperature.
    pub link: Vec3<P::L>,
}

fn conv<T>(x: Option<T>, joint: usize) -> Result<T, ChainError> {
    x.ok_or(ChainError::Range { joint: joint as u8 })
}

fn vec3<P: Precision>(v: [f64; 3], joint: usize) -> Result<Vec3<P::L>, ChainError> {
    Ok([
        conv(P::l_from_f64(v[0]), joint)?,
        conv(P::l_from_f64(v[1]), joint)?,
        conv(P::l_from_f64(v[2]), joint)?,
    ])
}

/// Converts a dimensionless f64 triple or quadruple.
pub(crate) fn units<P: Precision, const K: usize>(
    v: [f64; K],
    joint: usize,
) -> Result<[P::U; K], ChainError> {
    let mut out = [P::U::default(); K];
    for (o, x) in out.iter_mut().zip(v) {
        *o = conv(P::u_from_f64(x), joint)?;
    }
    Ok(out)
}

fn abs(x: f64) -> f64 {
    if x < 0.0 {
        -x
    } else {
        x
    }
}

impl<P: Precision> Model<P> {
    /// Converts a validated table; fails if a value does not fit this evaluator (for fixed
    /// point: the arm's reach, over ±100 °C of thermal expansion, must stay within 2 m).
    pub fn new(table: &Table<'_>) -> Result<Model<P>, ChainError> {
        let n = table.joint_count();
        let mut joints = [JointModel::<P>::default(); MAX_JOINTS];
        let mut reach = 0.0;
        for (i, jm) in joints.iter_mut().enumerate().take(n) {
            let j = table
                .joint(i)
                .ok_or(ChainError::Range { joint: i as u8 + 1 })?;
            let no = i + 1;
            let mut harmonics = [HarmonicTerm::<P>::default(); MAX_HARMONICS];
            let count = usize::from(j.harmonic_count).min(MAX_HARMONICS);
            for (h, src) in harmonics.iter_mut().zip(&j.harmonics[..count]) {
                *h = HarmonicTerm {
                    order: u32::from(src.order),
                    sin: conv(P::u_from_f64(src.sin), no)?,
                    cos: conv(P::u_from_f64(src.cos), no)?,
                };
            }
            harmonics[..count].sort_unstable_by_key(|h| h.order);
            reach += abs(j.link[0]) + abs(j.link[1]) + abs(j.link[2]);
            *jm = JointModel {
                axis: j.axis,
                scale: conv(CountScale::new(j.counts), no)?,
                link: vec3::<P>(j.link, no)?,
                thermal: conv(P::k_from_f64(j.thermal), no)?,
                has_thermal: j.thermal != 0.0,
                gravity: conv(P::g_from_f64(j.gravity), no)?,
                has_gravity: j.gravity != 0.0,
                harmonics,
                harmonic_count: count as u8,
            };
        }
        let p = table.probe();
        reach += abs(p.vector[0]) + abs(p.vector[1]) + abs(p.vector[2]);
        // Thermal expansion over the accepted temperatures stretches every link by at most
        // 4e-4 · 100 = 4 %.
        // Finite by the table's checks; written so that NaN would be refused too.
        let fits = reach * 1.04 < P::MAX_REACH_MM;
        if !fits {
            return Err(ChainError::Range { joint: 0 });
        }
        Ok(Model {
            n,
            joints,
            probe: vec3::<P>(p.vector, 0)?,
            dir: units::<P, 3>(p.direction, 0)?,
            probe_thermal: conv(P::k_from_f64(p.thermal), 0)?,
            probe_has_thermal: p.thermal != 0.0,
        })
    }

    /// Checks a reading and computes what both chains need per joint: the split raw angle,
    /// the harmonic angle error, the link at temperature; and the probe vector at temperature.
    #[inline(always)]
    pub fn state(&self, counts: &[u32], temp_mc: i32) -> Result<ReadingState<P>, ChainError> {
        if counts.len() != self.n {
            return Err(ChainError::JointCount {
                expected: self.n as u8,
                found: counts.len().min(255) as u8,
            });
        }
        let dt = temp_mc.wrapping_sub(REFERENCE_TEMP_MC);
        if !(-TEMP_RANGE_MC..=TEMP_RANGE_MC).contains(&dt) {
            return Err(ChainError::Temperature);
        }
        let mut out = [JointState::<P> {
            angle: JointAngle::default(),
            error: P::U::default(),
            link: [P::L::default(); 3],
        }; MAX_JOINTS];
        for (i, ((st, j), &count)) in out.iter_mut().zip(&self.joints).zip(counts).enumerate() {
            if count >= j.scale.counts() {
                return Err(ChainError::CountOutOfRange { joint: i as u8 + 1 });
            }
            st.angle = JointAngle::from_binary(j.scale.binary(count));
            st.error = harmonic_error(j, &st.angle);
            st.link = thermal::<P>(j.link, j.has_thermal, j.thermal, dt);
        }
        let probe = thermal::<P>(self.probe, self.probe_has_thermal, self.probe_thermal, dt);
        Ok((out, probe))
    }
}

/// The encoder-harmonic angle error e = Σ s_h sin(hθ) + c_h cos(hθ) of the raw reading.
#[inline(always)]
pub fn harmonic_error<P: Precision>(j: &JointModel<P>, angle: &JointAngle<P>) -> P::U {
    let mut e = P::U::default();
    if j.harmonic_count == 0 {
        return e;
    }
    let (c, s) = angle.full();
    let mut m = Multiples::<P>::new(c, s);
    for h in &j.harmonics[..usize::from(j.harmonic_count).min(MAX_HARMONICS)] {
        while m.order < h.order {
            m.step();
        }
        e = e + (m.s.scale(h.sin) + m.c.scale(h.cos));
    }
    e
}

/// A link vector at temperature: v (1 + κ ΔT).
#[inline(always)]
pub fn thermal<P: Precision>(v: Vec3<P::L>, has: bool, k: P::K, dt_mc: i32) -> Vec3<P::L> {
    if !has {
        return v;
    }
    let s = P::thermal(k, dt_mc);
    [
        v[0] + v[0].scale(s),
        v[1] + v[1].scale(s),
        v[2] + v[2].scale(s),
    ]
}

/// The gravity deflection of a joint, e = g · x, where x = a · (d × ẑ) = (a × d) · z is the
/// lever term: a the joint's axis, d the vector from the joint's origin to the tip, z the
/// vertical, all in one frame. Each chain evaluates x in the frame where it is cheapest.
#[inline(always)]
pub fn gravity_angle<P: Precision>(g: P::G, lever: P::L) -> P::U {
    P::gravity(g, lever)
}
