//! The budget's pose part on the hub (issue 27; the table's [`crate::table::pose`]): the
//! calibration's part of Σ_p widened where the reading's leverage is above the calibration's.
//!
//! With C = C_fit + P from the table (P = D Dᵀ + b · C_fit), a reading's parameter part is
//! J C Jᵀ + (max(1, ℓ) − 1) · J P Jᵀ, ℓ = tr(J C_fit Jᵀ)/m (`quatarm_ref::uncertainty::
//! PoseLeverage`, the contract). The hub has G = J C Jᵀ from its J·L pass
//! ([`super::parameters`]); one J·D product, E = J D (3 × r), gives the rest:
//!
//! - tr(J C_fit Jᵀ) = (tr G − ‖E‖²)/(1 + b), since J C_fit Jᵀ = (G − E Eᵀ)/(1 + b);
//! - J P Jᵀ = b/(1 + b) · (G − E Eᵀ) + E Eᵀ;
//!
//! so with f = max(1, ℓ) − 1 and β = b/(1 + b) the part is (1 + f β) G + f/(1 + b) · E Eᵀ:
//! a scale of G and r outer products, no second pass over L. Where the table has the joint
//! leverage, f = max(1, ℓ, ℓJ) − 1 instead, ℓJ from the reading's counts ([`super::joints`]). Cost: 3 · P · r multiply-adds
//! for E (the J·D rows stream past like L's, [`super::parameters::BLOCK`] columns of D at
//! a time, their sums in registers), the rest a few dozen operations.

use super::joints::JointPart;
use super::parameters::{accumulate, as_f32, Entries, BLOCK};
use super::Covariance;
use crate::table::pose::{Pose, MAX_FACTORS};
use crate::table::Table;
use core::mem::MaybeUninit;

/// A column of E = J D as `product` writes it (not zeroed before).
pub type Column = MaybeUninit<[f32; 3]>;

/// nm² per mm² (m is in mm², Σ_p in nm²).
const NM2_PER_MM2: f32 = 1.0e12;

/// The pose part of a table that has it, built at boot (its divisions done once).
#[derive(Clone, Copy, Debug)]
pub struct PosePart<'a> {
    /// D row by parameter, as the table's little-endian bytes.
    factor: &'a [u8],
    /// r, D's columns (within [`MAX_FACTORS`]).
    count: usize,
    /// β = b/(1 + b).
    shrink: f32,
    /// 1/(1 + b).
    keep: f32,
    /// 1/m, per nm².
    inverse_mean: f32,
    /// The joint leverage ℓJ, where the part has it ([`super::joints`]).
    joints: Option<JointPart>,
}

impl<'a> PosePart<'a> {
    /// The part of a validated table's pose part (b ≥ 0 and 0 < m ≤ 1e6 mm² there, so the
    /// divisions are finite: 1/m at most 1/(the smallest positive f32 · 10^12), ~1e33).
    pub fn new(pose: &Pose<'a>, table: &Table<'a>) -> PosePart<'a> {
        let keep = 1.0 / (1.0 + pose.shrink());
        PosePart {
            factor: pose.factor(),
            count: pose.count().min(MAX_FACTORS),
            shrink: pose.shrink() * keep,
            keep,
            inverse_mean: 1.0 / (pose.leverage_mean() * NM2_PER_MM2),
            joints: pose.joints().map(|j| JointPart::new(table, &j)),
        }
    }

    /// r, D's columns.
    pub fn count(&self) -> usize {
        self.count
    }

    /// The leverage ratio ℓ of a reading whose G = J C Jᵀ is `g` and E = J D is `e` (nm).
    pub fn leverage(&self, g: &Covariance, e: &[[f32; 3]]) -> f32 {
        let norm: f32 = e
            .iter()
            .map(|x| x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
            .sum();
        (g.0[0] + g.0[1] + g.0[2] - norm) * self.keep * self.inverse_mean
    }

    /// `g`, J C Jᵀ of a reading at `counts` whose columns of J are `d` (nm per the
    /// parameter's unit), becomes J C Jᵀ + (max(1, ℓ, ℓJ) − 1) · J P Jᵀ (ℓJ 0 where the part
    /// has no joint leverage).
    pub fn widen(&self, d: &[[f32; 3]], counts: &[u32], g: &mut Covariance) {
        // Not zeroed first (a `memset` a point): `product` writes the r columns it hands
        // back.
        let mut e = [MaybeUninit::uninit(); MAX_FACTORS];
        let e = self.product(d, &mut e);
        let f = self
            .leverage(g, e)
            .max(self.joints.as_ref().map_or(0.0, |j| j.ratio(counts)))
            - 1.0;
        // ℓ ≤ 1 (or a NaN, which a validated table cannot give): J C Jᵀ as it is.
        if f.is_nan() || f <= 0.0 {
            return;
        }
        let scale = 1.0 + f * self.shrink;
        for x in g.0.iter_mut() {
            *x *= scale;
        }
        let w = f * self.keep;
        for x in e.iter() {
            g.add_outer(*x, w);
        }
    }

    /// E = J D (nm) into `e`, its r columns written and returned.
    pub fn product<'e>(&self, d: &[[f32; 3]], e: &'e mut [Column; MAX_FACTORS]) -> &'e [[f32; 3]] {
        match as_f32(self.factor) {
            Some(aligned) => product_aligned(d, aligned, self.count, e),
            None => product(d, self.factor, self.count, e),
        }
        // SAFETY: both products write every column j < r (each block's `out` whole, the
        // blocks j0 … j0 + width − 1 covering 0 … r − 1; r = count ≤ MAX_FACTORS), and
        // MaybeUninit<T> has T's layout.
        unsafe { core::slice::from_raw_parts(e.as_ptr().cast::<[f32; 3]>(), self.count) }
    }
}

/// E's columns j = 0 … r − 1, [`BLOCK`] at a time (the last block narrower).
fn product<E: Entries>(d: &[[f32; 3]], factor: E, r: usize, e: &mut [Column; MAX_FACTORS]) {
    let mut j0 = 0;
    while j0 < r {
        let width = (r - j0).min(BLOCK);
        let out = &mut e[j0..j0 + width];
        match width {
            6 => columns::<E, 6>(d, factor, r, j0, out),
            5 => columns::<E, 5>(d, factor, r, j0, out),
            4 => columns::<E, 4>(d, factor, r, j0, out),
            3 => columns::<E, 3>(d, factor, r, j0, out),
            2 => columns::<E, 2>(d, factor, r, j0, out),
            _ => columns::<E, 1>(d, factor, r, j0, out),
        }
        j0 += BLOCK;
    }
}

/// [`product`] for D as aligned f32 (the hub's flash): its rows as `chunks_exact`, so that a
/// row's W entries are W loads with no bounds check of their own (the generic loop's
/// `Entries::run` checked each row and cost ~9 instructions a column of D a parameter on
/// qemu-m4f). The same sums in the same order: the same bits.
fn product_aligned(d: &[[f32; 3]], factor: &[f32], r: usize, e: &mut [Column; MAX_FACTORS]) {
    let mut j0 = 0;
    // Blocks of 8 columns in assembly where the core has it (`eight_columns`), the rest
    // (r mod 8) in Rust.
    while j0 + WIDE <= r && eight_columns(d, factor, r, j0, &mut e[j0..j0 + WIDE]) {
        j0 += WIDE;
    }
    while j0 < r {
        let width = (r - j0).min(BLOCK);
        let out = &mut e[j0..j0 + width];
        match width {
            6 => columns_aligned::<6>(d, factor, r, j0, out),
            5 => columns_aligned::<5>(d, factor, r, j0, out),
            4 => columns_aligned::<4>(d, factor, r, j0, out),
            3 => columns_aligned::<3>(d, factor, r, j0, out),
            2 => columns_aligned::<2>(d, factor, r, j0, out),
            _ => columns_aligned::<1>(d, factor, r, j0, out),
        }
        j0 += BLOCK;
    }
}

/// Columns of D a block of [`eight_columns`] takes at once.
const WIDE: usize = 8;

/// `out` becomes E_j = Σ_i D_ij d_i for the 8 columns j0 … j0 + 7 of D,
/// in assembly on a Cortex-M with single-precision floating point: the 24 sums in s0–s23
/// throughout, a row's column of J in s24–s26 and its 8 entries of D in s27–s31 (5, then 3),
/// so each `vldm` loads several entries and the three axes share each: 30 instructions a row
/// of 8 entries (the compiler's blocks of 6 and 2 took ~4.5–5 an entry; measured on
/// qemu-m4f, `docs/results/speed.md`). The same multiply-adds in the same order as
/// [`columns_aligned`] (`vmla` rounds the product, then the sum; the first row's `vmul` is
/// its 0 + x but for the sign of a zero), so the same values.
/// `false` (nothing done) where the block does not lie within D or on another core.
fn eight_columns(d: &[[f32; 3]], factor: &[f32], r: usize, j0: usize, out: &mut [Column]) -> bool {
    let rows = d.len();
    // Row i's 8 entries start at i · r + j0; the last row's end within D.
    if rows == 0 || out.len() != WIDE || j0 + WIDE > r || (rows - 1) * r + j0 + WIDE > factor.len()
    {
        return false;
    }
    #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
    {
        // SAFETY: `out` holds 24 f32 (read and written), `d` `rows` ≥ 1 triples (read); row
        // i reads D's entries i · r + j0 … i · r + j0 + 7, all within `factor` by the check
        // above. The floating-point registers are saved and restored on the stack inside (as
        // in `parameters`' block: `sreg` operands need VFP2); the core registers it writes
        // are declared.
        unsafe {
            core::arch::asm!(
                "vpush {{s0-s31}}",
                // The first row: the sums start at its products (0 + x is x).
                "vldmia {d}!, {{s24-s26}}",
                "vldmia {l}!, {{s27-s31}}",
                "vmul.f32 s0, s24, s27",
                "vmul.f32 s1, s25, s27",
                "vmul.f32 s2, s26, s27",
                "vmul.f32 s3, s24, s28",
                "vmul.f32 s4, s25, s28",
                "vmul.f32 s5, s26, s28",
                "vmul.f32 s6, s24, s29",
                "vmul.f32 s7, s25, s29",
                "vmul.f32 s8, s26, s29",
                "vmul.f32 s9, s24, s30",
                "vmul.f32 s10, s25, s30",
                "vmul.f32 s11, s26, s30",
                "vmul.f32 s12, s24, s31",
                "vmul.f32 s13, s25, s31",
                "vmul.f32 s14, s26, s31",
                "vldmia {l}, {{s27-s29}}",
                "add.w {l}, {l}, {skip}",
                "vmul.f32 s15, s24, s27",
                "vmul.f32 s16, s25, s27",
                "vmul.f32 s17, s26, s27",
                "vmul.f32 s18, s24, s28",
                "vmul.f32 s19, s25, s28",
                "vmul.f32 s20, s26, s28",
                "vmul.f32 s21, s24, s29",
                "vmul.f32 s22, s25, s29",
                "vmul.f32 s23, s26, s29",
                "cmp {n}, #0",
                "beq 3f",
                // The rows after it.
                "2:",
                "vldmia {d}!, {{s24-s26}}",
                "vldmia {l}!, {{s27-s31}}",
                "vmla.f32 s0, s24, s27",
                "vmla.f32 s1, s25, s27",
                "vmla.f32 s2, s26, s27",
                "vmla.f32 s3, s24, s28",
                "vmla.f32 s4, s25, s28",
                "vmla.f32 s5, s26, s28",
                "vmla.f32 s6, s24, s29",
                "vmla.f32 s7, s25, s29",
                "vmla.f32 s8, s26, s29",
                "vmla.f32 s9, s24, s30",
                "vmla.f32 s10, s25, s30",
                "vmla.f32 s11, s26, s30",
                "vmla.f32 s12, s24, s31",
                "vmla.f32 s13, s25, s31",
                "vmla.f32 s14, s26, s31",
                "vldmia {l}, {{s27-s29}}",
                "add.w {l}, {l}, {skip}",
                "vmla.f32 s15, s24, s27",
                "vmla.f32 s16, s25, s27",
                "vmla.f32 s17, s26, s27",
                "vmla.f32 s18, s24, s28",
                "vmla.f32 s19, s25, s28",
                "vmla.f32 s20, s26, s28",
                "vmla.f32 s21, s24, s29",
                "vmla.f32 s22, s25, s29",
                "vmla.f32 s23, s26, s29",
                "subs {n}, #1",
                "bne 2b",
                "3:",
                "vstmia {e}, {{s0-s23}}",
                "vpop {{s0-s31}}",
                e = in(reg) out.as_mut_ptr().cast::<f32>(),
                d = inout(reg) d.as_ptr() => _,
                l = inout(reg) factor.as_ptr().add(j0) => _,
                // From the row's sixth entry to the next row's first.
                skip = in(reg) 4 * (r - 5),
                n = inout(reg) rows - 1 => _,
            );
        }
        return true;
    }
    #[allow(unreachable_code)]
    false
}

/// [`columns`] for aligned f32 rows (`r` > 0, j0 + W ≤ r by [`product_aligned`]).
#[inline(never)]
fn columns_aligned<const W: usize>(
    d: &[[f32; 3]],
    factor: &[f32],
    r: usize,
    j0: usize,
    out: &mut [Column],
) {
    let mut acc = [[0.0f32; 3]; W];
    if r > 0 && j0 + W <= r {
        for (di, row) in d.iter().zip(factor.chunks_exact(r)) {
            let Some(x) = row.get(j0..j0 + W) else {
                break;
            };
            for (a, l) in acc.iter_mut().zip(x) {
                accumulate(a, di, *l);
            }
        }
    }
    for (o, a) in out.iter_mut().zip(acc) {
        o.write(a);
    }
}

/// E_j = Σ_i D_ij d_i for the `W` columns j0 … j0 + W − 1 of D (rows `r` entries apart).
/// Out of line and indexed by constants, so that the 3 · W sums stay in registers (as
/// [`super::parameters`]' blocks of L).
#[inline(never)]
fn columns<E: Entries, const W: usize>(
    d: &[[f32; 3]],
    factor: E,
    r: usize,
    j0: usize,
    out: &mut [Column],
) {
    let mut acc = [[0.0f32; 3]; W];
    let mut at = j0;
    for di in d {
        let Some(row) = factor.run::<W>(at) else {
            break;
        };
        for (a, l) in acc.iter_mut().zip(row) {
            accumulate(a, di, l);
        }
        at += r;
    }
    for (o, a) in out.iter_mut().zip(acc) {
        o.write(a);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// A part of D (`d`, row by parameter, r columns), b and m (mm²), as the table holds it.
    fn part(bytes: &[u8], r: usize, b: f32, m: f32) -> PosePart<'_> {
        let keep = 1.0 / (1.0 + b);
        PosePart {
            factor: bytes,
            count: r,
            shrink: b * keep,
            keep,
            inverse_mean: 1.0 / (m * NM2_PER_MM2),
            joints: None,
        }
    }

    /// A small deterministic generator (no dependency): values in [−1, 1).
    fn noise(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    /// The widened part against the formula in f64, J C Jᵀ + (max(1, ℓ) − 1) J P Jᵀ with
    /// C_fit and P formed as matrices, for r from 1 to 16 (every block width, at and past
    /// one block), b = 0 and b > 0, and m that puts ℓ below and far above 1.
    #[test]
    fn the_widened_part_is_the_formula() {
        let mut seed = 5;
        let p = 13;
        for r in 1..=MAX_FACTORS {
            for (b, m_scale) in [(0.0f64, 0.5), (0.3, 2.0), (1.5, 0.01)] {
                // J (nm per unit), C_fit = A Aᵀ, D: all random.
                let j: Vec<[f64; 3]> = (0..p)
                    .map(|_| [0; 3].map(|_| 1e6 * noise(&mut seed)))
                    .collect();
                let a: Vec<f64> = (0..p * p).map(|_| 1e-3 * noise(&mut seed)).collect();
                let d: Vec<f64> = (0..p * r).map(|_| 1e-3 * noise(&mut seed)).collect();
                let mut cfit = std::vec![0.0; p * p];
                let mut ddt = std::vec![0.0; p * p];
                for x in 0..p {
                    for y in 0..p {
                        cfit[x * p + y] = (0..p).map(|k| a[x * p + k] * a[y * p + k]).sum();
                        ddt[x * p + y] = (0..r).map(|k| d[x * r + k] * d[y * r + k]).sum();
                    }
                }
                let pose: Vec<f64> = (0..p * p).map(|k| ddt[k] + b * cfit[k]).collect();
                let c: Vec<f64> = (0..p * p).map(|k| cfit[k] + pose[k]).collect();
                let sandwich = |m: &[f64]| {
                    let pairs = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];
                    pairs.map(|(u, v)| {
                        let mut s = 0.0;
                        for x in 0..p {
                            for y in 0..p {
                                s += j[x][u] * m[x * p + y] * j[y][v];
                            }
                        }
                        s
                    })
                };
                let (g, gfit, gp) = (sandwich(&c), sandwich(&cfit), sandwich(&pose));
                let trfit = gfit[0] + gfit[1] + gfit[2];
                // m in mm², Σ in nm²: ℓ = m_scale⁻¹.
                let m = m_scale * trfit * 1e-12;
                let f = (trfit / (m * 1e12)).max(1.0) - 1.0;
                let want: [f64; 6] = core::array::from_fn(|k| g[k] + f * gp[k]);
                let bytes: Vec<u8> = d.iter().flat_map(|x| (*x as f32).to_le_bytes()).collect();
                let pp = part(&bytes, r, b as f32, m as f32);
                let cols: Vec<[f32; 3]> = j.iter().map(|c| c.map(|x| x as f32)).collect();
                let mut got = Covariance(g.map(|x| x as f32));
                pp.widen(&cols, &[], &mut got);
                let scale = want[0] + want[1] + want[2];
                for (x, w) in got.0.iter().zip(want) {
                    assert!(
                        (f64::from(*x) - w).abs() < 1e-5 * scale,
                        "r = {r}, b = {b}, ℓ = {}: {got:?} against {want:?}",
                        1.0 / m_scale
                    );
                }
                // The leverage itself.
                let mut e = [MaybeUninit::uninit(); MAX_FACTORS];
                let e = pp.product(&cols, &mut e);
                let l = pp.leverage(&Covariance(g.map(|x| x as f32)), e);
                assert!((f64::from(l) * m_scale - 1.0).abs() < 1e-3, "{l}");
            }
        }
    }

    /// D's bytes at an odd address (a host's buffer) give E bit for bit as aligned f32 does.
    #[test]
    fn aligned_and_byte_factors_give_the_same_product() {
        let (p, r) = (7, 9);
        let mut seed = 3;
        let d: Vec<f32> = (0..p * r).map(|_| noise(&mut seed) as f32).collect();
        let cols: Vec<[f32; 3]> = (0..p)
            .map(|_| [0; 3].map(|_| noise(&mut seed) as f32))
            .collect();
        let mut bytes = std::vec![0u8; 4 * d.len() + 8];
        let at = bytes.as_ptr().align_offset(4);
        for (k, x) in d.iter().enumerate() {
            bytes[at + 4 * k..at + 4 * k + 4].copy_from_slice(&x.to_le_bytes());
        }
        let mut odd = std::vec![0u8; 4 * d.len() + 8];
        let at_odd = at + 1;
        odd[at_odd..at_odd + 4 * d.len()].copy_from_slice(&bytes[at..at + 4 * d.len()]);
        let (mut e1, mut e2) = (
            [MaybeUninit::uninit(); MAX_FACTORS],
            [MaybeUninit::uninit(); MAX_FACTORS],
        );
        let a = part(&bytes[at..at + 4 * d.len()], r, 0.0, 1.0);
        let b = part(&odd[at_odd..at_odd + 4 * d.len()], r, 0.0, 1.0);
        assert!(as_f32(a.factor).is_some() && as_f32(b.factor).is_none());
        let e1 = a.product(&cols, &mut e1);
        assert_eq!(e1, b.product(&cols, &mut e2));
        assert_eq!(e1.len(), r);
        for j in 0..r {
            let want: [f64; 3] = core::array::from_fn(|c| {
                (0..p)
                    .map(|i| f64::from(d[i * r + j]) * f64::from(cols[i][c]))
                    .sum()
            });
            for c in 0..3 {
                assert!((f64::from(e1[j][c]) - want[c]).abs() < 1e-5, "{j} {c}");
            }
        }
    }
}

/// The Pico's profile (`fixed-u95`) does not take the pose part: a table with it is refused by
/// the parameter block's flag (here, where `cargo xtask test` runs the profile's tests).
#[cfg(all(test, feature = "fixed-u95"))]
mod refused {
    use crate::table::budget::BudgetData;
    use crate::table::joint_leverage::JointLeverageData;
    use crate::table::parameters::{Column, Kind, ParameterData};
    use crate::table::pose::PoseData;
    use crate::table::tests::sample;
    use crate::table::{Field, Table, TableError, MAX_TABLE_LEN};

    /// With or without the joint leverage inside it (the sample's 6 joints).
    #[test]
    fn the_fixed_point_profile_refuses_the_pose_part_by_its_flag() {
        let columns = [Column::new(Kind::Turn, 1)];
        let (mean, weight) = ([1.0f32; 6], [0.5f32; 21]);
        for joints in [
            None,
            Some(JointLeverageData {
                mean: &mean,
                weight: &weight,
            }),
        ] {
            let block = ParameterData {
                columns: &columns,
                factor: &[1e-5],
                pose: Some(PoseData {
                    factor: &[2e-6],
                    count: 1,
                    shrink: 0.0,
                    leverage_mean: 1e-6,
                    joints,
                }),
            };
            let mut buf = [0u8; MAX_TABLE_LEN];
            let n = sample()
                .encode_full(Some(&BudgetData::default()), Some(&block), &mut buf)
                .unwrap();
            assert_eq!(
                Table::parse(&buf[..n]).unwrap_err(),
                TableError::Invalid {
                    joint: 0,
                    field: Field::Flags
                },
                "joint leverage: {}",
                joints.is_some()
            );
        }
    }
}
