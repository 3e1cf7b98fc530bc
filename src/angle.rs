//! Joint angles from raw encoder counts: integer range reduction, half-angle sine and cosine,
//! full-angle sine and cosine, and the harmonics' multiple angles.
//!
//! A count never passes through a rounded floating-point angle. It becomes a 32-bit binary
//! angle t (one turn = 2^32) by one integer multiply; the top two bits of t (rounded) give the
//! quadrant q, an exact quarter turn that the chain applies as a permutation of components,
//! and the signed remainder r (|r| ≤ 2^29, an eighth of a turn) gives the half angle
//! x = r·π/2^32 ≤ π/8 of the joint's remaining rotation. The quaternion of that rotation is
//! (cos x, sin x · u); both come from short Taylor polynomials in x² whose truncation error
//! (< 3e-11) is far below either evaluator's resolution. Small arguments keep the relative
//! accuracy of the sine, which is what makes the half-angle form accurate in f32.

use crate::scalar::{mul_wide_u, Precision};

/// Converts counts of one joint into 32-bit binary angles (one turn = 2^32).
///
/// For `counts_per_rev` = N: t = round((count · K) / 2^j) with K = round(2^(32+j) / N) < 2^32,
/// j = ⌊log2 N⌋ (one less for a power of two, where K = 2^31 and t is exact). Otherwise off by
/// at most 1.5 units of 2^-32 turn (2.2e-9 rad, 3 nm at 1.5 m).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CountScale {
    counts: u32,
    k: u32,
    shift: u32,
}

impl CountScale {
    /// The scale for `counts_per_rev` counts per revolution; `None` outside 2..=2^31 − 1.
    pub fn new(counts_per_rev: u32) -> Option<CountScale> {
        if !(2..=i32::MAX as u32).contains(&counts_per_rev) {
            return None;
        }
        let mut j = 31 - counts_per_rev.leading_zeros(); // ⌊log2 N⌋
        if counts_per_rev.is_power_of_two() {
            j -= 1;
        }
        let n = u64::from(counts_per_rev);
        let k = ((1u64 << (32 + j)) + n / 2) / n; // < 2^32
        Some(CountScale {
            counts: counts_per_rev,
            k: k as u32,
            shift: j,
        })
    }

    /// Counts per revolution.
    pub fn counts(&self) -> u32 {
        self.counts
    }

    /// The binary angle of a count (the caller has checked `count < counts()`).
    #[inline(always)]
    pub fn binary(&self, count: u32) -> u32 {
        let half = (1u64 << self.shift) >> 1;
        ((mul_wide_u(count, self.k) + half) >> self.shift) as u32
    }
}

/// A joint's raw reading θ split for the chain: θ = q·π/2 + 2x.
#[derive(Clone, Copy, Debug, Default)]
pub struct JointAngle<P: Precision> {
    /// Quadrant q (0..=3): an exact quarter-turn rotation.
    pub quadrant: u8,
    /// cos x, x the half angle of the remainder (|x| ≤ π/8).
    pub c: P::U,
    /// sin x.
    pub s: P::U,
}

impl<P: Precision> JointAngle<P> {
    /// Splits a binary angle (one turn = 2^32) and evaluates the half-angle sine and cosine.
    #[inline(always)]
    pub fn from_binary(t: u32) -> JointAngle<P> {
        let mut quadrant = (t >> 30) as u8;
        let mut r = (t & 0x3fff_ffff) as i32;
        if r >= 1 << 29 {
            r -= 1 << 30;
            quadrant = (quadrant + 1) & 3;
        }
        let (c, s) = half_sin_cos::<P>(r);
        JointAngle { quadrant, c, s }
    }

    /// cos θ and sin θ of the whole raw reading: the double-angle formulas on the half angle,
    /// then the quadrant. Used for the harmonics and by the matrix chain.
    #[inline(always)]
    pub fn full(&self) -> (P::U, P::U) {
        let s2 = self.s.scale(self.s);
        let cr = P::ONE - (s2 + s2);
        let sc = self.s.scale(self.c);
        let sr = sc + sc;
        match self.quadrant {
            0 => (cr, sr),
            1 => (-sr, cr),
            2 => (-cr, -sr),
            _ => (sr, -cr),
        }
    }
}

use crate::scalar::Scale;

/// cos x and sin x for x = r·π/2^32, |r| ≤ 2^29.
#[inline(always)]
pub fn half_sin_cos<P: Precision>(r: i32) -> (P::U, P::U) {
    let x = P::half_angle(r);
    let x2 = x.scale(x);
    let [s1, s2, s3, s4] = P::SIN;
    let [c1, c2, c3, c4] = P::COS;
    let sp = s3 + x2.scale(s4);
    let sp = s2 + x2.scale(sp);
    let sp = s1 + x2.scale(sp);
    let sin = x + x.scale(x2.scale(sp));
    let cp = c3 + x2.scale(c4);
    let cp = c2 + x2.scale(cp);
    let cp = c1 + x2.scale(cp);
    let cos = P::ONE + x2.scale(cp);
    (cos, sin)
}

/// sin(hθ) and cos(hθ) for h = 1, 2, … by the angle-addition recurrence from sin θ, cos θ:
/// one complex multiplication per order instead of a sine and cosine each.
#[derive(Clone, Copy, Debug)]
pub struct Multiples<P: Precision> {
    c1: P::U,
    s1: P::U,
    /// cos(hθ) of the current order.
    pub c: P::U,
    /// sin(hθ) of the current order.
    pub s: P::U,
    /// The current order h.
    pub order: u32,
}

impl<P: Precision> Multiples<P> {
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

    /// Advances to the next order.
    #[inline(always)]
    pub fn step(&mut self) {
        let c = self.c.scale(self.c1) - self.s.scale(self.s1);
        let s = self.s.scale(self.c1) + self.c.scale(self.s1);
        self.c = c;
        self.s = s;
        self.order += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::{Fixed, F32};

    fn check_half<P: Precision>(step: usize, tol: f64) -> f64 {
        let mut worst = 0.0f64;
        for r in (-(1i64 << 29)..=(1i64 << 29)).step_by(step) {
            let (c, s) = half_sin_cos::<P>(r as i32);
            let x = r as f64 * core::f64::consts::PI / 4_294_967_296.0;
            worst = worst
                .max((P::u_to_f64(c) - x.cos()).abs())
                .max((P::u_to_f64(s) - x.sin()).abs());
        }
        assert!(worst < tol, "{} half-angle error {worst:e}", P::NAME);
        worst
    }

    #[test]
    fn half_angle_f32_dense_sweep() {
        // Every 64th remainder: 16.8 million evaluations.
        check_half::<F32>(64, 6.5e-8);
    }

    #[test]
    fn half_angle_fixed_dense_sweep() {
        check_half::<Fixed>(61, 3e-9);
    }

    #[test]
    fn every_count_of_a_2_20_encoder() {
        let scale = CountScale::new(1 << 20).unwrap();
        let mut worst = [0.0f64; 2];
        for count in 0..1u32 << 20 {
            let theta = 2.0 * core::f64::consts::PI * count as f64 / (1u64 << 20) as f64;
            let t = scale.binary(count);
            assert_eq!(t, count << 12);
            let a = JointAngle::<F32>::from_binary(t);
            let (c, s) = a.full();
            worst[0] = worst[0]
                .max((f64::from(c) - theta.cos()).abs())
                .max((f64::from(s) - theta.sin()).abs());
            let a = JointAngle::<Fixed>::from_binary(t);
            let (c, s) = a.full();
            worst[1] = worst[1]
                .max((Fixed::u_to_f64(c) - theta.cos()).abs())
                .max((Fixed::u_to_f64(s) - theta.sin()).abs());
        }
        assert!(worst[0] < 2.5e-7, "f32 full-angle {:e}", worst[0]);
        assert!(worst[1] < 6e-9, "fixed full-angle {:e}", worst[1]);
    }

    #[test]
    fn odd_counts_per_revolution() {
        for n in [2u32, 3, 360, 14_400, 1_000_000, (1 << 31) - 1, 1 << 24] {
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
        assert!(CountScale::new(0).is_none());
        assert!(CountScale::new(1).is_none());
        assert!(CountScale::new(1 << 31).is_none());
    }

    #[test]
    fn multiples_follow_the_recurrence() {
        let th = 0.73f64;
        let mut m = Multiples::<F32>::new(th.cos() as f32, th.sin() as f32);
        for h in 1..=8 {
            assert_eq!(m.order, h);
            assert!((f64::from(m.s) - (h as f64 * th).sin()).abs() < 1e-6);
            assert!((f64::from(m.c) - (h as f64 * th).cos()).abs() < 1e-6);
            m.step();
        }
    }
}
