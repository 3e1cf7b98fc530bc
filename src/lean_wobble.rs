//! The lean f32 chain with an axis wobble: the same calibrated model as
//! [`crate::chain::Chain::eval_quaternion`] with its wobble ([`crate::wobble`]), in the lean
//! form of [`crate::lean`], which the hub runs instead of the quaternion chain for an arm whose
//! joints wobble (behind the `wobble` feature: without it this module is empty and a table with
//! the block is refused).
//!
//! **The form.** Joint i's varied rotation in its z-axis frame is M̃_i W(φ_i) Rz(θ_i), with
//! M̃_i = Rz(a_i) Rx(α_i) Rz(b_i) split at boot ([`crate::lean`]) and W(φ) the wobble's small
//! turn about the rotation vector φ = A f1 + B f2 + ½ A B f1 × f2 ([`crate::wobble`]). Rz(b_i)
//! moves through W (Rz(b) W(φ) = W(Rz(b) φ) Rz(b)), so the lean form's count offset stays as it
//! is and the wobble's axes are turned by Rz(b_i) at boot; its harmonics, of the raw reading
//! like the encoder's, take coefficients rotated by the offset (exact identities, in f64 at
//! boot). What is left per point is a small turn between Rx(α_i) and Rz(θ'_i), which the pass
//! splits, to second order, into turns about the axes it already has:
//!
//! W(φ) = Rx(φx) Ry(φy) Rz(φz − ½ φx φy) + O(|φ|³)
//!
//! (Baker–Campbell–Hausdorff: Rx(a) Ry(b) = exp(a x̂ + b ŷ + ½ a b ẑ) to second order). So
//! φz − ½ φx φy joins the joint's harmonic error (the remainder is already turned by it, to
//! second order), φx joins α (Rx(α + φx): the tip's correction turned by φx) and only Ry(φy)
//! is a turn of its own, applied to the tip to second order, its corrections joined to the
//! sums Rz and Rx already round (`turn_tip`: each large coordinate rounded as often as in the
//! lean pass). The direction takes Rx(φx) Ry(φy) to first order where a boot bound on ½ Σ
//! |φ|² allows ([`MAX_DIRECTION_SECOND_ORDER`]), else Ry and cos α, sin α turned by φx to
//! second order. α's remainder r beside its quarter turns (a joint's tilt off its nominal
//! axis: at most 2.6e-3 rad on the hubs' arm) and φx are one small angle ρ = r + φx where
//! every joint's |r| plus its bound on |φx| is within [`MAX_RHO`] (a boot gate,
//! `LeanWobble::rho`): sin ρ and 1 − cos ρ from ρ itself (`small_turn`; r stored in f32,
//! formed in f64 at boot), in every copy of the pass; else the stored sin r, 1 − cos r turned
//! by φx to second order. With ρ, the direction's first-order turns are Ry(φy) alone, then
//! Rx(α + φx) as the tip's, by α's quarter turns and ρ (cos ρ = 1 − (1 − cos ρ)), instead of
//! d + (φx, φy, 0) × d and cos α, sin α whole (½ φy² left out where ½ (φx² + φy²) was).
//! The vertical of the first pass leaves the small turns out, as it leaves out the harmonic
//! error ([`crate::lean`]): it scales the gravity deflection only (Σ|φ| ≈ 6e-4 rad of
//! 4e-5 rad, at most 3e-8 rad).
//!
//! **What φ costs.** φx and φy are harmonic series in θ' (the terms' sin hθ', cos hθ' by
//! `angle::Multiples` from the pass's own cos θ', sin θ'), each term's four coefficients formed at
//! boot. The second pass (tip to base) forms them: its one selection by θ''s quarter turns
//! gives cos θ', sin θ' beside Rz's quarter turns of the tip and the direction, so nothing of
//! the wobble is stored between the passes. φz needs no series of its own: (φx, φy) =
//! A (f1x, f1y) + B (f2x, f2y) to first order
//! (f1 and f2 turned by Rz(b_i), whose z parts are of the size of the joint's tilt only), so A
//! and B are a fixed linear map of φx, φy, and φz − ½ φx φy = A f1z + B f2z + ½ A B (f1 × f2)·ẑ
//! − ½ φx φy is a linear and a quadratic form in φx, φy, five constants a joint.
//!
//! **Left out**, each third order: the x and y parts of ½ A B f1 × f2 (the tilt times A B),
//! f1's and f2's z parts inside A and B (the tilt times |φ|), the commutator of φz's first-order
//! part with φx, φy (½ |φz| |φ|), and the turns' own third-order terms (|φ|³/6). With the
//! table's |A| + |B| ≤ 1e-3 ([`crate::table::limits::HARMONIC_SUM`]) and the axes' z parts at
//! most [`MAX_AXIS_Z`] (else the quaternion chain runs), each is under 5e-9 rad, 10 nm on a 2 m
//! lever; a real wobble (≤ 1e-4) leaves under 1e-11 rad.
//!
//! The pass is written with the lean form's per-joint steps, by their names
//! ([`crate::lean`]): the reading, the harmonic error, the link, the remainder turned, Rz and
//! Rx; no fused multiply-add, so the host's numbers are the hub's bit for bit.

#[cfg(feature = "wobble")]
use crate::angle::quarter_turns;
#[cfg(feature = "wobble")]
use crate::angle::Multiples;
use crate::lean::LeanF32;
#[cfg(feature = "wobble")]
use crate::lean::{
    each_joint, own_block, rx_dir, turned, turned_cos, Angle, HINGES, PERPENDICULAR, RUNTIME,
    RUNTIME_ALPHA,
};
use crate::model::{ChainError, Model, Point};
use crate::scalar::F32;
use crate::table::Table;
#[cfg(feature = "wobble")]
use crate::table::{wobble::MAX_TERMS, MAX_JOINTS};
#[cfg(feature = "wobble")]
use core::mem::MaybeUninit;

/// Largest z part (|f1·ẑ| + |f2·ẑ|, in the joint's z-axis frame) of a wobbling joint's two
/// axes that the form takes: a bearing's tilt of a few mrad; the terms it leaves out grow
/// with it (module docs). An arm past it runs the quaternion chain.
pub const MAX_AXIS_Z: f64 = 0.01;

/// One wobble term: the (sin hθ', cos hθ') coefficients of φx and φy.
#[cfg(feature = "wobble")]
#[derive(Clone, Copy, Debug, Default)]
struct Term {
    order: u32,
    x: [f32; 2],
    y: [f32; 2],
}

/// Most wobble terms of all joints together the form keeps (the table allows
/// [`crate::table::wobble::MAX_TERMS`] a joint, 28 for seven joints). Each joint has fixed
/// room for the table's four (no start to read per point): 560 bytes of terms where a pool of
/// 19 took 380. That was too much for the stack while the boot held copies of the chain (the
/// qemu-m4f hub's peak went to 64,732 of its 65,536 bytes, measured); since issue 32 the boot
/// builds the chain in place and the peak stays far below it (docs/results/speed.md). The
/// bound is kept, as it decides which arms run the lean form: an arm with more runs the
/// quaternion chain.
pub const MAX_LEAN_TERMS: usize = 16;

/// One joint's wobble in the lean form (no terms where it has none).
#[cfg(feature = "wobble")]
#[derive(Clone, Copy, Debug, Default)]
struct WobbleJoint {
    /// Its terms, the first `count` of `terms`, sorted by order ([`Multiples`] only
    /// advances); the rest zero.
    count: u8,
    /// For the six-axis copy (its terms' orders each one of 1 to 4, no two the same): bit
    /// h − 1 for order h ([`small_series`]; none where it does not wobble).
    orders: Orders,
    /// φz − ½ φx φy as φx (l_x + q_xx φx + q_xy φy) + φy (l_y + q_yy φy): (l_x, l_y, q_xx,
    /// q_xy, q_yy).
    z: [f32; 5],
    /// α's remainder r (|r| ≤ π/4 beside its quarter turns, `LeanJoint::alpha_turn`), rad,
    /// rounded to f32 from f64 at boot: where [`LeanWobble::rho`], the pass turns it by φx
    /// as one small angle ρ = r + φx ([`small_turn`]). Every joint's, wobbling or not.
    alpha: f32,
    /// Room for the table's most terms a joint: the six-axis copy reads them at offsets
    /// known to the compiler.
    terms: [Term; MAX_TERMS],
}

/// The wobble's constants of an arm's lean form (empty without the `wobble` feature).
#[derive(Clone, Copy, Debug, Default)]
pub struct LeanWobble {
    #[cfg(feature = "wobble")]
    on: bool,
    /// Every wobbling joint's terms have distinct orders of 1 to 4 (the bearings' first
    /// harmonics): the six-axis copy forms each order's multiple without `Multiples`' loop.
    #[cfg(feature = "wobble")]
    small: bool,
    #[cfg(feature = "wobble")]
    joints: [WobbleJoint; MAX_JOINTS],
    /// ½ Σ |φ|² over the joints is at most [`MAX_DIRECTION_SECOND_ORDER`] (bounded by the terms'
    /// coefficients): the direction takes the small turns Rx(φx) Ry(φy) to first order.
    #[cfg(feature = "wobble")]
    dir_first: bool,
    /// Every joint's |r| (α's remainder) plus its bound on |φx| (the sum of its terms' φx
    /// coefficients) is at most [`MAX_RHO`]: the pass forms sin and 1 − cos of ρ = r + φx
    /// from ρ itself ([`small_turn`]) instead of turning the stored sin r, 1 − cos r by φx.
    #[cfg(feature = "wobble")]
    rho: bool,
    /// The z forms of [`Z_HUB`] (the hinges' φz − ½ φx φy as φx l_x, the swivels' after
    /// the base as φy (l_y − φx)) leave out at most [`MAX_Z_SECOND_ORDER`] over the joints
    /// (bounded by the terms' coefficients at boot): the six-axis copy takes them.
    #[cfg(feature = "wobble")]
    z_hub: bool,
}

/// A joint's φz − ½ φx φy in the six-axis copy, two bits a joint (joint i + 1 at bits 2i):
/// 0 whole (φx (l_x + q_xx φx + q_xy φy) + φy (l_y + q_yy φy)), 1 across (l_x, q_xx, q_yy
/// taken as 0 and q_xy as −1: φy (l_y − φx)), 2 along (l_y and the q taken as 0: φx l_x).
#[cfg(feature = "wobble")]
const Z_CROSS: u8 = 1;
#[cfg(feature = "wobble")]
const Z_LINEAR: u8 = 2;

/// The z forms of the hubs' arm ([`crate::lean::HINGES`], [`crate::lean::PERPENDICULAR`]):
/// the hinges' (joints 2, 4, 6) along, the swivels' 3 and 5 across, the base's whole. On
/// that arm the wobble's axes lie along the lean frame's x and y at the hinges (q up to
/// 2.6e-6, l_y up to 1.2e-8) and across them at the swivels (q_xy = −1 in f32, q_xx and q_yy
/// 2e-10, l_x 1e-12), but not quite at the base (q_xx 0.045, l_y 1.1e-3).
#[cfg(feature = "wobble")]
const Z_HUB: u16 = 0b10_01_10_01_10_00;

/// Joint `i`'s z form in the forms `z` (two bits a joint; 0, whole, past the seventh).
#[cfg(feature = "wobble")]
#[inline(always)]
const fn z_form(z: u16, i: usize) -> u8 {
    if i < 8 {
        (z >> (2 * i)) as u8 & 3
    } else {
        0
    }
}

/// Largest bound on the angle about the joints' axes that the z forms of `Z_HUB` leave
/// out (Σ over the joints of each dropped |q| or |l| (and |q_xy + 1| across) times the
/// bounds on |φx|, |φy| it multiplies, each the sum of the joint's terms' coefficients):
/// 1e-10 rad, 0.2 nm on a 2 m lever (f32 rounds the tip to 0.06 µm at 1.5 m). The hubs'
/// arm (`data/default-6-wobble.toml`): 2.3e-12 (3.7e-12 with its wobble × 1.6).
#[cfg(feature = "wobble")]
pub const MAX_Z_SECOND_ORDER: f64 = 1e-10;

/// Largest |ρ| = |r + φx| (α's remainder turned by the wobble, bounded at boot by |r| plus
/// the sum of the joint's φx coefficients) for which the pass takes sin ρ ≈ ρ − ρ³/6 and
/// 1 − cos ρ ≈ ½ ρ² (`small_turn`): the terms left out, ρ⁵/120 and ρ⁴/24, are at most
/// 8.4e-13 and 4.2e-10 rad there, under 1 nm a joint on a 2 m lever and 2.5e-9 on the
/// direction over six joints, far under f32's roundings of the tip (0.06 µm an ulp at
/// 1.5 m). The hubs' arm (`data/default-6-wobble.toml`) is bounded by 2.74e-3 (|r| up to
/// 2.60e-3, |φx| up to 1.6e-4); the table's wobble (Σ |coefficients| ≤ 1e-3 a joint, its
/// bound on |φx| then at most √2 × 1e-3: the offset's rotation of each coefficient pair)
/// cannot take an arm past the gate unless its |r| is past 8.5e-3, and an arm past it keeps
/// the remainder turned by φx.
pub const MAX_RHO: f64 = 0.01;

/// Largest bound on the direction's error from taking each joint's Rx(φx) Ry(φy) to first
/// order (½ Σ |φ|² over the joints, |φ| bounded by the sum of its terms' coefficients at
/// boot): a fifth of the 1e-6 the direction is held to. The default arm's wobble of 1e-4
/// (`data/default-6-wobble.toml`) bounds it by 1.4e-7; the tip keeps the second order.
pub const MAX_DIRECTION_SECOND_ORDER: f64 = 2e-7;

impl LeanWobble {
    /// Fills `self` (all zeros, off) with the wobble of `table`'s arm in the lean form, whose
    /// joints' z-x-z Euler angles are `euler` ([`crate::lean`]): left off where no joint
    /// wobbles; `false` where the form does not take it (an axis's z part past
    /// [`MAX_AXIS_Z`], more than [`MAX_LEAN_TERMS`] terms). In place: a first version that
    /// returned one took the qemu-m4f hub's stack peak from 64,732 to 65,332 bytes.
    pub(crate) fn build_in(
        &mut self,
        table: &Table<'_>,
        euler: &[[u32; 3]],
    ) -> Result<bool, ChainError> {
        #[cfg(feature = "wobble")]
        {
            use crate::lean::{mat_vec, rz, turn_cos_sin};
            use crate::model::{sort_by_order, units, unpermute};
            let n = euler.len();
            let out = self;
            out.small = true;
            out.rho = true;
            let mut taken = 0usize;
            let mut second = 0.0f64;
            // The angle that Z_HUB's forms leave out, bounded.
            let mut dropped = 0.0f64;
            for i in 0..n {
                // α's remainder r, in rad (as the lean form splits α).
                let (_, r) = crate::lean::turn_remainder(euler[i][1]);
                out.joints[i].alpha = r as f32;
                let w = table.joint_wobble(i);
                if w.count == 0 {
                    if r.abs() > MAX_RHO {
                        out.rho = false;
                    }
                    continue;
                }
                let no = i + 1;
                let axis = table
                    .joint(i)
                    .ok_or(ChainError::Range { joint: no as u8 })?
                    .axis;
                // The axes in the joint's z-axis frame, then through Rz(b_i).
                let turn_b = rz(euler[i][2]);
                let f1 = mat_vec(&turn_b, unpermute(w.f1, axis));
                let f2 = mat_vec(&turn_b, unpermute(w.f2, axis));
                if f1[2].abs() + f2[2].abs() > MAX_AXIS_Z {
                    return Ok(false);
                }
                let next = if i + 1 < n { euler[i + 1][0] } else { 0 };
                let offset = euler[i][2].wrapping_add(next);
                let used = usize::from(w.count).min(MAX_TERMS);
                if taken + used > MAX_LEAN_TERMS {
                    return Ok(false);
                }
                let jw = &mut out.joints[i];
                let terms = &mut jw.terms[..used];
                for (t, src) in terms.iter_mut().zip(&w.terms[..used]) {
                    let order = u32::from(src.order);
                    // θ = θ' − offset: (s, c) → (s cos hc + c sin hc, c cos hc − s sin hc).
                    let (ch, sh) = turn_cos_sin(offset.wrapping_mul(order));
                    let rot = |[s, c]: [f64; 2]| [s * ch + c * sh, c * ch - s * sh];
                    let (a, b) = (rot(src.alpha), rot(src.beta));
                    let along =
                        |k: usize| [a[0] * f1[k] + b[0] * f2[k], a[1] * f1[k] + b[1] * f2[k]];
                    *t = Term {
                        order,
                        x: units::<F32, 2>(along(0), no)?,
                        y: units::<F32, 2>(along(1), no)?,
                    };
                }
                sort_by_order(terms, |t| t.order);
                let mut orders = 0u8;
                let (mut bx_, mut by_) = (0.0f64, 0.0f64);
                for t in terms.iter() {
                    bx_ += f64::from(t.x[0].abs() + t.x[1].abs());
                    by_ += f64::from(t.y[0].abs() + t.y[1].abs());
                    let bit = 1u8.checked_shl(t.order.wrapping_sub(1)).unwrap_or(0);
                    if !(1..=4).contains(&t.order) || orders & bit != 0 {
                        out.small = false;
                    }
                    orders |= bit;
                }
                second += 0.5 * (bx_ * bx_ + by_ * by_);
                if r.abs() + bx_ > MAX_RHO {
                    out.rho = false;
                }
                (jw.count, jw.orders) = (used as u8, Orders::of(orders));
                taken += used;
                // (A, B) = M⁻¹ (φx, φy), M = [[f1x, f2x], [f1y, f2y]], |det M| ≥ 1 − MAX_AXIS_Z²
                // (unit orthogonal axes): A = ax·φ, B = bx·φ.
                let det = f1[0] * f2[1] - f1[1] * f2[0];
                let (ax, bx) = ([f2[1] / det, -f2[0] / det], [-f1[1] / det, f1[0] / det]);
                // A f1z + B f2z, then ½ A B kz − ½ φx φy, kz = (f1 × f2)·ẑ = det.
                let l = [0, 1].map(|k| ax[k] * f1[2] + bx[k] * f2[2]);
                let h = 0.5 * det;
                let q = [
                    h * ax[0] * bx[0],
                    h * (ax[0] * bx[1] + ax[1] * bx[0]) - 0.5,
                    h * ax[1] * bx[1],
                ];
                let cross = q[0].abs() * bx_ * bx_ + q[2].abs() * by_ * by_;
                dropped += match z_form(Z_HUB, i) {
                    Z_CROSS if i < 6 => cross + (q[1] + 1.0).abs() * bx_ * by_ + l[0].abs() * bx_,
                    Z_LINEAR if i < 6 => cross + q[1].abs() * bx_ * by_ + l[1].abs() * by_,
                    _ => 0.0,
                };
                jw.z = units::<F32, 5>([l[0], l[1], q[0], q[1], q[2]], no)?;
                out.on = true;
            }
            out.dir_first = second <= MAX_DIRECTION_SECOND_ORDER;
            out.z_hub = dropped <= MAX_Z_SECOND_ORDER;
            Ok(true)
        }
        #[cfg(not(feature = "wobble"))]
        {
            let _ = (table, euler);
            Ok(true)
        }
    }

    /// Whether the arm wobbles (this module's pass runs; always `false` without the feature,
    /// at compile time).
    #[inline(always)]
    pub(crate) fn on(&self) -> bool {
        #[cfg(feature = "wobble")]
        {
            self.on
        }
        #[cfg(not(feature = "wobble"))]
        {
            false
        }
    }

    /// Joint `i`'s φx, φy at θ' (cos `c`, sin `s`), and u, v with φz − ½ φx φy = φx u + φy v
    /// (u = l_x + q_xx φx + q_xy φy, v = l_y + q_yy φy: the pass adds φx u and φy v to the
    /// joint's error by multiply–adds); zeros where it does not wobble. `SMALL`: the arm's
    /// orders are [`LeanWobble::small`]'s (each joint's terms by [`small_series`]), else
    /// `Multiples` advances through them.
    #[cfg(feature = "wobble")]
    #[inline(always)]
    fn phi<const SMALL: bool, const Z: u16>(&self, i: usize, c: f32, s: f32) -> [f32; 4] {
        let j = &self.joints[i];
        let (x, y) = if SMALL {
            small_series(j.orders, &j.terms, c, s)
        } else {
            let terms = j.terms.get(..usize::from(j.count)).unwrap_or(&[]);
            let mut m = Multiples::<F32>::new(c, s);
            let (mut x, mut y) = (0.0f32, 0.0f32);
            for t in terms {
                m.advance(t.order);
                x = x + m.s * t.x[0] + m.c * t.x[1];
                y = y + m.s * t.y[0] + m.c * t.y[1];
            }
            (x, y)
        };
        // Each sum from its constant (multiply–adds into the loaded constant, no copies);
        // the form of `Z` (0, whole, for every joint but in the six-axis copy of Z_HUB).
        match z_form(Z, i) {
            Z_LINEAR => [x, y, j.z[0], 0.0],
            Z_CROSS => [x, y, 0.0, j.z[1] - x],
            _ => {
                let [lx, ly, qxx, qxy, qyy] = j.z;
                [x, y, (lx + qxx * x) + qxy * y, ly + qyy * y]
            }
        }
    }
}

/// A set of wobble orders 1 to 4, bit h − 1 for order h: an enum of its sixteen values, so
/// that the jump on it needs neither a mask nor a range test (a `u8` masked to four bits took
/// one instruction a joint more, measured).
#[cfg(feature = "wobble")]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(u8)]
enum Orders {
    #[default]
    O0,
    O1,
    O2,
    O3,
    O4,
    O5,
    O6,
    O7,
    O8,
    O9,
    O10,
    O11,
    O12,
    O13,
    O14,
    O15,
}

#[cfg(feature = "wobble")]
impl Orders {
    /// The set of the low four bits of `bits`.
    fn of(bits: u8) -> Orders {
        use Orders::*;
        const ALL: [Orders; 16] = [
            O0, O1, O2, O3, O4, O5, O6, O7, O8, O9, O10, O11, O12, O13, O14, O15,
        ];
        ALL[usize::from(bits & 15)]
    }
}

/// φx, φy of a joint's terms (sorted by order, the first as many as `orders` has bits, the
/// rest not read) whose orders are `orders` (bit h − 1 for order h ≤ 4): one jump to the code
/// of that set of orders ([`series`]); zeros where it is empty.
#[cfg(feature = "wobble")]
#[inline(always)]
fn small_series(orders: Orders, terms: &[Term; 4], c: f32, s: f32) -> (f32, f32) {
    macro_rules! arms {
        ($($v:ident $m:literal),*) => {
            match orders {
                $(Orders::$v => series::<$m>(c, s, terms),)*
                // (c − c, s − s: +0 for the finite c, s, formed in this arm only; a constant
                // zero was loaded before the jump on every joint.)
                Orders::O0 => (c - c, s - s),
            }
        };
    }
    arms!(
        O1 1, O2 2, O3 3, O4 4, O5 5, O6 6, O7 7, O8 8, O9 9, O10 10, O11 11, O12 12, O13 13,
        O14 14, O15 15
    )
}

/// φx, φy of the terms whose orders are the bits of `M` (bit h − 1 for order h ≤ 4), sorted
/// by order, the first of `t`: only the multiples these orders need, each formed as
/// `Multiples::advance` forms it (order 2 by doubling, 3 by a step from 2, 4 by a step from 3
/// where 3 is a term, else by doubling 2), and the sums as its loop adds them (a multiply–add
/// a product), so that the numbers are the looped copy's bit for bit (but for the sign of a
/// zero sum: the first term is not added to 0) — without its loop, its tests of the order
/// or its branches.
#[cfg(feature = "wobble")]
#[inline(always)]
fn series<const M: u8>(c: f32, s: f32, t: &[Term; 4]) -> (f32, f32) {
    let double = |(c, s): (f32, f32)| {
        let cs = c * s;
        ((c - s) * (c + s), cs + cs)
    };
    let step = |(ch, sh): (f32, f32)| (ch * c - sh * s, sh * c + ch * s);
    let m1 = (c, s);
    let m2 = double(m1);
    let m3 = step(m2);
    let m4 = if M & 4 != 0 { step(m3) } else { double(m2) };
    let m = [m1, m2, m3, m4];
    let (mut x, mut y) = (0.0f32, 0.0f32);
    let mut k = 0;
    for (h, &(mc, ms)) in m.iter().enumerate() {
        if M & (1 << h) != 0 {
            let t = &t[k];
            if k == 0 {
                x = ms * t.x[0] + mc * t.x[1];
                y = ms * t.y[0] + mc * t.y[1];
            } else {
                x = x + ms * t.x[0] + mc * t.x[1];
                y = y + ms * t.y[0] + mc * t.y[1];
            }
            k += 1;
        }
    }
    (x, y)
}

/// The probe-ball centre and direction of `lean`'s arm with its wobble (`lean.wobble`), as
/// [`crate::chain::Chain::eval`]. Out of line: the lean pass without the wobble stays the
/// function it was.
#[inline(never)]
pub(crate) fn eval(
    lean: &LeanF32,
    model: &Model<F32>,
    counts: &[u32],
    temp_mc: i32,
) -> Result<Point<F32>, ChainError> {
    #[cfg(feature = "wobble")]
    {
        // Six joints with power-of-two scales written out (the hubs' arms), any other arm
        // looped, as the lean pass without the wobble.
        // The six-axis arm of the hubs (gravity on the hinges, perpendicular axes, the
        // wobble's orders at most 4, α's remainders within MAX_RHO) with those known to the
        // compiler, as the lean pass's own copy.
        if counts.len() == 6 && lean.pow2 {
            let six_axis = lean.wobble.small
                && lean.wobble.dir_first
                && lean.wobble.rho
                && lean.gravity_mask == HINGES
                && lean.alpha_quarters == PERPENDICULAR;
            if six_axis && lean.wobble.z_hub {
                run::<6, true, HINGES, PERPENDICULAR, true, Z_HUB>(lean, model, counts, temp_mc)
            } else if six_axis {
                // The same arm's shape with its wobble's axes elsewhere in the lean frames
                // (past MAX_Z_SECOND_ORDER): every z form whole, 1,118 instructions a point
                // on qemu-m4f where Z_HUB's take 1,076 (docs/results/speed.md).
                run::<6, true, HINGES, PERPENDICULAR, true, 0>(lean, model, counts, temp_mc)
            } else {
                run::<6, true, RUNTIME, RUNTIME_ALPHA, false, 0>(lean, model, counts, temp_mc)
            }
        } else {
            run::<0, false, RUNTIME, RUNTIME_ALPHA, false, 0>(lean, model, counts, temp_mc)
        }
    }
    #[cfg(not(feature = "wobble"))]
    {
        // Never called: `LeanWobble::on` is false.
        let _ = (lean, model, counts, temp_mc);
        Err(ChainError::Range { joint: 0 })
    }
}

/// [`eval`] for `JOINTS` joints (0: as many as `counts` has); `POW2`: every joint's scale is
/// a power of two; `GRAVITY` and `ALPHA` the compliant joints and the quarter turns of α
/// where known to the compiler, as the lean pass's (`RUNTIME`, `RUNTIME_ALPHA`: read from
/// the joints); `SMALL`: the terms' orders are [`LeanWobble::small`]'s, the direction
/// takes its small turns to first order ([`LeanWobble::dir_first`]) and α's remainder and φx
/// are one angle ([`LeanWobble::rho`]; the other copies read both); `Z`: each joint's form of
/// φz − ½ φx φy ([`Z_HUB`] where [`LeanWobble::z_hub`], else 0: whole).
#[cfg(feature = "wobble")]
#[inline(always)]
fn run<
    const JOINTS: usize,
    const POW2: bool,
    const GRAVITY: u8,
    const ALPHA: u16,
    const SMALL: bool,
    const Z: u16,
>(
    lean: &LeanF32,
    model: &Model<F32>,
    counts: &[u32],
    temp_mc: i32,
) -> Result<Point<F32>, ChainError> {
    let wobble = &lean.wobble;
    let dt = model.check(counts, temp_mc)?;
    let n = if JOINTS > 0 { JOINTS } else { counts.len() }.min(MAX_JOINTS);
    let mut angles = [const { MaybeUninit::<Angle>::uninit() }; MAX_JOINTS];
    let mut verticals = [const { MaybeUninit::<[f32; 2]>::uninit() }; MAX_JOINTS];
    // Base to tip: the angles (the remainder not turned: the second pass forms θ''s cos and
    // sin again from it, for the harmonic error and φ), and the vertical up to the last
    // compliant joint; nothing of the wobble.
    let mut zb = [0.0f32, 0.0, 1.0];
    each_joint!(JOINTS, n, false, |i| {
        let j = &lean.joints[i];
        let (a, c, s) = j.reading::<POW2>(i, counts[i])?;
        angles[i].write(a);
        let vertical = if GRAVITY == RUNTIME {
            i < lean.vertical_joints
        } else {
            i < (8 - GRAVITY.leading_zeros()) as usize
        };
        if vertical {
            // Rx(−α), Rz(−θ'), as the lean pass: without the wobble's small turns or e.
            zb = j.turn_vertical(i == 0, c, s, zb);
            // Written for every joint up to the last compliant one (read only where
            // compliant), as the lean pass does.
            verticals[i].write([zb[0], zb[1]]);
        }
    });

    // Tip to base.
    let mut w = [0.0f32; 3];
    let mut d = lean.probe_dir;
    each_joint!(JOINTS, n, true, |i| {
        let j = &lean.joints[i];
        // SAFETY: the first pass wrote every angle below n (it returns early only with an
        // error, before this pass).
        let a = unsafe { angles[i].assume_init_read() };
        let link = j.link_at(dt);
        w = if i + 1 == n {
            link
        } else {
            [w[0] + link[0], w[1] + link[1], w[2] + link[2]]
        };
        // One selection by θ''s quarter turns: its cos and sin whole (as the first pass's
        // reading formed them), and Rz's quarter turns of the tip and the direction.
        let cr = 1.0 - a.omc;
        let ((c, s), (p, r), (dp, dr)) = match a.q & 3 {
            0 => {
                own_block();
                ((cr, a.sin), (w[0], w[1]), (d[0], d[1]))
            }
            1 => ((-a.sin, cr), (-w[1], w[0]), (-d[1], d[0])),
            2 => ((-cr, -a.sin), (-w[0], -w[1]), (-d[0], -d[1])),
            _ => ((a.sin, -cr), (w[1], -w[0]), (d[1], -d[0])),
        };
        // The harmonic error at θ' (here rather than in the first pass: not stored), and
        // φ: φz − ½ φx φy joins the error.
        let [px, py, u, v] = wobble.phi::<SMALL, Z>(i, c, s);
        let mut e = match z_form(Z, i) {
            Z_LINEAR => j.harmonic_error(c, s) + px * u,
            Z_CROSS => j.harmonic_error(c, s) + py * v,
            _ => (j.harmonic_error(c, s) + px * u) + py * v,
        };
        let compliant = if GRAVITY == RUNTIME {
            j.has_gravity
        } else {
            GRAVITY & (1 << i) != 0
        };
        if compliant {
            // SAFETY: the first pass wrote the vertical of every joint up to the last
            // compliant one.
            let v = unsafe { verticals[i].assume_init_read() };
            e += j.gravity * (w[0] * v[1] - w[1] * v[0]);
        }
        // Rz(θ' + e), e with φz's part; Ry(φy) and Rx(α + φx) (the tip's correction and the
        // direction's cos α, sin α turned by φx), the tip's turns by `turn_tip`.
        let (sin, omc) = turned(a.sin, a.omc, e);
        let al = &j.alpha_turn;
        let (asin, aomc) = if SMALL || wobble.rho {
            small_turn(wobble.joints[i].alpha + px)
        } else {
            turned_cos(al.sin, al.omc, al.cos, px)
        };
        let qa = if ALPHA == RUNTIME_ALPHA {
            al.q
        } else {
            ((ALPHA >> (2 * i)) & 3) as u8
        };
        w = turn_tip((p, r, sin, omc), (py, 0.5 * py), (qa, asin, aomc), w[2]);
        // The direction: Rz plainly (as `turn_z`), then Ry(φy) and Rx(α + φx).
        let cos = 1.0 - omc;
        d = [dp * cos - dr * sin, dp * sin + dr * cos, d[2]];
        let [ca, sa] = j.alpha_whole;
        let first = if SMALL { true } else { wobble.dir_first };
        if first && (SMALL || wobble.rho) {
            // Ry(φy) to first order (within MAX_DIRECTION_SECOND_ORDER), then Rx(α + φx) as
            // its quarter turns and ρ's sin and cos = 1 − (1 − cos), as the tip's. z takes
            // φy times x already turned (d_z − φy d_x − φy² d_z): what it leaves out of Ry's
            // second order is +½ φy² d_z where d_z − φy d_x left out −½ φy² d_z, the same
            // bound, and d_x is not needed beside x (one register copy a joint fewer).
            let x = d[0] + py * d[2];
            let (y, z) = quarter_turns(qa, (d[1], d[2] - py * x));
            let cr = 1.0 - aomc;
            d = [x, y * cr - z * asin, y * asin + z * cr];
        } else if first {
            // Rx(φx) Ry(φy) to first order, d + (φx, φy, 0) × d (within
            // MAX_DIRECTION_SECOND_ORDER), then Rx(α) as the lean pass.
            d = [
                d[0] + py * d[2],
                d[1] - px * d[2],
                d[2] + (px * d[1] - py * d[0]),
            ];
            d = rx_dir([ca, sa], d);
        } else {
            // Ry(φy), and cos α, sin α turned by φx, to second order.
            let h = 0.5 * (py * py);
            d = [
                d[0] + (py * d[2] - h * d[0]),
                d[1],
                d[2] - (py * d[0] + h * d[2]),
            ];
            let h = 0.5 * (px * px);
            d = rx_dir([ca - (sa * px + ca * h), sa + (ca * px - sa * h)], d);
        }
    });
    // Rz(a_1).
    (w, d) = lean.rz_base(w, d);
    Ok(Point { xyz: w, dir: d })
}

/// sin ρ and 1 − cos ρ of a small angle ρ (|ρ| ≤ [`MAX_RHO`]): ρ − ρ³/6 and ½ ρ², sharing
/// ρ² (errors ρ⁵/120 and ρ⁴/24).
#[cfg(feature = "wobble")]
#[inline(always)]
fn small_turn(rho: f32) -> (f32, f32) {
    /// −1/6 in f32 (relative error 3e-8 of a term under 2e-7).
    const S: f32 = -1.0 / 6.0;
    let z = rho * rho;
    (rho + (rho * z) * S, 0.5 * z)
}

/// The tip (x, y quarter turned by Rz, `p` and `r`; z `w2`) turned by Rz's remainder (its sin
/// and 1 − cos), then
/// Ry(φy) to second order (`py`, `hp` = ½ φy), then Rx (quarter turns `qa` and the remainder
/// turned by φx): with each large coordinate rounded as often as the lean pass rounds it.
/// Ry's corrections are small (φy times the tip); added to x and z on their own, each would
/// round a large coordinate once more a joint (two more roundings of up to 0.5 ulp at
/// 1.5 m, 0.06 µm each). Instead x's joins Rz's correction of x, and z's (dz) the sum that
/// Rx's quarter turn takes z into: the corrections' products take z − dz rounded (a small
/// rounding, scaled by sin or 1 − cos of the remainder), the large sum z itself and dz
/// exactly.
#[cfg(feature = "wobble")]
#[inline(always)]
fn turn_tip(
    (p, r, sin, omc): (f32, f32, f32, f32),
    (py, hp): (f32, f32),
    (qa, asin, aomc): (u8, f32, f32),
    w2: f32,
) -> [f32; 3] {
    // Rz: x's correction kept apart; x1, x after it, only for Ry's small products.
    let cx = r * sin + p * omc;
    let x1 = p - cx;
    let y = r + (p * sin - r * omc);
    let z = w2;
    // Ry(φy): x += py z − h x, z −= py x + h z, h = ½ φy²: with u = φy z and t = φy x,
    // x += xc = u − (½ φy) t and z −= t + (½ φy) xc (five operations where h took six;
    // xc where u was adds −¼ φy³ x to z, third order as the φy³ x / 6 Ry's second order
    // leaves out: 1.8 pm at 1.5 m for this arm's |φy| ≤ 1.7e-4, 1 nm at the table's
    // 1.4e-3; and u is not needed beside xc: one register copy a joint fewer).
    let (u, t) = (py * z, py * x1);
    let xc = u - hp * t;
    let x = p - (cx - xc);
    let dz = t + hp * xc;
    // Rx: the quarter turns of (y, z), of (y, z − dz) for the correction and of (−0, −dz)
    // (−0: a sum with it the compiler can drop where the quarter turn puts it on r).
    let (p, r) = quarter_turns(qa, (y, z));
    let (pc, rc) = quarter_turns(qa, (y, z - dz));
    let (dp, dr) = quarter_turns(qa, (-0.0f32, -dz));
    [
        x,
        p - ((rc * asin + pc * aomc) - dp),
        r + ((pc * asin - rc * aomc) + dr),
    ]
}

#[cfg(all(test, feature = "wobble"))]
mod tests {
    use super::*;
    use crate::chain::Chain;
    use crate::lean::LeanForm;
    use crate::table::wobble::{WobbleData, WobbleTerm};
    use crate::table::{tests::sample, TableData, FLAG_GEOMETRIC, MAX_TABLE_LEN};

    fn term(order: u16, alpha: [f64; 2], beta: [f64; 2]) -> WobbleTerm {
        WobbleTerm { order, alpha, beta }
    }

    /// The sample arm (first-order gravity) with a wobble on five of its six joints: orders
    /// 1 to 64, up to four terms, axes turned about z and tilted by `tilt` rad as the table
    /// builder makes them (f1 = Rz(−Δθ) Ry(−tilt) x̂, f2 = Rz(−Δθ) ŷ), a worn bearing's
    /// 1e-4 rad on each term times `size`.
    fn wobbling(tilt: f64, size: f64) -> TableData {
        wobbling_turned(tilt, size, 1.0)
    }

    /// [`wobbling`] with the axes' turns about z (0.4 + k rad at joint k + 1) times `turn`.
    fn wobbling_turned(tilt: f64, size: f64, turn: f64) -> TableData {
        let mut data = sample();
        for j in data.joints.iter_mut().filter(|j| j.gravity != 0.0) {
            j.gravity = 1e-8;
        }
        let terms: [&[WobbleTerm]; 6] = [
            &[term(1, [-3.2e-5, -8.4e-5], [-4.1e-5, -4.7e-5])],
            &[
                term(2, [5.3e-5, 4.5e-5], [-5.7e-5, 5.6e-5]),
                term(4, [1.5e-5, -4.3e-5], [-2.5e-5, 3.3e-5]),
            ],
            &[],
            &[
                term(1, [1.4e-5, 7.0e-5], [5.8e-5, -9.7e-6]),
                term(3, [9.3e-6, -4.2e-5], [-6.0e-6, 1.7e-5]),
                term(4, [2e-5, 0.0], [0.0, -2e-5]),
                term(64, [0.0, 1e-5], [-1e-5, 0.0]),
            ],
            &[term(2, [1.6e-5, -4.8e-5], [3.9e-5, -7.7e-5])],
            &[
                term(4, [-1.5e-5, 3.8e-5], [-3.1e-5, -1.2e-5]),
                term(3, [1.7e-5, -7.3e-6], [3.9e-6, 6.4e-6]),
            ],
        ];
        for (k, t) in terms.iter().enumerate() {
            if t.is_empty() {
                continue;
            }
            let turn = turn * (0.4 + k as f64);
            let (c, s) = (turn.cos(), turn.sin());
            let (ct, st) = (tilt.cos(), tilt.sin());
            // In the z-axis frame, then in the file's frame of the joint's axis (the inverse
            // relabelling).
            let back = [1, 0, 2][usize::from(data.joints[k].axis.min(2))];
            let mut w = WobbleData {
                f1: crate::model::unpermute([c * ct, -s * ct, st], back),
                f2: crate::model::unpermute([s, c, 0.0], back),
                count: t.len() as u8,
                ..WobbleData::default()
            };
            for (dst, src) in w.terms.iter_mut().zip(*t) {
                *dst = WobbleTerm {
                    alpha: src.alpha.map(|a| a * size),
                    beta: src.beta.map(|b| b * size),
                    ..*src
                };
            }
            data.wobble[k] = w;
        }
        data.flags = data.content_flags() | FLAG_GEOMETRIC;
        data
    }

    fn chain_of(data: &TableData) -> Chain<F32> {
        let mut buf = [0u8; MAX_TABLE_LEN];
        let len = data.encode(&mut buf).unwrap();
        Chain::<F32>::new(&Table::parse(&buf[..len]).unwrap()).unwrap()
    }

    /// The lean form of `data`'s arm and its model, as the hub builds them.
    fn lean_of(data: &TableData) -> (LeanF32, Model<F32>) {
        let mut buf = [0u8; MAX_TABLE_LEN];
        let len = data.encode(&mut buf).unwrap();
        let table = Table::parse(&buf[..len]).unwrap();
        let model = Model::<F32>::new(&table).unwrap();
        let mut place = core::mem::MaybeUninit::uninit();
        let lean = *LeanF32::build_in(&mut place, &table, &model, true).unwrap();
        (lean, model)
    }

    fn counts_of(k: u32) -> [u32; 6] {
        core::array::from_fn(|j| (k * 77_773 + j as u32 * 191_111) % (1 << 20))
    }

    /// The copies of the pass (six joints written out, looped; on an arm whose orders are 1
    /// to 4 and whose α remainders turned by φx stay within [`MAX_RHO`], the six-axis copy
    /// with the compliant set, the quarter turns of α and the orders known) give the same
    /// numbers bit for bit, with α's remainder and φx as one angle where the arm is within
    /// [`MAX_RHO`] and turned by φx where it is not (joint 1 tilted by 0.02 rad); they agree
    /// with the quaternion chain with its wobble to f32's rounding (under 0.5 µm, 1e-6 on the
    /// direction), while the wobble moves the tip by far more than that (the lean pass
    /// without it misses by micrometres); a count out of range is refused by each, naming
    /// its joint.
    #[test]
    fn the_copies_agree_and_meet_the_quaternion_chain() {
        // With joint 4's order-64 term (`Multiples`' loop), and without it (orders 1 to 4);
        // the latter with joint 1's α 0.02 rad off its quarter turn (past MAX_RHO).
        let mut small = wobbling(0.003, 1.0);
        small.wobble[3].count = 3;
        let mut steep = small;
        let h = 0.01f64;
        let q = [(1.0 - h * h).sqrt(), h, 0.0, 0.0];
        steep.joints[0].rotation = q;
        steep.joints[0].matrix = crate::table::quat_to_matrix(&q);
        for (data, is_small, is_rho) in [
            (wobbling(0.003, 1.0), false, true),
            (small, true, true),
            (steep, true, false),
        ] {
            let chain = chain_of(&data);
            assert!(chain.is_lean());
            let (lean, model) = lean_of(&data);
            assert!(lean.applies() && lean.pow2 && lean.wobble.on());
            assert_eq!(lean.wobble.small, is_small);
            assert_eq!(lean.wobble.rho, is_rho);
            assert!(lean.wobble.dir_first);
            assert_eq!(
                (lean.gravity_mask, lean.alpha_quarters),
                (HINGES, PERPENDICULAR)
            );
            // The same arm's lean pass with the wobble left out.
            let mut still = lean;
            still.wobble = LeanWobble::default();
            let bits = |p: &Point<F32>| (p.xyz.map(f32::to_bits), p.dir.map(f32::to_bits));
            let mut moved = 0i64;
            for k in 0..200u32 {
                let counts = counts_of(k);
                let temp = 10_000 + 125 * k as i32;
                let a =
                    run::<6, true, RUNTIME, RUNTIME_ALPHA, false, 0>(&lean, &model, &counts, temp)
                        .unwrap();
                let b =
                    run::<0, false, RUNTIME, RUNTIME_ALPHA, false, 0>(&lean, &model, &counts, temp)
                        .unwrap();
                assert_eq!(bits(&a), bits(&b), "{counts:?}");
                if is_small && is_rho {
                    let f = run::<6, true, HINGES, PERPENDICULAR, true, 0>(
                        &lean, &model, &counts, temp,
                    )
                    .unwrap();
                    assert_eq!(bits(&a), bits(&f), "{counts:?}");
                }
                assert_eq!(bits(&a), bits(&chain.eval(&counts, temp).unwrap()));
                let q = chain.eval_quaternion(&counts, temp).unwrap();
                let (pa, pq) = (a.xyz_nm(), q.xyz_nm());
                let (da, dq) = (a.dir_e9(), q.dir_e9());
                for m in 0..3 {
                    assert!((pa[m] - pq[m]).abs() < 500, "{counts:?}: {pa:?} {pq:?}");
                    assert!((da[m] - dq[m]).abs() < 1_000, "{counts:?}: {da:?} {dq:?}");
                }
                let s = still.eval(&model, &counts, temp).unwrap().xyz_nm();
                moved = moved.max((0..3).map(|m| i64::from(s[m] - pa[m]).abs()).max().unwrap());
            }
            assert!(moved > 20_000, "the wobble moves the tip by {moved} nm");
            let mut counts = [5u32; 6];
            counts[3] = 1 << 20;
            let want = Err(ChainError::CountOutOfRange { joint: 4 });
            let r6 =
                run::<6, true, RUNTIME, RUNTIME_ALPHA, false, 0>(&lean, &model, &counts, 20_000);
            let r0 =
                run::<0, false, RUNTIME, RUNTIME_ALPHA, false, 0>(&lean, &model, &counts, 20_000);
            let rf = run::<6, true, HINGES, PERPENDICULAR, true, 0>(&lean, &model, &counts, 20_000);
            assert_eq!(r6.map(|_| ()), want);
            assert_eq!(r0.map(|_| ()), want);
            assert_eq!(rf.map(|_| ()), want);
        }
    }

    /// The six-axis copy's z forms of `Z_HUB`: on an arm whose wobble's axes lie nearly
    /// along the lean frames' x and y (tilted by 1e-4 rad; the sample arm's frames leave the
    /// hinges' q_xx at 2e-3 to 6e-3 and l_y at 4e-7 to 1.2e-6, so a wobble of 2e-5 rad a term
    /// keeps the bound), within a nanometre and 1e-9 of the whole forms (the same copy with
    /// the whole form, 0, at every joint), and gated where they do not (the axes turned about
    /// z, q up to 0.97, 1e-4 a term).
    #[test]
    fn the_hub_s_z_forms_leave_out_little() {
        let mut along = wobbling_turned(1e-4, 0.2, 0.0);
        along.wobble[3].count = 3;
        let mut turned = wobbling(1e-4, 1.0);
        turned.wobble[3].count = 3;
        for (data, hub) in [(along, true), (turned, false)] {
            let (lean, model) = lean_of(&data);
            assert!(lean.wobble.small && lean.wobble.rho && lean.wobble.dir_first);
            assert_eq!(lean.wobble.z_hub, hub);
            if !hub {
                continue;
            }
            for k in 0..500u32 {
                let counts = counts_of(k);
                let temp = 10_000 + 125 * k as i32;
                let a =
                    run::<6, true, HINGES, PERPENDICULAR, true, 0>(&lean, &model, &counts, temp)
                        .unwrap();
                let b = run::<6, true, HINGES, PERPENDICULAR, true, Z_HUB>(
                    &lean, &model, &counts, temp,
                )
                .unwrap();
                let (pa, pb) = (a.xyz_nm(), b.xyz_nm());
                let (da, db) = (a.dir_e9(), b.dir_e9());
                for m in 0..3 {
                    assert!((pa[m] - pb[m]).abs() <= 1, "{counts:?}: {pa:?} {pb:?}");
                    assert!((da[m] - db[m]).abs() <= 1, "{counts:?}: {da:?} {db:?}");
                }
                assert_eq!(b.xyz, chain_of(&data).eval(&counts, temp).unwrap().xyz);
            }
        }
    }

    /// [`small_turn`] within [`MAX_RHO`]: sin ρ to f32's rounding of it (half an ulp of ρ,
    /// 4.7e-10 at 0.01, and the dropped ρ⁵/120), 1 − cos ρ within the dropped ρ⁴/24 (4.2e-10
    /// at 0.01) and its rounding.
    #[test]
    fn the_small_turn_is_sin_and_one_minus_cos() {
        for k in -1000..=1000 {
            let rho = k as f32 * (MAX_RHO as f32 / 1000.0);
            let (s, omc) = small_turn(rho);
            let r = f64::from(rho);
            let ulp = f64::from(f32::EPSILON) * r.abs();
            assert!((f64::from(s) - r.sin()).abs() <= ulp, "{rho}");
            let left_out = r.powi(4) / 24.0;
            assert!(
                (f64::from(omc) - (1.0 - r.cos())).abs() <= left_out + ulp * r.abs(),
                "{rho}"
            );
        }
    }

    /// Every set of orders 1 to 4 that [`small_series`] jumps to gives `Multiples`' loop's
    /// φx, φy bit for bit (on angles all round the circle); no orders give zeros.
    #[test]
    fn each_set_of_orders_is_the_loop_s() {
        let pool: [Term; 4] = core::array::from_fn(|k| Term {
            order: 0,
            x: [1.3e-5 * (k as f32 + 1.0), -2.1e-5],
            y: [-0.7e-5, 3.9e-5 / (k as f32 + 1.0)],
        });
        for orders in 1u8..16 {
            let terms: Vec<Term> = (0..4u32)
                .filter(|h| orders & (1 << h) != 0)
                .zip(&pool)
                .map(|(h, t)| Term { order: h + 1, ..*t })
                .collect();
            for k in 0..97 {
                let th = 0.37 + 0.0671 * k as f64;
                let (c, s) = (th.cos() as f32, th.sin() as f32);
                let mut m = Multiples::<F32>::new(c, s);
                let (mut x, mut y) = (0.0f32, 0.0f32);
                for t in &terms {
                    m.advance(t.order);
                    x = x + m.s * t.x[0] + m.c * t.x[1];
                    y = y + m.s * t.y[0] + m.c * t.y[1];
                }
                let mut four = [Term::default(); 4];
                four[..terms.len()].copy_from_slice(&terms);
                let got = small_series(Orders::of(orders), &four, c, s);
                assert_eq!(
                    (got.0.to_bits(), got.1.to_bits()),
                    (x.to_bits(), y.to_bits())
                );
            }
        }
        assert_eq!(small_series(Orders::O0, &pool, 0.6, 0.8), (0.0, 0.0));
    }

    /// At the table's largest wobble (Σ |coefficients| up to 0.98e-3 a joint, the limit 1e-3) the left-out third
    /// order terms stay under the module's bound: the form within 1 µm of the quaternion
    /// chain, 2e-6 on the direction (the two chains' own roundings included).
    #[test]
    fn the_largest_wobble_stays_second_order_exact() {
        let chain = chain_of(&wobbling(0.003, 3.0));
        assert!(chain.is_lean());
        for k in 0..200u32 {
            let counts = counts_of(k);
            let (a, q) = (
                chain.eval(&counts, 20_000).unwrap(),
                chain.eval_quaternion(&counts, 20_000).unwrap(),
            );
            let (pa, pq, da, dq) = (a.xyz_nm(), q.xyz_nm(), a.dir_e9(), q.dir_e9());
            for m in 0..3 {
                assert!((pa[m] - pq[m]).abs() < 1_000, "{counts:?}: {pa:?} {pq:?}");
                assert!((da[m] - dq[m]).abs() < 2_000, "{counts:?}: {da:?} {dq:?}");
            }
        }
    }

    /// An axis whose z part is past [`MAX_AXIS_Z`], or more than [`MAX_LEAN_TERMS`] terms in
    /// all, are left to the quaternion chain; just under either the lean form takes the arm.
    #[test]
    fn a_steep_axis_or_many_terms_are_left_to_the_quaternion_chain() {
        assert!(chain_of(&wobbling(0.009, 1.0)).is_lean());
        assert!(!chain_of(&wobbling(0.011, 1.0)).is_lean());
        // 10 terms; four on joint 3 (14), then joint 1's up to four (16, 17).
        let mut data = wobbling(0.003, 1.0);
        // (Joint 3's axes as joint 1's: both turn about z.)
        data.wobble[2] = WobbleData {
            terms: data.wobble[3].terms,
            count: 4,
            ..data.wobble[0]
        };
        assert!(chain_of(&data).is_lean());
        data.wobble[0].terms[1] = term(5, [1e-5, 0.0], [0.0, 1e-5]);
        data.wobble[0].count = 2;
        data.wobble[0].terms[2] = term(6, [1e-5, 0.0], [0.0, 1e-5]);
        data.wobble[0].count = 3;
        assert!(chain_of(&data).is_lean());
        data.wobble[0].terms[3] = term(7, [1e-5, 0.0], [0.0, 1e-5]);
        data.wobble[0].count = 4;
        assert!(!chain_of(&data).is_lean());
    }
}
