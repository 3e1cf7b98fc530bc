//! The number formats of the firmware evaluators, behind one small trait.
//!
//! The chain is written once, generically over [`Precision`]; two implementations exist:
//!
//! - [`F32`]: IEEE-754 single precision for FPU targets (Cortex-M4F). Only `+ - *` in a
//!   fixed order, never a fused multiply-add, `sqrt`, division or a libm call in the per-point
//!   path, so that host and target give bit-identical results.
//! - [`Fixed`]: 32-bit fixed point from crate `fixed` for targets without an FPU (Cortex-M0).
//!   Dimensionless numbers (sines, quaternion and direction components) are I2F30, resolution
//!   9.3e-10; lengths are I12F20 mm, resolution 0.95 nm, range ±2048 mm. Every product is
//!   rounded to nearest. Sums wrap instead of panicking; the table's range checks and
//!   [`crate::model::Model::new`] guarantee that no sum of a valid table can overflow.
//!
//! Two kinds of number are kept apart even though f32 uses one type for both: fixed point
//! cannot hold both a 1e-9 rad rotation and a 1.5 m lever in one 32-bit format.

use core::fmt::Debug;
use core::ops::{Add, Neg, Sub};
use fixed::types::{I12F20, I2F30};

/// A number of one of the chain's kinds, with the additive operations.
pub trait Scalar:
    Copy + Default + PartialEq + Debug + Add<Output = Self> + Sub<Output = Self> + Neg<Output = Self>
{
}

/// Scaling of a number by a dimensionless factor of the same precision.
pub trait Scale<P: Precision>: Scalar {
    /// `self · u`, rounded once.
    fn scale(self, u: P::U) -> Self;
}

/// One evaluator's number formats and the few operations that depend on them.
pub trait Precision: Copy + Default + Debug + 'static {
    /// Dimensionless, |x| < 2: sines, cosines, quaternion and direction components.
    type U: Scale<Self>;
    /// Lengths (mm).
    type L: Scale<Self>;
    /// Gravity compliance coefficient (rad/mm).
    type G: Copy + Default + Debug;
    /// Thermal expansion coefficient, per milli-degree Celsius.
    type K: Copy + Default + Debug;

    /// Short name, for reports.
    const NAME: &'static str;
    /// 1.
    const ONE: Self::U;
    /// Taylor coefficients of sin x / x in x²: −1/3!, 1/5!, −1/7!, 1/9!.
    const SIN: [Self::U; 4];
    /// Taylor coefficients of cos x in x²: −1/2!, 1/4!, −1/6!, 1/8!.
    const COS: [Self::U; 4];

    /// Half of the angle of a binary remainder: `r · π / 2^32` rad (|r| ≤ 2^29, so ≤ π/8).
    fn half_angle(r: i32) -> Self::U;
    /// `a / 2`.
    fn half(a: Self::U) -> Self::U;
    /// Gravity deflection angle `g · x` for a lever term x (mm).
    fn gravity(g: Self::G, x: Self::L) -> Self::U;
    /// Thermal strain `κ · ΔT` for ΔT in milli-degrees Celsius.
    fn thermal(k: Self::K, dt_mc: i32) -> Self::U;

    /// Conversion of a dimensionless table value; `None` where it does not fit.
    fn u_from_f64(x: f64) -> Option<Self::U>;
    /// Conversion of a length (mm); `None` where it does not fit.
    fn l_from_f64(x: f64) -> Option<Self::L>;
    /// Conversion of a gravity coefficient (rad/mm); `None` where it does not fit.
    fn g_from_f64(g: f64) -> Option<Self::G>;
    /// Conversion of a thermal coefficient (1/°C); `None` where it does not fit.
    fn k_from_f64(kappa: f64) -> Option<Self::K>;

    /// A length in integer nanometres, rounded to nearest (ties away from zero), saturating.
    fn l_to_nm(x: Self::L) -> i32;
    /// A dimensionless number in integer units of 1e-9, rounded to nearest, saturating.
    fn u_to_e9(x: Self::U) -> i32;
    /// Exact value of a length, for host-side comparisons.
    fn l_to_f64(x: Self::L) -> f64;
    /// Exact value of a dimensionless number, for host-side comparisons.
    fn u_to_f64(x: Self::U) -> f64;
    /// Largest absolute length (mm) that the chain may meet anywhere; the table must keep the
    /// arm's reach below it.
    const MAX_REACH_MM: f64;
}

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

impl Precision for F32 {
    type U = f32;
    type L = f32;
    type G = f32;
    type K = f32;
    const NAME: &'static str = "f32";
    const ONE: f32 = 1.0;
    const SIN: [f32; 4] = [
        (-1.0 / 6.0) as f32,
        (1.0 / 120.0) as f32,
        (-1.0 / 5040.0) as f32,
        (1.0 / 362880.0) as f32,
    ];
    const COS: [f32; 4] = [
        -0.5,
        (1.0 / 24.0) as f32,
        (-1.0 / 720.0) as f32,
        (1.0 / 40320.0) as f32,
    ];
    const MAX_REACH_MM: f64 = 1.0e6;

    #[inline(always)]
    fn half_angle(r: i32) -> f32 {
        // r has at most 30 significant bits (18 for a 2^20-count encoder, exact in f32); the
        // conversion rounds it to 24, a relative error of at most 6e-8.
        const K: f32 = (core::f64::consts::PI / 4_294_967_296.0) as f32;
        r as f32 * K
    }
    #[inline(always)]
    fn half(a: f32) -> f32 {
        a * 0.5
    }
    #[inline(always)]
    fn gravity(g: f32, x: f32) -> f32 {
        g * x
    }
    #[inline(always)]
    fn thermal(k: f32, dt_mc: i32) -> f32 {
        k * dt_mc as f32
    }
    fn u_from_f64(x: f64) -> Option<f32> {
        finite_below(x, 2.0).map(|x| x as f32)
    }
    fn l_from_f64(x: f64) -> Option<f32> {
        finite_below(x, Self::MAX_REACH_MM).map(|x| x as f32)
    }
    fn g_from_f64(g: f64) -> Option<f32> {
        finite_below(g, 1.0).map(|x| x as f32)
    }
    fn k_from_f64(kappa: f64) -> Option<f32> {
        finite_below(kappa, 1.0).map(|x| (x / 1000.0) as f32)
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
}

fn finite_below(x: f64, limit: f64) -> Option<f64> {
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
#[inline(always)]
pub fn mul_wide(a: i32, b: i32) -> i64 {
    #[cfg(all(target_arch = "arm", not(target_feature = "thumb2")))]
    {
        let (ah, al) = (a >> 16, a & 0xffff);
        let (bh, bl) = (b >> 16, b & 0xffff);
        let hh = ah * bh; // |.| ≤ 2^30
        let hl = ah * bl; // fits: −2^15·(2^16−1) ≥ −2^31
        let lh = al * bh;
        let ll = (al as u32) * (bl as u32);
        ((hh as i64) << 32) + (((hl as i64) + (lh as i64)) << 16) + ll as i64
    }
    #[cfg(not(all(target_arch = "arm", not(target_feature = "thumb2"))))]
    {
        a as i64 * b as i64
    }
}

/// Full 32×32→64-bit unsigned product (see [`mul_wide`]).
#[inline(always)]
pub fn mul_wide_u(a: u32, b: u32) -> u64 {
    #[cfg(all(target_arch = "arm", not(target_feature = "thumb2")))]
    {
        let (ah, al) = (a >> 16, a & 0xffff);
        let (bh, bl) = (b >> 16, b & 0xffff);
        (((ah * bh) as u64) << 32)
            + ((al * bl) as u64)
            + (((ah * bl) as u64 + (al * bh) as u64) << 16)
    }
    #[cfg(not(all(target_arch = "arm", not(target_feature = "thumb2"))))]
    {
        a as u64 * b as u64
    }
}

/// `(a·b) >> s`, rounded to nearest, truncated to 32 bits.
#[inline(always)]
fn mul_shift(a: i32, b: i32, s: u32) -> i32 {
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

/// Fractional bits of the gravity coefficient: g·2^50 in an i32 (|g| < 1.9e-6 rad/mm).
const G_FRAC: u32 = 50;
/// Fractional bits of the thermal coefficient per milli-degree: (κ/1000)·2^52 in an i32
/// (|κ| < 4.7e-4 /°C).
const K_FRAC: u32 = 52;

impl Scale<Fixed> for Unit {
    #[inline(always)]
    fn scale(self, u: Unit) -> Unit {
        Unit::from_bits(mul_shift(self.bits(), u.bits(), 30))
    }
}

impl Scale<Fixed> for Len {
    #[inline(always)]
    fn scale(self, u: Unit) -> Len {
        Len::from_bits(mul_shift(self.bits(), u.bits(), 30))
    }
}

impl Precision for Fixed {
    type U = Unit;
    type L = Len;
    type G = i32;
    type K = i32;
    const NAME: &'static str = "fixed";
    const ONE: Unit = Unit::from_bits(1 << 30);
    const SIN: [Unit; 4] = [
        q30(-1.0 / 6.0),
        q30(1.0 / 120.0),
        q30(-1.0 / 5040.0),
        q30(1.0 / 362880.0),
    ];
    const COS: [Unit; 4] = [
        q30(-0.5),
        q30(1.0 / 24.0),
        q30(-1.0 / 720.0),
        q30(1.0 / 40320.0),
    ];
    /// Positions are I12F20: keep 48 mm of the ±2048 mm range as margin for rounding.
    const MAX_REACH_MM: f64 = 2000.0;

    #[inline(always)]
    fn half_angle(r: i32) -> Unit {
        // x = r·π/2^32 in F30 = r·(π/4)·2^-30·... : multiply by round(π/4 · 2^31), shift 31.
        const PI_4_Q31: i32 = 1_686_629_713;
        Unit::from_bits(mul_shift(r, PI_4_Q31, 31))
    }
    #[inline(always)]
    fn half(a: Unit) -> Unit {
        Unit::from_bits(a.bits() >> 1)
    }
    #[inline(always)]
    fn gravity(g: i32, x: Len) -> Unit {
        // g·2^50 · x·2^20 → ·2^30: shift 40.
        Unit::from_bits(mul_shift(g, x.bits(), G_FRAC + 20 - 30))
    }
    #[inline(always)]
    fn thermal(k: i32, dt_mc: i32) -> Unit {
        Unit::from_bits(mul_shift(k, dt_mc, K_FRAC - 30))
    }
    fn u_from_f64(x: f64) -> Option<Unit> {
        I2F30::checked_from_num(x).map(Unit)
    }
    fn l_from_f64(x: f64) -> Option<Len> {
        if !(x.is_finite() && x.abs() < Self::MAX_REACH_MM) {
            return None;
        }
        I12F20::checked_from_num(x).map(Len)
    }
    fn g_from_f64(g: f64) -> Option<i32> {
        // Through an I14F50 in an i64 so that no f64 arithmetic is needed on the target.
        fixed::types::I14F50::checked_from_num(g).and_then(|v| i32::try_from(v.to_bits()).ok())
    }
    fn k_from_f64(kappa: f64) -> Option<i32> {
        // κ/1000 · 2^52 = κ · 2^52 / 1000: take κ·2^52 as I12F52 bits, then divide in integers.
        let v = fixed::types::I12F52::checked_from_num(kappa)?.to_bits();
        let q = v / 1000
            + if v % 1000 >= 500 {
                1
            } else if v % 1000 <= -500 {
                -1
            } else {
                0
            };
        i32::try_from(q).ok()
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
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let g = Fixed::g_from_f64(5e-8).unwrap();
        let e = Fixed::gravity(g, Fixed::l_from_f64(1000.0).unwrap());
        assert!((Fixed::u_to_f64(e) - 5e-5).abs() < 2e-9);
        let k = Fixed::k_from_f64(2.3e-5).unwrap();
        let s = Fixed::thermal(k, 15_000);
        assert!((Fixed::u_to_f64(s) - 2.3e-5 * 15.0).abs() < 2e-9);
        assert!(Fixed::g_from_f64(1e-3).is_none());
        assert!(Fixed::l_from_f64(3000.0).is_none());
        assert!(Fixed::u_from_f64(f64::NAN).is_none());
    }
}
