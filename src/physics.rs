//! The physical effects' terms in each evaluator's numbers: gravity deflection and thermal
//! expansion.
//!
//! [`crate::scalar::Arithmetic`] is the number format alone; what the model computes with it
//! for the arm's physical effects is here, one trait implemented by both formats. Each
//! effect's quantity gets a type of its own because fixed point needs its own scaling for it:
//! a gravity coefficient of 1e-8 rad/mm and an expansion rate of 1e-5 mm/m°C are far below
//! the resolution of the unit and length formats.

use core::fmt::Debug;

use crate::scalar::{finite_below, fixed_bits, mul_shift, Arithmetic, Fixed, Len, Unit, F32};

/// The terms of the physical effects in one evaluator's numbers.
pub trait Physics: Arithmetic {
    /// The gravity compliance coefficient, the parameter `gravity` (rad/mm).
    type Gravity: Copy + Default + Debug;
    /// A length's thermal expansion rate: mm per milli-degree Celsius.
    type R: Copy + Default + Debug;
    /// A temperature offset from 20 °C, converted once per reading.
    type T: Copy + Default + Debug;

    /// Gravity deflection angle `g · x` for a lever term x (mm).
    fn gravity(g: Self::Gravity, x: Self::L) -> Self::U;
    /// A temperature offset ΔT (milli-degrees Celsius, |ΔT| ≤ 10^5) in evaluator form.
    fn temperature(dt_mc: i32) -> Self::T;
    /// The thermal expansion `rate · ΔT` of a length (mm).
    fn expansion(rate: Self::R, dt: Self::T) -> Self::L;

    /// Conversion of a gravity coefficient (rad/mm); `None` where it does not fit.
    fn gravity_from_f64(g: f64) -> Option<Self::Gravity>;
    /// Conversion of an expansion rate (mm/°C); `None` where it does not fit.
    fn r_from_f64(mm_per_degc: f64) -> Option<Self::R>;
}

impl Physics for F32 {
    type Gravity = f32;
    type R = f32;
    type T = f32;

    #[inline(always)]
    fn gravity(g: f32, x: f32) -> f32 {
        g * x
    }
    #[inline(always)]
    fn temperature(dt_mc: i32) -> f32 {
        // Exact: |ΔT| ≤ 10^5 < 2^24.
        dt_mc as f32
    }
    #[inline(always)]
    fn expansion(rate: f32, dt: f32) -> f32 {
        rate * dt
    }
    fn gravity_from_f64(g: f64) -> Option<f32> {
        finite_below(g, 1.0).map(|x| x as f32)
    }
    fn r_from_f64(mm_per_degc: f64) -> Option<f32> {
        finite_below(mm_per_degc, 1.0e3).map(|x| (x / 1000.0) as f32)
    }
}

/// Fractional bits of the gravity coefficient: g·2^48 in an i32 (|g| < 7.6e-6 rad/mm,
/// resolution 3.6e-15 rad/mm: 7e-12 rad over a 2 m lever).
const G_FRAC: u32 = 48;
/// Fractional bits of an expansion rate in mm per milli-degree: 2^40 (|rate| < 1.9e-3 mm/m°C,
/// where 2 m at κ = 4e-4 /°C needs 8e-4; resolution 0.1 nm over 100 °C).
const R_FRAC: u32 = 40;

impl Physics for Fixed {
    type Gravity = i32;
    type R = i32;
    type T = i32;

    #[inline(always)]
    fn gravity(g: i32, x: Len) -> Unit {
        // g·2^48 · x·2^20 → ·2^30: shift 38.
        Unit::from_bits(mul_shift(g, x.bits(), G_FRAC + 20 - 30))
    }
    #[inline(always)]
    fn temperature(dt_mc: i32) -> i32 {
        dt_mc
    }
    #[inline(always)]
    fn expansion(rate: i32, dt_mc: i32) -> Len {
        Len::from_bits(mul_shift(rate, dt_mc, R_FRAC - 20))
    }
    fn gravity_from_f64(g: f64) -> Option<i32> {
        fixed_bits(g, G_FRAC)
    }
    fn r_from_f64(mm_per_degc: f64) -> Option<i32> {
        fixed_bits(mm_per_degc / 1000.0, R_FRAC)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_gravity_and_expansion() {
        let g = Fixed::gravity_from_f64(5e-8).unwrap();
        let e = Fixed::gravity(g, Fixed::l_from_f64(1000.0).unwrap());
        assert!((Fixed::u_to_f64(e) - 5e-5).abs() < 2e-9);
        let r = Fixed::r_from_f64(300.0 * 2.3e-5).unwrap();
        let x = Fixed::expansion(r, 15_000);
        assert!((Fixed::l_to_f64(x) - 300.0 * 2.3e-5 * 15.0).abs() < 1e-6);
        assert!(Fixed::r_from_f64(2.0).is_none());
        assert!(Fixed::gravity_from_f64(1e-3).is_none());
    }
}
