//! U95: the radius r of the sphere about the estimate that holds the true point with
//! probability 0.95 when the error is N(0, Σ) (`spec/uncertainty.md`).
//!
//! |x|² is then a weighted sum λ₁z₁² + λ₂z₂² + λ₃z₃² of χ²(1) variables (z standard normal,
//! λ₁ ≥ λ₂ ≥ λ₃ the eigenvalues of Σ), with no closed form unless the weights are equal. Two
//! of the three integrals are done in closed form here, leaving one over an angle:
//!
//! - (z₁, z₂) in polar coordinates (ρ, φ): at fixed φ, λ₁z₁² + λ₂z₂² = q(φ)ρ² with
//!   q = λ₁cos²φ + λ₂sin²φ, and ρ²/2 is exponential, so P(q ρ² ≤ t) = 1 − e^(−t/2q).
//! - z₃ given that: E[1 − e^(−(s − λ₃z₃²)/2q); λ₃z₃² ≤ s] is a Gaussian integral of a
//!   Gaussian, erf(c) − e^(−s/2q) erf(x)/√b with c = √(s/2λ₃), b = 1 − λ₃/q ∈ [0, 1]
//!   (λ₃ ≤ q always, which is why the smallest weight is the one done last: the exponent's
//!   sign stays that of an erf, never of an erfi), x = c√b.
//!
//! So P(|x|² ≤ s) = erf(c) − ⟨e^(−s/2q) erf(x)/√b⟩_φ, and its derivative in s is
//! ⟨e^(−s/2q) erf(x)/(2q√b)⟩_φ (the erf(c) term's derivative cancels the rest exactly).
//! The average over φ is of a smooth π-periodic function, which the midpoint rule
//! integrates spectrally: 24 points on a quarter period at the 95 % level, where the fast
//! radius agrees with the nested quadrature it replaced ([`quadrature`]) to 2e-8 over 10⁵
//! random covariances, the floor both share (`stats::erfc`, 1.2e-7 relative).
//! Newton on s from a two-moment (Patnaik / Wilson–Hilferty) start, safeguarded by the
//! bracket [χ²₁, χ²₃ quantiles]·λ₁ (a step that leaves it bisects), stops at 1e-12 relative.
//! `cargo run --release -p armcal --example u95_speed` measures speed and error against
//! the quadrature.

pub mod quadrature;

use crate::stats::erfc;
use nalgebra::{Matrix3, SymmetricEigen};
use std::f64::consts::{FRAC_PI_2, PI};

/// The probability the radius is for.
pub const LEVEL: f64 = 0.95;

/// Midpoint nodes on the quarter period [0, π/2] of the angle average, for |x|²/λ₁ ≥ 3.84
/// (every 95 % radius). Below, e^(−s/2q) turns on within √s of φ = π/2 where Σ is flat, and
/// the count grows as 1/√s ([`nodes_for`]).
const NODES: usize = 24;

/// Nodes for |x|²/λ₁ = s: [`NODES`] down to s = 4, then as 1/√s (at most 4096).
fn nodes_for(s: f64) -> usize {
    let n = (NODES as f64 * (4.0 / s).sqrt()).ceil();
    if n.is_finite() {
        (n as usize).clamp(NODES, 4096)
    } else {
        4096
    }
}

/// erf(x)/x, by its Taylor series for |x| ≤ 0.5 (12 terms: below 1e-16) and directly above.
fn erf_over_x(x: f64) -> f64 {
    if x.abs() > 0.5 {
        return (1.0 - erfc(x)) / x;
    }
    // erf(x) = 2/√π Σ (−1)ⁿ x²ⁿ⁺¹ / (n! (2n + 1)).
    let (x2, mut term, mut sum) = (x * x, 1.0, 1.0);
    for n in 1..12 {
        term *= -x2 / n as f64;
        sum += term / (2 * n + 1) as f64;
    }
    sum * 2.0 / PI.sqrt()
}

/// P(|x|² ≤ s) and its derivative in s for x ~ N(0, diag(1, α, β)), 1 ≥ α ≥ β ≥ 0 (the
/// module's one-dimensional form).
fn cdf_and_density(alpha: f64, beta: f64, s: f64) -> (f64, f64) {
    if s <= 0.0 {
        return (0.0, 0.0);
    }
    // c = √(s/2β): infinite for a flat Σ (β = 0), where erf(c) = 1 and b = 1.
    let c = (s / (2.0 * beta)).sqrt();
    let (mut p, mut d) = (0.0, 0.0);
    let nodes = nodes_for(s);
    for k in 0..nodes {
        let phi = (k as f64 + 0.5) * FRAC_PI_2 / nodes as f64;
        let (sin, cos) = phi.sin_cos();
        let q = cos * cos + alpha * sin * sin;
        let e = (-s / (2.0 * q)).exp();
        if e == 0.0 {
            continue;
        }
        let b = if beta == 0.0 {
            1.0
        } else {
            (1.0 - beta / q).max(0.0)
        };
        let x = c * b.sqrt();
        // erf(x)/√b, kept finite where b → 0 (q → β: a round cross-section) as c·erf(x)/x.
        let t = if x > 0.5 {
            (1.0 - erfc(x)) / b.sqrt()
        } else {
            c * erf_over_x(x)
        };
        p += e * t;
        d += e * t / (2.0 * q);
    }
    let n = nodes as f64;
    (1.0 - erfc(c) - p / n, d / n)
}

/// P(|x| ≤ r) for x ~ N(0, diag(λ)), λ sorted largest first (negative rounding clamped).
pub fn probability_within(lambda: [f64; 3], r: f64) -> f64 {
    let l1 = lambda[0].max(0.0);
    if l1 == 0.0 {
        return if r >= 0.0 { 1.0 } else { 0.0 };
    }
    let (alpha, beta) = (lambda[1].max(0.0) / l1, lambda[2].max(0.0) / l1);
    cdf_and_density(alpha.min(1.0), beta.min(alpha).min(1.0), r * r / l1).0
}

/// The 95 % quantiles of χ²(1) and χ²(3): |x|²/λ₁ at [`LEVEL`] lies between them, for a line
/// and a round ball.
const CHI2_95: [f64; 2] = [3.841_458_820_694_124, 7.814_727_903_251_178];

/// The standard normal's 95th percentile (Wilson–Hilferty's z for the one-sided 95 %).
const Z_95: f64 = 1.644_853_626_951_472_2;

/// s with P(|x|² ≤ s) = [`LEVEL`] for x ~ N(0, diag(1, α, β)), 1 ≥ α ≥ β ≥ 0.
fn quantile(alpha: f64, beta: f64) -> f64 {
    // Start: |x|² as g·χ²(ν) with its mean and variance (Patnaik), the χ² quantile by
    // Wilson–Hilferty: within a few per cent, which Newton then removes.
    let (m1, m2) = (1.0 + alpha + beta, 1.0 + alpha * alpha + beta * beta);
    let (g, nu) = (m2 / m1, m1 * m1 / m2);
    let h = 2.0 / (9.0 * nu);
    let (mut lo, mut hi) = (CHI2_95[0] * (1.0 - 1e-9), CHI2_95[1] * (1.0 + 1e-9));
    let mut s = (g * nu * (1.0 - h + Z_95 * h.sqrt()).powi(3)).clamp(lo, hi);
    for _ in 0..60 {
        let (p, d) = cdf_and_density(alpha, beta, s);
        let f = p - LEVEL;
        if f < 0.0 {
            lo = lo.max(s);
        } else {
            hi = hi.min(s);
        }
        let mut next = s - f / d;
        if !(next > lo && next < hi) {
            // A step out of the bracket (or not a number): bisect instead.
            next = 0.5 * (lo + hi);
        }
        if (next - s).abs() <= 1e-12 * s {
            return next;
        }
        s = next;
    }
    s
}

/// The eigenvalues of Σ, largest first.
pub fn eigenvalues(sigma: &Matrix3<f64>) -> [f64; 3] {
    let sym = 0.5 * (sigma + sigma.transpose());
    let e = SymmetricEigen::new(sym).eigenvalues;
    let mut l = [e[0], e[1], e[2]];
    l.sort_by(|a, b| b.total_cmp(a));
    l
}

/// U95 of Σ (mm for Σ in mm²): 0 for Σ = 0, NaN for a Σ that is not finite, else a positive
/// number (never 0 for a Σ that is not zero).
pub fn u95(sigma: &Matrix3<f64>) -> f64 {
    if sigma.iter().any(|x| !x.is_finite()) {
        return f64::NAN;
    }
    let l = eigenvalues(sigma);
    let l1 = l[0].max(0.0);
    if l1 == 0.0 {
        return 0.0;
    }
    let alpha = (l[1].max(0.0) / l1).min(1.0);
    let beta = (l[2].max(0.0) / l1).min(alpha);
    (l1 * quantile(alpha, beta)).sqrt()
}

/// U95 of diag(1, a², a²b²): the shape factor G(a, b) of a covariance with eigenvalues
/// λ₁ ≥ λ₂ ≥ λ₃, a = √(λ₂/λ₁), b = √(λ₃/λ₂), U95 = √λ₁ · G; the hub keeps it on a grid
/// (`quatarm::uncertainty::radius`, written by `cargo run -p armcal --example u95_grid`).
pub fn shape_factor(a: f64, b: f64) -> f64 {
    u95(&Matrix3::from_diagonal(&nalgebra::Vector3::new(
        1.0,
        a * a,
        a * a * b * b,
    )))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::chi2_tail;
    use std::f64::consts::SQRT_2;

    /// Shapes from a line to a ball, the hard ones included (a needle, a flat disc, two
    /// equal large and one tiny): the one-dimensional form against the nested quadrature.
    #[test]
    fn matches_the_quadrature_from_a_line_to_a_ball() {
        let shapes = [
            [1.0, 0.0, 0.0],
            [1.0, 1e-8, 0.0],
            [1.0, 1e-3, 1e-6],
            [1.0, 0.01, 0.01],
            [1.0, 1.0, 0.0],
            [1.0, 1.0, 1e-9],
            [1.0, 0.5, 0.25],
            [1.0, 0.9, 0.8],
            [1.0, 1.0, 1.0],
            [1.0, 0.3, 0.0],
        ];
        let mut rng = crate::rng::rng(3);
        let random = (0..40).map(|_| {
            use rand::Rng;
            let a: f64 = rng.gen();
            let b: f64 = rng.gen();
            [1.0, a * a, a * a * b * b]
        });
        for l in shapes.into_iter().chain(random) {
            let exact = quadrature::radius(l, LEVEL);
            let fast = u95(&Matrix3::from_diagonal(&l.into()));
            assert!((fast / exact - 1.0).abs() < 1e-7, "{l:?}: {fast} {exact}");
            for r in [0.5, 1.5, 2.5, 4.0] {
                let (p, q) = (
                    probability_within(l, r),
                    quadrature::probability_within(l, r),
                );
                assert!((p - q).abs() < 1e-7, "{l:?} r {r}: {p} {q}");
            }
        }
    }

    #[test]
    fn never_zero_or_nan_for_a_covariance_that_is_not_zero() {
        for scale in [1e-300, 1e-30, 1e-12, 1.0, 1e12, 1e100] {
            for l in [[1.0, 0.0, 0.0], [1.0, 1.0, 1.0], [1.0, 1e-20, 1e-40]] {
                let s = Matrix3::from_diagonal(&nalgebra::Vector3::from(l)) * scale;
                let u = u95(&s);
                assert!(u.is_finite() && u > 0.0, "{scale} {l:?}: {u}");
            }
        }
        assert!(u95(&(Matrix3::identity() * f64::INFINITY)).is_nan());
    }

    #[test]
    fn known_radii() {
        let s = 0.003;
        let iso = Matrix3::identity() * s * s;
        // χ²(3) 95 % quantile 7.814728: r = 2.795483 σ.
        assert!(
            (u95(&iso) / s - 2.795_483).abs() < 1e-5,
            "{}",
            u95(&iso) / s
        );
        let line = Matrix3::from_diagonal(&nalgebra::Vector3::new(0.0, s * s, 0.0));
        assert!((u95(&line) / s - 1.959_964).abs() < 1e-5);
        let plane = Matrix3::from_diagonal(&nalgebra::Vector3::new(s * s, 0.0, s * s));
        assert!((u95(&plane) / s - 2.447_747).abs() < 1e-5);
        assert_eq!(u95(&Matrix3::zeros()), 0.0);
    }

    #[test]
    fn probability_matches_chi2_and_a_sampled_ellipsoid() {
        for r in [0.5, 1.0, 2.0, 3.5] {
            // χ²(3) in closed form: P(|x| ≤ r) = erf(r/√2) − √(2/π) r e^(−r²/2).
            let exact = 1.0 - erfc(r / SQRT_2) - (2.0 / PI).sqrt() * r * (-0.5 * r * r).exp();
            let p = probability_within([1.0; 3], r);
            assert!((p - exact).abs() < 1e-6, "{r}: {p} {exact}");
            // Two equal components: 1 − e^(−r²/2).
            let p2 = probability_within([1.0, 1.0, 0.0], r);
            assert!((p2 - (1.0 - chi2_tail(r * r, 2))).abs() < 1e-6, "{r}: {p2}");
        }
        // An elongated Σ against a sampled estimate (200,000 draws: ±0.0005 at 95 %).
        let l = [100.0, 4.0, 0.25];
        let r = u95(&Matrix3::from_diagonal(&l.into()));
        let mut rng = crate::rng::rng(7);
        let n = 200_000;
        let inside = (0..n)
            .filter(|_| {
                let q: f64 = l
                    .iter()
                    .map(|v| v * crate::rng::normal(&mut rng).powi(2))
                    .sum();
                q <= r * r
            })
            .count();
        let frac = inside as f64 / n as f64;
        assert!((frac - LEVEL).abs() < 0.002, "{frac}");
    }
}
