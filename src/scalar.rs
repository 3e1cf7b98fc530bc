//! The number formats of the firmware evaluators and their arithmetic, behind one small trait.
//!
//! The chain is written once, generically over [`Arithmetic`]; two implementations exist:
//!
//! - [`F32`]: IEEE-754 single precision for FPU targets (Cortex-M4F). Only `+ - *` in a
//!   fixed order, never a fused multiply-add, `sqrt`, division or a libm call in the per-point
//!   path, so that host and target give bit-identical results. (The M4F's VMLA/VMLS round the
//!   product before the sum: they are a multiply and an add, not a fused operation.)
//! - [`Fixed`]: 32-bit fixed point from crate `fixed` for targets without an FPU (Cortex-M0).
//!   Dimensionless numbers (sines, quaternion and direction components) are I2F30, resolution
//!   9.3e-10; lengths are I12F20 mm, resolution 0.95 nm, range ±2048 mm. Every product is
//!   rounded to nearest (to within 2^-12 of a unit at ties, [`mul_q30`]). Sums wrap instead
//!   of panicking; the table's range checks and
//!   [`crate::model::Model::new`] guarantee that no sum of a valid table can overflow.
//!
//! Two kinds of number are kept apart even though f32 uses one type for both: fixed point
//! cannot hold both a 1e-9 rad rotation and a 1.5 m lever in one 32-bit format.
//!
//! This trait is arithmetic only. The physical effects' terms in each format (gravity
//! deflection, thermal expansion) are [`crate::physics::Physics`]; what a target may spend on
//! the chain (flash for speed) is [`crate::chain::Evaluator`].

use core::fmt::Debug;
use core::ops::{Add, Neg, Sub};
use fixed::types::{I12F20, I2F30};

/// A number of one of the chain's kinds, with the additive operations.
pub trait Scalar:
    Copy + Default + PartialEq + Debug + Add<Output = Self> + Sub<Output = Self> + Neg<Output = Self>
{
}

/// Scaling of a number by a dimensionless factor of the same precision.
pub trait Scale<P: Arithmetic>: Scalar {
    /// `self · u`, rounded once.
    fn scale(self, u: P::U) -> Self;
}

/// One evaluator's number formats and the few operations that depend on them.
pub trait Arithmetic: Copy + Default + Debug + 'static {
    /// Dimensionless, |x| < 2: sines, cosines, quaternion and direction components.
    type U: Scale<Self>;
    /// Lengths (mm).
    type L: Scale<Self>;

    /// Short name, for reports.
    const NAME: &'static str;
    /// 1.
    const ONE: Self::U;
    /// Minimax coefficients of (sin x − x) / x³ in x² on |x| ≤ π/8.
    const SIN: [Self::U; 3];
    /// Minimax coefficients of (cos x − 1) / x² in x² on |x| ≤ π/8.
    const COS: [Self::U; 3];
    /// √½.
    const SQRT_HALF: Self::U;

    /// The angle of a binary remainder: `r · π / 2^32` rad (|r| ≤ 2^29, so ≤ π/8).
    fn angle(r: i32) -> Self::U;
    /// `a / 2`.
    fn half(a: Self::U) -> Self::U;

    /// Conversion of a dimensionless table value; `None` where it does not fit.
    fn u_from_f64(x: f64) -> Option<Self::U>;
    /// Conversion of a length (mm); `None` where it does not fit.
    fn l_from_f64(x: f64) -> Option<Self::L>;

    /// A length in integer nanometres, rounded to nearest (ties away from zero), saturating.
    fn l_to_nm(x: Self::L) -> i32;
    /// A dimensionless number in integer units of 1e-9, rounded to nearest, saturating.
    fn u_to_e9(x: Self::U) -> i32;
    /// Exact value of a length, for host-side comparisons.
    fn l_to_f64(x: Self::L) -> f64;
    /// Exact value of a dimensionless number, for host-side comparisons.
    fn u_to_f64(x: Self::U) -> f64;
    /// A length (mm) as an f32, for the uncertainty's arithmetic (which needs 1e-4).
    fn l_to_f32(x: Self::L) -> f32;
    /// A dimensionless number as an f32, for the uncertainty's arithmetic.
    fn u_to_f32(x: Self::U) -> f32;
    /// A dimensionless number as a length of `x` · 1024 mm, exactly: a unit vector carried
    /// through the chain's position code (fixed point: the same bits, I2F30 read as I12F20).
    fn u_as_l1024(x: Self::U) -> Self::L;
    /// The inverse of [`Arithmetic::u_as_l1024`], exact.
    fn l1024_as_u(x: Self::L) -> Self::U;
    /// Largest absolute length (mm) that the chain may meet anywhere; the table must keep the
    /// arm's reach below it.
    const MAX_REACH_MM: f64;
    /// Largest sum of the levers, Σ_k (reach beyond joint k), mm with the thermal margin, that
    /// the chain keeps within its bound (`None`: no limit beyond the reach). Each joint's
    /// rounded turn (f32: its remainder's sine and cosine within 6e-8) moves the tip by that
    /// much times its lever, so the rounding grows with the sum of the levers, not with the
    /// reach alone.
    const MAX_LEVERS_MM: Option<f64>;
    /// Whether products drift |q| enough to matter, so that the quaternion chain divides the
    /// norm out of every rotation (f32: some 1e-7 per product, 0.3 µm at the tip) rather than
    /// trusting |q| = 1 (fixed point: 1e-9 per product, under a nanometre).
    const DIVIDE_NORM: bool;
}

/// Minimax sin x = x + x³(S1 + x²(S2 + x² S3)) on |x| ≤ π/8: absolute error 3.6e-12
/// (fitted for this chain; Taylor would leave 6e-10).
const SIN_F64: [f64; 3] = [
    -0.166_666_664_143_413_52,
    0.008_333_247_965_370_043,
    -0.000_197_543_313_478_740_45,
];
/// Minimax cos x − 1 = x²(C1 + x²(C2 + x² C3)) on |x| ≤ π/8: absolute error 1.3e-10
/// (Taylor would leave 1.4e-8).
const COS_F64: [f64; 3] = [
    -0.499_999_983_375_524_2,
    0.041_666_012_107_547_654,
    -0.001_381_560_031_694_282_4,
];

// ---------------------------------------------------------------------------------------------
// f32

/// The single-precision evaluator.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct F32;

impl Scalar for f32 {}

impl Scale<F32> for f32 {
    #[inline(always)]
    fn scale(self, u: f32) -> f32 {
        self * u
    }
}

impl Arithmetic for F32 {
    type U = f32;
    type L = f32;
    const NAME: &'static str = "f32";
    const ONE: f32 = 1.0;
    const SIN: [f32; 3] = [SIN_F64[0] as f32, SIN_F64[1] as f32, SIN_F64[2] as f32];
    const COS: [f32; 3] = [COS_F64[0] as f32, COS_F64[1] as f32, COS_F64[2] as f32];
    const SQRT_HALF: f32 = core::f32::consts::FRAC_1_SQRT_2;
    /// Not the format's (f32 holds far more) but the accuracy bound's: f32 rounds the
    /// partial sums at ulp(|w|), and an arm whose seven fixed rotations are all large (tilts
    /// of 1.4 rad, no links, a 1923 mm probe; found by the `chain_arm_accuracy` fuzz target)
    /// reached 1.125 µm, over the 1 µm bound. The limit was then 1700 mm (with the thermal
    /// margin), until the fuzz target found 1.047 µm at 1700 mm at 120 °C (a 1567 mm probe,
    /// seven joints; `f32-reach-1700mm-1.047um.toml`): the error does not shrink in
    /// proportion to the reach (f32 rounds at the ulp of the binade, 0.12 µm from 1024 to
    /// 2048 mm). The same arm scaled: 0.974 µm at 1690 mm, 0.853 at 1650, 0.845 at 1600, 0.72
    /// at 1300. 1650 mm still serves every arm of the MUKCa data (the longest, the Panda
    /// with its sensor: 1627.2 mm with the margin), and is inside the stream's i32
    /// nanometres (2147.48 mm).
    const MAX_REACH_MM: f64 = 1650.0;
    /// The fuzz target's fifth finding was inside the reach limit: 1.101 µm at 1649.998 mm
    /// with the margin (a 1550 mm probe at the end of six joints about x with no links, so
    /// every joint has the whole lever: Σ 11,363 mm). The findings before it had 11,711 mm
    /// (1.047 µm) and 14,000 mm (1.125 µm); the real arms at most 6,507 (the MUKCa Panda with
    /// its sensor; `default-6` 5,379). 9,000 mm keeps the bound (1.101 µm × 9,000 / 11,363 =
    /// 0.87 µm) and serves every one of them.
    const MAX_LEVERS_MM: Option<f64> = Some(9000.0);
    const DIVIDE_NORM: bool = true;

    #[inline(always)]
    fn angle(r: i32) -> f32 {
        // r has at most 30 significant bits (18 for a 2^20-count encoder, exact in f32); the
        // conversion rounds it to 24, a relative error of at most 6e-8.
        const K: f32 = (core::f64::consts::PI / 4_294_967_296.0) as f32;
        r as f32 * K
    }
    #[inline(always)]
    fn half(a: f32) -> f32 {
        a * 0.5
    }
    fn u_from_f64(x: f64) -> Option<f32> {
        // |x| = 2 included: E_i = M''_i − I of a half turn (a zero offset of π) has −2 on
        // its diagonal, which fixed point's I2F30 holds too.
        (x.is_finite() && x.abs() <= 2.0).then_some(x as f32)
    }
    fn l_from_f64(x: f64) -> Option<f32> {
        // Any length the table holds: the reach as a whole is checked against MAX_REACH_MM
        // ([`crate::model::Model::new`]), which names it.
        finite_below(x, 1.0e6).map(|x| x as f32)
    }
    fn l_to_nm(x: f32) -> i32 {
        f32_scaled(x, 1_000_000)
    }
    fn u_to_e9(x: f32) -> i32 {
        f32_scaled(x, 1_000_000_000)
    }
    fn l_to_f64(x: f32) -> f64 {
        f64::from(x)
    }
    fn u_to_f64(x: f32) -> f64 {
        f64::from(x)
    }
    #[inline(always)]
    fn l_to_f32(x: f32) -> f32 {
        x
    }
    #[inline(always)]
    fn u_to_f32(x: f32) -> f32 {
        x
    }
    #[inline(always)]
    fn u_as_l1024(x: f32) -> f32 {
        x * 1024.0
    }
    #[inline(always)]
    fn l1024_as_u(x: f32) -> f32 {
        x * (1.0 / 1024.0)
    }
}

/// `x` if it is finite and |x| < `limit`.
pub(crate) fn finite_below(x: f64, limit: f64) -> Option<f64> {
    if x.is_finite() && x.abs() < limit {
        Some(x)
    } else {
        None
    }
}

/// `round(x · scale)` computed exactly in integers from the bits of `x` (no f32 product, which
/// would err by up to ~90 nm at 1.5 m), ties away from zero, saturating at the i32 range.
pub fn f32_scaled(x: f32, scale: u32) -> i32 {
    let bits = x.to_bits();
    let negative = bits >> 31 != 0;
    let exp = ((bits >> 23) & 0xff) as i32;
    if exp == 0xff {
        // Infinity or NaN: cannot come out of a valid chain; saturate rather than panic.
        return if negative { i32::MIN } else { i32::MAX };
    }
    let mantissa = if exp == 0 {
        u64::from(bits & 0x7f_ffff)
    } else {
        u64::from((bits & 0x7f_ffff) | 0x80_0000)
    };
    // x = mantissa · 2^(e), e = exp − 150 (denormals: exp 0 counts as 1).
    let e = if exp == 0 { -149 } else { exp - 150 };
    let product = mantissa * u64::from(scale); // < 2^24 · 2^30 = 2^54
    let magnitude: u64 = if e >= 0 {
        if e >= 10 {
            u64::MAX
        } else {
            product << e
        }
    } else {
        let s = -e;
        if s >= 64 {
            0
        } else {
            (product + (1u64 << (s - 1))) >> s
        }
    };
    let clamped = if magnitude > i32::MAX as u64 {
        i32::MAX as i64
    } else {
        magnitude as i64
    };
    (if negative { -clamped } else { clamped }) as i32
}

// ---------------------------------------------------------------------------------------------
// Fixed point

/// The fixed-point evaluator: I2F30 dimensionless numbers, I12F20 millimetres.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Fixed;

/// A dimensionless fixed-point number, I2F30 (range ±2, resolution 2^-30).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub struct Unit(pub I2F30);

/// A fixed-point length in millimetres, I12F20 (range ±2048 mm, resolution 2^-20 mm).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub struct Len(pub I12F20);

macro_rules! wrapping_ops {
    ($t:ident, $inner:ty) => {
        impl Add for $t {
            type Output = $t;
            #[inline(always)]
            fn add(self, o: $t) -> $t {
                $t(<$inner>::from_bits(
                    self.0.to_bits().wrapping_add(o.0.to_bits()),
                ))
            }
        }
        impl Sub for $t {
            type Output = $t;
            #[inline(always)]
            fn sub(self, o: $t) -> $t {
                $t(<$inner>::from_bits(
                    self.0.to_bits().wrapping_sub(o.0.to_bits()),
                ))
            }
        }
        impl Neg for $t {
            type Output = $t;
            #[inline(always)]
            fn neg(self) -> $t {
                $t(<$inner>::from_bits(self.0.to_bits().wrapping_neg()))
            }
        }
        impl Scalar for $t {}
        impl $t {
            /// The raw two's-complement bits.
            #[inline(always)]
            pub fn bits(self) -> i32 {
                self.0.to_bits()
            }
            /// From raw bits.
            #[inline(always)]
            pub const fn from_bits(b: i32) -> $t {
                $t(<$inner>::from_bits(b))
            }
        }
    };
}
wrapping_ops!(Unit, I2F30);
wrapping_ops!(Len, I12F20);

/// Full 32×32→64-bit signed product. On ARMv6-M (no long multiply) this takes four 16×16
/// products inline, much cheaper than the `__aeabi_lmul` call that `i64 * i64` becomes there;
/// elsewhere the compiler's single instruction. Both give the same exact result.
///
/// ARMv6-M is told by its lack of 32-bit compare-and-swap (`target_has_atomic = "32"`, set
/// on thumbv7em and every later Arm target, never on thumbv6m): the `thumb2` target feature
/// this tested before is unstable, never set in `cfg` on a stable compiler, so the
/// Cortex-M4F took the four-product path too (~20 instructions for one `umull`/`smull`, per
/// joint and point in every chain; measured on qemu-m4f, `docs/results/speed.md`).
#[inline(always)]
pub fn mul_wide(a: i32, b: i32) -> i64 {
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    {
        let (ah, al) = (a >> 16, a & 0xffff);
        let (bh, bl) = (b >> 16, b & 0xffff);
        let hh = ah * bh; // |.| ≤ 2^30
        let hl = ah * bl; // fits: −2^15·(2^16−1) ≥ −2^31
        let lh = al * bh;
        let ll = (al as u32) * (bl as u32);
        ((hh as i64) << 32) + (((hl as i64) + (lh as i64)) << 16) + ll as i64
    }
    #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
    {
        a as i64 * b as i64
    }
}

/// Full 32×32→64-bit unsigned product (see [`mul_wide`]).
#[inline(always)]
pub fn mul_wide_u(a: u32, b: u32) -> u64 {
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    {
        let (ah, al) = (a >> 16, a & 0xffff);
        let (bh, bl) = (b >> 16, b & 0xffff);
        (((ah * bh) as u64) << 32)
            + ((al * bl) as u64)
            + (((ah * bl) as u64 + (al * bh) as u64) << 16)
    }
    #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
    {
        a as u64 * b as u64
    }
}

/// `a·b / 2^30` rounded to nearest (ties up): the product of two fixed-point numbers with 30
/// fractional bits in one of them, the chain's most frequent operation.
///
/// Built from the four 16×16-bit partial products in 32-bit arithmetic only, the same on
/// every target so that host and firmware agree bit for bit. With a = aₕ2¹⁶ + aₗ,
/// a·b/2³⁰ = 4aₕbₕ + ((aₕbₗ + aₗbₕ)/2 + aₗbₗ/2¹⁷)/2¹³; the three terms are floored to units
/// of 2¹⁷ before the sum (which keeps it within 32 bits), so the result is round-to-nearest
/// of a value at most 2⁻¹² of a unit below the exact product: it differs from exact rounding
/// only within 2⁻¹² of a tie. On ARMv6-M this is ~20 instructions where the 64-bit product
/// and shift took ~35.
#[inline(always)]
pub fn mul_q30(a: i32, b: i32) -> i32 {
    let (ah, al) = (a >> 16, (a as u32) & 0xffff);
    let (bh, bl) = (b >> 16, (b as u32) & 0xffff);
    let hh = ah.wrapping_mul(bh); // |.| ≤ 2^30
    let hl = ah.wrapping_mul(bl as i32); // |.| < 2^31
    let lh = (al as i32).wrapping_mul(bh);
    let ll = al.wrapping_mul(bl); // < 2^32
    let mid = (hl >> 1)
        .wrapping_add(lh >> 1)
        .wrapping_add((ll >> 17) as i32)
        .wrapping_add(1 << 12);
    (hh << 2).wrapping_add(mid >> 13)
}

/// `(a·b) >> s`, rounded to nearest, truncated to 32 bits.
#[inline(always)]
pub(crate) fn mul_shift(a: i32, b: i32, s: u32) -> i32 {
    ((mul_wide(a, b) + (1i64 << (s - 1))) >> s) as i32
}

const fn q30(x: f64) -> Unit {
    let scaled = x * 1_073_741_824.0;
    Unit::from_bits(if scaled >= 0.0 {
        (scaled + 0.5) as i32
    } else {
        (scaled - 0.5) as i32
    })
}

/// `x·2^frac` rounded to the nearest integer (ties to even, as `fixed`'s `from_num`), if `x`
/// is finite and the result fits an `i32`: the one float-to-fixed conversion of the boot path.
///
/// Written on the f64's bits and kept out of line because on the M0 every f64 operation is a
/// soft-float call: `fixed`'s generic conversion, inlined at four call sites with four target
/// formats, cost about 1.6 KB of the qemu-m0 image's 32 KiB; this is one copy in integers.
#[inline(never)]
pub(crate) fn fixed_bits(x: f64, frac: u32) -> Option<i32> {
    const MANT_BITS: u32 = 52;
    let bits = x.to_bits();
    let exp = ((bits >> MANT_BITS) & 0x7ff) as i32;
    if exp == 0x7ff {
        return None; // infinity or NaN
    }
    let mut mant = bits & ((1 << MANT_BITS) - 1);
    if exp != 0 {
        mant |= 1 << MANT_BITS;
    }
    // |x| = mant · 2^(max(exp, 1) − 1075); scaled by 2^frac.
    let shift = exp.max(1) - 1075 + frac as i32;
    let magnitude = if shift >= 0 {
        let s = shift as u32;
        if mant == 0 {
            0
        } else if s >= 32 || mant > u64::from(u32::MAX) >> s {
            return None;
        } else {
            mant << s
        }
    } else {
        let s = shift.unsigned_abs();
        if s > MANT_BITS + 1 {
            0 // below half a unit of the result
        } else {
            let q = mant >> s;
            let rest = mant & ((1 << s) - 1);
            let half = 1 << (s - 1);
            q + u64::from(rest > half || (rest == half && q & 1 == 1))
        }
    };
    if bits >> 63 == 0 {
        i32::try_from(magnitude).ok()
    } else if magnitude <= 1 << 31 {
        Some((magnitude as i64).wrapping_neg() as i32)
    } else {
        None
    }
}

impl Scale<Fixed> for Unit {
    #[inline(always)]
    fn scale(self, u: Unit) -> Unit {
        Unit::from_bits(mul_q30(self.bits(), u.bits()))
    }
}

impl Scale<Fixed> for Len {
    #[inline(always)]
    fn scale(self, u: Unit) -> Len {
        Len::from_bits(mul_q30(self.bits(), u.bits()))
    }
}

impl Arithmetic for Fixed {
    type U = Unit;
    type L = Len;
    const NAME: &'static str = "fixed";
    const ONE: Unit = Unit::from_bits(1 << 30);
    const SIN: [Unit; 3] = [q30(SIN_F64[0]), q30(SIN_F64[1]), q30(SIN_F64[2])];
    const COS: [Unit; 3] = [q30(COS_F64[0]), q30(COS_F64[1]), q30(COS_F64[2])];
    const SQRT_HALF: Unit = q30(core::f64::consts::FRAC_1_SQRT_2);
    /// Positions are I12F20: keep 48 mm of the ±2048 mm range as margin for rounding.
    const MAX_REACH_MM: f64 = 2000.0;
    /// Fixed point's rounding is absolute (2^-30 a turn, 1e-6 mm a length): within its bound
    /// at any sum of levers the table holds (the fuzz target's arms up to 14,000 mm).
    const MAX_LEVERS_MM: Option<f64> = None;
    const DIVIDE_NORM: bool = false;

    #[inline(always)]
    fn angle(r: i32) -> Unit {
        // x = r·π/2^32 in F30 is r·π/4: multiply by round(π/4 · 2^31), shift 31.
        const PI_4_Q31: i32 = 1_686_629_713;
        Unit::from_bits(mul_shift(r, PI_4_Q31, 31))
    }
    #[inline(always)]
    fn half(a: Unit) -> Unit {
        Unit::from_bits(a.bits() >> 1)
    }
    fn u_from_f64(x: f64) -> Option<Unit> {
        fixed_bits(x, 30).map(Unit::from_bits)
    }
    fn l_from_f64(x: f64) -> Option<Len> {
        // Any value the format holds: the arm's reach, which bounds every sum, is checked
        // against MAX_REACH_MM as a whole ([`crate::model::Model::new`]).
        fixed_bits(x, 20).map(Len::from_bits)
    }
    fn l_to_nm(x: Len) -> i32 {
        // bits·10^6 / 2^20, rounded (ties up).
        ((x.bits() as i64 * 1_000_000 + (1 << 19)) >> 20) as i32
    }
    fn u_to_e9(x: Unit) -> i32 {
        ((x.bits() as i64 * 1_000_000_000 + (1 << 29)) >> 30) as i32
    }
    fn l_to_f64(x: Len) -> f64 {
        x.bits() as f64 / 1_048_576.0
    }
    fn u_to_f64(x: Unit) -> f64 {
        x.bits() as f64 / 1_073_741_824.0
    }
    fn l_to_f32(x: Len) -> f32 {
        x.bits() as f32 * (1.0 / 1_048_576.0)
    }
    fn u_to_f32(x: Unit) -> f32 {
        x.bits() as f32 * (1.0 / 1_073_741_824.0)
    }
    #[inline(always)]
    fn u_as_l1024(x: Unit) -> Len {
        // 30 fractional bits of a unit are 20 of a millimetre and 10 of 1024.
        Len::from_bits(x.bits())
    }
    #[inline(always)]
    fn l1024_as_u(x: Len) -> Unit {
        Unit::from_bits(x.bits())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The integer conversion gives exactly what `fixed`'s own `checked_from_num` gives, on
    /// ties, subnormals, the edges of the i32 range and values that do not fit.
    #[test]
    fn fixed_bits_is_fixed_from_num() {
        use fixed::types::{I16F48, I24F40};
        fn via_fixed(x: f64, frac: u32) -> Option<i32> {
            let bits = match frac {
                20 => I12F20::checked_from_num(x).map(|v| i64::from(v.to_bits())),
                30 => I2F30::checked_from_num(x).map(|v| i64::from(v.to_bits())),
                40 => I24F40::checked_from_num(x).map(|v| v.to_bits()),
                48 => I16F48::checked_from_num(x).map(|v| v.to_bits()),
                _ => unreachable!(),
            };
            bits.and_then(|b| i32::try_from(b).ok())
        }
        let mut vals = vec![
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            5e-324,
            f64::MAX,
            f64::INFINITY,
            f64::NAN,
            2.0,
            -2.0,
            1.999_999_999,
            2_047.999_999,
            -2048.0,
        ];
        for frac in [20u32, 30, 40, 48] {
            let unit = 2f64.powi(-(frac as i32));
            for k in [0.5, 1.5, 2.5, -0.5, -1.5, 3.5] {
                vals.push(k * unit); // exact ties
            }
            vals.push(2147483647.0 * unit);
            vals.push(2147483648.0 * unit);
            vals.push(-2147483648.0 * unit);
            vals.push(-2147483649.0 * unit);
        }
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..20_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let mag = (state >> 11) as f64 / (1u64 << 53) as f64;
            let e = (state % 64) as i32 - 50;
            vals.push(if state & 1 == 0 { mag } else { -mag } * 2f64.powi(e));
        }
        for &x in &vals {
            for frac in [20u32, 30, 40, 48] {
                assert_eq!(
                    fixed_bits(x, frac),
                    via_fixed(x, frac),
                    "x = {x:e}, frac {frac}"
                );
            }
        }
    }

    #[test]
    fn wide_products_are_exact() {
        let vals = [
            0,
            1,
            -1,
            0x7fff_ffff,
            i32::MIN,
            0x1234_5678,
            -0x0fed_cba9,
            65535,
            -65536,
        ];
        for &a in &vals {
            for &b in &vals {
                assert_eq!(mul_wide(a, b), a as i64 * b as i64);
            }
        }
    }

    #[test]
    fn q30_products_round_to_nearest() {
        // Against the exact product: equal, except one unit low within 2^-12 of a tie.
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as i32
        };
        let edges = [
            0,
            1,
            -1,
            i32::MAX,
            i32::MIN,
            1 << 30,
            -(1 << 30),
            0xffff,
            -0x10000,
        ];
        let mut pairs: Vec<(i32, i32)> = edges
            .iter()
            .flat_map(|&a| edges.iter().map(move |&b| (a, b)))
            .collect();
        for _ in 0..2_000_000 {
            // Operands of the chain's size: |a|, |b| ≤ 2^31 with |a·b| < 2^61.
            let (a, b) = (next(), next() >> (next() as u32 & 3));
            pairs.push((a, b));
        }
        for (a, b) in pairs {
            let p = a as i128 * b as i128;
            if (p >> 30) > i32::MAX as i128 || (p >> 30) < i32::MIN as i128 {
                continue;
            }
            let exact = ((p + (1 << 29)) >> 30) as i32;
            let got = mul_q30(a, b);
            let frac = (p & ((1 << 30) - 1)) as f64 / (1u64 << 30) as f64;
            assert!(
                got == exact || (got == exact - 1 && (frac - 0.5).abs() < 1.0 / 4096.0),
                "{a} * {b}: {got} vs {exact}"
            );
        }
    }

    #[test]
    fn f32_scaling_is_exact() {
        // 1234.5678 mm is not representable; the f32 nearest is converted exactly.
        let x = 1234.5678f32;
        let exact = (f64::from(x) * 1e6).round() as i32;
        assert_eq!(f32_scaled(x, 1_000_000), exact);
        assert_eq!(f32_scaled(-x, 1_000_000), -exact);
        assert_eq!(f32_scaled(0.0, 1_000_000), 0);
        assert_eq!(f32_scaled(1e-30, 1_000_000), 0);
        assert_eq!(f32_scaled(1e30, 1_000_000), i32::MAX);
        assert_eq!(f32_scaled(f32::NAN, 1_000_000), i32::MAX);
        for i in 0..100_000 {
            let x = (i as f32 - 50_000.0) * 0.0313;
            let want = (f64::from(x) * 1e6).round() as i32;
            assert_eq!(f32_scaled(x, 1_000_000), want, "{x}");
            let u = (i as f32 - 50_000.0) * 1.7e-5;
            let want = (f64::from(u) * 1e9).round() as i32;
            assert_eq!(f32_scaled(u, 1_000_000_000), want, "{u}");
        }
    }

    #[test]
    fn fixed_conversions() {
        assert_eq!(Fixed::l_to_nm(Fixed::l_from_f64(1.5).unwrap()), 1_500_000);
        assert_eq!(Fixed::u_to_e9(Fixed::ONE), 1_000_000_000);
        assert!(Fixed::l_from_f64(3000.0).is_none());
        assert!(Fixed::u_from_f64(f64::NAN).is_none());
    }
}
