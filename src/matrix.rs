//! The comparison chain: the same calibrated model with 3×4 matrices, base to tip.
//!
//! The straightforward Denavit–Hartenberg-style evaluation: each joint's rotation
//! R_i = M'_i · Rot(u_i, θ_i + e_i) is a 3×3 matrix (M'_i precomputed on the host, the axis
//! rotation from cos θ and sin θ), the pose accumulates as R_0i = R_0(i−1) R_i and
//! o_(i+1) = o_i + R_0i v_i. It shares the angles, harmonics, thermal expansion and the gravity
//! deflection angle with [`crate::chain`]; only the rotation representation differs. Gravity is
//! applied as the spec's first-order sum Δp = Σ e_k a_k × (p − o_k), Δn = Σ e_k a_k × n.
//!
//! It exists to measure, on the same arm and targets, whether the quaternion chain is really
//! as accurate and as cheap (`armcal accuracy`, `cargo xtask bench-target`).

use crate::model::{gravity_angle, ChainError, Model, Point};
use crate::rotate::{cyclic, Vec3};
use crate::scalar::{Fixed, Precision, Scale, F32};
use crate::table::{Table, MAX_JOINTS};

type Mat<P> = [[<P as Precision>::U; 3]; 3];

/// The 3×4 matrix chain of one evaluator.
#[derive(Clone, Copy, Debug)]
pub struct MatrixChain<P: Precision> {
    model: Model<P>,
    rotation: [Mat<P>; MAX_JOINTS],
}

/// The f32 matrix chain.
pub type MatrixChainF32 = MatrixChain<F32>;
/// The fixed-point matrix chain.
pub type MatrixChainFixed = MatrixChain<Fixed>;

#[inline(always)]
fn mat_vec<P: Precision, E: Scale<P>>(m: &Mat<P>, v: &Vec3<E>) -> Vec3<E> {
    let row = |r: &[P::U; 3]| v[0].scale(r[0]) + v[1].scale(r[1]) + v[2].scale(r[2]);
    [row(&m[0]), row(&m[1]), row(&m[2])]
}

#[inline(always)]
fn cross<P: Precision, E: Scale<P>>(a: &Vec3<P::U>, b: &Vec3<E>) -> Vec3<E> {
    [
        b[2].scale(a[1]) - b[1].scale(a[2]),
        b[0].scale(a[2]) - b[2].scale(a[0]),
        b[1].scale(a[0]) - b[0].scale(a[1]),
    ]
}

impl<P: Precision> MatrixChain<P> {
    /// Builds the chain from a validated table.
    pub fn new(table: &Table<'_>) -> Result<MatrixChain<P>, ChainError> {
        let model = Model::<P>::new(table)?;
        let zero = P::U::default();
        let mut rotation = [[[zero; 3]; 3]; MAX_JOINTS];
        for (i, r) in rotation.iter_mut().enumerate().take(model.n) {
            let j = table
                .joint(i)
                .ok_or(ChainError::Range { joint: i as u8 + 1 })?;
            for (row, src) in r.iter_mut().zip(j.matrix) {
                *row = crate::model::units::<P, 3>(src, i + 1)?;
            }
        }
        Ok(MatrixChain { model, rotation })
    }

    /// Number of joints.
    pub fn joint_count(&self) -> usize {
        self.model.n
    }

    /// Probe-ball centre and direction; same contract as [`crate::chain::Chain::eval`].
    pub fn eval(&self, counts: &[u32], temp_mc: i32) -> Result<Point<P>, ChainError> {
        let m = &self.model;
        let n = m.n;
        let (st, probe) = m.state(counts, temp_mc)?;
        let zero = P::U::default();
        let lzero = P::L::default();
        let mut r: Mat<P> = [
            [P::ONE, zero, zero],
            [zero, P::ONE, zero],
            [zero, zero, P::ONE],
        ];
        let mut o: Vec3<P::L> = [lzero; 3];
        let mut axes = [[zero; 3]; MAX_JOINTS];
        let mut origins = [[lzero; 3]; MAX_JOINTS];
        for i in 0..n {
            let (j, s) = (&m.joints[i], &st[i]);
            let (mut c, mut sn) = s.angle.full();
            if j.harmonic_count > 0 {
                let e = s.error;
                let h = P::half(e.scale(e));
                let c2 = c - (sn.scale(e) + c.scale(h));
                sn = sn + (c.scale(e) - sn.scale(h));
                c = c2;
            }
            // R_i = M' · Rot(u, θ): column u of M' stays, the other two turn by θ.
            let mj = &self.rotation[i];
            let (a, b, d) = {
                let (b, d) = cyclic(j.axis);
                (usize::from(j.axis), b, d)
            };
            let mut ri: Mat<P> = [[zero; 3]; 3];
            for k in 0..3 {
                ri[k][a] = mj[k][a];
                ri[k][b] = mj[k][b].scale(c) + mj[k][d].scale(sn);
                ri[k][d] = mj[k][d].scale(c) - mj[k][b].scale(sn);
            }
            let mut next: Mat<P> = [[zero; 3]; 3];
            for (nrow, rrow) in next.iter_mut().zip(&r) {
                for (col, x) in nrow.iter_mut().enumerate() {
                    *x = rrow[0].scale(ri[0][col])
                        + rrow[1].scale(ri[1][col])
                        + rrow[2].scale(ri[2][col]);
                }
            }
            r = next;
            if j.has_gravity {
                axes[i] = [r[0][a], r[1][a], r[2][a]];
                origins[i] = o;
            }
            let v = mat_vec::<P, P::L>(&r, &s.link);
            o = [o[0] + v[0], o[1] + v[1], o[2] + v[2]];
        }
        let v = mat_vec::<P, P::L>(&r, &probe);
        let mut p = [o[0] + v[0], o[1] + v[1], o[2] + v[2]];
        let mut dir = mat_vec::<P, P::U>(&r, &m.dir);
        // First-order gravity, every deflection from the undeflected pose.
        let (mut dp, mut dn) = ([lzero; 3], [zero; 3]);
        for i in 0..n {
            let j = &m.joints[i];
            if !j.has_gravity {
                continue;
            }
            let ok = &origins[i];
            let lever = [p[0] - ok[0], p[1] - ok[1], p[2] - ok[2]];
            let c = cross::<P, P::L>(&axes[i], &lever);
            let e = gravity_angle::<P>(j.gravity, c[2]);
            let cn = cross::<P, P::U>(&axes[i], &dir);
            for k in 0..3 {
                dp[k] = dp[k] + c[k].scale(e);
                dn[k] = dn[k] + cn[k].scale(e);
            }
        }
        for k in 0..3 {
            p[k] = p[k] + dp[k];
            dir[k] = dir[k] + dn[k];
        }
        Ok(Point { xyz: p, dir })
    }
}
