//! U95: the radius of the sphere about the point that holds N(0, Σ) with probability 0.95.
//!
//! In Σ's eigenbasis |x|² = λ₁z₁² + λ₂z₂² + λ₃z₃² (z_i standard normal), so the radius is
//! √λ₁ · G(a, b) with a = √(λ₂/λ₁), b = √(λ₃/λ₂), both in [0, 1]: from 1.960 (a line) to
//! 2.796 (a round ball). G has no closed form; the host computes it exactly (nested
//! quadrature, `armcal::uncertainty::u95`), and the module `grid` holds it on a 17 × 17
//! grid of (a, b), generated from the host's function (`cargo run -p armcal --example
//! u95_grid`; the test `u95_grid_is_current` checks it). G is smooth in a and b (even in
//! each at 0), so bilinear interpolation is within 0.07 % of it (measured by the same test).
//!
//! The eigenvalues come from cyclic Jacobi rotations (a 3×3 converges to f32 rounding in a
//! few sweeps, and needs no trigonometry), the square roots from micromath's `sqrt` refined
//! by two Newton steps. micromath alone is not harmless here: its `sqrt` is a bit trick within
//! 5 %, and with it (and its `acos`/`cos` in the closed-form eigenvalues) the hub's U95 was
//! 8 % off the host's on random covariances (`armcal` test `hub_u95_agrees_with_the_host`);
//! two Newton steps take the 5 % to 1e-6 for two divisions each.

use super::grid::{GRID, GRID_N};
use super::Covariance;
use micromath::F32Ext;

/// √x (x ≥ 0): micromath's estimate, refined by two Newton steps (5 % → 1e-3 → 1e-6).
pub fn sqrt(x: f32) -> f32 {
    if x <= 0.0 {
        return 0.0;
    }
    let r = F32Ext::sqrt(x);
    let r = 0.5 * (r + x / r);
    0.5 * (r + x / r)
}

/// Jacobi sweeps: each squares the off-diagonal's size; four take any 3×3 in f32 to its
/// rounding (the loop stops earlier when the off-diagonal is gone).
const SWEEPS: usize = 6;

/// The eigenvalues of Σ, largest first (each ≥ 0).
pub fn eigenvalues(c: &Covariance) -> [f32; 3] {
    let [xx, yy, zz, xy, xz, yz] = c.0;
    let mut a = [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]];
    for _ in 0..SWEEPS {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        let diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if off.is_nan() || off <= 1e-14 * diag {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            rotate(&mut a, p, q);
        }
    }
    let mut l = [a[0][0].max(0.0), a[1][1].max(0.0), a[2][2].max(0.0)];
    if l[1] > l[0] {
        l.swap(0, 1);
    }
    if l[2] > l[1] {
        l.swap(1, 2);
    }
    if l[1] > l[0] {
        l.swap(0, 1);
    }
    l
}

/// One Jacobi rotation in the (p, q) plane that zeroes a[p][q] (Numerical Recipes' stable
/// form: t the smaller root of t² + 2θt − 1 = 0).
fn rotate(a: &mut [[f32; 3]; 3], p: usize, q: usize) {
    let apq = a[p][q];
    // Below f32's resolution of the diagonal the rotation would change nothing but could
    // overflow θ²: the entry is taken as zero.
    if apq.abs() <= 1e-9 * (a[p][p].abs() + a[q][q].abs()) {
        a[p][q] = 0.0;
        a[q][p] = 0.0;
        return;
    }
    let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
    let t = 1.0 / (theta.abs() + sqrt(theta * theta + 1.0));
    let t = if theta < 0.0 { -t } else { t };
    let c = 1.0 / sqrt(t * t + 1.0);
    let s = t * c;
    let r = 3 - p - q;
    let (arp, arq) = (a[r][p], a[r][q]);
    a[p][p] -= t * apq;
    a[q][q] += t * apq;
    a[p][q] = 0.0;
    a[q][p] = 0.0;
    a[r][p] = c * arp - s * arq;
    a[p][r] = a[r][p];
    a[r][q] = s * arp + c * arq;
    a[q][r] = a[r][q];
}

/// G(a, b), bilinear on the grid (a, b clamped to [0, 1]).
pub fn shape_factor(a: f32, b: f32) -> f32 {
    let last = (GRID_N - 1) as f32;
    let (x, y) = (a.clamp(0.0, 1.0) * last, b.clamp(0.0, 1.0) * last);
    // Truncation is the floor for x, y ≥ 0.
    let (i, j) = ((x as usize).min(GRID_N - 2), (y as usize).min(GRID_N - 2));
    let (u, v) = (x - i as f32, y - j as f32);
    let g = |i: usize, j: usize| GRID[i * GRID_N + j];
    (1.0 - u) * ((1.0 - v) * g(i, j) + v * g(i, j + 1))
        + u * ((1.0 - v) * g(i + 1, j) + v * g(i + 1, j + 1))
}

/// U95 of Σ (Σ's unit, square-rooted: nm for nm²).
pub fn u95(c: &Covariance) -> f32 {
    let [l1, l2, l3] = eigenvalues(c);
    if l1 <= 0.0 {
        return 0.0;
    }
    let a = sqrt(l2 / l1);
    let b = if l2 > 0.0 { sqrt(l3 / l2) } else { 0.0 };
    sqrt(l1) * shape_factor(a, b)
}
