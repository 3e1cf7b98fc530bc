//! The quaternion chain: the calibrated arm as joint quaternions, the orientation composed base
//! to tip, the position summed tip to base.
//!
//! Joint i turns about z of its own frame ([`crate::model`]); its fixed rotation is
//! M̃_i = C_i ⊗ M''_i, where C_i only relabels the axes (a cyclic permutation, exact on
//! vectors) and M''_i = R(e1, δα) R(e2, δβ) R(z, Δθ) is any rotation the table holds (a few
//! mrad from the identity on a CMM hub, a D–H twist of π/2 or a zero offset of a radian on a
//! robot). Two passes:
//!
//! 1. **Base to tip**: each joint's angle (quarter turns q, remainder 2x, harmonic error) and
//!    the orientation Q_0i = Q_0(i−1) ⊗ M̃_i ⊗ (cos θ_i/2, sin θ_i/2 ẑ), 24 products a joint
//!    (8 for the first). θ_i/2 = q·π/4 + x: the table keeps M̃_i ⊗ (cos qπ/4, sin qπ/4 ẑ) for
//!    each quadrant (formed in f64 at boot), so the product takes (cos x, sin x) as they come
//!    from the polynomial. Q is used where rounding does not reach the position: the vertical
//!    seen by each compliant joint, the joint axes for the direction's gravity correction, and
//!    the probe direction n = Q v̂_p Q*, which divides |Q|² out rather than renormalising Q.
//!    Only the angle is recorded for the second pass.
//! 2. **Tip to base** (Horner form): w = v_N + v_p, then w ← v_(i−1) + C_i M''_i R(z, θ_i) w,
//!    with the link at temperature formed here. Each step adds a *small* correction to w — the
//!    quarter turns are exact, the remainder turn is at most π/4, M''_i is applied as
//!    w + E_i w with E_i = M''_i − I (formed in f64 at boot; entries of a few mrad on a hub,
//!    a plain rotation on a twisted arm) — so the large partial sums (1.5 m, ulp 0.12 µm) are
//!    rounded about once per joint, and no orientation error accumulates into the position.
//!    The gravity deflection e_k = g_k (u_k × w_k)·z_k, with w_k the tip seen from joint k,
//!    joins the joint's angle before its turn, like the exactly deflected reference.
//!
//! Where the arm's deflections are large enough to matter at second order (decided at boot,
//! [`crate::model::SECOND_ORDER_DEFLECTION`]), two more vectors ride the tip-to-base pass
//! through the same code: the *shift* the deflections beyond joint k have made, so that e_k
//! takes its lever on the undeflected chain as the spec says (grown exactly by each
//! deflection, and carried through every turn, fixed rotation and relabelling — it once
//! skipped M''_i, which cost 5.4–15.8 µm on arms with large zero offsets or twists, issue 15),
//! and the probe direction as a 1024 mm vector, which so comes out of the deflected chain
//! itself. Below the threshold the lever is taken as it stands and the direction from Q turned
//! by Σ e_k a_k, to first order.
//!
//! An axis wobble ([`crate::wobble`], behind the `wobble` feature) is a small rotation vector φ
//! per wobbling joint and reading, applied right after M̃_i: base to tip as one more product,
//! Q ⊗ M̃_i ⊗ Z(qπ/2) ⊗ W' with W' the small turn about φ turned back by the quarter turns
//! (exact), tip to base on every carried vector before E_i. An arm without one (and without
//! the second-order gravity terms) takes a copy of the code with both compiled out.
//!
//! A matrix chain could not be written this way for the same price: it would still have to
//! compose its matrices for the direction and the verticals, and a composed 3×3 matrix costs
//! 27 products a joint where a quaternion costs 16. (Measured cost: `docs/results/chain.md`;
//! on the Cortex-M4F this chain still takes more instructions than the straightforward matrix
//! chain, on the Cortex-M0 fewer.)

use crate::angle::{quarter_turns, Quarter};
use crate::lean::{LeanF32, LeanForm, NoLean};
use crate::model::{units, ChainError, Model, Point, BASE_AXIS};
use crate::physics::Physics;
use crate::rotate::{cross, Quat, Vec3};
use crate::scalar::{Fixed, Scale, F32};
use crate::table::{Table, MAX_JOINTS};
use crate::wobble::{small_quat, turn_small, Wobble};
use core::mem::MaybeUninit;
use core::ptr::{addr_of, addr_of_mut};

/// What the quaternion chain is evaluated in: a number format with the physical effects' terms
/// in it ([`Physics`]), and what the targets that use the format may spend on the chain.
pub trait Evaluator: Physics {
    /// Whether the chain may spend flash on a second copy of a hot path to save instructions
    /// per point (f32: the FPU targets have flash to spare; fixed point: the Cortex-M0 hub's
    /// image must stay within 32 KiB). A build policy, not a property of the numbers: it
    /// changes no result, only size and speed.
    const SPEND_FLASH: bool;
    /// The chain's lean form in this format ([`crate::lean`]), which [`Chain::eval`] runs
    /// where it applies, or [`NoLean`].
    type Lean: LeanForm<Self>;
}

impl Evaluator for F32 {
    const SPEND_FLASH: bool = true;
    type Lean = LeanF32;
}

impl Evaluator for Fixed {
    const SPEND_FLASH: bool = false;
    type Lean = NoLean;
}

/// One joint's constants in the quaternion chain.
#[derive(Clone, Copy, Debug, Default)]
struct JointRotation<P: Physics> {
    /// M̃_i ⊗ (cos qπ/4, sin qπ/4 ẑ) for the quadrant q = 0..3 of the reading, for the
    /// orientation: the quarter turns' half angles taken in f64 at boot, so that the per-point
    /// product needs only the remainder's half angle (no branch, no √½ rounding).
    full: [Quat<P>; 4],
    /// E_i = M''_i − I (row-major), M''_i = C_i⁻¹ M̃_i near the identity, for the position:
    /// w + E_i w is M''_i w with a small correction, computed in f64 at boot and rounded once.
    near: [P::U; 9],
    /// C_i as a vector permutation: component k of C_i v is component (k + shift) mod 3 of v.
    shift: u8,
}

/// The quaternion chain of one evaluator.
// In this order (`repr(C)`): the wobble last, so that the fields the lean copy of `eval`
// reads keep the offsets they had before the wobble.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct Chain<P: Evaluator> {
    model: Model<P>,
    rotation: [JointRotation<P>; MAX_JOINTS],
    /// The arm's compliances are large enough for the second-order gravity terms to matter
    /// ([`crate::model::SECOND_ORDER_DEFLECTION`]).
    second_order: bool,
    /// The joints' axis wobble ([`crate::wobble`]; empty without its feature).
    wobble: Wobble<P>,
    /// The same model in the lean form, where the evaluator has one and the arm fits it.
    lean: P::Lean,
}

/// The f32 quaternion chain (FPU targets).
pub type ChainF32 = Chain<F32>;
/// The fixed-point quaternion chain (targets without FPU).
pub type ChainFixed = Chain<Fixed>;

/// The base frame's vertical (its x and y, all the lever needs) and the joint's axis, for a
/// compliant joint.
#[derive(Clone, Copy)]
struct Frame<P: Physics> {
    vertical: [P::U; 2],
    axis: Vec3<P::U>,
}

/// What the first pass leaves for the second, per joint: the angle, and the frame where the
/// joint is compliant. One record per joint, so both share one address; left uninitialised,
/// since zeroing them per reading would cost more than the records themselves.
struct Record<P: Physics> {
    angle: MaybeUninit<Quarter<P>>,
    frame: MaybeUninit<Frame<P>>,
}

impl<P: Physics> Record<P> {
    const UNINIT: Record<P> = Record {
        angle: MaybeUninit::uninit(),
        frame: MaybeUninit::uninit(),
    };
}

/// Cyclic relabelling of a vector's components (exact).
#[inline(always)]
fn relabel<E: Copy>(v: Vec3<E>, shift: u8) -> Vec3<E> {
    match shift {
        1 => [v[1], v[2], v[0]],
        2 => [v[2], v[0], v[1]],
        _ => v,
    }
}

/// m ⊗ (cos qπ/4, 0, 0, sin qπ/4), in f64 (q = 0..3).
fn quarter_half_turns(m: [f64; 4], q: usize) -> [f64; 4] {
    let h = core::f64::consts::FRAC_1_SQRT_2;
    let (c, s) = [(1.0, 0.0), (h, h), (0.0, 1.0), (-h, h)][q & 3];
    [
        m[0] * c - m[3] * s,
        m[1] * c + m[2] * s,
        m[2] * c - m[1] * s,
        m[3] * c + m[0] * s,
    ]
}

/// R(q) − I for a quaternion q (any length: divided out), row-major, each entry formed
/// directly rather than as a difference from 1, so that a near-identity rotation keeps the
/// relative accuracy of its small entries.
fn near_matrix([w, x, y, z]: [f64; 4]) -> [f64; 9] {
    let k = 2.0 / (w * w + x * x + y * y + z * z);
    [
        -k * (y * y + z * z),
        k * (x * y - w * z),
        k * (x * z + w * y),
        k * (x * y + w * z),
        -k * (x * x + z * z),
        k * (y * z - w * x),
        k * (x * z - w * y),
        k * (y * z + w * x),
        -k * (x * x + y * y),
    ]
}

/// Joint `no`'s (1-based, for errors) constants: its fixed rotation `rotation` about `axis`,
/// the joint before it turning about `prev`.
fn joint_rotation<P: Physics>(
    rotation: [f64; 4],
    axis: u8,
    prev: u8,
    no: usize,
) -> Result<JointRotation<P>, ChainError> {
    let full = crate::model::z_frame_quat(rotation, prev, axis);
    let mut full_q = [Quat::<P>::default(); 4];
    for (q, f) in full_q.iter_mut().enumerate() {
        *f = Quat::new(units::<P, 4>(quarter_half_turns(full, q), no)?);
    }
    let near = near_matrix(crate::model::near_quat(rotation, axis));
    // (prev − axis) mod 3 for axes 0..=2, without `%` (a runtime call on the M0).
    let shift = prev + 3 - axis;
    Ok(JointRotation {
        full: full_q,
        near: units::<P, 9>(near, no)?,
        shift: if shift >= 3 { shift - 3 } else { shift },
    })
}

impl<P: Evaluator> Chain<P> {
    /// Builds the chain from a validated table.
    pub fn new(table: &Table<'_>) -> Result<Chain<P>, ChainError> {
        let mut chain = MaybeUninit::uninit();
        Chain::build_in(&mut chain, table)?;
        // SAFETY: `build_in` returned `Ok`, so it wrote every field.
        Ok(unsafe { chain.assume_init() })
    }

    /// Builds the chain of a validated table in `out`: [`Chain::new`] in place, every field
    /// written where it stays, the chain returned only on success (`out` is then initialised).
    /// A hub builds its chain at boot straight into the place it runs from: the f32 chain is
    /// 3,740 bytes, and returned by value it was on the boot's stack two and three times over
    /// (the qemu-m4f hub's stack peak, issue 32). On an error `out` may hold part of a chain,
    /// and is to be taken as uninitialised.
    pub fn build_in<'o>(
        out: &'o mut MaybeUninit<Chain<P>>,
        table: &Table<'_>,
    ) -> Result<&'o mut Chain<P>, ChainError> {
        let p = out.as_mut_ptr();
        // SAFETY: raw pointers to the fields of `out`, written with `write` and the lean form
        // through a `MaybeUninit` over its field, which its `build_in` writes whole (nothing
        // is read or dropped); the chain is only referenced once all five fields are written.
        unsafe {
            addr_of_mut!((*p).model).write(Model::<P>::new(table)?);
            let model = &*addr_of!((*p).model);
            let rotation = addr_of_mut!((*p).rotation).cast::<JointRotation<P>>();
            let mut prev = BASE_AXIS;
            for i in 0..MAX_JOINTS {
                rotation.add(i).write(if i < model.n {
                    let j = table
                        .joint(i)
                        .ok_or(ChainError::Range { joint: i as u8 + 1 })?;
                    let r = joint_rotation::<P>(j.rotation, j.axis, prev, i + 1)?;
                    prev = j.axis;
                    r
                } else {
                    JointRotation::default()
                });
            }
            addr_of_mut!((*p).second_order).write(model.second_order_gravity);
            addr_of_mut!((*p).wobble).write(Wobble::new(table, model)?);
            // The lean form takes the wobble where it can ([`crate::lean_wobble`]).
            let lean = addr_of_mut!((*p).lean).cast::<MaybeUninit<P::Lean>>();
            P::Lean::build_in(&mut *lean, table, model, true)?;
            Ok(out.assume_init_mut())
        }
    }

    /// Number of joints.
    pub fn joint_count(&self) -> usize {
        self.model.n
    }

    /// Whether this arm's compliances call for the second-order gravity terms (decided at
    /// boot, [`crate::model::SECOND_ORDER_DEFLECTION`]).
    pub fn second_order_gravity(&self) -> bool {
        self.second_order
    }

    /// The model this chain evaluates.
    pub fn model(&self) -> &Model<P> {
        &self.model
    }

    /// Mounts the table's probe `k` (0 the first, then the others in the table's order): the
    /// chain ends at its ball from the next reading on. `table` must be the one the chain
    /// was built from; nothing changes on an error (a `k` past the table's probes).
    pub fn mount(&mut self, table: &Table<'_>, k: usize) -> Result<(), ChainError> {
        self.model.mount(table, k)?;
        self.lean.mount(&self.model);
        Ok(())
    }

    /// Whether [`Chain::eval`] runs the lean form ([`crate::lean`]) for this arm, rather than
    /// the quaternion chain.
    pub fn is_lean(&self) -> bool {
        self.lean.applies()
    }

    /// Probe-ball centre and direction for raw encoder counts (one per joint, each below its
    /// counts per revolution) at temperature `temp_mc` (milli-degrees Celsius): the lean form
    /// where it applies ([`Chain::is_lean`]; the fewest instructions on a Cortex-M4F, same
    /// model), else the quaternion chain ([`Chain::eval_quaternion`]).
    #[inline(always)]
    pub fn eval(&self, counts: &[u32], temp_mc: i32) -> Result<Point<P>, ChainError> {
        if self.lean.applies() {
            self.lean.eval(&self.model, counts, temp_mc)
        } else {
            self.eval_quaternion(counts, temp_mc)
        }
    }

    /// [`Chain::eval`] by the quaternion chain, whatever the arm: the model's own form.
    // Out of line: inlined into a caller's loop, the evaluation competes for registers with
    // the caller's code and spills (measured on qemu-m4f: 1,404 inlined against 1,350 out of
    // line for the quaternion chain, 1,245 against 1,201 for the matrix chain).
    #[inline(never)]
    pub fn eval_quaternion(&self, counts: &[u32], temp_mc: i32) -> Result<Point<P>, ChainError> {
        if !P::SPEND_FLASH {
            self.eval_with(counts, temp_mc, self.second_order, true)
        } else if !self.second_order && !self.wobble.any() {
            // A copy of the code with the second-order gravity terms and the axis wobble
            // compiled out, so that a hub-class arm does not pay for testing them.
            self.eval_with(counts, temp_mc, false, false)
        } else {
            self.eval_every_term(counts, temp_mc)
        }
    }

    /// [`Chain::eval`] with every term. Out of line, so that the lean copy is a function of
    /// its own, as before the wobble (its instructions a point on qemu-m4f: 1,341 before,
    /// 1,344 after).
    #[inline(never)]
    fn eval_every_term(&self, counts: &[u32], temp_mc: i32) -> Result<Point<P>, ChainError> {
        self.eval_with(counts, temp_mc, self.second_order, true)
    }

    /// [`Chain::eval`], with the second-order gravity terms or without, with the wobble or
    /// without.
    #[inline(always)]
    fn eval_with(
        &self,
        counts: &[u32],
        temp_mc: i32,
        second_order: bool,
        wobble: bool,
    ) -> Result<Point<P>, ChainError> {
        let m = &self.model;
        let dt = m.check(counts, temp_mc)?;
        let zero = P::U::default();

        // Base to tip.
        let mut records = [Record::<P>::UNINIT; MAX_JOINTS];
        // The wobble's rotation vector φ of each joint that wobbles (apart from the records:
        // without the feature it is never written and takes no stack).
        let mut phis = [const { MaybeUninit::<Vec3<P::U>>::uninit() }; MAX_JOINTS];
        let mut q = Quat::<P>::default();
        // `check` made counts.len() = n ≤ MAX_JOINTS.
        let n = counts.len().min(MAX_JOINTS);
        for i in 0..n {
            let (j, r, count) = (&m.joints[i], &self.rotation[i], counts[i]);
            let wobbles = wobble && self.wobble.has(i);
            let jr = j.reading(i, count, dt, false)?;
            let mut angle = jr.angle;
            if j.harmonic_count > 0 {
                angle = angle.turned(P::half(jr.e));
            }
            // θ/2 = q·π/4 + x: the quadrant's half turn is in the table, the remainder's is
            // (cos x, sin x).
            let fq = &r.full[usize::from(angle.q & 3)];
            q = if i == 0 { *fq } else { q.mul(fq) };
            let rec = &mut records[i];
            if wobbles {
                // M̃ ⊗ W ⊗ Z(qπ/2) = M̃ ⊗ Z(qπ/2) ⊗ W', W' the wobble about φ turned back
                // by the quarter turns (exact).
                // Of the raw reading (the harmonics have not turned `jr.angle`); taken here
                // rather than by `reading`, which would keep `jr` in memory on the lean path
                // (29 instructions a point more on qemu-m4f, in padding stores).
                let (c, s) = jr.angle.full();
                let phi = self.wobble.turn(i, c, s);
                let (x, y) = quarter_turns(4 - (angle.q & 3), (phi[0], phi[1]));
                q = q.mul(&small_quat(&[x, y, phi[2]]));
                phis[i].write(phi);
            }
            q = q.mul_z(P::ONE + angle.cm1, angle.s);
            if j.has_gravity {
                let v = q.z_row();
                rec.frame.write(Frame {
                    vertical: [v[0], v[1]],
                    axis: q.z_axis(),
                });
            }
            // The link at temperature is formed in the second pass, where it is used: cheaper
            // than a record.
            rec.angle.write(angle);
        }

        // Tip to base. Three vectors share the pass, each turned, rotated and relabelled
        // joint by joint (one copy of that code: the Cortex-M0 image's budget is 32 KiB):
        // the tip w; with the second-order gravity terms also the shift (how far the
        // deflections of the joints already passed have moved the tip: the spec's e_k is taken
        // on the chain *without* gravity, so joint k's lever uses the undeflected tip
        // u = w − shift), and the probe direction as a 1024 mm vector (the deflected chain's
        // own direction, every deflection in its joint's angle).
        const TIP: usize = 0;
        const DIR: usize = 2;
        let carried = if second_order { 3 } else { 1 };
        // The tip, the shift, the direction.
        let mut v: [Vec3<P::L>; 3] = [[P::L::default(); 3]; 3];
        v[DIR] = m.probe_dir.map(P::u_as_l1024);
        // Without the second-order terms: Ω = Σ e_k a_k, the first-order turn of the
        // direction by the deflections (the deflected orientation is R(ω_1) … R(ω_N) Q with
        // ω_k = e_k a_k about the undeflected axes).
        let mut omega = [zero; 3];
        let mut deflected = false;
        for i in (0..n).rev() {
            let (j, r) = (&m.joints[i], &self.rotation[i]);
            let rec = &records[i];
            // SAFETY: the first pass wrote every angle below n (it returns early only
            // with an error, before this pass).
            let mut a = unsafe { rec.angle.assume_init_read() };
            let link = j.link_at(dt);
            let w = &mut v[TIP];
            *w = [w[0] + link[0], w[1] + link[1], w[2] + link[2]];
            if j.has_gravity {
                // SAFETY: the first pass wrote the frame exactly where `has_gravity`.
                let f = unsafe { rec.frame.assume_init_read() };
                let [w, shift, _] = &mut v;
                let (ux, uy) = (w[0] - shift[0], w[1] - shift[1]);
                let lever = ux.scale(f.vertical[1]) - uy.scale(f.vertical[0]);
                let eg = P::gravity(j.gravity, lever);
                if second_order {
                    // The half angle h = e/2 of the deflection: sin h to third order, 1 − cos h
                    // to second (errors h⁵/120 and h⁴/24: under 1e-12 at the table's largest
                    // deflection, e ≈ 6.2e-3 on a 2064 mm lever); the joint turns by it.
                    let h = P::half(eg);
                    let h2 = h.scale(h);
                    let sh = h + h.scale(h2).scale(P::SIN[0]);
                    let ch = P::half(h2);
                    a = a.turned_by(sh, ch);
                    // The full deflection: sin e = 2 sin h (1 − (1 − cos h)), 1 − cos e = 2 sin² h.
                    let se = sh - sh.scale(ch);
                    let se = se + se;
                    let ce = sh.scale(sh);
                    let ce = ce + ce;
                    // The deflected joint sees the undeflected tip at R(−e) u, the deflected at
                    // w = u + shift: the shift grows by (I − R(−e)) u.
                    *shift = [
                        shift[0] + (ux.scale(ce) - uy.scale(se)),
                        shift[1] + (uy.scale(ce) + ux.scale(se)),
                        shift[2],
                    ];
                } else {
                    a = a.turned(P::half(eg));
                    let wk = f.axis.map(|x| x.scale(eg));
                    omega = [omega[0] + wk[0], omega[1] + wk[1], omega[2] + wk[2]];
                    deflected = true;
                }
            }
            let (sin2, omc) = a.double();
            let e = &r.near;
            // SAFETY: the first pass wrote φ exactly where the joint wobbles.
            let phi = (wobble && self.wobble.has(i)).then(|| unsafe { phis[i].assume_init_read() });
            for x in v.iter_mut().take(carried) {
                // The remainder turn as a correction, the wobble's small turn, M''_i as
                // x + E_i x, the relabelling.
                let (p, q) = quarter_turns(a.q, (x[0], x[1]));
                let mut t = [
                    p - (q.scale(sin2) + p.scale(omc)),
                    q + (p.scale(sin2) - q.scale(omc)),
                    x[2],
                ];
                if let Some(phi) = &phi {
                    t = turn_small(phi, t);
                }
                *x = relabel(
                    [
                        t[0] + (t[0].scale(e[0]) + t[1].scale(e[1]) + t[2].scale(e[2])),
                        t[1] + (t[0].scale(e[3]) + t[1].scale(e[4]) + t[2].scale(e[5])),
                        t[2] + (t[0].scale(e[6]) + t[1].scale(e[7]) + t[2].scale(e[8])),
                    ],
                    r.shift,
                );
            }
        }

        let dir = if second_order {
            v[DIR].map(P::l1024_as_u)
        } else {
            // n = Q v̂_p Q*, turned by Ω to first order.
            let n = q.rotate(&m.probe_dir, q.rotation_factor());
            if deflected {
                let t = cross::<P>(&omega, &n);
                [n[0] + t[0], n[1] + t[1], n[2] + t[2]]
            } else {
                n
            }
        };
        let w = v[TIP];
        Ok(Point { xyz: w, dir })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matrix::MatrixChain;
    use crate::table::probes::tests::several;
    use crate::table::{TableData, MAX_TABLE_LEN};

    /// `data` with its probe `k` first and the others after it in their order.
    fn with_first(data: &TableData, k: usize) -> TableData {
        let mut all = [data.probe; 8];
        all[1..].copy_from_slice(&data.more_probes);
        let n = 1 + usize::from(data.more_probe_count);
        all[..n].rotate_left(k);
        let mut d = *data;
        d.probe = all[0];
        d.more_probes.copy_from_slice(&all[1..]);
        d
    }

    fn points<P: Evaluator>(chain: &Chain<P>) -> Vec<([i32; 3], [i32; 3])> {
        (0..40u32)
            .map(|i| {
                let counts: Vec<u32> = (0..6)
                    .map(|j| (i * 26_041 + j * 191_111) % (1 << 20))
                    .collect();
                let p = chain.eval(&counts, 12_000 + 500 * i as i32).unwrap();
                (p.xyz_nm(), p.dir_e9())
            })
            .collect()
    }

    /// Mounting probe k gives, bit for bit, the chain of the same arm whose table has probe k
    /// first; mounting the first again gives the boot's chain back; a probe past the table's
    /// is refused and changes nothing. Both evaluators, both chains.
    fn mounting<P: Evaluator>() {
        let data = several();
        let mut buf = [0u8; MAX_TABLE_LEN];
        let n = data.encode(&mut buf).unwrap();
        let table = Table::parse(&buf[..n]).unwrap();
        let mut chain = Chain::<P>::new(&table).unwrap();
        let mut matrix = MatrixChain::<P>::new(&table).unwrap();
        let boot = points(&chain);
        for k in [1, 2, 0] {
            chain.mount(&table, k).unwrap();
            matrix.mount(&table, k).unwrap();
            let mut other = [0u8; MAX_TABLE_LEN];
            let m = with_first(&data, k).encode(&mut other).unwrap();
            let first = Table::parse(&other[..m]).unwrap();
            let want = Chain::<P>::new(&first).unwrap();
            assert_eq!(points(&chain), points(&want), "probe {k}");
            let counts = [1, 2, 3, 4, 5, 6];
            let (a, b) = (
                matrix.eval(&counts, 20_000).unwrap(),
                MatrixChain::<P>::new(&first)
                    .unwrap()
                    .eval(&counts, 20_000)
                    .unwrap(),
            );
            assert_eq!(
                (a.xyz_nm(), a.dir_e9()),
                (b.xyz_nm(), b.dir_e9()),
                "probe {k}"
            );
            if k != 0 {
                assert_ne!(points(&chain), boot, "probe {k} moves the tip");
            }
        }
        assert_eq!(points(&chain), boot);
        assert_eq!(
            chain.mount(&table, 3).unwrap_err(),
            ChainError::Range { joint: 0 }
        );
        assert_eq!(points(&chain), boot);
    }

    #[test]
    fn a_mounted_probe_is_the_chain_of_that_probe() {
        mounting::<F32>();
        mounting::<Fixed>();
    }
}
