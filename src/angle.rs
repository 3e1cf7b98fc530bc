//! Joint angles from raw encoder counts: integer range reduction to an exact quarter turn and
//! a small remainder, its sine and cosine, and what the chains build from them (the full
//! angle, the joint quaternion's half angle, the harmonics' multiple angles).
//!
//! A count never passes through a rounded floating-point angle. It becomes a 32-bit binary
//! angle t (one turn = 2^32) by one integer multiply (a shift for the usual power-of-two
//! encoder). Its top two bits, rounded, give the quadrant q: θ = q·π/2 + 2x with the half
//! remainder x = r·π/2^32, |r| ≤ 2^29, |x| ≤ π/8. Quarter turns are exact for vectors (a
//! permutation with signs); x is small, so a turn by 2x written as a correction to the vector
//! (v + (sin 2x · v⊥ − (1 − cos 2x) · v)) rounds little more than v itself. That is what keeps
//! the f32 chain's large partial sums accurate ([`crate::chain`]).
//!
//! sin x and cos x − 1 are minimax polynomials in x² on [−π/8, π/8] (absolute error 4e-12 and
//! 1.3e-10, under an eighth of the fixed-point resolution). Computing cos x − 1 directly keeps
//! its relative accuracy where it is small, which the correction form needs.

use crate::scalar::{mul_wide_u, Arithmetic, Scale};

/// Converts counts of one joint into 32-bit binary angles (one turn = 2^32).
///
/// For `counts_per_rev` = 2^k: t = count · 2^(32−k), exact. Otherwise t = round(count' · K /
/// 2^31) with count' = count · 2^(31−j), K = round(2^(32+j) / N) ∈ [2^31, 2^32), j = ⌊log2 N⌋,
/// off by at most 1.5 units of 2^-32 turn (2.2e-9 rad, 3 nm at 1.5 m).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CountScale {
    counts: u32,
    k: u32,
    /// Left shift of the count: 32 − k for 2^k counts, 31 − j otherwise.
    pre: u8,
    /// Whether `counts` is a power of two (then t = count << pre, no multiply).
    pow2: bool,
}

/// ⌊num / den⌋ (den ≤ 2^31) by shift and subtract, one quotient bit a step: the one 64-bit
/// division of the chains, at boot, without the runtime's, whose code (1.3 KB with its
/// 32-bit helper) the Cortex-M0 hub's image has no room for.
fn div_u64(num: u64, den: u64) -> u64 {
    let (mut q, mut r) = (0u64, 0u64);
    for i in (0..64).rev() {
        // r < den ≤ 2^31 before the shift: no bit is lost.
        r = (r << 1) | ((num >> i) & 1);
        if r >= den {
            r -= den;
            q |= 1 << i;
        }
    }
    q
}

impl CountScale {
    /// The scale for `counts_per_rev` counts per revolution; `None` outside 2..=2^31 − 1.
    pub fn new(counts_per_rev: u32) -> Option<CountScale> {
        if !(2..=i32::MAX as u32).contains(&counts_per_rev) {
            return None;
        }
        let j = 31 - counts_per_rev.leading_zeros(); // ⌊log2 N⌋
        if counts_per_rev.is_power_of_two() {
            return Some(CountScale {
                counts: counts_per_rev,
                k: 0,
                pre: (32 - j) as u8,
                pow2: true,
            });
        }
        let n = u64::from(counts_per_rev);
        let k = div_u64((1u64 << (32 + j)) + n / 2, n); // in [2^31, 2^32)
        Some(CountScale {
            counts: counts_per_rev,
            k: k as u32,
            pre: (31 - j) as u8,
            pow2: false,
        })
    }

    /// Counts per revolution.
    #[inline(always)]
    pub fn counts(&self) -> u32 {
        self.counts
    }

    /// For a power-of-two count per revolution, the binary angle of one count, 2^(32−k): the
    /// binary angle of a count is then `count.wrapping_mul(unit)`, one multiply with no test of
    /// the scale's kind (the lean chain, [`crate::lean`], takes it where every joint has one).
    pub fn unit(&self) -> Option<u32> {
        self.pow2.then(|| 1u32 << (self.pre & 31))
    }

    /// The binary angle of a count (the caller has checked `count < counts()`).
    #[inline(always)]
    pub fn binary(&self, count: u32) -> u32 {
        let c = count << (self.pre & 31);
        if self.pow2 {
            c
        } else {
            // c < 2^32 and K < 2^32: the product and the rounding constant fit in a u64.
            ((mul_wide_u(c, self.k) + (1 << 30)) >> 31) as u32
        }
    }
}

/// A joint's raw reading split as θ = q·π/2 + 2x, |x| ≤ π/8.
#[derive(Clone, Copy, Debug, Default)]
pub struct Quarter<P: Arithmetic> {
    /// Quadrant q, 0..=3: whole quarter turns.
    pub q: u8,
    /// cos x − 1.
    pub cm1: P::U,
    /// sin x.
    pub s: P::U,
}

impl<P: Arithmetic> Quarter<P> {
    /// Splits a binary angle (one turn = 2^32) and evaluates the remainder's sine and cosine.
    #[inline(always)]
    pub fn from_binary(t: u32) -> Quarter<P> {
        let q = t.wrapping_add(1 << 29) >> 30;
        let r = t.wrapping_sub(q << 30) as i32; // |r| ≤ 2^29
        let x = P::angle(r);
        let z = x.scale(x);
        let [s1, s2, s3] = P::SIN;
        let [c1, c2, c3] = P::COS;
        let s = x + x.scale(z).scale(s1 + z.scale(s2 + z.scale(s3)));
        let cm1 = z.scale(c1 + z.scale(c2 + z.scale(c3)));
        Quarter { q: q as u8, cm1, s }
    }

    /// The same remainder turned by a small extra angle 2h (harmonic and gravity
    /// deflections, |h| ≤ 1e-3), to second order: x → x + h.
    #[inline(always)]
    pub fn turned(self, h: P::U) -> Quarter<P> {
        self.turned_by(h, P::half(h.scale(h)))
    }

    /// The same remainder turned by a small angle h given as sin h and 1 − cos h: x → x + h.
    #[inline(always)]
    pub fn turned_by(self, sin: P::U, omc: P::U) -> Quarter<P> {
        let c = P::ONE + self.cm1;
        Quarter {
            q: self.q,
            cm1: self.cm1 - (self.s.scale(sin) + c.scale(omc)),
            s: self.s + (c.scale(sin) - self.s.scale(omc)),
        }
    }

    /// sin 2x and 1 − cos 2x = 2 sin²x: the remainder turn of a vector.
    #[inline(always)]
    pub fn double(&self) -> (P::U, P::U) {
        let s2 = self.s + self.s;
        (s2.scale(P::ONE + self.cm1), self.s.scale(s2))
    }

    /// cos θ and sin θ: the remainder's double angle, then the quadrant (exact).
    #[inline(always)]
    pub fn full(&self) -> (P::U, P::U) {
        let (sin2, omc) = self.double();
        quarter_turns(self.q, (P::ONE - omc, sin2))
    }

    /// cos θ/2 and sin θ/2 up to a shared sign, for the joint quaternion: the half remainder
    /// x turned by q·π/4 — exact for even q, one rounding of (c ∓ s)·√½ for odd q.
    #[inline(always)]
    pub fn half(&self) -> (P::U, P::U) {
        let (mut c, mut s) = (P::ONE + self.cm1, self.s);
        if self.q & 2 != 0 {
            (c, s) = (-s, c);
        }
        if self.q & 1 != 0 {
            (c, s) = ((c - s).scale(P::SQRT_HALF), (c + s).scale(P::SQRT_HALF));
        }
        (c, s)
    }
}

/// (x, y) turned by q quarter turns about z: exact.
#[inline(always)]
pub fn quarter_turns<E: Copy + core::ops::Neg<Output = E>>(q: u8, (x, y): (E, E)) -> (E, E) {
    match q & 3 {
        0 => (x, y),
        1 => (-y, x),
        2 => (-x, -y),
        _ => (y, -x),
    }
}

/// sin(hθ) and cos(hθ) for h = 1, 2, … from sin θ, cos θ: angle doubling where it reaches
/// the next wanted order, else one angle-addition step — a complex product instead of a sine
/// and cosine each.
#[derive(Clone, Copy, Debug)]
pub struct Multiples<P: Arithmetic> {
    c1: P::U,
    s1: P::U,
    /// cos(hθ) of the current order.
    pub c: P::U,
    /// sin(hθ) of the current order.
    pub s: P::U,
    /// The current order h.
    pub order: u32,
}

impl<P: Arithmetic> Multiples<P> {
    /// Starts at order 1.
    #[inline(always)]
    pub fn new(cos: P::U, sin: P::U) -> Multiples<P> {
        Multiples {
            c1: cos,
            s1: sin,
            c: cos,
            s: sin,
            order: 1,
        }
    }

    /// Advances to order `h` (no-op if already there or past it).
    #[inline(always)]
    pub fn advance(&mut self, h: u32) {
        while self.order < h {
            if 2 * self.order <= h {
                let cs = self.c.scale(self.s);
                self.c = (self.c - self.s).scale(self.c + self.s);
                self.s = cs + cs;
                self.order *= 2;
            } else {
                let c = self.c.scale(self.c1) - self.s.scale(self.s1);
                let s = self.s.scale(self.c1) + self.c.scale(self.s1);
                self.c = c;
                self.s = s;
                self.order += 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::{Fixed, F32};

    proptest::proptest! {
        /// The shift-and-subtract division is the runtime's, for every quotient a scale
        /// takes (a numerator below 2^63, a divisor of 2..2^31).
        #[test]
        fn the_boot_division_is_exact(num in 0u64..(1 << 63), den in 2u64..(1 << 31)) {
            proptest::prop_assert_eq!(div_u64(num, den), num / den);
        }
    }

    fn check_remainder<P: Arithmetic>(step: usize, tol: f64) -> f64 {
        let mut worst = 0.0f64;
        for r in (-(1i64 << 29)..=(1i64 << 29)).step_by(step) {
            let a = Quarter::<P>::from_binary(r as u32);
            assert!(a.q <= 1);
            let x = (r as f64 - f64::from(a.q) * 1_073_741_824.0) * core::f64::consts::PI
                / 4_294_967_296.0;
            worst = worst
                .max((P::u_to_f64(a.cm1) - (x.cos() - 1.0)).abs())
                .max((P::u_to_f64(a.s) - x.sin()).abs());
        }
        assert!(worst < tol, "{} remainder error {worst:e}", P::NAME);
        worst
    }

    #[test]
    fn remainder_f32_dense_sweep() {
        // Every 61st remainder over ±π/8: 17.6 million evaluations.
        check_remainder::<F32>(61, 6e-8);
    }

    #[test]
    fn remainder_fixed_dense_sweep() {
        check_remainder::<Fixed>(59, 2e-9);
    }

    /// Largest errors over every count of a 2^20 encoder: (cos θ, sin θ) and the half angle
    /// (sign-aligned).
    fn every_count<P: Arithmetic>() -> (f64, f64) {
        let scale = CountScale::new(1 << 20).unwrap();
        let mut worst = (0.0f64, 0.0f64);
        for count in 0..1u32 << 20 {
            let theta = 2.0 * core::f64::consts::PI * count as f64 / (1u64 << 20) as f64;
            let t = scale.binary(count);
            assert_eq!(t, count << 12);
            assert_eq!(t, count.wrapping_mul(scale.unit().unwrap()));
            let a = Quarter::<P>::from_binary(t);
            let (fc, fs) = a.full();
            worst.0 = worst
                .0
                .max((P::u_to_f64(fc) - theta.cos()).abs())
                .max((P::u_to_f64(fs) - theta.sin()).abs());
            let (c, s) = a.half();
            let (c, s) = (P::u_to_f64(c), P::u_to_f64(s));
            let (hc, hs) = ((theta / 2.0).cos(), (theta / 2.0).sin());
            let sign = if c * hc + s * hs < 0.0 { -1.0 } else { 1.0 };
            worst.1 = worst
                .1
                .max((sign * c - hc).abs())
                .max((sign * s - hs).abs());
        }
        worst
    }

    #[test]
    fn every_count_of_a_2_20_encoder() {
        let (f, h) = every_count::<F32>();
        assert!(f < 1.2e-7, "f32 full-angle {f:e}");
        assert!(h < 1.5e-7, "f32 half-angle {h:e}");
        let (f, h) = every_count::<Fixed>();
        assert!(f < 4e-9, "fixed full-angle {f:e}");
        assert!(h < 4e-9, "fixed half-angle {h:e}");
    }

    #[test]
    fn small_turn_is_second_order() {
        let t = 0x1234_5678u32;
        let h = 7e-4f64;
        let a = Quarter::<F32>::from_binary(t).turned(h as f32);
        let theta = t as f64 / 4_294_967_296.0 * 2.0 * core::f64::consts::PI + 2.0 * h;
        let (c, s) = a.full();
        assert!((f64::from(c) - theta.cos()).abs() < 2e-7);
        assert!((f64::from(s) - theta.sin()).abs() < 2e-7);
    }

    #[test]
    fn quarter_turns_follow_the_right_hand() {
        assert_eq!(quarter_turns(1, (1.0f32, 0.0)), (0.0, 1.0));
        assert_eq!(quarter_turns(2, (1.0f32, 2.0)), (-1.0, -2.0));
        assert_eq!(quarter_turns(3, (0.0f32, 1.0)), (1.0, 0.0));
    }

    #[test]
    fn odd_counts_per_revolution() {
        for n in [
            2u32,
            3,
            360,
            14_400,
            1_000_000,
            (1 << 31) - 1,
            1 << 24,
            1 << 20,
        ] {
            let scale = CountScale::new(n).unwrap();
            for count in [0, 1, n / 3, n / 2, n - 1] {
                let want = count as f64 / n as f64 * 4_294_967_296.0;
                let got = scale.binary(count) as f64;
                assert!(
                    (got - want).abs() <= 1.5,
                    "n={n} count={count}: {got} vs {want}"
                );
            }
        }
        assert_eq!(CountScale::new(360).unwrap().unit(), None);
        assert_eq!(CountScale::new(2).unwrap().unit(), Some(1 << 31));
        assert!(CountScale::new(0).is_none());
        assert!(CountScale::new(1).is_none());
        assert!(CountScale::new(1 << 31).is_none());
    }

    #[test]
    fn multiples_follow_the_recurrence() {
        let th = 0.73f64;
        for target in 1..=9u32 {
            let mut m = Multiples::<F32>::new(th.cos() as f32, th.sin() as f32);
            m.advance(target);
            assert_eq!(m.order, target);
            let h = target as f64;
            assert!((f64::from(m.s) - (h * th).sin()).abs() < 2e-6);
            assert!((f64::from(m.c) - (h * th).cos()).abs() < 2e-6);
        }
    }
}
