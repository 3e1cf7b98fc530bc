//! What both chains share: the calibrated model converted to one evaluator's numbers, each
//! joint's part of a reading (angle, encoder-harmonic error, link at temperature), the gravity
//! coefficients, and the output point.
//!
//! The chains differ in how they represent rotations and sum the position ([`crate::chain`]:
//! quaternions, orientation base to tip and position tip to base; [`crate::matrix`]: 3×3
//! matrices, base to tip with the spec's first-order gravity sum, [`Gravity`]).
//!
//! **Every joint turns about z.** A joint about x or y is rewritten at boot with the cyclic
//! permutation P_a of the coordinates that takes z to its axis: R(u_a, θ) = P_a R(z, θ) P_a⁻¹,
//! so the joint's fixed rotation becomes P_(a−1)⁻¹ M'_i P_a (a−1: the previous joint's axis),
//! its link P_a⁻¹ v_i, the probe P_aN⁻¹ v_p. Permutations move components without arithmetic,
//! so the rewritten constants are exact (the quaternion products with P are taken in f64 and
//! rounded once, like any table value). The per-point code then has one shape, no branches or
//! indexed loads for the axis, and the axis of joint k in the base frame is always the third
//! column of its accumulated rotation.
//!
//! The table is built in f64 on the host; everything here that needs arithmetic beyond a
//! conversion (the permuted rotations, link expansion rates, the probe folded into the last
//! link) is computed in f64 at boot and rounded once.

use crate::angle::{CountScale, Multiples, Quarter};
use crate::physics::Physics;
use crate::rotate::Vec3;
use crate::scalar::{Arithmetic, Scale};
use crate::table::{JointData, ProbeData, Table, MAX_HARMONICS, MAX_JOINTS};
use core::fmt;
use core::mem::MaybeUninit;

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
    /// The arm's reach (Σ |components| of links and probe, +4 % for thermal expansion)
    /// exceeds what this evaluator's numbers hold (fixed point: I12F20 millimetres).
    Reach {
        /// The reach with its thermal margin, whole mm rounded up.
        reach_mm: u32,
        /// The evaluator's limit, mm.
        limit_mm: u32,
    },
    /// The arm's sum of levers (Σ over the joints of the reach beyond each, +4 % thermal)
    /// exceeds what this evaluator keeps within its bound (f32: its rounding of each joint's
    /// turn, times the lever).
    Levers {
        /// The sum with its thermal margin, whole mm rounded up.
        levers_mm: u32,
        /// The evaluator's limit, mm.
        limit_mm: u32,
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
            ChainError::Range { joint: 0 } => f.write_str("probe does not fit this evaluator"),
            ChainError::Reach { reach_mm, limit_mm } => write!(
                f,
                "reach {reach_mm} mm (links and probe, +4 % thermal) exceeds this evaluator's {limit_mm} mm"
            ),
            ChainError::Levers {
                levers_mm,
                limit_mm,
            } => write!(
                f,
                "sum of levers {levers_mm} mm (the reach beyond each joint, +4 % thermal) exceeds this evaluator's {limit_mm} mm"
            ),
            ChainError::Range { joint } => {
                write!(f, "joint {joint}: table value does not fit this evaluator")
            }
        }
    }
}

impl core::error::Error for ChainError {}

/// A probe-ball centre and probe direction in one evaluator's numbers.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Point<P: Arithmetic> {
    /// Probe-ball centre, base frame (mm).
    pub xyz: Vec3<P::L>,
    /// Probe direction, unit vector.
    pub dir: Vec3<P::U>,
}

impl<P: Arithmetic> Point<P> {
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
pub struct HarmonicTerm<P: Arithmetic> {
    /// Order h.
    pub order: u32,
    /// Coefficient of sin(hθ).
    pub sin: P::U,
    /// Coefficient of cos(hθ).
    pub cos: P::U,
}

/// One joint's constants, except its fixed rotation (the chains keep that in their own form).
#[derive(Clone, Copy, Debug, Default)]
pub struct JointModel<P: Physics> {
    /// The joint's axis in the table: 0 = x, 1 = y, 2 = z (the chain turns about z, see the
    /// module docs).
    pub axis: u8,
    /// Count to binary angle.
    pub scale: CountScale,
    /// Link vector with its error (mm), in the z-axis frame of the joint; for the last joint
    /// the mounted probe's vector is added (both turn with the last joint, so one rotation
    /// serves both; [`Model::mount`]).
    pub link: Vec3<P::L>,
    /// Its thermal expansion, mm per m°C (κ v, and κ_p v_p for the probe).
    pub link_rate: Vec3<P::R>,
    /// Whether `link_rate` is non-zero.
    pub has_thermal: bool,
    /// Gravity compliance.
    pub gravity: P::Gravity,
    /// Whether `gravity` is non-zero.
    pub has_gravity: bool,
    /// Harmonic terms, ascending order.
    pub harmonics: [HarmonicTerm<P>; MAX_HARMONICS],
    /// Number of harmonic terms.
    pub harmonic_count: u8,
    /// For harmonics of orders 1 and 2 only (eccentricity and ellipticity, what calibrations
    /// fit): (s₁, c₁, 2s₂, c₂), see [`JointModel::reading`].
    pub harmonic_12: Option<[P::U; 4]>,
}

/// The calibrated model in one evaluator's numbers.
#[derive(Clone, Copy, Debug, Default)]
pub struct Model<P: Physics> {
    /// Number of joints.
    pub n: usize,
    /// Joints, base first.
    pub joints: [JointModel<P>; MAX_JOINTS],
    /// Unit direction of the mounted probe's vector, in the z-axis frame of the last joint.
    pub probe_dir: Vec3<P::U>,
    /// Whether the arm's deflections call for the second-order gravity terms
    /// ([`SECOND_ORDER_DEFLECTION`]).
    pub second_order_gravity: bool,
}

/// Joint i's part of one reading.
#[derive(Clone, Copy, Debug)]
pub struct JointReading<P: Physics> {
    /// The raw reading θ as quarter turns and a small remainder.
    pub angle: Quarter<P>,
    /// cos θ and sin θ of the raw reading, where the harmonics or the caller needed them.
    pub full: Option<(P::U, P::U)>,
    /// The encoder-harmonic angle error e (rad).
    pub e: P::U,
    /// The link at the reading's temperature.
    pub link: Vec3<P::L>,
}

fn conv<T>(x: Option<T>, joint: usize) -> Result<T, ChainError> {
    x.ok_or(ChainError::Range { joint: joint as u8 })
}

fn vec3<P: Arithmetic>(v: [f64; 3], joint: usize) -> Result<Vec3<P::L>, ChainError> {
    Ok([
        conv(P::l_from_f64(v[0]), joint)?,
        conv(P::l_from_f64(v[1]), joint)?,
        conv(P::l_from_f64(v[2]), joint)?,
    ])
}

fn rates<P: Physics>(v: [f64; 3], joint: usize) -> Result<Vec3<P::R>, ChainError> {
    Ok([
        conv(P::r_from_f64(v[0]), joint)?,
        conv(P::r_from_f64(v[1]), joint)?,
        conv(P::r_from_f64(v[2]), joint)?,
    ])
}

/// Converts a dimensionless f64 triple or quadruple.
pub(crate) fn units<P: Arithmetic, const K: usize>(
    v: [f64; K],
    joint: usize,
) -> Result<[P::U; K], ChainError> {
    let mut out = [P::U::default(); K];
    for (o, x) in out.iter_mut().zip(v) {
        *o = conv(P::u_from_f64(x), joint)?;
    }
    Ok(out)
}

pub(crate) fn abs(x: f64) -> f64 {
    if x < 0.0 {
        -x
    } else {
        x
    }
}

/// Orders a joint's periodic terms (harmonics, wobble) by `order`, in place, so that
/// [`Multiples`] reaches each order from the one before: an insertion sort, since there are
/// at most [`MAX_HARMONICS`] of them and `core`'s `sort_unstable` brings about 2 KB of general
/// sorting code into the M0 image at `opt-level = "z"`.
pub(crate) fn sort_by_order<T>(terms: &mut [T], order: impl Fn(&T) -> u32) {
    for i in 1..terms.len() {
        let mut k = i;
        while k > 0 && order(&terms[k - 1]) > order(&terms[k]) {
            terms.swap(k - 1, k);
            k -= 1;
        }
    }
}

/// Σ |components| of a vector: a bound on its length that needs no square root.
fn l1(v: [f64; 3]) -> f64 {
    abs(v[0]) + abs(v[1]) + abs(v[2])
}

/// Thermal expansion over the accepted temperatures stretches every link by at most
/// |κ| ΔT = 4e-4 · 100 = 4 % ([`crate::table::limits::THERMAL`], [`TEMP_RANGE_MC`]).
const THERMAL_MARGIN: f64 = 1.04;

/// The bound on the arm's gravity deflections, G·R = Σ_k |g_k| · reach (rad), above which the
/// chains take the second-order gravity terms (the levers on the undeflected chain, the
/// deflections in the direction exactly).
///
/// Leaving them out costs at most (G R)² in the direction (the deflections' rotations summed
/// to first order, |Ω| ≤ G R) and (G R)² R / 2 at the tip (joint k's lever taken on the
/// deflected chain is off by at most Σ_{j>k} |g_j| R², its angle by |g_k| times that, the tip
/// by R times that again): at this threshold 2e-8 and, at the largest reach a table holds
/// (2147 mm with the thermal margin), 21 nm — within fixed point's bounds (1e-7 and 0.1 µm)
/// with its own floor (4e-8, 0.014 µm). Hub-class arms stay below it and do not pay for the
/// terms: `default-6-full` (4, 3 and 1e-8 rad/mm on its hinges, 1.57 m) is at 1.26e-4. The
/// MUKCa robots' 1e-6 rad/mm is far above.
pub const SECOND_ORDER_DEFLECTION: f64 = 1.4e-4;

/// A vector of a joint's frame in the calibration file's coordinates (its axis x, y or z) in
/// the chain's z-axis frame of that joint, P_a⁻¹ v: component k is component (k + a + 1)
/// mod 3 of v (a = 2, z: the identity). A relabelling, exact.
// Out of line: the set-up code calls it at boot, in one copy per element type (inlined at
// each call on the Cortex-M0, its image had 312 bytes more than its room).
#[inline(never)]
pub(crate) fn unpermute<T: Copy>(v: [T; 3], axis: u8) -> [T; 3] {
    unpermute_inline(v, axis)
}

/// [`unpermute`] inlined, for a hot path (U95's columns, every point: no call, no bounds
/// check; indices from a table cost 900 instructions a point on qemu-m4f, measured).
#[inline(always)]
pub(crate) fn unpermute_inline<T: Copy>(v: [T; 3], axis: u8) -> [T; 3] {
    // Spelt out: `% 3` is a call to the runtime's division on the Cortex-M0.
    match axis {
        0 => [v[1], v[2], v[0]],
        1 => [v[2], v[0], v[1]],
        _ => v,
    }
}

/// The quaternion of P_a: a 120° turn about (1, 1, 1) for x, −120° for y, none for z.
fn perm_quat(axis: u8) -> [f64; 4] {
    match axis {
        0 => [0.5, 0.5, 0.5, 0.5],
        1 => [0.5, -0.5, -0.5, -0.5],
        _ => [1.0, 0.0, 0.0, 0.0],
    }
}

fn qmul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// Joint i's fixed rotation as a quaternion in the z-axis frames: P_prev⁻¹ M'_i P_axis.
pub(crate) fn z_frame_quat(m: [f64; 4], prev_axis: u8, axis: u8) -> [f64; 4] {
    let p = perm_quat(prev_axis);
    let prev_inv = [p[0], -p[1], -p[2], -p[3]];
    qmul(qmul(prev_inv, m), perm_quat(axis))
}

/// Joint i's fixed rotation without its relabelling, P_axis⁻¹ M'_i P_axis: M'_i itself, its
/// vector part permuted into the joint's z-axis frame (exact), near the identity on a real arm.
pub(crate) fn near_quat(m: [f64; 4], axis: u8) -> [f64; 4] {
    let v = unpermute([m[1], m[2], m[3]], axis);
    [m[0], v[0], v[1], v[2]]
}

/// Joint i's fixed rotation as a matrix in the z-axis frames: P_prev⁻¹ M'_i P_axis, which only
/// permutes rows and columns.
pub(crate) fn z_frame_matrix(m: [[f64; 3]; 3], prev_axis: u8, axis: u8) -> [[f64; 3]; 3] {
    let (pa, a) = (usize::from(prev_axis % 3), usize::from(axis % 3));
    let mut out = [[0.0; 3]; 3];
    for (r, row) in out.iter_mut().enumerate() {
        for (c, x) in row.iter_mut().enumerate() {
            *x = m[(r + pa + 1) % 3][(c + a + 1) % 3];
        }
    }
    out
}

/// Puts `probe` on the last joint `jm` (joint `i` of `table`): its link carries the probe's
/// vector and expansion, formed in f64 and rounded once; `dir` takes the probe's direction.
/// Every value is converted before any is written, so that nothing changes on an error.
fn put_probe<P: Physics>(
    table: &Table<'_>,
    i: usize,
    jm: &mut JointModel<P>,
    dir: &mut Vec3<P::U>,
    probe: &ProbeData,
) -> Result<(), ChainError> {
    let (axis, mut link, thermal) = table
        .joint_link(i)
        .ok_or(ChainError::Range { joint: i as u8 + 1 })?;
    let mut rate = link.map(|x| x * thermal);
    for k in 0..3 {
        link[k] += probe.vector[k];
        rate[k] += probe.vector[k] * probe.thermal;
    }
    let no = i + 1;
    let link_p = vec3::<P>(unpermute(link, axis), no)?;
    let rate_p = rates::<P>(unpermute(rate, axis), no)?;
    *dir = units::<P, 3>(unpermute(probe.direction, axis), 0)?;
    (jm.link, jm.link_rate, jm.has_thermal) = (link_p, rate_p, rate != [0.0; 3]);
    Ok(())
}

impl<P: Physics> JointModel<P> {
    /// Sets joint `no`'s (1-based, for errors) model from its table record: its link without
    /// the probe (the last joint's takes the probe's vector when one is mounted, in
    /// [`put_probe`]), its harmonics sorted by order, and the combined first- and
    /// second-order harmonic where the joint has no other. Written in place, as
    /// [`put_probe`] is: returned by value, it raised the Cortex-M0 hub's stack peak by
    /// 40 bytes.
    fn set(&mut self, j: &JointData, no: usize) -> Result<(), ChainError> {
        let mut harmonics = [HarmonicTerm::<P>::default(); MAX_HARMONICS];
        let count = usize::from(j.harmonic_count).min(MAX_HARMONICS);
        for (h, src) in harmonics.iter_mut().zip(&j.harmonics[..count]) {
            *h = HarmonicTerm {
                order: u32::from(src.order),
                sin: conv(P::u_from_f64(src.sin), no)?,
                cos: conv(P::u_from_f64(src.cos), no)?,
            };
        }
        sort_by_order(&mut harmonics[..count], |h| h.order);
        let mut h12 = [0.0f64; 4]; // s1, c1, s2, c2
        let mut low = count > 0;
        for src in &j.harmonics[..count] {
            match src.order {
                1 => (h12[0], h12[1]) = (h12[0] + src.sin, h12[1] + src.cos),
                2 => (h12[2], h12[3]) = (h12[2] + src.sin, h12[3] + src.cos),
                _ => low = false,
            }
        }
        let harmonic_12 = if low {
            let [s1, c1, s2, c2] = h12;
            Some(units::<P, 4>([s1, c1, 2.0 * s2, c2], no)?)
        } else {
            None
        };
        let (link, rate) = (j.link, j.link.map(|x| x * j.thermal));
        *self = JointModel {
            axis: j.axis,
            scale: conv(CountScale::new(j.counts), no)?,
            link: vec3::<P>(unpermute(link, j.axis), no)?,
            link_rate: rates::<P>(unpermute(rate, j.axis), no)?,
            has_thermal: rate != [0.0; 3],
            gravity: conv(P::gravity_from_f64(j.gravity), no)?,
            has_gravity: j.gravity != 0.0,
            harmonics,
            harmonic_count: count as u8,
            harmonic_12,
        };
        Ok(())
    }
}

/// The arm's reach and sum of levers (mm, the longest probe included) with the thermal
/// margin, refused when either is beyond what evaluator `P` holds; the reach with its margin
/// when both fit.
fn within_limits<P: Physics>(reach: f64, levers: f64) -> Result<f64, ChainError> {
    // Finite by the table's checks; written so that NaN would be refused too.
    let reach = reach * THERMAL_MARGIN;
    let fits = reach < P::MAX_REACH_MM;
    if !fits {
        // Saturating conversions: the table's limits keep both far inside u32.
        return Err(ChainError::Reach {
            reach_mm: reach as u32 + 1,
            limit_mm: P::MAX_REACH_MM as u32,
        });
    }
    if let Some(limit) = P::MAX_LEVERS_MM {
        let levers = levers * THERMAL_MARGIN;
        let fits = levers < limit;
        if !fits {
            return Err(ChainError::Levers {
                levers_mm: levers as u32 + 1,
                limit_mm: limit as u32,
            });
        }
    }
    Ok(reach)
}

/// The axis the base frame stands for before joint 1: z (no permutation).
pub(crate) const BASE_AXIS: u8 = 2;

impl<P: Physics> Model<P> {
    /// Converts a validated table with its first probe mounted; fails if a value does not fit
    /// this evaluator (for fixed point: the arm's reach, over ±100 °C of thermal expansion,
    /// must stay within 2 m). The reach and the sum of levers are taken with the table's
    /// longest probe, so that every probe the table holds fits once this succeeds, and so
    /// that whether the chains take the second-order gravity terms is the same whichever is
    /// mounted.
    pub fn new(table: &Table<'_>) -> Result<Model<P>, ChainError> {
        let n = table.joint_count();
        let mut joints = [JointModel::<P>::default(); MAX_JOINTS];
        let mut reach = 0.0;
        let mut levers = 0.0;
        let mut gravity = 0.0;
        for (i, jm) in joints.iter_mut().enumerate().take(n) {
            let j = table
                .joint(i)
                .ok_or(ChainError::Range { joint: i as u8 + 1 })?;
            jm.set(&j, i + 1)?;
            reach += l1(j.link);
            // Link i lies beyond joints 1..=i + 1: it is in i + 1 levers.
            levers += l1(j.link) * (i + 1) as f64;
            gravity += abs(j.gravity);
        }
        // The longest probe: the one that reaches farthest, beyond all n joints.
        let mut longest = 0.0;
        for k in 0..table.probe_count() {
            let l = table.probe_at(k).map_or(0.0, |p| l1(p.vector));
            if l > longest {
                longest = l;
            }
        }
        reach += longest;
        levers += longest * n as f64;
        let reach = within_limits::<P>(reach, levers)?;
        // The first probe on the last joint, converted into the joints' own array rather
        // than into a whole model mounted afterwards: a second model on the Cortex-M0's boot
        // stack was 840 bytes its 8 KiB do not have.
        let last = n.clamp(1, MAX_JOINTS) - 1;
        let mut probe_dir = [P::U::default(); 3];
        put_probe(
            table,
            last,
            &mut joints[last],
            &mut probe_dir,
            &table.probe(),
        )?;
        Ok(Model {
            n,
            joints,
            probe_dir,
            second_order_gravity: gravity * reach > SECOND_ORDER_DEFLECTION,
        })
    }

    /// Mounts the table's probe `k`: the last joint's link carries its vector and its
    /// expansion, and the chain's direction is its direction. Converted from the table's f64
    /// when a probe is selected (rarely), rather than holding every probe converted. On an
    /// error nothing changes: `Range` for a `k` past the table's probes, and none for a probe
    /// of the table the model was built from, whose reach [`Model::new`] checked with the
    /// longest probe.
    pub fn mount(&mut self, table: &Table<'_>, k: usize) -> Result<(), ChainError> {
        let probe = table.probe_at(k).ok_or(ChainError::Range { joint: 0 })?;
        let i = self.n.clamp(1, MAX_JOINTS) - 1;
        put_probe(table, i, &mut self.joints[i], &mut self.probe_dir, &probe)
    }

    /// Checks the reading's shape and temperature; returns the temperature offset from 20 °C.
    #[inline(always)]
    pub fn check(&self, counts: &[u32], temp_mc: i32) -> Result<P::T, ChainError> {
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
        Ok(P::temperature(dt))
    }
}

impl<P: Physics> JointModel<P> {
    /// The link at temperature: v (1 + κ ΔT) = v + (κ v) ΔT.
    #[inline(always)]
    pub fn link_at(&self, dt: P::T) -> Vec3<P::L> {
        let v = self.link;
        if !self.has_thermal {
            return v;
        }
        let r = self.link_rate;
        [
            v[0] + P::expansion(r[0], dt),
            v[1] + P::expansion(r[1], dt),
            v[2] + P::expansion(r[2], dt),
        ]
    }

    /// Joint `i`'s part of a reading: its angle split into quarter turns and a remainder, the
    /// harmonic error and the link at temperature. `want_full` asks for cos θ and sin θ even
    /// without harmonics.
    ///
    /// Harmonics of orders 1 and 2 take the double-angle identities in C = cos θ, S = sin θ:
    /// e = S (s₁ + 2s₂ C − c₂ S) + C (c₁ + c₂ C) — 5 products, no loop.
    #[inline(always)]
    pub fn reading(
        &self,
        i: usize,
        count: u32,
        dt: P::T,
        want_full: bool,
    ) -> Result<JointReading<P>, ChainError> {
        if count >= self.scale.counts() {
            return Err(ChainError::CountOutOfRange { joint: i as u8 + 1 });
        }
        let angle = Quarter::<P>::from_binary(self.scale.binary(count));
        let mut e = P::U::default();
        let mut full = None;
        if self.harmonic_count > 0 || want_full {
            let (fc, fs) = angle.full();
            full = Some((fc, fs));
            if let Some([s1, c1, s2, c2]) = self.harmonic_12 {
                e = fs.scale(s1 + fc.scale(s2) - fs.scale(c2)) + fc.scale(c1 + fc.scale(c2));
            } else {
                let mut m = Multiples::<P>::new(fc, fs);
                for h in &self.harmonics[..usize::from(self.harmonic_count).min(MAX_HARMONICS)] {
                    m.advance(h.order);
                    e = e + (m.s.scale(h.sin) + m.c.scale(h.cos));
                }
            }
        }
        Ok(JointReading {
            angle,
            full,
            e,
            link: self.link_at(dt),
        })
    }
}

/// The spec's first-order gravity correction (the matrix chain's), gathered base to tip and
/// applied at the end:
/// with d_k = p − o_k and e_k = g_k a_k · (d_k × ẑ) = g_k (a_kx d_ky − a_ky d_kx),
/// Δp = Σ e_k a_k × d_k, Δn = (Σ e_k a_k) × n. It agrees with the exactly deflected chain to
/// a few nanometres (`armcal accuracy`, last row).
pub struct Gravity<P: Physics> {
    // Filled base to tip; only the first `count` are ever read. Left uninitialised because
    // zeroing seven slots per reading (a memset) cost more than the whole correction.
    terms: [MaybeUninit<GravityTerm<P>>; MAX_JOINTS],
}

/// How many [`Gravity`] slots are filled. Kept apart from the slots: in one struct, LLVM
/// merges the zero count and the uninitialised slots into one memset of the whole.
#[derive(Clone, Copy, Debug, Default)]
pub struct GravityCount(usize);

#[derive(Clone, Copy)]
struct GravityTerm<P: Physics> {
    g: P::Gravity,
    axis: Vec3<P::U>,
    origin: Vec3<P::L>,
}

impl<P: Physics> Default for Gravity<P> {
    #[inline(always)]
    fn default() -> Self {
        Gravity {
            terms: [const { MaybeUninit::uninit() }; MAX_JOINTS],
        }
    }
}

impl<P: Physics> Gravity<P> {
    /// Records a compliant joint: its coefficient, its axis and its origin in the base frame.
    #[inline(always)]
    pub fn push(
        &mut self,
        n: &mut GravityCount,
        g: P::Gravity,
        axis: Vec3<P::U>,
        origin: Vec3<P::L>,
    ) {
        if let Some(slot) = self.terms.get_mut(n.0) {
            slot.write(GravityTerm { g, axis, origin });
            n.0 += 1;
        }
    }

    /// The deflections e_k = g_k a_k · ((p − o_k) × ẑ) of the recorded joints at the
    /// undeflected tip p, in the order they were pushed.
    #[inline(always)]
    pub fn deflections(&self, count: GravityCount, p: Vec3<P::L>, out: &mut [P::U; MAX_JOINTS]) {
        for (slot, e) in self.terms.iter().take(count.0).zip(out.iter_mut()) {
            // SAFETY: `push` wrote every slot below `count` before counting it.
            let GravityTerm {
                g,
                axis: a,
                origin: o,
            } = unsafe { slot.assume_init_read() };
            let d = [p[0] - o[0], p[1] - o[1]];
            *e = P::gravity(g, d[1].scale(a[0]) - d[0].scale(a[1]));
        }
    }

    /// The corrected tip and direction.
    #[inline(always)]
    pub fn apply(
        &self,
        count: GravityCount,
        p: Vec3<P::L>,
        n: Vec3<P::U>,
    ) -> (Vec3<P::L>, Vec3<P::U>) {
        let zero = P::U::default();
        let (mut w, mut dp) = ([zero; 3], [P::L::default(); 3]);
        for slot in self.terms.iter().take(count.0) {
            // SAFETY: `push` wrote every slot below `count` before counting it.
            let GravityTerm {
                g,
                axis: a,
                origin: o,
            } = unsafe { slot.assume_init_read() };
            let d = [p[0] - o[0], p[1] - o[1], p[2] - o[2]];
            let e = P::gravity(g, d[1].scale(a[0]) - d[0].scale(a[1]));
            let b = [a[0].scale(e), a[1].scale(e), a[2].scale(e)];
            w = [w[0] + b[0], w[1] + b[1], w[2] + b[2]];
            dp = [
                dp[0] + (d[2].scale(b[1]) - d[1].scale(b[2])),
                dp[1] + (d[0].scale(b[2]) - d[2].scale(b[0])),
                dp[2] + (d[1].scale(b[0]) - d[0].scale(b[1])),
            ];
        }
        (
            [p[0] + dp[0], p[1] + dp[1], p[2] + dp[2]],
            [
                n[0] + (n[2].scale(w[1]) - n[1].scale(w[2])),
                n[1] + (n[0].scale(w[2]) - n[2].scale(w[0])),
                n[2] + (n[1].scale(w[0]) - n[0].scale(w[1])),
            ],
        )
    }
}
