//! The comparison chain: the same calibrated model with 3×4 matrices, base to tip.
//!
//! The straightforward Denavit–Hartenberg-style evaluation: each joint's rotation
//! R_i = M̃_i · Rot(z, θ_i + e_i) is a 3×3 matrix (M̃_i precomputed on the host and permuted to
//! z-axis frames at boot, the turn from cos θ and sin θ), the pose accumulates as
//! R_0i = R_0(i−1) R_i and o_(i+1) = o_i + R_0i v_i. It shares the angles, harmonics, thermal
//! expansion, the probe and the first-order gravity correction with [`crate::chain`]; only the
//! rotation representation differs. The harmonic error joins cos θ, sin θ to second order
//! (a matrix has no cheap way to divide out a length error, unlike a quaternion). Where the
//! first-order gravity correction would miss ([`crate::model::SECOND_ORDER_DEFLECTION`]), it
//! evaluates the spec's truth instead: the chain again with the deflections in the angles.
//!
//! An axis wobble ([`crate::wobble`]) turns M̃_i's rows by −φ, so that R_i = M̃_i W_i Rot(z, θ_i).
//!
//! It carries two things. On the hubs that stream U95 (feature `parameters`) it is load-bearing:
//! [`crate::uncertainty`]'s parameter part, J_π C J_πᵀ, is built on the joints' frames this
//! chain composes anyway ([`MatrixChain::eval_frames`], [`Frames`]), so every streamed U95
//! stands on it. And it is the comparison: on the same arm and targets it measures whether the
//! quaternion chain is really as accurate and as cheap (`armcal accuracy`,
//! `cargo xtask bench-target`). The hub's coordinates always come from [`crate::chain`].

use crate::model::{units, ChainError, Gravity, GravityCount, Model, Point, BASE_AXIS};
use crate::physics::Physics;
use crate::rotate::Vec3;
use crate::scalar::{Arithmetic, Fixed, Scale, F32};
use crate::table::{Table, MAX_JOINTS};
use crate::wobble::{turn_small, Wobble};

type Mat<P> = [[<P as Arithmetic>::U; 3]; 3];

/// The joints' frames at a reading, in f32, for the Jacobians of the uncertainty
/// ([`crate::uncertainty`]): what this chain composes anyway, kept.
#[derive(Clone, Copy, Debug, Default)]
pub struct Frames {
    /// R_0i after joint i's turn, row-major, in the chain's z-axis frames (column 2 is the
    /// joint's axis in the base frame).
    pub rotation: [[[f32; 3]; 3]; MAX_JOINTS],
    /// Joint i's origin o_i (mm, base frame).
    pub origin: [[f32; 3]; MAX_JOINTS],
    /// cos θ_i and sin θ_i of joint i's raw reading (the harmonics' angle), which the chain
    /// forms anyway: the harmonic columns of the parameter part take their weights from
    /// them instead of a sine and cosine of their own.
    pub turn: [[f32; 2]; MAX_JOINTS],
    /// ∂p/∂T, the tip's thermal expansion (mm per 10 °C, base frame): Σ_i R_0i κ_i v_i, the
    /// links' expansion rates turned by the frames (the probe's with the last link). The
    /// links are linear in T, so this is the temperature's column of the Jacobian exactly
    /// (up to the gravity correction's 1e-5 of it).
    pub expansion: [f32; 3],
}

/// The temperature step of [`Frames::expansion`] (m°C).
pub const EXPANSION_STEP_MC: i32 = 10_000;

/// One reading as a pass of the chain takes it: the counts, the temperature offset, and
/// whether the pass applies the wobble (a constant in each copy of the code).
struct Reading<'a, P: Physics> {
    counts: &'a [u32],
    dt: P::T,
    wobble: bool,
}

/// The 3×4 matrix chain of one evaluator (`Default`: an empty one, no joints, the place
/// [`MatrixChain::build_in`] builds one in).
#[derive(Clone, Copy, Debug, Default)]
pub struct MatrixChain<P: Physics> {
    model: Model<P>,
    rotation: [Mat<P>; MAX_JOINTS],
    wobble: Wobble<P>,
}

/// The f32 matrix chain.
pub type MatrixChainF32 = MatrixChain<F32>;
/// The fixed-point matrix chain.
pub type MatrixChainFixed = MatrixChain<Fixed>;

#[inline(always)]
fn mat_vec<P: Arithmetic, E: Scale<P>>(m: &Mat<P>, v: &Vec3<E>) -> Vec3<E> {
    let row = |r: &[P::U; 3]| v[0].scale(r[0]) + v[1].scale(r[1]) + v[2].scale(r[2]);
    [row(&m[0]), row(&m[1]), row(&m[2])]
}

impl<P: Physics> MatrixChain<P> {
    /// Builds the chain from a validated table.
    pub fn new(table: &Table<'_>) -> Result<MatrixChain<P>, ChainError> {
        let mut chain = MatrixChain::default();
        chain.build_in(table)?;
        Ok(chain)
    }

    /// Builds the chain of a validated table in `self`, whatever it held: [`MatrixChain::new`]
    /// in place, as [`crate::chain::Chain::build_in`] (the uncertainty's chain, built at a
    /// hub's boot). On an error, `self` holds no usable chain.
    pub fn build_in(&mut self, table: &Table<'_>) -> Result<(), ChainError> {
        *self = MatrixChain::default();
        self.model = Model::<P>::new(table)?;
        let model = &self.model;
        let mut prev = BASE_AXIS;
        for (i, r) in self.rotation.iter_mut().enumerate().take(model.n) {
            let j = table
                .joint(i)
                .ok_or(ChainError::Range { joint: i as u8 + 1 })?;
            let m = crate::model::z_frame_matrix(j.matrix, prev, j.axis);
            for (row, src) in r.iter_mut().zip(m) {
                *row = units::<P, 3>(src, i + 1)?;
            }
            prev = j.axis;
        }
        self.wobble = Wobble::new(table, model)?;
        Ok(())
    }

    /// Number of joints.
    pub fn joint_count(&self) -> usize {
        self.model.n
    }

    /// Mounts the table's probe `k`, as [`crate::chain::Chain::mount`].
    pub fn mount(&mut self, table: &Table<'_>, k: usize) -> Result<(), ChainError> {
        self.model.mount(table, k)
    }

    /// Probe-ball centre and direction; same contract as [`crate::chain::Chain::eval`].
    ///
    /// Gravity: the spec's first-order correction, where it is within the bounds
    /// ([`crate::model::SECOND_ORDER_DEFLECTION`]); beyond, the spec's truth itself — the
    /// deflections e_k taken on the undeflected chain, then the chain evaluated again with
    /// them in the joint angles (twice the cost, for the arms that need it).
    // Out of line: inlined into a caller's loop, the evaluation competes for registers with
    // the caller's code and spills (measured on qemu-m4f: 1,404 inlined against 1,350 out of
    // line for the quaternion chain, 1,245 against 1,201 for the matrix chain).
    #[inline(never)]
    pub fn eval(&self, counts: &[u32], temp_mc: i32) -> Result<Point<P>, ChainError> {
        self.eval_seen(counts, temp_mc, &mut |_, _, _, _| {})
    }

    /// As [`Self::eval`], with the joints' frames of the (last) pass in `frames`: the
    /// undeflected chain's, where gravity is corrected to first order, which moves them by
    /// g·L ≈ 1e-5 of themselves — far below what a Jacobian for U95 needs.
    pub fn eval_frames(
        &self,
        counts: &[u32],
        temp_mc: i32,
        frames: &mut Frames,
    ) -> Result<Point<P>, ChainError> {
        let step = P::temperature(EXPANSION_STEP_MC);
        // A second pass (second-order gravity) sees every joint again: the sum restarts.
        let mut rate = [0.0f32; 3];
        let tip = self.eval_seen(counts, temp_mc, &mut |i, r, o, (c, s)| {
            if i == 0 {
                rate = [0.0; 3];
            }
            let (Some(fr), Some(fo), Some(ft), Some(j)) = (
                frames.rotation.get_mut(i),
                frames.origin.get_mut(i),
                frames.turn.get_mut(i),
                self.model.joints.get(i),
            ) else {
                return;
            };
            *fr = r.map(|row| row.map(P::u_to_f32));
            *fo = o.map(P::l_to_f32);
            *ft = [P::u_to_f32(c), P::u_to_f32(s)];
            if j.has_thermal {
                let v = j.link_rate.map(|x| P::l_to_f32(P::expansion(x, step)));
                for (x, row) in rate.iter_mut().zip(fr.iter()) {
                    *x += row[0] * v[0] + row[1] * v[1] + row[2] * v[2];
                }
            }
        })?;
        frames.expansion = rate;
        Ok(tip)
    }

    #[inline(always)]
    fn eval_seen(
        &self,
        counts: &[u32],
        temp_mc: i32,
        seen: &mut impl FnMut(usize, &Mat<P>, &Vec3<P::L>, (P::U, P::U)),
    ) -> Result<Point<P>, ChainError> {
        // A copy without the wobble's tests for the arms that have none (always, without the
        // feature: `any` is then `false` at compile time and the other copy is not built).
        if self.wobble.any() {
            self.eval_seen_wobbling(counts, temp_mc, seen)
        } else {
            self.eval_seen_with(counts, temp_mc, false, seen)
        }
    }

    /// [`Self::eval_seen`] with the wobble. Out of line, as the quaternion chain's copy with
    /// every term (the lean matrix chain on qemu-m4f: 1,228 instructions a point inlined,
    /// 1,215 so).
    #[inline(never)]
    fn eval_seen_wobbling(
        &self,
        counts: &[u32],
        temp_mc: i32,
        seen: &mut impl FnMut(usize, &Mat<P>, &Vec3<P::L>, (P::U, P::U)),
    ) -> Result<Point<P>, ChainError> {
        self.eval_seen_with(counts, temp_mc, true, seen)
    }

    #[inline(always)]
    fn eval_seen_with(
        &self,
        counts: &[u32],
        temp_mc: i32,
        wobble: bool,
        seen: &mut impl FnMut(usize, &Mat<P>, &Vec3<P::L>, (P::U, P::U)),
    ) -> Result<Point<P>, ChainError> {
        let m = &self.model;
        let dt = m.check(counts, temp_mc)?;
        let mut gravity = Gravity::<P>::default();
        let mut gravity_count = GravityCount::default();
        let at = Reading { counts, dt, wobble };
        let undeflected = self.pass(&at, None, &mut gravity, &mut gravity_count, seen)?;
        if !m.second_order_gravity {
            let (xyz, dir) = gravity.apply(gravity_count, undeflected.xyz, undeflected.dir);
            return Ok(Point { xyz, dir });
        }
        let mut e = [P::U::default(); MAX_JOINTS];
        gravity.deflections(gravity_count, undeflected.xyz, &mut e);
        let mut unused = GravityCount::default();
        self.pass(&at, Some(&e), &mut gravity, &mut unused, seen)
    }

    /// The chain base to tip: tip and direction. With `deflections` (one per compliant
    /// joint, base first) they join the joints' angles; without, the compliant joints'
    /// axes and origins are recorded for the first-order correction. `seen` gets each joint's
    /// frame after its turn, its origin, and cos θ, sin θ of its raw reading.
    #[inline(always)]
    fn pass(
        &self,
        at: &Reading<'_, P>,
        deflections: Option<&[P::U; MAX_JOINTS]>,
        gravity: &mut Gravity<P>,
        gravity_count: &mut GravityCount,
        seen: &mut impl FnMut(usize, &Mat<P>, &Vec3<P::L>, (P::U, P::U)),
    ) -> Result<Point<P>, ChainError> {
        let (m, counts, dt) = (&self.model, at.counts, at.dt);
        let zero = P::U::default();
        let mut r: Mat<P> = [[zero; 3]; 3];
        let mut o: Vec3<P::L> = [P::L::default(); 3];
        let mut compliant = 0;
        // `check` made counts.len() = n ≤ MAX_JOINTS.
        for (i, &count) in counts.iter().enumerate().take(MAX_JOINTS) {
            let j = &m.joints[i];
            let jr = j.reading(i, count, dt, true)?;
            let (mut c, mut sn) = jr.full.unwrap_or((P::ONE, zero));
            let raw = (c, sn);
            let wobbled;
            let mj = if at.wobble && self.wobble.has(i) {
                // M̃ W: each row r of M̃ times W is Wᵀ r, r turned by −φ.
                let phi = self.wobble.turn(i, c, sn).map(|x| -x);
                wobbled = self.rotation[i].map(|row| turn_small(&phi, row));
                &wobbled
            } else {
                &self.rotation[i]
            };
            let mut e = jr.e;
            let mut turn = j.harmonic_count > 0;
            if let (true, Some(d)) = (j.has_gravity, deflections) {
                e = e + d[compliant.min(MAX_JOINTS - 1)];
                compliant += 1;
                turn = true;
            }
            if turn {
                // cos and sin of θ + e to second order; with a deflection (|e| up to 7e-3)
                // sin e to third (errors under 3e-12).
                let z = e.scale(e);
                let se = if deflections.is_some() {
                    e + e.scale(z).scale(P::SIN[0])
                } else {
                    e
                };
                let h = P::half(z);
                let c2 = c - (sn.scale(se) + c.scale(h));
                sn = sn + (c.scale(se) - sn.scale(h));
                c = c2;
            }
            // R_i = M̃ · Rot(z, θ): the third column of M̃ stays, the first two turn by θ.
            let mut ri: Mat<P> = [[zero; 3]; 3];
            for (row, src) in ri.iter_mut().zip(mj) {
                *row = [
                    src[0].scale(c) + src[1].scale(sn),
                    src[1].scale(c) - src[0].scale(sn),
                    src[2],
                ];
            }
            r = if i == 0 {
                ri
            } else {
                let mut next: Mat<P> = [[zero; 3]; 3];
                for (nrow, rrow) in next.iter_mut().zip(&r) {
                    for (col, x) in nrow.iter_mut().enumerate() {
                        *x = rrow[0].scale(ri[0][col])
                            + rrow[1].scale(ri[1][col])
                            + rrow[2].scale(ri[2][col]);
                    }
                }
                next
            };
            if j.has_gravity && deflections.is_none() {
                gravity.push(gravity_count, j.gravity, [r[0][2], r[1][2], r[2][2]], o);
            }
            seen(i, &r, &o, raw);
            let v = mat_vec::<P, P::L>(&r, &jr.link);
            o = [o[0] + v[0], o[1] + v[1], o[2] + v[2]];
        }
        Ok(Point {
            xyz: o,
            dir: mat_vec::<P, P::U>(&r, &m.probe_dir),
        })
    }
}
