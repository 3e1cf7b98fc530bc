//! The calibration's part of Σ_p: J_π C J_πᵀ, exactly, as (J_π L)(J_π L)ᵀ with C = L Lᵀ
//! from the table ([`crate::table::parameters`]).
//!
//! J_π's columns come from the joints' frames at the reading, which the matrix chain composes
//! anyway ([`crate::matrix::MatrixChain::eval_frames`]): each parameter is a turn about a
//! joint's axis, a turn about a fixed axis, or a shift (the table's column kinds; a probe's
//! shift only while that probe is mounted), evaluated in f32. The frames are the undeflected
//! chain's (~1e-5 of a column off), and the harmonic weights cos hθ, sin hθ are the chain's
//! own cos θ, sin θ raised to the h-th power (as complex numbers, by squaring: a few
//! roundings), where U95 must agree with the host to 1e-3.
//!
//! Cost per point: P columns of a few dozen operations, and 3 · P(P+1)/2 multiply-adds with
//! the factor read from the table (4,134 for P = 52). The product J_π L runs in blocks of
//! [`BLOCK`] of L's columns, their accumulators kept in registers while L's rows stream past:
//! each entry of L is loaded once and each column of J_π once a block.

use super::Covariance;
use crate::matrix::Frames;
use crate::model::{unpermute_inline, ChainError, BASE_AXIS, REFERENCE_TEMP_MC};
use crate::rotate::{cross, Vec3};
use crate::scalar::F32;
use crate::table::parameters::{factor_len, Column, Kind, Parameters, MAX_PARAMETERS};
use crate::table::{Table, MAX_JOINTS};

/// Columns of L whose sums J_π L's block accumulates at once: 6 × 3 accumulators, a column
/// of J_π and a row's 6 entries of L fill 27 of the Cortex-M4F's 32 single-precision
/// registers (with 8, 24 sums and their operands did not fit: the compiler shuffled
/// registers at every row, ~9 instructions an entry of L; measured on qemu-m4f).
pub const BLOCK: usize = 6;

/// The parameter part of a table with a parameter block, built at boot. It borrows the
/// block (the columns' records and the factor, read at every point) rather than copying it:
/// a copy is 11 KB at 64 parameters, and the boot's moves of a struct that size overflowed
/// the qemu-m4f hub's 64 KiB of RAM.
#[derive(Clone, Debug)]
pub struct ParameterPart<'a> {
    block: Parameters<'a>,
    /// Each joint's axis (0, 1, 2: x, y, z), for the records' relabelling.
    axes: [u8; MAX_JOINTS],
    /// The id of the probe mounted: a probe's shift ([`Kind::ProbeShift`]) of another is 0.
    probe: u8,
}

fn sub(a: Vec3<f32>, b: Vec3<f32>) -> Vec3<f32> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn scaled(a: Vec3<f32>, s: f32) -> Vec3<f32> {
    a.map(|x| x * s)
}

fn mat_vec(m: &[[f32; 3]; 3], v: Vec3<f32>) -> Vec3<f32> {
    m.map(|row| row[0] * v[0] + row[1] * v[1] + row[2] * v[2])
}

/// cos hθ and sin hθ from cos θ and sin θ: (cos θ + i sin θ)^h by squaring (at most
/// 2 log₂ h + 1 complex products, each within a few 1e-8 of its exact value).
fn harmonic(turn: [f32; 2], order: u16) -> [f32; 2] {
    let ([mut c, mut s], [mut bc, mut bs]) = ([1.0f32, 0.0f32], turn);
    let mut h = order;
    while h > 0 {
        if h & 1 == 1 {
            (c, s) = (c * bc - s * bs, c * bs + s * bc);
        }
        h >>= 1;
        if h > 0 {
            (bc, bs) = (bc * bc - bs * bs, 2.0 * bc * bs);
        }
    }
    [c, s]
}

/// g += d · l.
#[inline(always)]
fn accumulate(g: &mut [f32; 3], d: &[f32; 3], l: f32) {
    g[0] += d[0] * l;
    g[1] += d[1] * l;
    g[2] += d[2] * l;
}

/// g_b += L_(i, k0 + b) d_i for the rows i = first, first + 1, … whose columns d are given,
/// each holding the block's BLOCK entries. Out of line and indexed by constants only, so that
/// the 24 sums stay in registers: one load, one move and three multiply-adds an entry of L
/// (inlined into `add_to`, its sums went to the stack at every row: measured on qemu-m4f).
#[inline(never)]
fn full_rows(g: &mut [[f32; 3]; BLOCK], d: &[[f32; 3]], factor: &[u8], first: usize, k0: usize) {
    let mut acc = *g;
    let mut at = 4 * (factor_len(first) + k0);
    for (i, di) in d.iter().enumerate() {
        let Some(row) = factor.get(at..at + 4 * BLOCK) else {
            break;
        };
        for (b, gb) in acc.iter_mut().enumerate() {
            accumulate(gb, di, entry(row, b));
        }
        // Row first + i + 1 starts first + i + 1 entries after row first + i.
        at += 4 * (first + i + 1);
    }
    *g = acc;
}

/// g_b += L_(k0 + r, k0 + b) d_(k0 + r) for the rows r = 0, 1, … of the block's triangle
/// (row k0 + r holds r + 1 of the block's `width` entries), indexed by constants as
/// [`full_rows`].
#[inline(never)]
fn triangle_rows(
    g: &mut [[f32; 3]; BLOCK],
    d: &[[f32; 3]],
    factor: &[u8],
    k0: usize,
    width: usize,
) {
    let mut acc = *g;
    for (r, di) in d.iter().enumerate() {
        let at = 4 * (factor_len(k0 + r) + k0);
        let m = (r + 1).min(width);
        for (b, gb) in acc.iter_mut().enumerate() {
            let l = factor.get(at + 4 * b..at + 4 * b + 4).filter(|_| b < m);
            accumulate(gb, di, l.map_or(0.0, |l| entry(l, 0)));
        }
    }
    *g = acc;
}

/// An entry of L from its four little-endian bytes.
#[inline(always)]
fn entry(b: &[u8], k: usize) -> f32 {
    f32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]])
}

const IDENTITY: [[f32; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// nm per mm.
const NM_PER_MM: f32 = 1.0e6;

impl<'a> ParameterPart<'a> {
    /// The part of a validated table; `None` where it has no parameter block.
    pub fn new(table: &Table<'a>) -> Result<Option<ParameterPart<'a>>, ChainError> {
        let Some(block) = table.parameters() else {
            return Ok(None);
        };
        let mut axes = [BASE_AXIS; MAX_JOINTS];
        for (k, a) in axes.iter_mut().enumerate() {
            if let Some(j) = table.joint(k) {
                *a = j.axis;
            }
        }
        Ok(Some(ParameterPart {
            block,
            axes,
            probe: table.probe().id,
        }))
    }

    /// Follows the hub's chain to the table's probe `k`: the columns of a probe's shift are
    /// that probe's. Nothing changes on an error.
    pub fn mount(&mut self, table: &Table<'a>, k: usize) -> Result<(), ChainError> {
        self.probe = table.probe_id(k).ok_or(ChainError::Range { joint: 0 })?;
        Ok(())
    }

    /// Number of parameters.
    pub fn count(&self) -> usize {
        self.block.count().min(MAX_PARAMETERS)
    }

    /// Σ += J_π C J_πᵀ (nm²) at a reading at `temp_mc` whose frames are `frames` and tip `p`
    /// (mm).
    pub fn add_to(&self, frames: &Frames, p: Vec3<f32>, temp_mc: i32, sigma: &mut Covariance) {
        let dt = temp_mc.wrapping_sub(REFERENCE_TEMP_MC) as f32 * 1.0e-3;
        let n = self.count();
        // J_π's columns, in nm per the parameter's unit.
        let mut d = [[0.0f32; 3]; MAX_PARAMETERS];
        for (i, di) in d.iter_mut().enumerate().take(n) {
            // The table's check read every record (kind, joint within the table).
            if let Some(col) = self.block.column(i) {
                *di = scaled(self.column(&col, frames, p, dt), NM_PER_MM);
            }
        }
        let factor = self.block.factor();
        // g_k = Σ_(i ≥ k) L_ik d_i, column k of J_π L, for BLOCK columns k at a time: first
        // the rows of the block's triangle (row i holds L_ik for k ≤ i only), then the rows
        // below it, whole, in `full_rows`.
        let mut k0 = 0;
        while k0 < n {
            let mut g = [[0.0f32; 3]; BLOCK];
            let width = (n - k0).min(BLOCK);
            let top = if width == BLOCK { k0 + BLOCK - 1 } else { n };
            triangle_rows(&mut g, d.get(k0..top).unwrap_or(&[]), factor, k0, width);
            full_rows(&mut g, d.get(top..n).unwrap_or(&[]), factor, top, k0);
            for gb in &g[..width] {
                sigma.add_outer(*gb, 1.0);
            }
            k0 += BLOCK;
        }
    }

    /// ∂p/∂π for one parameter (mm per the parameter's unit).
    fn column(&self, col: &Column, frames: &Frames, p: Vec3<f32>, dt: f32) -> Vec3<f32> {
        let k = usize::from(col.joint).min(MAX_JOINTS - 1);
        // The record's vector is in the calibration file's frame: a tilt's in the frame
        // before its joint (the previous joint's, or the base's, labelled like a z joint),
        // a shift's in its joint's.
        let tilt = matches!(col.kind, Kind::Tilt | Kind::TiltSin | Kind::TiltCos);
        let frame_axis = match (tilt, k) {
            (true, 0) => BASE_AXIS,
            (true, _) => self.axes[k - 1],
            _ => self.axes[k],
        };
        let vector = unpermute_inline(col.vector, frame_axis);
        let r = &frames.rotation[k];
        let lever = sub(p, frames.origin[k]);
        let axis = [r[0][2], r[1][2], r[2][2]];
        let turn = || cross::<F32>(&axis, &lever);
        let tilt = || {
            let before = if k == 0 {
                &IDENTITY
            } else {
                &frames.rotation[k - 1]
            };
            cross::<F32>(&mat_vec(before, vector), &lever)
        };
        let weight = || harmonic(frames.turn[k], col.order);
        match col.kind {
            Kind::Turn => turn(),
            Kind::TurnSin => scaled(turn(), weight()[1]),
            Kind::TurnCos => scaled(turn(), weight()[0]),
            // The first-order lever of the spec: a_k · ((p − o_k) × ẑ).
            Kind::Gravity => scaled(turn(), axis[0] * lever[1] - axis[1] * lever[0]),
            Kind::Tilt => tilt(),
            Kind::TiltSin => scaled(tilt(), weight()[1]),
            Kind::TiltCos => scaled(tilt(), weight()[0]),
            Kind::ProbeShift if col.order != u16::from(self.probe) => [0.0; 3],
            Kind::Shift | Kind::ProbeShift => scaled(mat_vec(r, vector), col.w0 + col.w1 * dt),
        }
    }
}

#[cfg(all(test, feature = "parameters"))]
mod tests {
    use super::*;
    use crate::matrix::MatrixChain;
    use crate::table::budget::BudgetData;
    use crate::table::parameters::{Column, ParameterData};
    use crate::table::probes::tests::several;
    use crate::table::MAX_TABLE_LEN;

    /// The three-probe test table with a budget and the parameter block `columns`, `factor`,
    /// encoded into `buf` and parsed back.
    fn with_block<'a>(
        columns: &[Column],
        factor: &[f32],
        buf: &'a mut [u8; MAX_TABLE_LEN],
    ) -> Table<'a> {
        let block = ParameterData { columns, factor };
        let n = several()
            .encode_full(Some(&BudgetData::default()), Some(&block), buf)
            .unwrap();
        Table::parse(&buf[..n]).unwrap()
    }

    /// A probe's shift moves the tip only while its probe is mounted: with the first probe
    /// (id 4) the part is the plain shift's alone, with the extension (id 9) mounted both
    /// shifts', with the probe of id 0 the plain one's again.
    #[test]
    fn a_probes_shift_counts_only_while_it_is_mounted() {
        let shift = |kind, order| Column {
            order,
            vector: [1.0, 0.0, 0.0],
            w0: 1.0,
            w1: 0.0,
            ..Column::new(kind, 5)
        };
        let columns = [shift(Kind::Shift, 0), shift(Kind::ProbeShift, 9)];
        // Two independent parameters of 1 µm and 2 µm.
        let factor = [1e-3, 0.0, 2e-3];
        let mut buf = [0u8; MAX_TABLE_LEN];
        let table = with_block(&columns, &factor, &mut buf);
        let mut part = ParameterPart::new(&table).unwrap().unwrap();
        let chain = MatrixChain::<F32>::new(&table).unwrap();
        let mut frames = Frames::default();
        let tip = chain
            .eval_frames(&[1, 2, 3, 4, 5, 6], 20_000, &mut frames)
            .unwrap();
        let trace = |part: &ParameterPart<'_>| {
            let mut sigma = Covariance::default();
            part.add_to(&frames, tip.xyz, 20_000, &mut sigma);
            sigma.0[0] + sigma.0[1] + sigma.0[2]
        };
        // nm²: 1 µm alone, then 1 + 4.
        let close = |a: f32, b: f32| (a - b).abs() < 1e-3 * b;
        assert!(close(trace(&part), 1.0e6), "{}", trace(&part));
        part.mount(&table, 1).unwrap();
        assert!(close(trace(&part), 5.0e6), "{}", trace(&part));
        part.mount(&table, 2).unwrap();
        assert!(close(trace(&part), 1.0e6), "{}", trace(&part));
        assert!(part.mount(&table, 3).is_err());
        assert!(close(trace(&part), 1.0e6), "nothing changed");
    }

    /// The blocked product (J_π L)(J_π L)ᵀ against the plain one in f64, for counts of
    /// parameters below, at and across the block's width (the triangle's partial rows, the
    /// last narrow block).
    #[test]
    fn the_blocked_product_is_the_plain_one() {
        for p in [1, 5, 6, 7, 8, 9, 13, 19, 52] {
            // Tilts and shifts on several joints, with vectors and factor entries that vary.
            let columns: std::vec::Vec<Column> = (0..p)
                .map(|i| {
                    let (x, shift) = (i as f32, i % 2 == 0);
                    Column {
                        vector: [(0.3 * x).sin(), (0.7 * x).cos(), 0.5],
                        w0: if shift { 1.0 } else { 0.0 },
                        ..Column::new(if shift { Kind::Shift } else { Kind::Tilt }, (i % 6) as u8)
                    }
                })
                .collect();
            let factor: std::vec::Vec<f32> = (0..factor_len(p))
                .map(|k| 1e-3 * ((k as f32 * 1.37).sin() + 0.1))
                .collect();
            let mut buf = [0u8; MAX_TABLE_LEN];
            let table = with_block(&columns, &factor, &mut buf);
            let part = ParameterPart::new(&table).unwrap().unwrap();
            let chain = MatrixChain::<F32>::new(&table).unwrap();
            let mut frames = Frames::default();
            let tip = chain
                .eval_frames(&[100, 2000, 30_000, 4, 50, 6000], 23_000, &mut frames)
                .unwrap();
            let mut got = Covariance::default();
            part.add_to(&frames, tip.xyz, 23_000, &mut got);
            // Σ = J L Lᵀ Jᵀ in f64 from the same columns.
            let d: std::vec::Vec<[f64; 3]> = (0..p)
                .map(|i| {
                    let col = part.block.column(i).unwrap();
                    part.column(&col, &frames, tip.xyz, 3.0)
                        .map(|x| f64::from(x) * 1e6)
                })
                .collect();
            let mut want = [0.0f64; 6];
            for k in 0..p {
                let mut g = [0.0f64; 3];
                for (i, di) in d.iter().enumerate().skip(k) {
                    let l = f64::from(factor[factor_len(i) + k]);
                    for c in 0..3 {
                        g[c] += di[c] * l;
                    }
                }
                let pairs = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];
                for (w, (a, b)) in want.iter_mut().zip(pairs) {
                    *w += g[a] * g[b];
                }
            }
            let scale = want[0] + want[1] + want[2];
            for (g, w) in got.0.iter().zip(want) {
                assert!(
                    (f64::from(*g) - w).abs() < 1e-5 * scale,
                    "P = {p}: {got:?} against {want:?}"
                );
            }
        }
    }
}

#[cfg(test)]
mod product_tests {
    use super::*;

    /// cos hθ, sin hθ by squaring against f64's, for orders 0 to 300 at angles all round.
    #[test]
    fn harmonic_weights_match_f64() {
        let mut worst = 0.0f64;
        for a in 0..1000 {
            let t = f64::from(a) * 0.00731 - 3.0;
            for h in 0..300u16 {
                let [c, s] = harmonic([t.cos() as f32, t.sin() as f32], h);
                let ht = f64::from(h) * t;
                worst = worst.max((f64::from(c) - ht.cos()).abs());
                worst = worst.max((f64::from(s) - ht.sin()).abs());
            }
        }
        // The input's rounding (6e-8 of θ) grows h-fold; orders of a real calibration are ≤ 8.
        assert!(worst < 300.0 * 1.2e-7, "{worst}");
    }
}
