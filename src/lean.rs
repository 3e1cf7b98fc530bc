//! The lean f32 chain: the same calibrated model as [`crate::chain`], evaluated in the form
//! that takes the fewest instructions on a Cortex-M4F, which the hub runs by default for an
//! arm it fits (f32, first-order gravity, harmonics of orders 1 and 2; an axis wobble by
//! [`crate::lean_wobble`]'s pass, written with this one's per-joint steps, where it takes it).
//!
//! **The form.** Each joint's fixed rotation in its z-axis frame ([`crate::model`]) is split
//! at boot, in f64, into Euler angles M̃_i = Rz(a_i) Rx(α_i) Rz(b_i). A turn about z commutes
//! into the joint's own turn, so b_i and a_(i+1) (the next joint's first turn, moved back
//! through link i, which is turned by Rz(−a_(i+1)) at boot to match) join joint i's count as a
//! binary-angle offset: one integer add a point. The harmonics, functions of the raw angle,
//! take coefficients rotated by the offset (exact identities, in f64 at boot). What is left
//! per joint is a turn about x by a constant and a turn about z by the reading:
//!
//! p = Rz(a_1) · [Rx(α_1) Rz(θ'_1) (v'_1 + Rx(α_2) Rz(θ'_2) (v'_2 + …))],
//!
//! evaluated tip to base (Horner form), the probe direction carried along as a second vector.
//! Both turns are written as an exact quarter turn plus a small correction (|angle| ≤ π/4), as
//! the quaternion chain does, so that each large partial sum is rounded about once a turn.
//!
//! **Gravity** needs the base frame's vertical in each compliant joint's frame, which only a
//! base-to-tip pass has: a first pass turns (0, 0, 1) by Rx(−α_k) Rz(−θ'_k) (the vertical
//! is a unit vector: rounding here scales the deflection, 1e-7 of 4e-5 rad, not the tip; the
//! harmonic errors left out of its turns move it by Σ|e|, a bound measured in
//! `docs/results/speed.md`) and keeps the joints' angles (a joint without gravity's with its
//! remainder already turned by its harmonic error); the second pass, tip to base, adds each deflection
//! e_k = g_k (w × ẑ_base)·ẑ_k to its joint's angle before the turn, so the direction
//! and the tip are both deflected exactly (no Σ e_k a_k correction afterwards).
//!
//! The quaternion chain stays the model's own form ([`crate::chain::Chain::eval_quaternion`]),
//! and the hub falls back to it for any arm this form does not take. Where the two forms'
//! costs come from: `docs/results/speed.md`.

use crate::angle::{quarter_turns, CountScale};
use crate::lean_wobble::LeanWobble;
use crate::model::{units, unpermute, ChainError, Model, Point, BASE_AXIS};
use crate::physics::Physics;
use crate::scalar::{Arithmetic, F32};
use crate::table::{Table, MAX_JOINTS};
use core::fmt::Debug;
use core::mem::MaybeUninit;

/// What a chain's evaluator offers as its lean form: the f32 chain of this module, or none.
pub trait LeanForm<P: Physics>: Copy + Debug {
    /// Writes in `out` the lean form of `table`'s arm, or one that does not apply (`applies`
    /// false) where the arm has what the form does not take (second-order gravity, harmonics
    /// past order 2, an axis wobble [`crate::lean_wobble`] does not take) or the caller wants
    /// none (`eligible` false). In place, as the chain that holds it
    /// ([`crate::chain::Chain::build_in`]): the f32 form is 1,360 bytes, and built in a local
    /// and returned it was on the hub's boot stack twice more. On an error `out` holds no
    /// usable form.
    fn build_in<'o>(
        out: &'o mut MaybeUninit<Self>,
        table: &Table<'_>,
        model: &Model<P>,
        eligible: bool,
    ) -> Result<&'o mut Self, ChainError>;
    /// Whether [`LeanForm::eval`] evaluates this arm.
    fn applies(&self) -> bool;
    /// The probe-ball centre and direction, as [`crate::chain::Chain::eval`].
    fn eval(&self, model: &Model<P>, counts: &[u32], temp_mc: i32) -> Result<Point<P>, ChainError>;
    /// Takes the probe `model` has mounted.
    fn mount(&mut self, model: &Model<P>);
}

/// No lean form (the fixed-point evaluator: the Cortex-M0's image has no room for a second
/// chain).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoLean;

impl<P: Physics> LeanForm<P> for NoLean {
    fn build_in<'o>(
        out: &'o mut MaybeUninit<NoLean>,
        _: &Table<'_>,
        _: &Model<P>,
        _: bool,
    ) -> Result<&'o mut NoLean, ChainError> {
        Ok(out.write(NoLean))
    }
    #[inline(always)]
    fn applies(&self) -> bool {
        false
    }
    fn eval(&self, _: &Model<P>, _: &[u32], _: i32) -> Result<Point<P>, ChainError> {
        // Never called: `applies` is false.
        Err(ChainError::Range { joint: 0 })
    }
    fn mount(&mut self, _: &Model<P>) {}
}

/// A turn as an exact quarter turn and a remainder of at most π/4: q, sin r, 1 − cos r.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Turn {
    pub(crate) q: u8,
    pub(crate) sin: f32,
    pub(crate) omc: f32,
    /// cos r = 1 − omc, for the direction's plain rotation.
    pub(crate) cos: f32,
}

/// One joint's constants in the lean form. A term the joint does not have is stored as zeros
/// (harmonics, thermal rate), which give the same numbers as leaving it out (a sum with ±0), so
/// the per-point code tests no flag for it; gravity keeps its flag, since its term needs the
/// vertical the first pass computes only up to the last compliant joint.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct LeanJoint {
    scale: CountScale,
    /// The binary angle of one count where the counts per revolution are a power of two
    /// ([`CountScale::unit`]), else 0.
    unit: u32,
    /// b_i + a_(i+1) as a binary angle (one turn = 2^32), added to the reading's.
    offset: u32,
    /// (s₁, c₁, 2s₂, c₂) rotated to the offset angle; zeros without harmonics.
    harmonics: [f32; 4],
    /// v'_i = Rz(−a_(i+1)) v_i and its thermal rate (zeros without thermal expansion).
    link: [f32; 3],
    rate: [f32; 3],
    pub(crate) gravity: f32,
    pub(crate) has_gravity: bool,
    /// Rx(α_i) for the tip, as an exact quarter turn and a correction with the quarter turn's
    /// selection made at boot ([`QuarterTurned`]).
    pub(crate) alpha: QuarterTurned,
    /// Rx(α_i) as its quarter turn and remainder: the wobble's pass turns the remainder by
    /// φx per point where the remainder and φx are not one small angle
    /// ([`crate::lean_wobble::MAX_RHO`]); its `cos` is 1 − omc rounded in f32, as
    /// [`turned`] would form it.
    #[cfg(feature = "wobble")]
    pub(crate) alpha_turn: Turn,
    /// cos α_i and sin α_i whole, the quarter turns applied at boot (exact): the plain turns
    /// of the direction and the vertical, which need no quarter-turn selection per point.
    pub(crate) alpha_whole: [f32; 2],
}

/// A turn by a constant angle q·π/2 + r (|r| ≤ π/4) of a pair (p, q) of coordinates, with the
/// quarter turn chosen at boot instead of selected each point: (c₀, s₀) the quarter turn's
/// cosine and sine (0 or ±1), A = −(s₀ sin r + c₀ (1 − cos r)) and B = s₀ (1 − cos r) − c₀ sin
/// r, each exactly ±sin r or ±(1 − cos r) since one of c₀, s₀ is 0. Then
///
/// p' = ((A p + B q) + c₀ p) − s₀ q,   q' = ((A q − B p) + s₀ p) + c₀ q:
///
/// the first sum is the remainder's correction (the same two rounded products as the selected
/// form's), the products by c₀ and s₀ are exact, one of them ±0, so the result is the quarter
/// turned coordinate plus the correction rounded once — the numbers of the form that selects
/// the quarter turn, bit for bit, in four multiply–adds a coordinate and no branch.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct QuarterTurned {
    a: f32,
    b: f32,
    c0: f32,
    s0: f32,
}

impl QuarterTurned {
    fn of(t: &Turn) -> QuarterTurned {
        let (c0, s0) = quarter_turns(t.q, (1.0f32, 0.0));
        QuarterTurned {
            a: -(s0 * t.sin + c0 * t.omc),
            b: s0 * t.omc - c0 * t.sin,
            c0,
            s0,
        }
    }

    /// (p, q) turned where the quarter turns `quarters` are known to the compiler: the exact
    /// quarter-turned coordinate added to the correction, without the products by c₀ and s₀
    /// (the same numbers as [`QuarterTurned::turn`], less a sum with ±0).
    #[inline(always)]
    fn turn_known(&self, quarters: u8, (p, q): (f32, f32)) -> (f32, f32) {
        let k = self;
        let (bp, bq) = quarter_turns(quarters, (p, q));
        (k.a * p + k.b * q + bp, k.a * q - k.b * p + bq)
    }

    /// (p, q) turned.
    #[inline(always)]
    pub(crate) fn turn(&self, (p, q): (f32, f32)) -> (f32, f32) {
        let k = self;
        (
            k.a * p + k.b * q + k.c0 * p - k.s0 * q,
            k.a * q - k.b * p + k.s0 * p + k.c0 * q,
        )
    }
}

/// [`LeanF32::run`]'s compliant joints read from each joint's flag.
pub(crate) const RUNTIME: u8 = u8::MAX;
/// The compliant joints of a six-axis arm with gravity on its hinges (joints 2, 4 and 6).
pub(crate) const HINGES: u8 = 0b10_1010;
/// [`LeanF32::run`]'s quarter turns of Rx(α) multiplied in from each joint's constants.
pub(crate) const RUNTIME_ALPHA: u16 = u16::MAX;
/// The six-axis arm's geometry: joint 1's axis along the base's (α₁ within π/4 of 0, no
/// quarter turn), each next axis perpendicular to the one before (α within π/4 of π/2, one
/// quarter turn).
pub(crate) const PERPENDICULAR: u16 = 0b01_01_01_01_01_00;

/// The lean f32 chain of an arm (or none, `on` false).
#[derive(Clone, Copy, Debug, Default)]
pub struct LeanF32 {
    on: bool,
    n: usize,
    /// Every joint's counts per revolution are a power of two: the count's binary angle is
    /// one multiply ([`LeanJoint::unit`]).
    pub(crate) pow2: bool,
    pub(crate) joints: [LeanJoint; MAX_JOINTS],
    /// Rz(a_1), applied last: the tip's turn with its quarter turn chosen at boot, and cos a_1,
    /// sin a_1 whole for the direction.
    pub(crate) base: QuarterTurned,
    pub(crate) base_whole: [f32; 2],
    pub(crate) probe_dir: [f32; 3],
    /// Joints from the base up to the last compliant one: those the first pass turns the
    /// vertical through.
    pub(crate) vertical_joints: usize,
    /// The compliant joints, bit i for joint i + 1 (the first eight).
    pub(crate) gravity_mask: u8,
    /// The quarter turns of each joint's Rx(α), bits 2i and 2i + 1 for joint i + 1 (the
    /// first eight).
    pub(crate) alpha_quarters: u16,
    /// The axis wobble's constants where the arm has one ([`crate::lean_wobble`]; its pass
    /// runs instead of this module's).
    pub(crate) wobble: LeanWobble,
}

/// cos and sin of a binary angle t (one turn = 2^32) split as q·π/2 + r, in f64: (q, sin r,
/// 1 − cos r), Taylor series to r^22 (|r| ≤ π/4: error under 1e-19). Boot only: the per-point
/// path has no f64.
fn split_turn(t: u32) -> (u8, f64, f64) {
    let (q, x) = turn_remainder(t);
    let z = x * x;
    let (mut s, mut omc) = (0.0, 0.0);
    // Horner from the highest term: sin x = x Σ (−z)^k/(2k+1)!, 1 − cos x = −Σ_(k≥1) (−z)^k/(2k)!.
    for k in (0..11).rev() {
        let k = f64::from(k);
        s = 1.0 - z * s / ((2.0 * k + 2.0) * (2.0 * k + 3.0));
        omc = z / ((2.0 * k + 1.0) * (2.0 * k + 2.0)) * (1.0 - omc);
    }
    (q, x * s, omc)
}

/// A binary angle's quarter turns q and its remainder in radians (|r| ≤ π/4), in f64: the
/// split every boot-time turn of the lean form makes ([`split_turn`], and α's remainder of
/// the wobble's pass, `crate::lean_wobble`).
pub(crate) fn turn_remainder(t: u32) -> (u8, f64) {
    let q = t.wrapping_add(1 << 29) >> 30;
    let r = t.wrapping_sub(q << 30) as i32;
    (
        q as u8,
        f64::from(r) * (core::f64::consts::PI / 2_147_483_648.0),
    )
}

/// cos and sin of a binary angle, in f64.
pub(crate) fn turn_cos_sin(t: u32) -> (f64, f64) {
    let (q, s, omc) = split_turn(t);
    quarter_turns(q, (1.0 - omc, s))
}

/// The binary angle nearest to the direction (c, s) (not both zero): the quadrant, then one
/// bit a step by turning the remainder back (successive approximation), then rounding.
fn binary_angle(c: f64, s: f64) -> u32 {
    let q: u8 = match (c > 0.0, s >= 0.0) {
        (true, true) => 0,
        (false, true) => 1,
        (false, false) => 2,
        (true, false) => 3,
    };
    // Turned back by q quarter turns: the remainder's angle is in [0, π/2).
    let (mut x, mut y) = quarter_turns(4 - q, (c, s));
    let mut t = u32::from(q) << 30;
    for k in (0..30).rev() {
        // The remainder is in [0, 2β): at or past β exactly when (cos β, sin β) × (x, y) ≥ 0.
        let (cb, sb) = turn_cos_sin(1 << k);
        if cb * y - sb * x >= 0.0 {
            (x, y) = (x * cb + y * sb, y * cb - x * sb);
            t += 1 << k;
        }
    }
    // The remainder is below one unit of 2π/2^32; round to the nearer.
    if y >= x * (core::f64::consts::PI / 4_294_967_296.0) {
        t = t.wrapping_add(1);
    }
    t
}

/// R(z, t) as a matrix.
pub(crate) fn rz(t: u32) -> [[f64; 3]; 3] {
    let (c, s) = turn_cos_sin(t);
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

/// R(x, t) as a matrix.
fn rx(t: u32) -> [[f64; 3]; 3] {
    let (c, s) = turn_cos_sin(t);
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}

fn mat_mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut out = [[0.0; 3]; 3];
    for (r, row) in out.iter_mut().enumerate() {
        for (c, x) in row.iter_mut().enumerate() {
            *x = a[r][0] * b[0][c] + a[r][1] * b[1][c] + a[r][2] * b[2][c];
        }
    }
    out
}

pub(crate) fn mat_vec(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
}

/// The transpose (the inverse of a rotation).
fn transpose(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|r| [m[0][r], m[1][r], m[2][r]])
}

/// A rotation's z-x-z Euler angles as binary angles: m ≈ Rz(a) Rx(α) Rz(b), α ∈ [0, π]. Each
/// angle is taken from what the previous ones leave of m, so that the three together
/// reproduce m to their rounding even where α is near 0 or π (a and b then shared freely).
fn euler_zxz(m: &[[f64; 3]; 3]) -> [u32; 3] {
    // Column 2 of Rz(a) Rx(α) is (sin a sin α, −cos a sin α, cos α).
    let a = binary_angle(-m[1][2], m[0][2]);
    let n = mat_mul(&transpose(&rz(a)), m);
    // Rx(α) Rz(b): column 2 is (0, −sin α, cos α).
    let alpha = binary_angle(n[2][2], -n[1][2]);
    let p = mat_mul(&transpose(&rx(alpha)), &n);
    let b = binary_angle(p[0][0], p[1][0]);
    [a, alpha, b]
}

fn turn_of(t: u32) -> Result<Turn, ChainError> {
    let (q, s, omc) = split_turn(t);
    let [sin, omc, cos] = units::<F32, 3>([s, omc, 1.0 - omc], 0)?;
    Ok(Turn { q, sin, omc, cos })
}

/// One reading's angle of a joint, as the first pass leaves it for the second.
#[derive(Clone, Copy)]
pub(crate) struct Angle {
    pub(crate) q: u8,
    /// sin r and 1 − cos r of the remainder r, |r| ≤ π/4.
    pub(crate) sin: f32,
    pub(crate) omc: f32,
    /// The harmonic error, rad (with the wobble's turn about z, [`crate::lean_wobble`]);
    /// where [`LeanF32::run`] turns the remainder by it in the first pass (a joint without
    /// gravity), 0 and unread: `sin` and `omc` are then the turned remainder's.
    pub(crate) e: f32,
}

impl LeanForm<F32> for LeanF32 {
    fn build_in<'o>(
        out: &'o mut MaybeUninit<LeanF32>,
        table: &Table<'_>,
        model: &Model<F32>,
        eligible: bool,
    ) -> Result<&'o mut LeanF32, ChainError> {
        let out = out.write(LeanF32::default());
        let n = model.n;
        let takes = eligible
            && !model.second_order_gravity
            && model.joints[..n]
                .iter()
                .all(|j| j.harmonic_count == 0 || j.harmonic_12.is_some());
        if !takes {
            return Ok(out);
        }
        (out.on, out.n) = (true, n);
        let mut prev = BASE_AXIS;
        // Each joint's Euler angles [a, α, b], in the z-axis frames.
        let mut euler = [[0u32; 3]; MAX_JOINTS];
        for (i, e) in euler.iter_mut().enumerate().take(n) {
            let j = table
                .joint(i)
                .ok_or(ChainError::Range { joint: i as u8 + 1 })?;
            *e = euler_zxz(&crate::model::z_frame_matrix(j.matrix, prev, j.axis));
            prev = j.axis;
        }
        if !out.wobble.build_in(table, &euler[..n])? {
            *out = LeanF32::default();
            return Ok(out);
        }
        let base = turn_of(euler[0][0])?;
        out.base = QuarterTurned::of(&base);
        let (cb, sb) = quarter_turns(base.q, (base.cos, base.sin));
        out.base_whole = [cb, sb];
        for i in 0..n {
            let no = i + 1;
            let j = table
                .joint(i)
                .ok_or(ChainError::Range { joint: no as u8 })?;
            // The next joint's first turn, a_(i+1); none after the last.
            let next = if i + 1 < n { euler[i + 1][0] } else { 0 };
            let offset = euler[i][2].wrapping_add(next);
            let jm = &model.joints[i];
            // e(θ) = Σ s_h sin hθ + c_h cos hθ with θ = θ' − c: s'_h = s_h cos hc + c_h sin hc,
            // c'_h = c_h cos hc − s_h sin hc.
            let (mut s, mut c) = ([0.0f64; 2], [0.0f64; 2]);
            for h in &j.harmonics[..usize::from(j.harmonic_count)] {
                let k = usize::from(h.order.clamp(1, 2)) - 1;
                s[k] += h.sin;
                c[k] += h.cos;
            }
            let mut rotated = [0.0f64; 4];
            for k in 0..2 {
                let (ch, sh) = turn_cos_sin(offset.wrapping_mul(k as u32 + 1));
                let (s2, c2) = (s[k] * ch + c[k] * sh, c[k] * ch - s[k] * sh);
                rotated[2 * k] = s2;
                rotated[2 * k + 1] = c2;
            }
            rotated[2] *= 2.0;
            // Link i turned back by a_(i+1); the last link (with the probe) as the model has it.
            let (link, rate) = if i + 1 < n {
                let (axis, link, thermal) = table
                    .joint_link(i)
                    .ok_or(ChainError::Range { joint: no as u8 })?;
                let back = transpose(&rz(next));
                let v = mat_vec(&back, unpermute(link, axis));
                let (mut l, mut r) = ([0.0f32; 3], [0.0f32; 3]);
                for k in 0..3 {
                    l[k] = F32::l_from_f64(v[k]).ok_or(ChainError::Range { joint: no as u8 })?;
                    r[k] = F32::r_from_f64(v[k] * thermal)
                        .ok_or(ChainError::Range { joint: no as u8 })?;
                }
                (l, r)
            } else {
                (jm.link, jm.link_rate)
            };
            let alpha = turn_of(euler[i][1])?;
            if i < 8 {
                out.alpha_quarters |= u16::from(alpha.q & 3) << (2 * i);
            }
            let (ca, sa) = quarter_turns(alpha.q, (alpha.cos, alpha.sin));
            out.joints[i] = LeanJoint {
                scale: jm.scale,
                unit: jm.scale.unit().unwrap_or(0),
                offset,
                harmonics: units::<F32, 4>(rotated, no)?,
                link,
                rate,
                gravity: jm.gravity,
                has_gravity: jm.has_gravity,
                alpha: QuarterTurned::of(&alpha),
                // cos r as the per-point turn forms it from 1 − cos r (f32), so that the
                // wobble's pass reads it instead of forming it (the same numbers).
                #[cfg(feature = "wobble")]
                alpha_turn: Turn {
                    cos: 1.0 - alpha.omc,
                    ..alpha
                },
                alpha_whole: [ca, sa],
            };
            if jm.has_gravity {
                out.vertical_joints = i + 1;
                if i < 8 {
                    out.gravity_mask |= 1 << i;
                }
            }
        }
        out.probe_dir = model.probe_dir;
        out.pow2 = out.joints[..n].iter().all(|j| j.unit != 0);
        Ok(out)
    }

    #[inline(always)]
    fn applies(&self) -> bool {
        self.on
    }

    #[inline(never)]
    fn eval(
        &self,
        model: &Model<F32>,
        counts: &[u32],
        temp_mc: i32,
    ) -> Result<Point<F32>, ChainError> {
        // Six joints (the hubs' arms) with the joint count a constant, so that the compiler
        // unrolls both passes, the power-of-two scales (the usual encoders) without a test
        // per joint, and for gravity on the hinges 2, 4 and 6 (the six-axis arm's compliant
        // joints) the compliant joints and the vertical's reach known to the compiler, so
        // that neither is tested per joint; any other count, scale or compliant set with the
        // same code, looped or testing the joints' flags. An arm with an axis wobble runs the
        // wobble's pass instead.
        if self.wobble.on() {
            return crate::lean_wobble::eval(self, model, counts, temp_mc);
        }
        match (counts.len(), self.pow2) {
            (6, true) if self.gravity_mask == HINGES && self.alpha_quarters == PERPENDICULAR => {
                self.run::<6, true, HINGES, PERPENDICULAR>(model, counts, temp_mc)
            }
            (6, true) if self.gravity_mask == HINGES => {
                self.run::<6, true, HINGES, RUNTIME_ALPHA>(model, counts, temp_mc)
            }
            (6, true) => self.run::<6, true, RUNTIME, RUNTIME_ALPHA>(model, counts, temp_mc),
            (6, false) => self.run::<6, false, RUNTIME, RUNTIME_ALPHA>(model, counts, temp_mc),
            _ => self.run::<0, false, RUNTIME, RUNTIME_ALPHA>(model, counts, temp_mc),
        }
    }

    fn mount(&mut self, model: &Model<F32>) {
        if !self.on {
            return;
        }
        let last = self.n.clamp(1, MAX_JOINTS) - 1;
        let (jm, j) = (&model.joints[last], &mut self.joints[last]);
        // Without thermal expansion the model's rate is zero, as the lean form wants it.
        (j.link, j.rate) = (jm.link, jm.link_rate);
        self.probe_dir = model.probe_dir;
    }
}

/// Runs `$body` for every joint `$i`, base to tip (`$rev` false) or tip to base: written out
/// joint by joint where the count is a constant 6 (`$joints`; the compiler did not unroll the
/// loop by itself, nor inline a closure called six times, and each joint so reads its
/// constants at fixed offsets with no loop counter), else looped over `$n`. A `return` in the
/// body returns from the enclosing function.
macro_rules! each_joint {
    ($joints:expr, $n:expr, $rev:expr, |$i:ident| $body:block) => {
        if $joints == 6 {
            {
                let $i = if $rev { 5 } else { 0 };
                $body
            }
            {
                let $i = if $rev { 4 } else { 1 };
                $body
            }
            {
                let $i = if $rev { 3 } else { 2 };
                $body
            }
            {
                let $i = if $rev { 2 } else { 3 };
                $body
            }
            {
                let $i = if $rev { 1 } else { 4 };
                $body
            }
            {
                let $i = if $rev { 0 } else { 5 };
                $body
            }
        } else {
            for k in 0..$n {
                let $i = if $rev { $n - 1 - k } else { k };
                $body
            }
        }
    };
}

/// The joints written out or looped, for the wobble's pass ([`crate::lean_wobble`]) too.
#[cfg(feature = "wobble")]
pub(crate) use each_joint;

impl LeanF32 {
    /// [`LeanForm::eval`] for `JOINTS` joints (0: as many as `counts` has); `POW2`: every
    /// joint's scale is a power of two; `GRAVITY`: the compliant joints where they are this
    /// set (bit i for the joint numbered i + 1), [`RUNTIME`] to read each joint's flag;
    /// `ALPHA`: the quarter turns of the joints' Rx(α) (two bits a joint,
    /// [`LeanF32::alpha_quarters`]) where they are these, [`RUNTIME_ALPHA`] to multiply by
    /// the stored c₀ and s₀.
    #[inline(always)]
    fn run<const JOINTS: usize, const POW2: bool, const GRAVITY: u8, const ALPHA: u16>(
        &self,
        model: &Model<F32>,
        counts: &[u32],
        temp_mc: i32,
    ) -> Result<Point<F32>, ChainError> {
        let dt = model.check(counts, temp_mc)?;
        let n = if JOINTS > 0 { JOINTS } else { counts.len() }.min(MAX_JOINTS);
        let mut angles = [const { MaybeUninit::<Angle>::uninit() }; MAX_JOINTS];
        let mut verticals = [const { MaybeUninit::<[f32; 2]>::uninit() }; MAX_JOINTS];
        // Base to tip: the angles, and the vertical up to the last compliant joint.
        let mut zb = [0.0f32, 0.0, 1.0];
        each_joint!(JOINTS, n, false, |i| {
            let j = &self.joints[i];
            let (a, c, s) = j.reading::<POW2>(i, counts[i])?;
            let e = j.harmonic_error(c, s);
            let compliant = if GRAVITY == RUNTIME {
                j.has_gravity
            } else {
                GRAVITY & (1 << i) != 0
            };
            angles[i].write(if compliant {
                // Gravity's deflection joins e in the second pass, which turns the remainder.
                Angle { e, ..a }
            } else {
                // The whole error is known here: the remainder turned now, with the numbers
                // the second pass would give (the same operations on the same values), so
                // that e is neither kept nor read back.
                let (sin, omc) = turned(a.sin, a.omc, e);
                Angle {
                    sin,
                    omc,
                    e: 0.0,
                    ..a
                }
            });
            let vertical = if GRAVITY == RUNTIME {
                i < self.vertical_joints
            } else {
                i < (8 - GRAVITY.leading_zeros()) as usize
            };
            if vertical {
                zb = j.turn_vertical(i == 0, c, s, zb);
                // Written for every joint up to the last compliant one (read only where
                // compliant): a store is cheaper than testing the flag.
                verticals[i].write([zb[0], zb[1]]);
            }
        });

        // Tip to base.
        let mut w = [0.0f32; 3];
        let mut d = self.probe_dir;
        each_joint!(JOINTS, n, true, |i| {
            let j = &self.joints[i];
            // SAFETY: the first pass wrote every angle below n (it returns early only with an
            // error, before this pass).
            let a = unsafe { angles[i].assume_init_read() };
            // The link at temperature (a zero rate without thermal expansion: the link itself).
            // (Written out: `map` over the three became a call once the joints were unrolled.)
            let link = j.link_at(dt);
            w = if i + 1 == n {
                // The tip's link: 0 + link, without the additions.
                link
            } else {
                [w[0] + link[0], w[1] + link[1], w[2] + link[2]]
            };
            let compliant = if GRAVITY == RUNTIME {
                j.has_gravity
            } else {
                GRAVITY & (1 << i) != 0
            };
            let (sin, omc) = if compliant {
                // SAFETY: the first pass wrote the vertical of every joint up to the last
                // compliant one.
                let v = unsafe { verticals[i].assume_init_read() };
                let e = a.e + j.gravity * (w[0] * v[1] - w[1] * v[0]);
                // The remainder turned by the harmonic error and the deflection together.
                turned(a.sin, a.omc, e)
            } else {
                // Turned by the first pass.
                (a.sin, a.omc)
            };
            // Rz(θ'): the quarter turns, the turned remainder as a correction.
            (w, d) = turn_z(a.q, sin, omc, w, d);
            // Rx(α): the tip by a quarter turn and a correction (chosen at boot), the
            // direction plainly.
            let (y, z) = if ALPHA == RUNTIME_ALPHA {
                j.alpha.turn((w[1], w[2]))
            } else {
                j.alpha
                    .turn_known(((ALPHA >> (2 * i)) & 3) as u8, (w[1], w[2]))
            };
            w = [w[0], y, z];
            d = rx_dir(j.alpha_whole, d);
        });
        // Rz(a_1).
        (w, d) = self.rz_base(w, d);
        Ok(Point { xyz: w, dir: d })
    }
}

// The per-joint steps of the pass, by name: this module's pass and the wobble's
// ([`crate::lean_wobble`]) are both written with them.

impl LeanF32 {
    /// Rz(a_1), the last turn of both passes: the tip by its quarter turn chosen at boot and
    /// the correction, the direction plainly by cos a_1, sin a_1 whole.
    #[inline(always)]
    pub(crate) fn rz_base(&self, w: [f32; 3], d: [f32; 3]) -> ([f32; 3], [f32; 3]) {
        let (x, y) = self.base.turn((w[0], w[1]));
        let [cb, sb] = self.base_whole;
        (
            [x, y, w[2]],
            [cb * d[0] - sb * d[1], sb * d[0] + cb * d[1], d[2]],
        )
    }
}

impl LeanJoint {
    /// The reading's angle θ' = θ + offset as a quarter turn and a remainder (`e` zero), and
    /// its cos and sin whole; a count past the scale is refused, naming joint `i + 1`.
    /// `POW2`: the scale is a power of two ([`LeanJoint::unit`]).
    #[inline(always)]
    pub(crate) fn reading<const POW2: bool>(
        &self,
        i: usize,
        count: u32,
    ) -> Result<(Angle, f32, f32), ChainError> {
        if count >= self.scale.counts() {
            return Err(ChainError::CountOutOfRange { joint: i as u8 + 1 });
        }
        let t = if POW2 {
            count.wrapping_mul(self.unit)
        } else {
            self.scale.binary(count)
        };
        let (q, sin, omc) = remainder(t.wrapping_add(self.offset));
        // Its cos and sin whole by the quarter turns, the turn 0 in a block of its own, each
        // arm forming its 1 − omc (with 1 − omc formed once before the jump the compiler's
        // choices gave the lean chain 3 instructions a point fewer, the wobble's 7 more).
        let (c, s) = match q & 3 {
            0 => {
                own_block();
                (1.0 - omc, sin)
            }
            1 => (-sin, 1.0 - omc),
            2 => (-(1.0 - omc), -sin),
            _ => (sin, -(1.0 - omc)),
        };
        let angle = Angle {
            q,
            sin,
            omc,
            e: 0.0,
        };
        Ok((angle, c, s))
    }

    /// The harmonic error at θ' (cos `c`, sin `s`); zero coefficients (a joint without
    /// harmonics) give ±0.
    #[inline(always)]
    pub(crate) fn harmonic_error(&self, c: f32, s: f32) -> f32 {
        let [s1, c1, s2, c2] = self.harmonics;
        s * (s1 + c * s2 - s * c2) + c * (c1 + c * c2)
    }

    /// The vertical `zb` (the base frame's ẑ in the frame before this joint; (0, 0, 1) where
    /// `base`) in the frame after it: Rx(−α), then Rz(−θ') (cos `c`, sin `s`) without the
    /// harmonic error e — and, in the wobble's pass ([`crate::lean_wobble`]), without the small
    /// turns of the wobble. The vertical is then off by at most Σ|e| (5.4e-4 rad on
    /// default-6-full), and Σ|φ| with the wobble, about the joints' axes, which moves each
    /// deflection g (w × ẑ_base)·ẑ_k of up to 5e-5 rad by at most 3e-8 rad (Σ|e|; twice that
    /// with a wobble as large as the harmonics: docs/results/speed.md, "The lean chain from
    /// 835" and "The wobble from 1.76×").
    #[inline(always)]
    pub(crate) fn turn_vertical(&self, base: bool, c: f32, s: f32, zb: [f32; 3]) -> [f32; 3] {
        let [ca, sa] = self.alpha_whole;
        if base {
            // The base frame's vertical is (0, 0, 1) itself: the same numbers without the
            // products by 0 and 1 (the compiler may not drop those in floating point).
            [s * sa, c * sa, ca]
        } else {
            let (y, z) = (ca * zb[1] + sa * zb[2], ca * zb[2] - sa * zb[1]);
            [c * zb[0] + s * y, c * y - s * zb[0], z]
        }
    }

    /// The link at temperature (a zero rate without thermal expansion: the link itself).
    /// (Written out: `map` over the three became a call once the joints were unrolled.)
    #[inline(always)]
    pub(crate) fn link_at(&self, dt: f32) -> [f32; 3] {
        let (v, r) = (&self.link, &self.rate);
        [v[0] + r[0] * dt, v[1] + r[1] * dt, v[2] + r[2] * dt]
    }
}

/// Minimax sin r − r = r³ (S₁ + r² (S₂ + r² S₃)) on |r| ≤ π/4, fitted with the coefficients
/// rounded to f32: absolute error 2.3e-9 (of f32's rounding of sin r, up to 3e-8).
const SIN_R: [f32; 3] = [-0.166_666_51, 0.008_331_979, -0.000_194_956_46];
/// Minimax 1 − cos r = r² (C₀ + r² (C₁ + r² (C₂ + r² C₃))) on |r| ≤ π/4, likewise: absolute
/// error 1.7e-9.
const OMC_R: [f32; 4] = [0.5, -0.041_666_623, 0.001_388_676_3, -2.439_040_3e-5];

/// A binary angle t (one turn = 2^32) as q quarter turns and a remainder r, |r| ≤ π/4: q,
/// sin r and 1 − cos r, each from its own polynomial in r. The chain's turns want these two
/// (a quarter turn and a correction); [`crate::angle::Quarter`] takes them from the half
/// angle's sine and cosine (both its chains want the half angle), which costs a multiply–add
/// more each and the doubling's four operations: 17 floating-point operations a joint here
/// become 15, for errors of 2e-9, far under f32's rounding of the results.
#[inline(always)]
pub(crate) fn remainder(t: u32) -> (u8, f32, f32) {
    /// π / 2^31: the remainder's binary angle in radians.
    const K: f32 = (core::f64::consts::PI / 2_147_483_648.0) as f32;
    let q = t.wrapping_add(1 << 29) >> 30;
    // |r| ≤ 2^29; as f32 a relative error of at most 6e-8 (none for a 2^20-count encoder).
    let r = t.wrapping_sub(q << 30) as i32;
    let x = r as f32 * K;
    let z = x * x;
    let [s1, s2, s3] = SIN_R;
    let [c0, c1, c2, c3] = OMC_R;
    let sin = x + x * z * (s1 + z * (s2 + z * s3));
    let omc = z * (c0 + z * (c1 + z * (c2 + z * c3)));
    (q as u8, sin, omc)
}

/// A remainder's sin r and 1 − cos r turned by a small angle e, to second order (|e| ≤ 1e-3:
/// error e³/6 < 2e-10).
#[inline(always)]
pub(crate) fn turned(sin: f32, omc: f32, e: f32) -> (f32, f32) {
    turned_cos(sin, omc, 1.0 - omc, e)
}

/// [`turned`] with cos r = 1 − omc already formed (a constant remainder's, stored).
#[inline(always)]
pub(crate) fn turned_cos(sin: f32, omc: f32, c: f32, e: f32) -> (f32, f32) {
    let h = 0.5 * (e * e);
    (sin + (c * e - sin * h), omc + (sin * e + c * h))
}

/// Rz by q quarter turns and a remainder: the tip `w` as a correction, the direction `d`
/// plainly (cos r = 1 − omc).
#[inline(always)]
pub(crate) fn turn_z(q: u8, sin: f32, omc: f32, w: [f32; 3], d: [f32; 3]) -> ([f32; 3], [f32; 3]) {
    let cos = 1.0 - omc;
    let (p, r) = quarter_turns(q, (w[0], w[1]));
    let w = [p - (r * sin + p * omc), r + (p * sin - r * omc), w[2]];
    let (p, r) = quarter_turns(q, (d[0], d[1]));
    let d = [p * cos - r * sin, p * sin + r * cos, d[2]];
    (w, d)
}

/// Nothing (an empty `asm!`, no instruction): a match arm that only passes its values on
/// (the quarter turn 0) gets a block of its own, where the compiler places the register
/// copies that join it to the other arms. Without it those copies stood before the jump and
/// ran on every quarter turn, the other arms overwriting them (docs/results/speed.md, "The
/// wobble, round 2": the M4F hub's lean chain 790 → 777 instructions a point with the
/// reading's selection apart, the wobble's second pass 4 a joint fewer).
#[inline(always)]
pub(crate) fn own_block() {
    // SAFETY: an empty template: no instruction, no operand, no memory, stack or flags.
    unsafe { core::arch::asm!("", options(nomem, nostack, preserves_flags)) };
}

/// Rx(α) of the direction, plainly by cos α and sin α whole.
#[inline(always)]
pub(crate) fn rx_dir([ca, sa]: [f32; 2], d: [f32; 3]) -> [f32; 3] {
    [d[0], ca * d[1] - sa * d[2], sa * d[1] + ca * d[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The copies of the lean pass (six joints written out with power-of-two scales, with
    /// the compliant set and then also the quarter turns of α constants, six written out
    /// with any scale, looped) give the same numbers bit for bit, and agree
    /// with the quaternion chain to f32's rounding (under 1 µm, 2e-6 on the direction) — a
    /// joint without harmonics or thermal expansion (zeros stored, no flag) included; a count
    /// out of range is refused by each, naming its joint.
    #[test]
    fn the_copies_agree() {
        use crate::chain::Chain;
        use crate::table::{tests::sample, FLAG_GEOMETRIC, MAX_TABLE_LEN};
        let mut data = sample();
        data.joints[2].harmonic_count = 0;
        data.joints[2].harmonics = Default::default();
        data.joints[2].thermal = 0.0;
        // First-order gravity (the sample's 3e-8 on three hinges reaches the second order).
        for j in data.joints.iter_mut().filter(|j| j.gravity != 0.0) {
            j.gravity = 1e-8;
        }
        data.flags = data.content_flags() | FLAG_GEOMETRIC;
        let mut buf = [0u8; MAX_TABLE_LEN];
        let len = data.encode(&mut buf).unwrap();
        let table = Table::parse(&buf[..len]).unwrap();
        let model = Model::<F32>::new(&table).unwrap();
        let lean = *LeanF32::build_in(&mut MaybeUninit::uninit(), &table, &model, true).unwrap();
        assert!(lean.on && lean.pow2);
        assert_eq!(lean.gravity_mask, HINGES);
        let quat = Chain::<F32>::new(&table).unwrap();
        let bits = |p: &Point<F32>| (p.xyz.map(f32::to_bits), p.dir.map(f32::to_bits));
        for k in 0..60u32 {
            let counts: [u32; 6] =
                core::array::from_fn(|j| (k * 77_773 + j as u32 * 191_111) % (1 << 20));
            let temp = 10_000 + 400 * k as i32;
            let a = lean
                .run::<6, true, RUNTIME, RUNTIME_ALPHA>(&model, &counts, temp)
                .unwrap();
            let b = lean
                .run::<6, false, RUNTIME, RUNTIME_ALPHA>(&model, &counts, temp)
                .unwrap();
            let c = lean
                .run::<0, false, RUNTIME, RUNTIME_ALPHA>(&model, &counts, temp)
                .unwrap();
            // The compliant set as a constant (the sample's are the hinges), and the quarter
            // turns of α as constants (the sample's own).
            let v = lean
                .run::<6, true, HINGES, RUNTIME_ALPHA>(&model, &counts, temp)
                .unwrap();
            assert_eq!(bits(&a), bits(&v), "{counts:?}");
            let k = match lean.alpha_quarters {
                PERPENDICULAR => lean.run::<6, true, HINGES, PERPENDICULAR>(&model, &counts, temp),
                q => panic!("the sample's quarter turns {q:#b}: add their copy to the test"),
            };
            assert_eq!(bits(&a), bits(&k.unwrap()), "{counts:?}");
            assert_eq!(bits(&a), bits(&b), "{counts:?}");
            assert_eq!(bits(&a), bits(&c), "{counts:?}");
            let q = quat.eval_quaternion(&counts, temp).unwrap();
            let (pa, pq) = (a.xyz_nm(), q.xyz_nm());
            let (da, dq) = (a.dir_e9(), q.dir_e9());
            for m in 0..3 {
                assert!((pa[m] - pq[m]).abs() < 1_000, "{counts:?}: {pa:?} {pq:?}");
                assert!((da[m] - dq[m]).abs() < 2_000, "{counts:?}: {da:?} {dq:?}");
            }
        }
        let mut counts = [5u32; 6];
        counts[3] = 1 << 20;
        let want = Err(ChainError::CountOutOfRange { joint: 4 });
        assert_eq!(
            lean.run::<6, true, RUNTIME, RUNTIME_ALPHA>(&model, &counts, 20_000)
                .map(|_| ()),
            want
        );
        assert_eq!(
            lean.run::<6, false, RUNTIME, RUNTIME_ALPHA>(&model, &counts, 20_000)
                .map(|_| ()),
            want
        );
        assert_eq!(
            lean.run::<0, false, RUNTIME, RUNTIME_ALPHA>(&model, &counts, 20_000)
                .map(|_| ()),
            want
        );
        assert_eq!(
            lean.run::<6, true, HINGES, PERPENDICULAR>(&model, &counts, 20_000)
                .map(|_| ()),
            want
        );
    }

    /// The per-point remainder: q and r as the binary angle has them, sin r and 1 − cos r
    /// within f32's rounding (an ulp of the result and the polynomials' 2e-9) of f64's, over
    /// the whole turn and at the quarter turns' edges.
    #[test]
    fn remainder_matches_f64() {
        let mut t = 0u32;
        let mut worst = [0.0f64; 2];
        for k in 0..200_000u32 {
            t = t.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let t = match k % 4 {
                0 => t,
                // The quarter turns' edges (r = ±π/4).
                1 => (t & 0xc000_0000).wrapping_add(1 << 29),
                2 => (t & 0xc000_0000).wrapping_add((1 << 29) - 1),
                _ => (t & 0xffff_f000) | 0x1ff,
            };
            let (q, sin, omc) = remainder(t);
            let (want_q, _, _) = split_turn(t);
            assert_eq!(q, want_q, "{t:#x}");
            let ri = t.wrapping_sub(u32::from(q) << 30) as i32;
            let exact = f64::from(ri) * (core::f64::consts::PI / 2_147_483_648.0);
            assert!(
                exact.abs() <= core::f64::consts::FRAC_PI_4 + 1e-12,
                "{t:#x}"
            );
            // The angle as the f32 path has it (r to f32, scaled by π/2^31 in f32: at most
            // three roundings, 2e-7 relative): the test bounds the polynomials and their
            // rounding, not the input's.
            let r = f64::from(ri as f32 * (core::f64::consts::PI / 2_147_483_648.0) as f32);
            assert!((r - exact).abs() <= 2e-7 * exact.abs(), "{t:#x}");
            let es = (f64::from(sin) - r.sin()).abs();
            let eo = (f64::from(omc) - (1.0 - r.cos())).abs();
            worst = [worst[0].max(es), worst[1].max(eo)];
        }
        // An ulp at 0.71 is 6e-8, at 0.29 3e-8: at most about an ulp and a half each.
        assert!(worst[0] < 9e-8 && worst[1] < 5e-8, "{worst:?}");
        assert!(worst[0] > 0.0 && worst[1] > 0.0);
    }

    /// The boot's angles: a binary angle comes back from its own cosine and sine, and the
    /// z-x-z split reproduces the matrix it came from.
    #[test]
    fn binary_angles_and_euler_split() {
        for t in [
            0u32,
            1,
            12_345,
            1 << 29,
            (1 << 30) + 7,
            3 << 30,
            u32::MAX,
            0x9e37_79b9,
        ] {
            let (c, s) = turn_cos_sin(t);
            assert!(((c * c + s * s) - 1.0).abs() < 1e-15);
            assert_eq!(binary_angle(c, s), t, "{t}");
        }
        let m = mat_mul(
            &mat_mul(&rz(0x1234_5678), &rx(0x3fff_0000)),
            &rz(0xdead_beef),
        );
        let [a, al, b] = euler_zxz(&m);
        let back = mat_mul(&mat_mul(&rz(a), &rx(al)), &rz(b));
        for r in 0..3 {
            for c in 0..3 {
                assert!((back[r][c] - m[r][c]).abs() < 1e-8, "{r} {c}");
            }
        }
        // Degenerate: no turn about x at all.
        let m = rz(0x4000_1234);
        let [a, al, b] = euler_zxz(&m);
        assert_eq!(al, 0);
        assert!(a.wrapping_add(b).abs_diff(0x4000_1234) <= 1);
    }
}
