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

use super::{Covariance, PosePart};
use crate::matrix::Frames;
use crate::model::{unpermute_inline, ChainError, BASE_AXIS, REFERENCE_TEMP_MC};
use crate::rotate::{cross, Vec3};
use crate::scalar::F32;
use crate::table::parameters::{factor_len, Column, Kind, MAX_PARAMETERS};
use crate::table::{Table, MAX_JOINTS};
use core::mem::MaybeUninit;

/// Columns of L whose sums J_π L's block accumulates at once: 6 × 3 accumulators, a column
/// of J_π and a row's 6 entries of L fill 27 of the Cortex-M4F's 32 single-precision
/// registers (with 8, 24 sums and their operands did not fit: the compiler shuffled
/// registers at every row, ~9 instructions an entry of L; measured on qemu-m4f).
pub const BLOCK: usize = 6;

/// The parameter part of a table with a parameter block, built at boot. It borrows the
/// factor (8.3 KB at 64 parameters: as a copy, the boot's moves of a struct that size
/// overflowed the qemu-m4f hub's 64 KiB of RAM) and keeps the columns' records decoded
/// (24 B a parameter): decoding each record from the table's bytes at every point, with its
/// frame's relabelling, cost more than the column it gives (measured on qemu-m4f,
/// `docs/results/speed.md`).
#[derive(Clone, Debug)]
pub struct ParameterPart<'a> {
    /// L, row after row, as the table's little-endian bytes.
    factor: &'a [u8],
    /// The columns' records, decoded ([`Record`]); the first `count` hold the block's.
    records: [Record; MAX_PARAMETERS],
    /// Number of parameters.
    count: usize,
    /// The id of the probe mounted: a probe's shift ([`Kind::ProbeShift`]) of another is 0.
    probe: u8,
    /// L in integers, for the product on a core without an FPU (feature `fixed-u95`).
    #[cfg(feature = "fixed-u95")]
    fixed: super::fixed_product::FixedFactor,
    /// The budget's pose part, where the block has it ([`super::pose`]).
    pose: Option<PosePart<'a>>,
}

/// A parameter's record as every point reads it: the table's, with its vector relabelled
/// into the frame the chain's matrices use (a tilt's: the frame before its joint, the
/// previous joint's or the base's, labelled like a z joint; a shift's: its joint's) and in
/// nm per the parameter's unit (the record's is in mm).
#[derive(Clone, Copy, Debug)]
struct Record {
    kind: Kind,
    /// Its joint, within [`MAX_JOINTS`].
    joint: u8,
    order: u16,
    vector: Vec3<f32>,
    w0: f32,
    w1: f32,
}

const NO_RECORD: Record = Record {
    kind: Kind::Turn,
    joint: 0,
    order: 0,
    vector: [0.0; 3],
    w0: 0.0,
    w1: 0.0,
};

impl Record {
    /// The table's column `col`, its joints' axes `axes` (0, 1, 2: x, y, z).
    fn of(col: &Column, axes: &[u8; MAX_JOINTS]) -> Record {
        let k = usize::from(col.joint).min(MAX_JOINTS - 1);
        let tilt = matches!(col.kind, Kind::Tilt | Kind::TiltSin | Kind::TiltCos);
        let frame_axis = match (tilt, k) {
            (true, 0) => BASE_AXIS,
            (true, _) => axes[k - 1],
            _ => axes[k],
        };
        Record {
            kind: col.kind,
            joint: k as u8,
            order: col.order,
            vector: scaled(unpermute_inline(col.vector, frame_axis), NM_PER_MM),
            w0: col.w0,
            w1: col.w1,
        }
    }
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
pub(super) fn accumulate(g: &mut [f32; 3], d: &[f32; 3], l: f32) {
    g[0] += d[0] * l;
    g[1] += d[1] * l;
    g[2] += d[2] * l;
}

/// L's entries as the product reads them: an aligned run of f32 where the table's bytes
/// allow it (the hub's flash: the block's factor starts at a multiple of 4 bytes in the
/// format, and the table region is aligned), else the raw little-endian bytes (a host's
/// buffer of any alignment).
pub(super) trait Entries: Copy {
    /// The [`BLOCK`] entries from entry `at` on; `None` past the end.
    fn block(self, at: usize) -> Option<[f32; BLOCK]>;
    /// Entry `at`; `None` past the end.
    fn one(self, at: usize) -> Option<f32>;

    /// The `W` entries from entry `at` on; `None` past the end (the pose part's rows of D,
    /// [`super::pose`]).
    #[inline(always)]
    fn run<const W: usize>(self, at: usize) -> Option<[f32; W]> {
        let mut v = [0.0; W];
        for (b, x) in v.iter_mut().enumerate() {
            *x = self.one(at + b)?;
        }
        Some(v)
    }

    /// g_b = Σ_i L_(i, k0 + b) d_i for a whole block (its BLOCK columns k0 … k0 + 5 all
    /// within L; `g` overwritten, so the caller need not zero it): `d` holds the columns of the rows k0, k0 + 1, … to the last, the first five the
    /// block's triangle (row k0 + r holds r + 1 of its entries), the rest whole rows.
    #[inline(always)]
    fn whole_block(self, g: &mut [[f32; 3]; BLOCK], d: &[[f32; 3]], k0: usize) {
        whole_block_portable(self, g, d, k0);
    }
}

/// The accumulators' start in the assembly block: its 18 sums loaded from here (one `vldm`).
#[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
static ZERO_BLOCK: [f32; 3 * BLOCK] = [0.0; 3 * BLOCK];

/// [`Entries::whole_block`] in Rust, for every target.
#[inline(always)]
fn whole_block_portable<E: Entries>(
    factor: E,
    g: &mut [[f32; 3]; BLOCK],
    d: &[[f32; 3]],
    k0: usize,
) {
    let mut acc = [[0.0f32; 3]; BLOCK];
    let (top, rest) = d.split_at(d.len().min(BLOCK - 1));
    triangle_rows(&mut acc, top, factor, k0, BLOCK);
    rows_portable(factor, &mut acc, rest, k0 + BLOCK - 1, k0);
    *g = acc;
}

/// g_b += L_(i, k0 + b) d_i for the rows i = first, first + 1, … whose columns d are given,
/// each holding the block's BLOCK entries.
#[inline(always)]
fn rows_portable<E: Entries>(
    factor: E,
    g: &mut [[f32; 3]; BLOCK],
    d: &[[f32; 3]],
    first: usize,
    k0: usize,
) {
    let mut at = factor_len(first) + k0;
    for (i, di) in d.iter().enumerate() {
        let Some(row) = factor.block(at) else {
            break;
        };
        for (b, gb) in g.iter_mut().enumerate() {
            accumulate(gb, di, row[b]);
        }
        // Row first + i + 1 starts first + i + 1 entries after row first + i.
        at += first + i + 1;
    }
}

impl Entries for &[f32] {
    #[inline(always)]
    fn block(self, at: usize) -> Option<[f32; BLOCK]> {
        self.get(at..at + BLOCK)?.try_into().ok()
    }
    #[inline(always)]
    fn run<const W: usize>(self, at: usize) -> Option<[f32; W]> {
        self.get(at..at + W)?.try_into().ok()
    }
    #[inline(always)]
    fn one(self, at: usize) -> Option<f32> {
        self.get(at).copied()
    }

    /// On a Cortex-M with single-precision floating point, the block in assembly: the
    /// triangle's rows written out, then a loop over the whole rows, a row's entries and its
    /// column each one `vldm`, the 18 sums in s0–s17 throughout: 24 instructions a whole row
    /// (the compiler's loop took 35: a load an entry and a bounds check a row; its triangle,
    /// ~300 a block, this one 66; measured on qemu-m4f, `docs/results/speed.md`). The same
    /// multiply-adds in the same order as the portable code (`vmla` rounds the product and
    /// the sum, as `g += d * l` does), so the sums are its bit for bit.
    #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
    #[inline(always)]
    fn whole_block(self, g: &mut [[f32; 3]; BLOCK], d: &[[f32; 3]], k0: usize) {
        let rows = d.len();
        // The block is whole: rows k0 … k0 + 5 at least, and the last row's block ends
        // within the slice.
        if rows < BLOCK || factor_len(k0 + rows - 1) + k0 + BLOCK > self.len() {
            return whole_block_portable(self, g, d, k0);
        }
        // SAFETY: `g` holds 18 f32 (written), `ZERO_BLOCK` 18 (read), and `d` `rows` ≥ 6
        // triples (read). Row k0 + r's entries start at entry factor_len(k0 + r) + k0 = that
        // of row k0 plus Σ_(j<r) (k0 + 1 + j); the triangle's row r reads r + 1 of them, the
        // whole rows 6, the last ending at the entry checked above. The floating-point
        // registers it uses are saved and restored on the stack inside (Rust's `sreg`
        // operands need double-precision VFP2, which this FPU does not have); the core
        // registers it writes are declared.
        unsafe {
            core::arch::asm!(
                "vpush {{s0-s26}}",
                "vldmia {z}, {{s0-s17}}",
                // The triangle: rows k0 … k0 + 4, 1 to 5 entries.
                "vldmia {d}!, {{s18-s20}}",
                "vldr s21, [{l}]",
                "add.w {l}, {l}, {step}, lsl #2",
                "adds {step}, #1",
                "vmla.f32 s0, s18, s21",
                "vmla.f32 s1, s19, s21",
                "vmla.f32 s2, s20, s21",
                "vldmia {d}!, {{s18-s20}}",
                "vldmia {l}, {{s21-s22}}",
                "add.w {l}, {l}, {step}, lsl #2",
                "adds {step}, #1",
                "vmla.f32 s0, s18, s21",
                "vmla.f32 s1, s19, s21",
                "vmla.f32 s2, s20, s21",
                "vmla.f32 s3, s18, s22",
                "vmla.f32 s4, s19, s22",
                "vmla.f32 s5, s20, s22",
                "vldmia {d}!, {{s18-s20}}",
                "vldmia {l}, {{s21-s23}}",
                "add.w {l}, {l}, {step}, lsl #2",
                "adds {step}, #1",
                "vmla.f32 s0, s18, s21",
                "vmla.f32 s1, s19, s21",
                "vmla.f32 s2, s20, s21",
                "vmla.f32 s3, s18, s22",
                "vmla.f32 s4, s19, s22",
                "vmla.f32 s5, s20, s22",
                "vmla.f32 s6, s18, s23",
                "vmla.f32 s7, s19, s23",
                "vmla.f32 s8, s20, s23",
                "vldmia {d}!, {{s18-s20}}",
                "vldmia {l}, {{s21-s24}}",
                "add.w {l}, {l}, {step}, lsl #2",
                "adds {step}, #1",
                "vmla.f32 s0, s18, s21",
                "vmla.f32 s1, s19, s21",
                "vmla.f32 s2, s20, s21",
                "vmla.f32 s3, s18, s22",
                "vmla.f32 s4, s19, s22",
                "vmla.f32 s5, s20, s22",
                "vmla.f32 s6, s18, s23",
                "vmla.f32 s7, s19, s23",
                "vmla.f32 s8, s20, s23",
                "vmla.f32 s9, s18, s24",
                "vmla.f32 s10, s19, s24",
                "vmla.f32 s11, s20, s24",
                "vldmia {d}!, {{s18-s20}}",
                "vldmia {l}, {{s21-s25}}",
                "add.w {l}, {l}, {step}, lsl #2",
                "adds {step}, #1",
                "vmla.f32 s0, s18, s21",
                "vmla.f32 s1, s19, s21",
                "vmla.f32 s2, s20, s21",
                "vmla.f32 s3, s18, s22",
                "vmla.f32 s4, s19, s22",
                "vmla.f32 s5, s20, s22",
                "vmla.f32 s6, s18, s23",
                "vmla.f32 s7, s19, s23",
                "vmla.f32 s8, s20, s23",
                "vmla.f32 s9, s18, s24",
                "vmla.f32 s10, s19, s24",
                "vmla.f32 s11, s20, s24",
                "vmla.f32 s12, s18, s25",
                "vmla.f32 s13, s19, s25",
                "vmla.f32 s14, s20, s25",
                // The whole rows k0 + 5 … to the last.
                "2:",
                "vldmia {d}!, {{s18-s20}}",
                "vldmia {l}, {{s21-s26}}",
                "add.w {l}, {l}, {step}, lsl #2",
                "adds {step}, #1",
                "vmla.f32 s0, s18, s21",
                "vmla.f32 s1, s19, s21",
                "vmla.f32 s2, s20, s21",
                "vmla.f32 s3, s18, s22",
                "vmla.f32 s4, s19, s22",
                "vmla.f32 s5, s20, s22",
                "vmla.f32 s6, s18, s23",
                "vmla.f32 s7, s19, s23",
                "vmla.f32 s8, s20, s23",
                "vmla.f32 s9, s18, s24",
                "vmla.f32 s10, s19, s24",
                "vmla.f32 s11, s20, s24",
                "vmla.f32 s12, s18, s25",
                "vmla.f32 s13, s19, s25",
                "vmla.f32 s14, s20, s25",
                "vmla.f32 s15, s18, s26",
                "vmla.f32 s16, s19, s26",
                "vmla.f32 s17, s20, s26",
                "subs {n}, #1",
                "bne 2b",
                "vstmia {g}, {{s0-s17}}",
                "vpop {{s0-s26}}",
                g = in(reg) g.as_mut_ptr(),
                z = in(reg) ZERO_BLOCK.as_ptr(),
                d = inout(reg) d.as_ptr() => _,
                l = inout(reg) self.as_ptr().add(factor_len(k0) + k0) => _,
                step = inout(reg) k0 + 1 => _,
                n = inout(reg) rows - (BLOCK - 1) => _,
            );
        }
    }
}

impl Entries for &[u8] {
    #[inline(always)]
    fn block(self, at: usize) -> Option<[f32; BLOCK]> {
        let row = self.get(4 * at..4 * (at + BLOCK))?;
        Some(core::array::from_fn(|b| entry(row, b)))
    }
    #[inline(always)]
    fn one(self, at: usize) -> Option<f32> {
        self.get(4 * at..4 * at + 4).map(|b| entry(b, 0))
    }
}

/// The factor's bytes as f32 where they are aligned for it (and the machine is little
/// endian, the format's order); `None` otherwise.
pub(super) fn as_f32(bytes: &[u8]) -> Option<&[f32]> {
    if cfg!(target_endian = "big") {
        return None;
    }
    // SAFETY: every bit pattern is a valid f32, and `align_to` hands out only the aligned
    // middle of the slice (whole f32s within it); the check below takes it only when it is
    // the whole slice.
    let (head, mid, tail) = unsafe { bytes.align_to::<f32>() };
    (head.is_empty() && tail.is_empty()).then_some(mid)
}

/// One block of BLOCK columns of J_π L from k0 on (`width` of them within L) into `g`
/// (overwritten; a narrow block's columns past `width` zero): `d` holds the
/// columns of the rows k0, k0 + 1, … to the last. Out of line and indexed by constants only,
/// so that the 18 sums stay in registers (inlined into `add_to`, its sums went to the stack
/// at every row: measured on qemu-m4f).
#[inline(never)]
fn block<E: Entries>(
    g: &mut [[f32; 3]; BLOCK],
    d: &[[f32; 3]],
    factor: E,
    k0: usize,
    width: usize,
) {
    if width == BLOCK {
        factor.whole_block(g, d, k0);
    } else {
        // The last, narrow block: all its rows are its triangle's.
        let mut acc = [[0.0f32; 3]; BLOCK];
        triangle_rows(&mut acc, d, factor, k0, width);
        *g = acc;
    }
}

/// g_b += L_(k0 + r, k0 + b) d_(k0 + r) for the rows r = 0, 1, … of the block's triangle
/// (row k0 + r holds the first r + 1 of the block's `width` entries), indexed by constants:
/// each row leaves its loop at its last entry (reading all six and selecting the row's took
/// ~110 instructions a row, measured on qemu-m4f).
#[inline(always)]
fn triangle_rows<E: Entries>(
    g: &mut [[f32; 3]; BLOCK],
    d: &[[f32; 3]],
    factor: E,
    k0: usize,
    width: usize,
) {
    let mut acc = *g;
    for (r, di) in d.iter().enumerate() {
        let at = factor_len(k0 + r) + k0;
        let m = (r + 1).min(width);
        for (b, gb) in acc.iter_mut().enumerate() {
            if b >= m {
                break;
            }
            let Some(l) = factor.one(at + b) else {
                break;
            };
            accumulate(gb, di, l);
        }
    }
    *g = acc;
}

/// Σ += (J_π L)(J_π L)ᵀ for the columns `d` of J_π (nm): g_k = Σ_(i ≥ k) L_ik d_i, column k
/// of J_π L, for BLOCK columns k at a time: first the rows of the block's triangle (row i
/// holds L_ik for k ≤ i only), then the rows below it, whole ([`block`]).
fn product<E: Entries>(d: &[[f32; 3]], factor: E, sigma: &mut Covariance) {
    let n = d.len();
    let mut k0 = 0;
    // Each block overwrites it (zeroing it a block was a `memset` call: measured on qemu-m4f).
    let mut g = [[0.0f32; 3]; BLOCK];
    while k0 < n {
        let width = (n - k0).min(BLOCK);
        block(&mut g, d.get(k0..).unwrap_or(&[]), factor, k0, width);
        for gb in &g[..width] {
            sigma.add_outer(*gb, 1.0);
        }
        k0 += BLOCK;
    }
}

/// An entry of L from its four little-endian bytes.
#[inline(always)]
fn entry(b: &[u8], k: usize) -> f32 {
    f32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]])
}

const IDENTITY: [[f32; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// nm per mm.
const NM_PER_MM: f32 = 1.0e6;

/// What every column of a point reads from its joint: the frames, and per joint the lever
/// p − o_k, the turn a_k × (p − o_k) (nm) and cos 2θ, sin 2θ ([`harmonic`] of order 2, once
/// a joint instead of once a column).
struct Joint<'f> {
    frames: &'f Frames,
    levers: &'f [Vec3<f32>; MAX_JOINTS],
    turns: &'f [Vec3<f32>; MAX_JOINTS],
    second: &'f [[f32; 2]; MAX_JOINTS],
}

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
        let count = block.count().min(MAX_PARAMETERS);
        let mut records = [NO_RECORD; MAX_PARAMETERS];
        for (i, r) in records.iter_mut().enumerate().take(count) {
            // The table's check read every record (kind, joint within the table).
            *r = Record::of(
                &block.column(i).ok_or(ChainError::Range { joint: 0 })?,
                &axes,
            );
        }
        let factor = block.factor();
        Ok(Some(ParameterPart {
            factor,
            records,
            count,
            probe: table.probe().id,
            #[cfg(feature = "fixed-u95")]
            fixed: super::fixed_product::FixedFactor::new(
                |i| factor.get(4 * i..4 * i + 4).map(|b| entry(b, 0)),
                count,
            )
            .ok_or(ChainError::Range { joint: 0 })?,
            pose: block.pose().map(|p| PosePart::new(&p, table)),
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
        self.count
    }

    /// The budget's pose part, where the block has it.
    pub fn pose(&self) -> Option<&PosePart<'a>> {
        self.pose.as_ref()
    }

    /// Σ += J_π C J_πᵀ (nm²) at a reading at `temp_mc` whose frames are `frames` and tip `p`
    /// (mm) and counts `counts`; where the block has the budget's pose part,
    /// Σ += J_π C J_πᵀ + (max(1, ℓ, ℓJ) − 1) · J_π P J_πᵀ ([`super::pose`]).
    pub fn add_to(
        &self,
        frames: &Frames,
        p: Vec3<f32>,
        temp_mc: i32,
        counts: &[u32],
        sigma: &mut Covariance,
    ) {
        // Not zeroed first (768 bytes, a `memset` a point): `columns` writes the part it
        // hands back.
        let mut d = [MaybeUninit::uninit(); MAX_PARAMETERS];
        let d = self.columns(frames, p, temp_mc, &mut d);
        match &self.pose {
            None => self.product(d, sigma),
            Some(pose) => {
                let mut g = Covariance::default();
                self.product(d, &mut g);
                pose.widen(d, counts, &mut g);
                sigma.add(&g);
            }
        }
    }

    /// Σ += J_π C J_πᵀ = (J_π L)(J_π L)ᵀ for J_π's columns `d`.
    fn product(&self, d: &[[f32; 3]], sigma: &mut Covariance) {
        // In integers where the feature asks for it (a core without an FPU); the f32 product
        // stays compiled (its tests compare the two), and drops out of the image.
        #[cfg(feature = "fixed-u95")]
        let done = {
            self.fixed.add_to(d, sigma);
            true
        };
        #[cfg(not(feature = "fixed-u95"))]
        let done = false;
        if !done {
            match as_f32(self.factor) {
                Some(aligned) => product(d, aligned, sigma),
                None => product(d, self.factor, sigma),
            }
        }
    }

    /// J_π's columns (nm per the parameter's unit) into `d`, the filled part returned: per
    /// joint once the lever p − o_k and the turn about its axis, then each parameter's
    /// column from its joint's.
    fn columns<'d>(
        &self,
        frames: &Frames,
        p: Vec3<f32>,
        temp_mc: i32,
        d: &'d mut [MaybeUninit<[f32; 3]>; MAX_PARAMETERS],
    ) -> &'d [[f32; 3]] {
        let dt = temp_mc.wrapping_sub(REFERENCE_TEMP_MC) as f32 * 1.0e-3;
        // Every one of the MAX_JOINTS frames (those past the table's joints are the frames'
        // zeros, and no record of a validated table names them): each array written once,
        // where zeroing it first and filling the table's joints cost a `memset` call each
        // (~70 instructions; measured on qemu-m4f).
        let levers: [Vec3<f32>; MAX_JOINTS] = core::array::from_fn(|k| sub(p, frames.origin[k]));
        let turns: [Vec3<f32>; MAX_JOINTS] = core::array::from_fn(|k| {
            let r = &frames.rotation[k];
            scaled(
                cross::<F32>(&[r[0][2], r[1][2], r[2][2]], &levers[k]),
                NM_PER_MM,
            )
        });
        let second: [[f32; 2]; MAX_JOINTS] = core::array::from_fn(|k| harmonic(frames.turn[k], 2));
        let n = self.count;
        let joint = Joint {
            frames,
            levers: &levers,
            turns: &turns,
            second: &second,
        };
        for (di, rec) in d.iter_mut().zip(&self.records[..n]) {
            di.write(self.column(rec, &joint, dt));
        }
        // SAFETY: the loop wrote d[0 … n − 1] (n = count ≤ MAX_PARAMETERS, the length of both
        // `records` and `d`), and MaybeUninit<T> has T's layout.
        unsafe { core::slice::from_raw_parts(d.as_ptr().cast::<[f32; 3]>(), n) }
    }

    /// ∂p/∂π for one parameter (nm per the parameter's unit), from its joint's lever and
    /// turn.
    fn column(&self, rec: &Record, joint: &Joint<'_>, dt: f32) -> Vec3<f32> {
        let frames = joint.frames;
        let k = usize::from(rec.joint).min(MAX_JOINTS - 1);
        let (r, lever, turn) = (&frames.rotation[k], joint.levers[k], joint.turns[k]);
        let tilt = || {
            let before = if k == 0 {
                &IDENTITY
            } else {
                &frames.rotation[k - 1]
            };
            cross::<F32>(&mat_vec(before, rec.vector), &lever)
        };
        // Orders 1 and 2 (a calibration's usual harmonics) from the joint's, the same
        // numbers `harmonic` gives (order 1 is cos θ, sin θ as the chain formed them).
        let weight = || match rec.order {
            1 => frames.turn[k],
            2 => joint.second[k],
            h => harmonic(frames.turn[k], h),
        };
        match rec.kind {
            Kind::Turn => turn,
            Kind::TurnSin => scaled(turn, weight()[1]),
            Kind::TurnCos => scaled(turn, weight()[0]),
            // The first-order lever of the spec: a_k · ((p − o_k) × ẑ).
            Kind::Gravity => scaled(turn, r[0][2] * lever[1] - r[1][2] * lever[0]),
            Kind::Tilt => tilt(),
            Kind::TiltSin => scaled(tilt(), weight()[1]),
            Kind::TiltCos => scaled(tilt(), weight()[0]),
            Kind::ProbeShift if rec.order != u16::from(self.probe) => [0.0; 3],
            Kind::Shift | Kind::ProbeShift => scaled(mat_vec(r, rec.vector), rec.w0 + rec.w1 * dt),
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
        let block = ParameterData {
            columns,
            factor,
            pose: None,
        };
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
            part.add_to(&frames, tip.xyz, 20_000, &[1, 2, 3, 4, 5, 6], &mut sigma);
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
            part.add_to(
                &frames,
                tip.xyz,
                23_000,
                &[100, 2000, 30_000, 4, 50, 6000],
                &mut got,
            );
            // Σ = J L Lᵀ Jᵀ in f64 from the same columns.
            let mut cols = [MaybeUninit::uninit(); MAX_PARAMETERS];
            let d: std::vec::Vec<[f64; 3]> = part
                .columns(&frames, tip.xyz, 23_000, &mut cols)
                .iter()
                .map(|c| c.map(f64::from))
                .collect();
            assert_eq!(d.len(), p);
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
            // With `fixed-u95` the product is in integers (`fixed_product`): this factor's
            // rows, all entries alike, leave each column of J_π ~14 bits (2.7e-4 of a
            // variance seen at P = 8 with rows of 2^13: U95 within 1.4e-4).
            let tol = if cfg!(feature = "fixed-u95") {
                5e-4
            } else {
                1e-5
            };
            for (g, w) in got.0.iter().zip(want) {
                assert!(
                    (f64::from(*g) - w).abs() < tol * scale,
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

#[cfg(test)]
mod factor_tests {
    use super::*;

    /// The product reads L the same whether as aligned f32 or as bytes at any alignment (the
    /// hub takes the first, a host's unaligned buffer the second): equal sums, bit for bit,
    /// and both within f32 rounding of the plain product in f64.
    #[test]
    fn aligned_and_byte_factors_give_the_same_product() {
        for p in [1, 6, 7, 13, 52] {
            let d: std::vec::Vec<[f32; 3]> = (0..p)
                .map(|i| {
                    let x = i as f32;
                    [(0.3 * x).sin() * 1e3, (0.7 * x).cos() * 1e3, 500.0 - x]
                })
                .collect();
            let factor: std::vec::Vec<f32> = (0..factor_len(p))
                .map(|k| 1e-3 * ((k as f32 * 1.37).sin() + 0.1))
                .collect();
            let mut bytes = std::vec![0u8; 4 * factor.len() + 1];
            for (k, l) in factor.iter().enumerate() {
                bytes[1 + 4 * k..5 + 4 * k].copy_from_slice(&l.to_le_bytes());
            }
            let (mut a, mut b) = (Covariance::default(), Covariance::default());
            product(&d, factor.as_slice(), &mut a);
            product(&d, &bytes[1..], &mut b);
            assert_eq!(a, b, "P = {p}");
            let mut want = [0.0f64; 6];
            for k in 0..p {
                let mut g = [0.0f64; 3];
                for (i, di) in d.iter().enumerate().skip(k) {
                    let l = f64::from(factor[factor_len(i) + k]);
                    for c in 0..3 {
                        g[c] += f64::from(di[c]) * l;
                    }
                }
                let pairs = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];
                for (w, (x, y)) in want.iter_mut().zip(pairs) {
                    *w += g[x] * g[y];
                }
            }
            let scale = want[0] + want[1] + want[2];
            for (g, w) in a.0.iter().zip(want) {
                assert!(
                    (f64::from(*g) - w).abs() < 1e-5 * scale,
                    "P = {p}: {a:?} against {want:?}"
                );
            }
        }
    }

    /// Bytes at an aligned address are read as f32, whole; at an odd one they are not.
    #[test]
    fn only_aligned_bytes_are_read_as_f32() {
        let words = [1.5f32, -2.0, 3.25];
        let mut bytes = [0u8; 20];
        // A [u8; 20] has alignment 1: its first address that is a multiple of 4.
        let at = bytes.as_ptr().align_offset(4);
        for (k, w) in words.iter().enumerate() {
            bytes[at + 4 * k..at + 4 * k + 4].copy_from_slice(&w.to_le_bytes());
        }
        assert_eq!(as_f32(&bytes[at..at + 12]), Some(&words[..]));
        assert_eq!(as_f32(&bytes[at + 1..at + 5]), None);
    }
}
