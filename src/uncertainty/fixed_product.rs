//! J_π C J_πᵀ = (J_π L)(J_π L)ᵀ with the product J_π L in integers, for a core without a
//! floating-point unit (the Raspberry Pi Pico's Cortex-M0+, feature `fixed-u95`): its
//! 3 · P(P+1)/2 multiply-adds (4,134 at 52 parameters) are each a call to software `fmul` and
//! `fadd` in f32, and one 32-bit `muls` and an `add` here.
//!
//! At boot, each row k of L is scaled by a power of two 2^s_k so that its largest entry lies
//! in [2^14, 2^15), and rounded to i16 (relative error ≤ 2^-15 of the row's largest entry).
//! At each point, the columns d_k of J_π (f32, nm per the parameter's unit) are scaled by
//! 2^-s_k and by one common power of two 2^t so that the largest is at most 2^16, and
//! rounded to i32; each product d'_k q_kj then fits i32 (one `muls`) and G_j = Σ_k d'_k q_kj
//! is summed in i64 (an `adds` and an `adcs`). Every scale is a power of two: the rounding of
//! the inputs is the only error (~2^-16 of the largest column, 2^-15 of a row's largest
//! entry), and Σ G_j G_jᵀ is formed in f32 and scaled back once. (Summed in i32 instead, the
//! columns had to keep below 2^30 over the largest column sum of |q|: at 52 strongly
//! correlated parameters that left them 11 bits and the covariance 5e-4 off.)
//!
//! Its accuracy against the f32 product and the host: `cargo test -p quatarm --features
//! fixed-u95,parameters --lib uncertainty::fixed_product`, `cargo test -p armcal --features
//! quatarm/fixed-u95 --test hub_u95`; its cost on the M0: `docs/results/boards.md`.

use super::Covariance;
use crate::table::parameters::{factor_len, MAX_PARAMETERS};

/// Entries of the largest factor.
const MAX_ENTRIES: usize = factor_len(MAX_PARAMETERS);

/// The scaled columns of J_π are at most 2^COLUMN_BITS: times an entry of L below 2^15, the
/// product fits i32.
const COLUMN_BITS: i32 = 16;

/// Each row's largest entry is scaled into [2^ROW_BITS, 2^(ROW_BITS + 1)): i16 (rounded to 32,768 at most: clamped).
const ROW_BITS: i32 = 14;

/// L rounded to integers, row after row, and the scales that undo it.
#[derive(Clone, Debug)]
pub struct FixedFactor {
    /// q_kj = round(L_kj · 2^shift_k).
    q: [i16; MAX_ENTRIES],
    /// The power of two of each row.
    shift: [i16; MAX_PARAMETERS],
    /// Number of parameters.
    count: usize,
}

/// The binary exponent of a finite, non-zero `x`: |x| ∈ [2^e, 2^(e + 1)) (subnormals give
/// −127, below their own).
fn exponent(x: f32) -> i32 {
    ((x.to_bits() >> 23) & 0xff) as i32 - 127
}

/// round(x · 2^e) from the bits of `x`: an integer shift of its mantissa (no floating-point
/// operation, so no software `fmul` on the M0). The caller keeps |x · 2^e| below 2^31.
fn to_fixed(x: f32, e: i32) -> i32 {
    let b = x.to_bits();
    let ex = ((b >> 23) & 0xff) as i32;
    if ex == 0 {
        return 0; // zero or subnormal: far below any scale used here
    }
    let m = ((b & 0x7f_ffff) | 0x80_0000) as i32;
    // x = m · 2^(ex − 150), so x · 2^e = m · 2^s.
    let s = ex - 150 + e;
    let v = if s >= 0 {
        // m < 2^24: up to 7 places fit i32; beyond, the caller's bound was broken.
        if s <= 7 {
            m << s
        } else {
            i32::MAX
        }
    } else if s > -25 {
        (m + (1 << (-s - 1))) >> -s
    } else {
        0
    };
    if b >> 31 == 1 {
        -v
    } else {
        v
    }
}

/// 2^e as f32, for e within the normal range (clamped to it).
fn pow2(e: i32) -> f32 {
    f32::from_bits(((e.clamp(-126, 127) + 127) as u32) << 23)
}

impl FixedFactor {
    /// The factor `entries` (L row after row, `factor_len(count)` of them, as f32) of a
    /// validated block; `None` where `count` is above [`MAX_PARAMETERS`] or `entries` is
    /// short.
    pub fn new(entries: impl Fn(usize) -> Option<f32>, count: usize) -> Option<FixedFactor> {
        if count > MAX_PARAMETERS {
            return None;
        }
        let mut f = FixedFactor {
            q: [0; MAX_ENTRIES],
            shift: [0; MAX_PARAMETERS],
            count,
        };
        for k in 0..count {
            let row = factor_len(k);
            let mut largest = 0.0f32;
            for j in 0..=k {
                let l = entries(row + j)?;
                if l.abs() > largest {
                    largest = l.abs();
                }
            }
            let shift = if largest > 0.0 {
                ROW_BITS - exponent(largest)
            } else {
                0
            };
            f.shift[k] = shift as i16;
            for j in 0..=k {
                // |q| ≤ 2^15 by the row's scale: only the row's largest can round to 2^15.
                let q = to_fixed(entries(row + j)?, shift).clamp(-32_767, 32_767);
                f.q[row + j] = q as i16;
            }
        }
        Some(f)
    }

    /// Number of parameters.
    pub fn count(&self) -> usize {
        self.count
    }

    /// Σ += (J_π L)(J_π L)ᵀ for the columns `d` of J_π (nm per the parameter's unit; the
    /// first [`Self::count`] are used).
    pub fn add_to(&self, d: &[[f32; 3]], sigma: &mut Covariance) {
        let n = self.count.min(d.len());
        // The common scale: the largest scaled column at most 2^COLUMN_BITS.
        let mut top = i32::MIN;
        for (k, dk) in d[..n].iter().enumerate() {
            for &x in dk {
                if x != 0.0 {
                    top = top.max(exponent(x) - i32::from(self.shift[k]));
                }
            }
        }
        if top == i32::MIN {
            return; // every column 0: nothing to add
        }
        // |d_k · 2^-shift_k| < 2^(top + 1), so · 2^t rounds to at most 2^COLUMN_BITS.
        let t = COLUMN_BITS - 1 - top;
        let mut g = [[0i64; 3]; MAX_PARAMETERS];
        for (k, dk) in d[..n].iter().enumerate() {
            let e = t - i32::from(self.shift[k]);
            let y = [to_fixed(dk[0], e), to_fixed(dk[1], e), to_fixed(dk[2], e)];
            let row = factor_len(k);
            for (gj, &q) in g[..=k].iter_mut().zip(&self.q[row..row + k + 1]) {
                let q = i32::from(q);
                // |y q| ≤ 2^16 · 32,767 < 2^31; 64 of them sum far inside i64.
                gj[0] += i64::from(y[0].wrapping_mul(q));
                gj[1] += i64::from(y[1].wrapping_mul(q));
                gj[2] += i64::from(y[2].wrapping_mul(q));
            }
        }
        // G_j = 2^t · (J_π L)_j: Σ G Gᵀ in f32, scaled back by 2^-2t once.
        let mut s = Covariance::default();
        for gj in &g[..n] {
            s.add_outer([gj[0] as f32, gj[1] as f32, gj[2] as f32], 1.0);
        }
        // 2^-2t in two factors: t may reach ~120 (columns of 1e-10 nm), past f32's range.
        let (h1, h2) = (pow2(-t), pow2(-t));
        for (c, x) in sigma.0.iter_mut().zip(s.0) {
            *c += x * h1 * h2;
        }
    }
}

#[cfg(all(test, feature = "parameters"))]
mod tests {
    use super::*;

    #[test]
    fn to_fixed_rounds_the_scaled_value() {
        for (x, e, want) in [
            (1.0f32, 0, 1),
            (1.5, 0, 2),
            (-1.5, 0, -2),
            (1.25, 1, 3),
            (3.0e-5, 20, 31),
            (-3.0e-5, 20, -31),
            (0.0, 10, 0),
            (1234.567, 4, 19753),
        ] {
            assert_eq!(to_fixed(x, e), want, "{x} · 2^{e}");
        }
    }

    /// Against the product in f64 on random factors of every size, rows of scales 1e-6 to
    /// 1e-2 with strong correlations (off-diagonal entries up to half the diagonal's), and
    /// columns of very different magnitudes (nm per rad and nm per mm, as J_π's): the
    /// covariance within 1e-4 of its largest diagonal entry (U95 within 5e-5). The worst
    /// is printed (`-- --nocapture`).
    #[test]
    fn the_integer_product_is_the_f32_one_to_its_rounding() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut rand = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for p in [1usize, 2, 5, 17, 52, 64] {
            // L lower triangular, rows of scales 1e-6 … 1e-2 with correlations.
            let mut l = [0.0f32; MAX_ENTRIES];
            for k in 0..p {
                let scale = 10f64.powf(-6.0 + 4.0 * (rand() + 1.0) / 2.0);
                for j in 0..=k {
                    let v = if j == k { 1.0 } else { 0.5 * rand() };
                    l[factor_len(k) + j] = (v * scale) as f32;
                }
            }
            let mut d = [[0.0f32; 3]; MAX_PARAMETERS];
            for dk in d.iter_mut().take(p) {
                let scale = 10f64.powf(3.0 + 6.0 * (rand() + 1.0) / 2.0);
                *dk = [rand(), rand(), rand()].map(|x| (x * scale) as f32);
            }
            let f = FixedFactor::new(|i| l.get(i).copied(), p).unwrap();
            let mut got = Covariance::default();
            f.add_to(&d[..p], &mut got);
            // In f64: Σ_j g_j g_jᵀ, g_j = Σ_k d_k L_kj.
            let mut want = [0.0f64; 6];
            for j in 0..p {
                let mut g = [0.0f64; 3];
                for (k, dk) in d.iter().enumerate().take(p).skip(j) {
                    let lkj = f64::from(l[factor_len(k) + j]);
                    for (gc, &x) in g.iter_mut().zip(dk) {
                        *gc += f64::from(x) * lkj;
                    }
                }
                for (w, (a, b)) in
                    want.iter_mut()
                        .zip([(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)])
                {
                    *w += g[a] * g[b];
                }
            }
            let big = want[..3].iter().copied().fold(0.0, f64::max);
            let mut worst: f64 = 0.0;
            for (c, (&g, &w)) in got.0.iter().zip(&want).enumerate() {
                let e = (f64::from(g) - w).abs() / big;
                worst = worst.max(e);
                assert!(e < 1e-4, "P = {p}, entry {c}: {g} against {w}");
            }
            std::println!("P = {p}: worst {worst:.2e} of the largest variance");
        }
    }
}
