//! U95: the radius r of the sphere about the estimate that holds the true point with
//! probability 0.95 when the error is N(0, Σ) (`spec/uncertainty.md`).
//!
//! |x|² is then a weighted sum of χ²(1) variables, the weights the eigenvalues λ₁ ≥ λ₂ ≥ λ₃ of Σ,
//! and P(|x| ≤ r) has no closed form unless they are equal. In Σ's eigenbasis the components
//! are independent, so the probability is computed exactly as a nested integral: the largest
//! component in closed form (erf), the other two by Gauss–Legendre quadrature, each with the
//! substitution x = a·sin φ that removes the square-root end point of the circle. A series
//! (Ruben's, or Imhof's oscillatory integral) would converge slowly for the very elongated Σ an
//! arm gives (a long lever makes one direction ten times the others); this does not care.

use crate::stats::erfc;
use nalgebra::{Matrix3, SymmetricEigen};
use std::f64::consts::{FRAC_PI_2, PI, SQRT_2};
use std::sync::OnceLock;

/// The probability the radius is for.
pub const LEVEL: f64 = 0.95;

/// Gauss–Legendre nodes on [0, 1] (64 of them), computed once by Newton on P_n.
fn nodes() -> &'static [(f64, f64)] {
    static NODES: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    NODES.get_or_init(|| {
        const N: usize = 64;
        let mut out = Vec::with_capacity(N);
        for i in 0..N {
            let mut x = (PI * (i as f64 + 0.75) / (N as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=N {
                    let k = k as f64;
                    let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
                    p0 = p1;
                    p1 = p2;
                }
                dp = N as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            out.push((0.5 * (x + 1.0), 0.5 * w));
        }
        out
    })
}

/// ∫₀^L f, Gauss–Legendre.
fn integrate(l: f64, f: impl Fn(f64) -> f64) -> f64 {
    nodes().iter().map(|(x, w)| w * f(l * x)).sum::<f64>() * l
}

/// P(|y| ≤ √s) for y ~ N(0, σ²).
fn p1(s: f64, sigma: f64) -> f64 {
    if s <= 0.0 {
        return 0.0;
    }
    if sigma == 0.0 {
        return 1.0;
    }
    1.0 - erfc(s.sqrt() / (SQRT_2 * sigma))
}

/// E[inner(s − x²); |x| ≤ √s] for x ~ N(0, σ²): one more dimension of the ball.
fn add_dimension(s: f64, sigma: f64, inner: &dyn Fn(f64) -> f64) -> f64 {
    if s <= 0.0 {
        return 0.0;
    }
    if sigma == 0.0 {
        return inner(s);
    }
    let a = s.sqrt();
    let density = |x: f64| (-0.5 * (x / sigma).powi(2)).exp() / (sigma * (2.0 * PI).sqrt());
    let half = if a <= 8.0 * sigma {
        // x = a sin φ: the integrand is smooth in φ up to the circle's edge.
        integrate(FRAC_PI_2, |phi| {
            let x = a * phi.sin();
            density(x) * inner(s - x * x) * a * phi.cos()
        })
    } else {
        // The density is e^-32 before the edge: integrate where it lives.
        integrate(8.0 * sigma, |x| density(x) * inner(s - x * x))
    };
    2.0 * half
}

/// P(|x| ≤ r) for x ~ N(0, diag(λ)), λ sorted largest first (negative rounding clamped).
pub fn probability_within(lambda: [f64; 3], r: f64) -> f64 {
    let s = lambda.map(|l| l.max(0.0).sqrt());
    let innermost = |t: f64| p1(t, s[0]);
    let middle = |t: f64| add_dimension(t, s[1], &innermost);
    add_dimension(r * r, s[2], &middle)
}

/// The eigenvalues of Σ, largest first.
pub fn eigenvalues(sigma: &Matrix3<f64>) -> [f64; 3] {
    let sym = 0.5 * (sigma + sigma.transpose());
    let e = SymmetricEigen::new(sym).eigenvalues;
    let mut l = [e[0], e[1], e[2]];
    l.sort_by(|a, b| b.total_cmp(a));
    l
}

/// The radius holding probability `level` of N(0, Σ).
pub fn radius(sigma: &Matrix3<f64>, level: f64) -> f64 {
    let l = eigenvalues(sigma);
    let trace: f64 = l.iter().map(|x| x.max(0.0)).sum();
    if trace <= 0.0 || !trace.is_finite() {
        return if trace == 0.0 { 0.0 } else { f64::NAN };
    }
    let f = |r: f64| probability_within(l, r) - level;
    // One component alone needs at least its own two-sided quantile; three equal ones with
    // the same trace need the most, 2.7955 √(trace/3) < 2.8 √trace.
    let (mut a, mut b) = (0.0, 2.8 * trace.sqrt());
    let (mut fa, mut fb) = (f(a), f(b));
    while fb < 0.0 {
        b *= 2.0;
        fb = f(b);
    }
    // Illinois regula falsi: bracketing, so it cannot leave [a, b].
    let mut side = 0;
    for _ in 0..100 {
        let c = (a * fb - b * fa) / (fb - fa);
        let fc = f(c);
        if fc.abs() < 1e-12 || (b - a) < 1e-12 * b {
            return c;
        }
        if fc * fb > 0.0 {
            b = c;
            fb = fc;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        } else {
            a = c;
            fa = fc;
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        }
    }
    0.5 * (a + b)
}

/// U95 of Σ (mm for Σ in mm²).
pub fn u95(sigma: &Matrix3<f64>) -> f64 {
    radius(sigma, LEVEL)
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
        let r = radius(&Matrix3::from_diagonal(&l.into()), LEVEL);
        let mut rng = crate::sim::rng(7);
        let n = 200_000;
        let inside = (0..n)
            .filter(|_| {
                let q: f64 = l
                    .iter()
                    .map(|v| v * crate::sim::normal(&mut rng).powi(2))
                    .sum();
                q <= r * r
            })
            .count();
        let frac = inside as f64 / n as f64;
        assert!((frac - LEVEL).abs() < 0.002, "{frac}");
    }
}
