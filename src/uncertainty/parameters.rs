//! The calibration's part of Σ_p: J_π C J_πᵀ, exactly, as (J_π L)(J_π L)ᵀ with C = L Lᵀ
//! from the table ([`crate::table::parameters`]).
//!
//! J_π's columns come from the joints' frames at the reading, which the matrix chain composes
//! anyway ([`MatrixChain::eval_frames`]): each parameter is a turn about a joint's axis, a
//! turn about a fixed axis, or a shift (the table's column kinds; a probe's shift only while
//! that probe is mounted), evaluated in f32. The
//! frames are the undeflected chain's and the harmonic weights come from micromath's
//! `sin`/`cos`; both err by ~1e-3 of a column at most, where U95 must agree with the host to
//! 1 % (measured: `cargo test -p armcal --test hub_u95`).
//!
//! Cost per point: the matrix chain once, P columns of a few dozen operations, and
//! 3 · P(P+1)/2 multiply-adds with the block read from the table (4,134 for P = 52).

use super::Covariance;
use crate::matrix::{Frames, MatrixChain};
use crate::model::{unpermute_inline, ChainError, BASE_AXIS, REFERENCE_TEMP_MC};
use crate::physics::Physics;
use crate::rotate::{cross, Vec3};
use crate::scalar::F32;
use crate::table::parameters::{Column, Kind, Parameters, MAX_PARAMETERS};
use crate::table::{Table, MAX_JOINTS};
use micromath::F32Ext;

/// The parameter part of a table with a parameter block, built at boot. It borrows the
/// block (the columns' records and the factor, read at every point) rather than copying it:
/// a copy is 11 KB at 64 parameters, and the boot's moves of a struct that size overflowed
/// the qemu-m4f hub's 64 KiB of RAM.
#[derive(Clone, Debug)]
pub struct ParameterPart<'a, P: Physics> {
    chain: MatrixChain<P>,
    block: Parameters<'a>,
    /// Each joint's axis (0, 1, 2: x, y, z), for the records' relabelling.
    axes: [u8; MAX_JOINTS],
    /// Each joint's counts per revolution, for the harmonics' angle.
    counts: [u32; MAX_JOINTS],
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

const IDENTITY: [[f32; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

impl<'a, P: Physics> ParameterPart<'a, P> {
    /// The part of a validated table; `None` where it has no parameter block.
    pub fn new(table: &Table<'a>) -> Result<Option<ParameterPart<'a, P>>, ChainError> {
        let Some(block) = table.parameters() else {
            return Ok(None);
        };
        let chain = MatrixChain::new(table)?;
        let (mut axes, mut counts) = ([BASE_AXIS; MAX_JOINTS], [1; MAX_JOINTS]);
        for (k, (a, c)) in axes.iter_mut().zip(&mut counts).enumerate() {
            if let Some(j) = table.joint(k) {
                (*a, *c) = (j.axis, j.counts);
            }
        }
        Ok(Some(ParameterPart {
            chain,
            block,
            axes,
            counts,
            probe: table.probe().id,
        }))
    }

    /// Follows the hub's chain to the table's probe `k`: its matrix chain mounts it, and the
    /// columns of a probe's shift are that probe's. Nothing changes on an error.
    pub fn mount(&mut self, table: &Table<'a>, k: usize) -> Result<(), ChainError> {
        let id = table.probe_id(k).ok_or(ChainError::Range { joint: 0 })?;
        self.chain.mount(table, k)?;
        self.probe = id;
        Ok(())
    }

    /// Number of parameters.
    pub fn count(&self) -> usize {
        self.block.count().min(MAX_PARAMETERS)
    }

    /// Σ += J_π C J_πᵀ at the reading (`counts`, `temp_mc`), in nm².
    pub fn add_to(
        &self,
        counts: &[u32],
        temp_mc: i32,
        sigma: &mut Covariance,
    ) -> Result<(), ChainError> {
        let mut frames = Frames::default();
        let tip = self.chain.eval_frames(counts, temp_mc, &mut frames)?;
        let p = tip.xyz.map(P::l_to_f32);
        let dt = temp_mc.wrapping_sub(REFERENCE_TEMP_MC) as f32 * 1.0e-3;
        // g_k = Σ_i J_i L_ik: column k of J_π L, filled row by row of L.
        let mut g = [[0.0f32; 3]; MAX_PARAMETERS];
        let n = self.count();
        for i in 0..n {
            // The table's check read every record (kind, joint within the table).
            let Some(col) = self.block.column(i) else {
                continue;
            };
            let d = self.column(&col, &frames, p, counts, dt);
            for (gk, l) in g.iter_mut().zip(self.block.factor_row(i).chunks_exact(4)) {
                let l = f32::from_le_bytes([l[0], l[1], l[2], l[3]]);
                for (x, dx) in gk.iter_mut().zip(d) {
                    *x += dx * l;
                }
            }
        }
        // mm → nm.
        for gk in &g[..n] {
            sigma.add_outer(scaled(*gk, 1.0e6), 1.0);
        }
        Ok(())
    }

    /// sin hθ_k or cos hθ_k of a periodic column, hθ reduced to a turn in integers first
    /// (θ = 2π c / counts), so that the f32 angle stays below 2π whatever the order.
    /// micromath's (≈ 1e-3 off): a weight of one column, harmless at U95's 1 %.
    #[inline(always)]
    fn weight(&self, col: &Column, counts: &[u32], k: usize) -> f32 {
        let c = u64::from(counts.get(k).copied().unwrap_or(0));
        let n = u64::from(self.counts[k].max(1));
        let phase = (u64::from(col.order) * c) % n;
        let a = phase as f32 / n as f32 * core::f32::consts::TAU;
        if matches!(col.kind, Kind::TurnSin | Kind::TiltSin) {
            F32Ext::sin(a)
        } else {
            F32Ext::cos(a)
        }
    }

    /// ∂p/∂π for one parameter (mm per the parameter's unit).
    fn column(
        &self,
        col: &Column,
        frames: &Frames,
        p: Vec3<f32>,
        counts: &[u32],
        dt: f32,
    ) -> Vec3<f32> {
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
        match col.kind {
            Kind::Turn => turn(),
            Kind::TurnSin | Kind::TurnCos => scaled(turn(), self.weight(col, counts, k)),
            // The first-order lever of the spec: a_k · ((p − o_k) × ẑ).
            Kind::TurnGravity => scaled(turn(), axis[0] * lever[1] - axis[1] * lever[0]),
            Kind::Tilt => tilt(),
            Kind::TiltSin | Kind::TiltCos => scaled(tilt(), self.weight(col, counts, k)),
            Kind::ProbeShift if col.order != u16::from(self.probe) => [0.0; 3],
            Kind::Shift | Kind::ProbeShift => scaled(mat_vec(r, vector), col.w0 + col.w1 * dt),
        }
    }
}

#[cfg(all(test, feature = "parameters"))]
mod tests {
    use super::*;
    use crate::table::budget::BudgetData;
    use crate::table::parameters::{Column, ParameterData};
    use crate::table::probes::tests::several;
    use crate::table::MAX_TABLE_LEN;

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
        let block = ParameterData {
            columns: &columns,
            factor: &factor,
        };
        let mut buf = [0u8; MAX_TABLE_LEN];
        let n = several()
            .encode_full(Some(&BudgetData::default()), Some(&block), &mut buf)
            .unwrap();
        let table = Table::parse(&buf[..n]).unwrap();
        let mut part = ParameterPart::<F32>::new(&table).unwrap().unwrap();
        let trace = |part: &ParameterPart<'_, F32>| {
            let mut sigma = Covariance::default();
            part.add_to(&[1, 2, 3, 4, 5, 6], 20_000, &mut sigma)
                .unwrap();
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
}
