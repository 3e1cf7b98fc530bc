//! The slow, independent check of [`super::probability_within`]: the same probability as a
//! nested integral in Σ's eigenbasis, the largest component in closed form (erf), the other
//! two by 64-point Gauss–Legendre quadrature, each with the substitution x = a·sin φ that
//! removes the square-root end point of the circle.
//!
//! This was the host's radius until the one-dimensional form replaced it (4096 erfc and exp
//! per probability, ~10 probabilities per radius: 96 % of `calibrate`'s time). It stays only
//! to measure the fast form against (`cargo run --release -p armcal --example u95_speed`, and
//! the module's tests): it shares no formula with it.

use crate::stats::erfc;
use std::f64::consts::{FRAC_PI_2, PI, SQRT_2};
use std::sync::OnceLock;

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

/// The radius holding probability `level` of N(0, diag(λ)) (λ largest first), by Illinois
/// regula falsi on [`probability_within`]: the host's radius before the fast form.
pub fn radius(lambda: [f64; 3], level: f64) -> f64 {
    let trace: f64 = lambda.iter().map(|x| x.max(0.0)).sum();
    if trace <= 0.0 || !trace.is_finite() {
        return if trace == 0.0 { 0.0 } else { f64::NAN };
    }
    let f = |r: f64| probability_within(lambda, r) - level;
    let (mut a, mut b) = (0.0, 2.8 * trace.sqrt());
    let (mut fa, mut fb) = (f(a), f(b));
    while fb < 0.0 {
        b *= 2.0;
        fb = f(b);
    }
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
