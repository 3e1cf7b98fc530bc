//! The quaternion chain: the calibrated arm evaluated tip to base (Horner form).
//!
//! The spec's sum p = Σ Q_0i v_i Q_0i* + Q_0N v_p Q_0N* is rearranged as
//!
//! ```text
//! p = T_1(v_1 + T_2(v_2 + … T_N(v_N + v_p)…))      n = T_1(T_2(… T_N(v_p/|v_p|)…))
//! T_i(v) = M'_i · R(u_i, q_i·π/2) · R(u_i, 2x_i) · R(u_i, e_i) v      (each a quaternion sandwich)
//! ```
//!
//! so that no product of quaternions is ever formed: each joint's rotation is applied fresh,
//! and |Q_0i| cannot drift. The quarter turns are exact permutations, the half-angle quaternion
//! (cos x, sin x·u) with |x| ≤ π/8 and the small correction e (harmonics, gravity) rotate with
//! small terms added to the vector, and M'_i = R(e1, δα) R(e2, δβ) R(u, Δθ) is near the identity
//! on a real arm, so every stage adds little rounding to the vector it carries. The partial
//! sums never exceed the remaining reach, which keeps the f32 rounding of the large terms away
//! from the small ones.
//!
//! Gravity compliance is folded in as an angle: at hinge k the partial sum is p − o_k in joint
//! k's frame and the vertical there is z_k (one forward sweep of the inverse rotations, up to
//! the last compliant joint), so e_k = g_k (u_k × (p − o_k)) · z_k joins the joint's angle
//! error before its rotation is applied — the spec's deflected chain rather than its first-order
//! sum, for the cost of two products.

use crate::model::{gravity_angle, ChainError, Model, Point};
use crate::rotate::{axis_rotate, cyclic, quadrant_rotate, small_rotate, Quat, Vec3};
use crate::scalar::{Fixed, Precision, Scale, F32};
use crate::table::{Table, MAX_JOINTS};

/// The quaternion chain of one evaluator.
#[derive(Clone, Copy, Debug)]
pub struct Chain<P: Precision> {
    model: Model<P>,
    rotation: [Quat<P>; MAX_JOINTS],
    last_gravity: Option<usize>,
}

/// The f32 quaternion chain (FPU targets).
pub type ChainF32 = Chain<F32>;
/// The fixed-point quaternion chain (targets without FPU).
pub type ChainFixed = Chain<Fixed>;

impl<P: Precision> Chain<P> {
    /// Builds the chain from a validated table.
    pub fn new(table: &Table<'_>) -> Result<Chain<P>, ChainError> {
        let model = Model::<P>::new(table)?;
        let mut rotation = [Quat::<P>::default(); MAX_JOINTS];
        let mut last_gravity = None;
        for (i, r) in rotation.iter_mut().enumerate().take(model.n) {
            let j = table
                .joint(i)
                .ok_or(ChainError::Range { joint: i as u8 + 1 })?;
            let [w, x, y, z] = crate::model::units::<P, 4>(j.rotation, i + 1)?;
            *r = Quat { w, v: [x, y, z] };
            if model.joints[i].has_gravity {
                last_gravity = Some(i);
            }
        }
        Ok(Chain {
            model,
            rotation,
            last_gravity,
        })
    }

    /// Number of joints.
    pub fn joint_count(&self) -> usize {
        self.model.n
    }

    /// The model this chain evaluates.
    pub fn model(&self) -> &Model<P> {
        &self.model
    }

    /// Probe-ball centre and direction for raw encoder counts (one per joint, each below its
    /// counts per revolution) at temperature `temp_mc` (milli-degrees Celsius).
    pub fn eval(&self, counts: &[u32], temp_mc: i32) -> Result<Point<P>, ChainError> {
        let m = &self.model;
        let n = m.n;
        let (st, probe) = m.state(counts, temp_mc)?;

        // The vertical in each compliant joint's frame: z_k = T_k⁻¹ … T_1⁻¹ ẑ (no gravity).
        let zero = P::U::default();
        let mut zs = [[zero; 3]; MAX_JOINTS];
        if let Some(last) = self.last_gravity {
            let mut z = [zero, zero, P::ONE];
            for i in 0..=last.min(n - 1) {
                let (j, s) = (&m.joints[i], &st[i]);
                z = self.rotation[i].rotate_inverse(z);
                z = quadrant_rotate(j.axis, 4 - s.angle.quadrant, z);
                z = axis_rotate::<P, P::U>(j.axis, s.angle.c, -s.angle.s, z);
                if j.harmonic_count > 0 {
                    let h = P::half(s.error.scale(s.error));
                    z = small_rotate::<P, P::U>(j.axis, -s.error, h, z);
                }
                zs[i] = z;
            }
        }

        // Tip to base.
        let last = &st[n - 1].link;
        let mut w: Vec3<P::L> = [last[0] + probe[0], last[1] + probe[1], last[2] + probe[2]];
        let mut d = m.dir;
        for i in (0..n).rev() {
            let (j, s) = (&m.joints[i], &st[i]);
            let mut e = s.error;
            if j.has_gravity {
                let (b, c) = cyclic(j.axis);
                let z = &zs[i];
                let lever = w[b].scale(z[c]) - w[c].scale(z[b]);
                e = e + gravity_angle::<P>(j.gravity, lever);
            }
            if j.harmonic_count > 0 || j.has_gravity {
                let h = P::half(e.scale(e));
                w = small_rotate::<P, P::L>(j.axis, e, h, w);
                d = small_rotate::<P, P::U>(j.axis, e, h, d);
            }
            w = axis_rotate::<P, P::L>(j.axis, s.angle.c, s.angle.s, w);
            d = axis_rotate::<P, P::U>(j.axis, s.angle.c, s.angle.s, d);
            w = quadrant_rotate(j.axis, s.angle.quadrant, w);
            d = quadrant_rotate(j.axis, s.angle.quadrant, d);
            w = self.rotation[i].rotate(w);
            d = self.rotation[i].rotate(d);
            if i > 0 {
                let l = &st[i - 1].link;
                w = [w[0] + l[0], w[1] + l[1], w[2] + l[2]];
            }
        }
        Ok(Point { xyz: w, dir: d })
    }
}
