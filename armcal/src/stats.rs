//! Every distribution the tool uses, in one place: the F, t, normal and χ² tails (a cause's
//! in-sample test, a calibration's significance test), the paired comparison of held-out
//! errors a diagnosis's out-of-sample test rests on, the exact binomial tail (the sign test,
//! with the smallest p a number of sessions allows; a held-out group's coverage).

/// ln Γ(x) for x > 0 (Lanczos, g = 7, nine terms; relative error below 1e-14).
pub(crate) fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x) Γ(1 − x) = π / sin(πx).
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// The regularised incomplete beta function I_x(a, b) (continued fraction, Lentz).
pub(crate) fn inc_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln();
    // The fraction converges fast for x < (a + 1) / (a + b + 2); use the symmetry otherwise.
    if x < (a + 1.0) / (a + b + 2.0) {
        ln_front.exp() * beta_fraction(a, b, x) / a
    } else {
        1.0 - ln_front.exp() * beta_fraction(b, a, 1.0 - x) / b
    }
}

fn beta_fraction(a: f64, b: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < TINY {
        d = TINY;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..500 {
        let m = m as f64;
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        d = if d.abs() < TINY { TINY } else { d };
        c = 1.0 + aa / c;
        c = if c.abs() < TINY { TINY } else { c };
        d = 1.0 / d;
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        d = if d.abs() < TINY { TINY } else { d };
        c = 1.0 + aa / c;
        c = if c.abs() < TINY { TINY } else { c };
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < 1e-15 {
            break;
        }
    }
    h
}

/// P(F > f) for an F distribution with (d1, d2) degrees of freedom.
pub(crate) fn f_tail(f: f64, d1: f64, d2: f64) -> f64 {
    if f.is_nan() || f <= 0.0 || d1 <= 0.0 || d2 <= 0.0 {
        return 1.0;
    }
    inc_beta(d2 / 2.0, d1 / 2.0, d2 / (d2 + d1 * f))
}

/// P(T > t) for Student's t with `df` degrees of freedom (one-sided).
pub fn t_tail(t: f64, df: f64) -> f64 {
    if t.is_nan() || df <= 0.0 {
        return 1.0;
    }
    if t.is_infinite() {
        return if t > 0.0 { 0.0 } else { 1.0 };
    }
    let half = 0.5 * inc_beta(df / 2.0, 0.5, df / (df + t * t));
    if t > 0.0 {
        half
    } else {
        1.0 - half
    }
}

/// The two-sided critical value of Student's t with `df` degrees of freedom at `alpha`
/// (bisection on [`t_tail`]).
pub fn t_critical(alpha: f64, df: f64) -> f64 {
    let target = alpha / 2.0;
    let (mut lo, mut hi) = (0.0f64, 1e3f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if t_tail(mid, df) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// P(Z > z) for a standard normal Z (the t tail with unbounded degrees of freedom).
pub(crate) fn normal_tail(z: f64) -> f64 {
    t_tail(z, 1e12)
}

/// P(|Z| > t) for a standard normal Z, through [`erfc`]. The calibration's significance test
/// uses it; kept beside [`normal_tail`] (which is exact to rounding) because the calibration's
/// figures were measured with it.
pub(crate) fn normal_tail_two_sided(t: f64) -> f64 {
    erfc(t / std::f64::consts::SQRT_2)
}

/// P(χ²_k > w) for k = 1 or 2 (and a Wilson–Hilferty approximation beyond).
pub(crate) fn chi2_tail(w: f64, k: usize) -> f64 {
    match k {
        1 => erfc((w / 2.0).sqrt()),
        2 => (-w / 2.0).exp(),
        _ => {
            let k = k as f64;
            let z = ((w / k).cbrt() - (1.0 - 2.0 / (9.0 * k))) / (2.0 / (9.0 * k)).sqrt();
            0.5 * erfc(z / std::f64::consts::SQRT_2)
        }
    }
}

/// The complementary error function (Numerical Recipes' erfcc, relative error below 1.2e-7).
pub(crate) fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
            .exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// Exact one-sided sign test: P(X ≥ `better`) for X ~ Binomial(`n`, ½), the chance that a
/// model no better than the other wins on at least `better` of `n` independent units (held-out
/// sessions). It assumes nothing about the size or the distribution of the differences, only
/// that each unit is a fair coin under the null, so it is the test an outside reader checks by
/// hand. Ties are the caller's to count: [`crate::diagnose::nested`] counts a tie as a loss,
/// which can only make the p larger.
pub fn sign_test_p(better: usize, n: usize) -> f64 {
    if n == 0 || better == 0 {
        return 1.0;
    }
    binomial_at_least(better.min(n), n, 0.5)
}

/// P(X ≥ `k`) for X ~ Binomial(`n`, `p`): the sign test's tail ([`sign_test_p`]) and a
/// held-out group's coverage against 95 % ([`crate::uncertainty::misfit::group_coverage`],
/// as P(misses ≥ m) with p = 0.05).
pub fn binomial_at_least(k: usize, n: usize, p: f64) -> f64 {
    if k == 0 || p >= 1.0 {
        return 1.0;
    }
    if k > n || p <= 0.0 || p.is_nan() {
        return 0.0;
    }
    let top = p.powf(n as f64);
    if n <= 1000 && top > 1e-290 {
        // Σ_{j ≥ k} C(n, j) pʲ qⁿ⁻ʲ from the top term pⁿ down, each term the one above times
        // j/(n − j + 1) · q/p: exact to rounding, no overflow.
        let r = (1.0 - p) / p;
        let mut term = top;
        let mut sum = term;
        for j in (k + 1..=n).rev() {
            term *= j as f64 / (n - j + 1) as f64 * r;
            sum += term;
        }
        return sum.min(1.0);
    }
    let ln_choose = |j: usize| {
        ln_gamma(n as f64 + 1.0) - ln_gamma(j as f64 + 1.0) - ln_gamma((n - j) as f64 + 1.0)
    };
    let (lp, lq) = (p.ln(), (1.0 - p).ln());
    (k..=n)
        .map(|j| (ln_choose(j) + j as f64 * lp + (n - j) as f64 * lq).exp())
        .sum::<f64>()
        .min(1.0)
}

/// The smallest one-sided p any test that only uses the signs (or the sign-flips) of `n`
/// paired units can give: ½ⁿ, when every unit goes one way. With 4 sessions no such test can
/// reach p < 0.0625, so a claim at 5 % needs 5 sessions or more; the t-test can go lower only
/// by assuming the differences are normal.
pub fn min_sign_p(n: usize) -> f64 {
    0.5f64.powi(n.min(i32::MAX as usize) as i32)
}

/// Percentile bootstrap interval of the mean of `x` (units resampled with replacement,
/// `draws` times, from a seeded ChaCha8 generator so the figure is reproducible): the
/// (1 − `level`)/2 and (1 + `level`)/2 quantiles of the resampled means. With few units
/// (7 test sessions) it is narrower than it should be (the resamples cannot go beyond the
/// units seen); it is reported beside the paired t- and sign tests, not instead of them.
/// `None` for no units.
pub fn bootstrap_mean_interval(
    x: &[f64],
    level: f64,
    draws: usize,
    seed: u64,
) -> Option<(f64, f64)> {
    use rand::{Rng, SeedableRng};
    if x.is_empty() || draws == 0 {
        return None;
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let n = x.len();
    let mut means: Vec<f64> = (0..draws)
        .map(|_| (0..n).map(|_| x[rng.gen_range(0..n)]).sum::<f64>() / n as f64)
        .collect();
    means.sort_by(f64::total_cmp);
    let q = |p: f64| means[((p * draws as f64).floor() as usize).min(draws - 1)];
    Some((q((1.0 - level) / 2.0), q((1.0 + level) / 2.0)))
}

/// Fewest held-out units for held-out evidence.
pub const MIN_UNITS: usize = 3;

/// A paired comparison of two models' held-out errors over the same units (a `point` row, a
/// `spat` or `length` group): how much the second lowers the sum of squares, and the standard
/// error of that from the spread of the per-unit differences.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Paired {
    /// Σ over units of (first − second) squared error (mm²): positive when the second is
    /// better.
    pub gain: f64,
    /// Standard error of `gain` (mm²): √U · sd of the per-unit differences.
    pub se: f64,
    /// Units compared.
    pub units: usize,
}

impl Paired {
    /// From per-unit sums of squares of the two models.
    pub fn of(first: &[f64], second: &[f64]) -> Paired {
        let d: Vec<f64> = first.iter().zip(second).map(|(a, b)| a - b).collect();
        let u = d.len();
        if u == 0 {
            return Paired {
                gain: 0.0,
                se: f64::INFINITY,
                units: 0,
            };
        }
        let mean = d.iter().sum::<f64>() / u as f64;
        let var = if u > 1 {
            d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (u - 1) as f64
        } else {
            f64::INFINITY
        };
        Paired {
            gain: mean * u as f64,
            se: (var * u as f64).sqrt(),
            units: u,
        }
    }

    /// One-sided p-value of the gain (paired t-test, units − 1 degrees of freedom): the
    /// chance of a gain this large if the second model predicted no better. Few units (three
    /// sessions) need a large gain: t > 4.5 at the level of z = 2. Fewer than
    /// [`MIN_UNITS`] units give 1: the spread of the gains over two units says too little
    /// (and the test leans wholly on their normality), so two sessions confirm nothing.
    pub fn p_value(&self) -> f64 {
        if self.units < MIN_UNITS {
            return 1.0;
        }
        t_tail(self.z(), (self.units - 1) as f64)
    }

    /// Gain in standard errors.
    pub fn z(&self) -> f64 {
        if self.se > 0.0 {
            self.gain / self.se
        } else if self.gain > 0.0 {
            f64::INFINITY
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_matches_factorials() {
        for (n, f) in [(1.0, 1.0), (5.0, 24.0), (10.0, 362_880.0)] {
            assert!((ln_gamma(n) - f64::ln(f)).abs() < 1e-12, "{n}");
        }
        assert!((ln_gamma(0.5) - std::f64::consts::PI.sqrt().ln()).abs() < 1e-12);
    }

    #[test]
    fn f_tail_matches_tables() {
        // Upper 5 % and 1 % points of F from standard tables.
        for (f, d1, d2, p) in [
            (4.35, 1.0, 20.0, 0.05),
            (3.49, 2.0, 20.0, 0.05),
            (8.10, 1.0, 20.0, 0.01),
            (3.84, 1.0, 1e6, 0.05),
            (4.61, 2.0, 1e6, 0.01),
        ] {
            let got = f_tail(f, d1, d2);
            assert!(
                (got - p).abs() < 0.002 * p.max(0.01) / 0.01,
                "F({d1},{d2}) > {f}: {got}"
            );
        }
        // With d1 = 2 and d2 → ∞, 2F is χ²₂, whose tail is exp(−F).
        assert!((f_tail(10.0, 2.0, 1e9) - (-10.0f64).exp()).abs() < 1e-8);
        assert_eq!(f_tail(0.0, 1.0, 10.0), 1.0);
    }

    #[test]
    fn t_tail_matches_tables() {
        // Upper points of Student's t: t(0.025; 2) = 4.303, t(0.05; 8) = 1.860, t(0.01; 30) = 2.457.
        for (t, df, p) in [(4.303, 2.0, 0.025), (1.860, 8.0, 0.05), (2.457, 30.0, 0.01)] {
            let got = t_tail(t, df);
            assert!((got - p).abs() < 0.01 * p, "t({df}) > {t}: {got}");
        }
        assert!((t_tail(-1.860, 8.0) - 0.95).abs() < 1e-3);
        assert!((normal_tail(2.0) - 0.02275).abs() < 1e-5);
        assert_eq!(t_tail(0.0, 5.0), 0.5);
    }

    #[test]
    fn paired_gain_and_error() {
        let a = [2.0, 3.0, 4.0, 5.0];
        let b = [1.0, 2.0, 3.0, 4.0];
        let p = Paired::of(&a, &b);
        assert_eq!(p.gain, 4.0);
        assert_eq!(p.se, 0.0);
        assert!(p.z().is_infinite());
        let p = Paired::of(&b, &a);
        assert!(p.gain < 0.0 && p.z() <= 0.0);
        let c = [1.0, 3.0, 2.0, 6.0];
        let p = Paired::of(&a, &c);
        assert!((p.gain - 2.0).abs() < 1e-12);
        assert!(p.se > 0.0 && p.z() < 1.0);
        // Two units prove nothing, however consistent.
        assert_eq!(Paired::of(&[5.0, 5.1], &[1.0, 1.0]).p_value(), 1.0);
        assert!(Paired::of(&[5.0, 5.1, 5.05], &[1.0, 1.0, 1.0]).p_value() < 1e-3);
    }

    #[test]
    fn sign_test_is_the_binomial_tail() {
        // 6 of 6: 1/64; 5 of 6: 7/64; 4 of 4: 1/16; 3 of 4: 5/16; 0 of n: 1.
        assert!((sign_test_p(6, 6) - 1.0 / 64.0).abs() < 1e-12);
        assert!((sign_test_p(5, 6) - 7.0 / 64.0).abs() < 1e-12);
        assert!((sign_test_p(4, 4) - 0.0625).abs() < 1e-12);
        assert!((sign_test_p(3, 4) - 5.0 / 16.0).abs() < 1e-12);
        assert_eq!(sign_test_p(0, 5), 1.0);
        assert_eq!(sign_test_p(0, 0), 1.0);
        // 8 of 10: (45 + 10 + 1) / 1024.
        assert!((sign_test_p(8, 10) - 56.0 / 1024.0).abs() < 1e-12);
        // Large n stays finite and matches the symmetric middle: P(X ≥ 100 | n = 200) > ½.
        let p = sign_test_p(100, 200);
        assert!(p > 0.5 && p < 0.56, "{p}");
        let p = sign_test_p(1000, 2000);
        assert!(p > 0.5 && p < 0.52, "{p}");
    }

    /// The general tail: small cases by hand, the complement of the lower tail, and the
    /// long path (terms in logs) where pⁿ would underflow.
    #[test]
    fn the_binomial_tail_is_its_sum() {
        // P(X ≥ 2 | 3, 0.9) = 3 · 0.81 · 0.1 + 0.729 = 0.972.
        assert!((binomial_at_least(2, 3, 0.9) - 0.972).abs() < 1e-12);
        assert_eq!(binomial_at_least(0, 5, 0.3), 1.0);
        assert_eq!(binomial_at_least(6, 5, 0.3), 0.0);
        // P(X ≥ k) + P(X ≤ k − 1) = 1, the latter as P(n − X ≥ n − k + 1) with 1 − p.
        for (k, n, p) in [
            (3, 10, 0.3),
            (50, 60, 0.95),
            (590, 600, 0.05),
            (12, 2000, 0.01),
        ] {
            let s = binomial_at_least(k, n, p) + binomial_at_least(n - k + 1, n, 1.0 - p);
            assert!((s - 1.0).abs() < 1e-9, "{k} {n} {p}: {s}");
        }
        // 0.05⁶⁰⁰ underflows: the log path. P(misses ≥ 30 | 600, 0.05) is about ½ (mean 30).
        let mid = binomial_at_least(30, 600, 0.05);
        assert!(mid > 0.45 && mid < 0.6, "{mid}");
    }

    #[test]
    fn the_smallest_p_sessions_allow() {
        assert_eq!(min_sign_p(4), 0.0625);
        assert!((min_sign_p(6) - 1.0 / 64.0).abs() < 1e-15);
        // It is the sign test's p when every unit goes one way.
        for n in 1..12 {
            assert!((sign_test_p(n, n) - min_sign_p(n)).abs() < 1e-12, "{n}");
        }
        // Four sessions cannot reach 5 %, five can.
        assert!(min_sign_p(4) > 0.05 && min_sign_p(5) < 0.05);
    }

    #[test]
    fn bootstrap_interval_holds_the_mean_and_shrinks_with_units() {
        let x: Vec<f64> = (0..7).map(|i| i as f64).collect();
        let (lo, hi) = bootstrap_mean_interval(&x, 0.95, 4000, 1).unwrap();
        assert!(lo < 3.0 && hi > 3.0 && lo >= 0.0 && hi <= 6.0, "{lo} {hi}");
        // Reproducible from its seed.
        assert_eq!(bootstrap_mean_interval(&x, 0.95, 4000, 1), Some((lo, hi)));
        // Four times the units (same spread): about half the width.
        let y: Vec<f64> = (0..28).map(|i| (i % 7) as f64).collect();
        let (a, b) = bootstrap_mean_interval(&y, 0.95, 4000, 1).unwrap();
        let ratio = (b - a) / (hi - lo);
        assert!(ratio > 0.35 && ratio < 0.65, "{ratio}");
        assert_eq!(bootstrap_mean_interval(&[], 0.95, 100, 1), None);
        assert_eq!(
            bootstrap_mean_interval(&[2.0; 3], 0.95, 100, 1),
            Some((2.0, 2.0))
        );
    }
}
