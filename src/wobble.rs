//! The axis wobble in the chains: each wobbling joint's two small turns at a reading.
//!
//! The table keeps, per joint, two fixed orthogonal axes f1, f2 and the harmonic terms of the
//! two tilt angles ([`crate::table::wobble`]); the varied joint rotation is exactly
//! M'_k R(f1, A(θ)) R(f2, B(θ)) R(u, θ + e). The chains apply the two turns as one small
//! rotation vector φ (in the joint's z-axis frame, [`crate::model`]): by the
//! Baker–Campbell–Hausdorff series, R(f1, A) R(f2, B) = exp(\[φ\]×) with
//! φ = A f1 + B f2 + ½ A B f1 × f2 to second order, and exp(\[φ\]×) v = v + φ × v +
//! ½ φ × (φ × v) to second order again. The terms left out are third order: with the table's
//! |A| + |B| ≤ 1e-3 ([`crate::table::limits::HARMONIC_SUM`]), under 2e-10 rad, 0.4 nm on a
//! 2 m lever; a real wobble (≤ 1e-4) leaves 1e-13.
//!
//! A(θ) and B(θ) take sin hθ, cos hθ from the reading's cos θ, sin θ
//! (`angle::Multiples`, the terms sorted by order at boot), as the encoder harmonics
//! do, of the raw reading θ (the spec's: the tilt is the bearing's at the
//! encoder's reading, not at the corrected angle).
//!
//! Behind the `wobble` feature: without it [`Wobble`] is empty, [`Wobble::has`] is `false`
//! at compile time and both chains compile to what they were (the Cortex-M0 image has no
//! room for the code), and a table with the block is refused by its flag.

#[cfg(feature = "wobble")]
use crate::angle::Multiples;
use crate::model::{ChainError, Model};
use crate::physics::Physics;
use crate::rotate::{Quat, Vec3};
use crate::scalar::{Arithmetic, Scale};
use crate::table::Table;
use core::marker::PhantomData;

/// One wobble term in evaluator numbers.
#[cfg(feature = "wobble")]
#[derive(Clone, Copy, Debug, Default)]
struct Term<P: Arithmetic> {
    order: u32,
    /// α's sin and cos coefficients.
    alpha: [P::U; 2],
    /// β's sin and cos coefficients.
    beta: [P::U; 2],
}

/// One joint's wobble in evaluator numbers, its axes in the joint's z-axis frame.
#[cfg(feature = "wobble")]
#[derive(Clone, Copy, Debug, Default)]
struct JointWobble<P: Arithmetic> {
    count: u8,
    terms: [Term<P>; crate::table::wobble::MAX_TERMS],
    f1: Vec3<P::U>,
    f2: Vec3<P::U>,
    /// ½ f1 × f2: the second-order term of the two turns composed.
    half_cross: Vec3<P::U>,
}

/// Every joint's axis wobble, for one evaluator.
#[derive(Clone, Copy, Debug, Default)]
pub struct Wobble<P: Arithmetic> {
    #[cfg(feature = "wobble")]
    joints: [JointWobble<P>; crate::table::MAX_JOINTS],
    /// Some joint wobbles (kept: the chains test it per point).
    #[cfg(feature = "wobble")]
    any: bool,
    _p: PhantomData<P>,
}

impl<P: Arithmetic> Wobble<P> {
    /// The wobble of a validated table, for the chain of `model` (none without the `wobble`
    /// feature, which refuses a table that has one).
    pub fn new(table: &Table<'_>, model: &Model<P>) -> Result<Wobble<P>, ChainError>
    where
        P: Physics,
    {
        #[cfg(feature = "wobble")]
        {
            use crate::model::{units, unpermute};
            let mut joints = [JointWobble::<P>::default(); crate::table::MAX_JOINTS];
            for (i, jw) in joints.iter_mut().enumerate().take(table.joint_count()) {
                let w = table.joint_wobble(i);
                if w.count == 0 {
                    continue;
                }
                let no = i + 1;
                let axis = model.joints[i].axis;
                let (f1, f2) = (unpermute(w.f1, axis), unpermute(w.f2, axis));
                let c = [
                    f1[1] * f2[2] - f1[2] * f2[1],
                    f1[2] * f2[0] - f1[0] * f2[2],
                    f1[0] * f2[1] - f1[1] * f2[0],
                ];
                jw.count = w.count;
                jw.f1 = units::<P, 3>(f1, no)?;
                jw.f2 = units::<P, 3>(f2, no)?;
                jw.half_cross = units::<P, 3>(c.map(|x| 0.5 * x), no)?;
                let used = usize::from(w.count).min(crate::table::wobble::MAX_TERMS);
                for (t, src) in jw.terms.iter_mut().zip(&w.terms[..used]) {
                    *t = Term {
                        order: u32::from(src.order),
                        alpha: units::<P, 2>(src.alpha, no)?,
                        beta: units::<P, 2>(src.beta, no)?,
                    };
                }
                crate::model::sort_by_order(&mut jw.terms[..used], |t| t.order);
            }
            Ok(Wobble {
                any: joints.iter().any(|j| j.count > 0),
                joints,
                _p: PhantomData,
            })
        }
        #[cfg(not(feature = "wobble"))]
        {
            let _ = (table, model);
            Ok(Wobble { _p: PhantomData })
        }
    }

    /// Whether any joint wobbles (always `false` without the feature, at compile time): the
    /// chains keep a copy of their code without the wobble for the arms that have none.
    #[inline(always)]
    pub fn any(&self) -> bool {
        #[cfg(feature = "wobble")]
        {
            self.any
        }
        #[cfg(not(feature = "wobble"))]
        {
            false
        }
    }

    /// Whether joint `i` wobbles (always `false` without the feature, at compile time).
    #[inline(always)]
    pub fn has(&self, i: usize) -> bool {
        #[cfg(feature = "wobble")]
        {
            self.joints.get(i).is_some_and(|j| j.count > 0)
        }
        #[cfg(not(feature = "wobble"))]
        {
            let _ = i;
            false
        }
    }

    /// Joint `i`'s rotation vector φ at the reading whose cos θ and sin θ are `c`, `s`
    /// (zero where it does not wobble).
    // Out of line: one copy for both chains and both of the quaternion chain's variants
    // (inlined, the qemu-m4f image grew by 2.8 KB in the chain alone).
    #[inline(never)]
    pub fn turn(&self, i: usize, c: P::U, s: P::U) -> Vec3<P::U> {
        let zero = P::U::default();
        #[cfg(feature = "wobble")]
        if let Some(j) = self.joints.get(i) {
            let (mut a, mut b) = (zero, zero);
            let mut m = Multiples::<P>::new(c, s);
            for t in &j.terms[..usize::from(j.count).min(crate::table::wobble::MAX_TERMS)] {
                m.advance(t.order);
                a = a + (m.s.scale(t.alpha[0]) + m.c.scale(t.alpha[1]));
                b = b + (m.s.scale(t.beta[0]) + m.c.scale(t.beta[1]));
            }
            let ab = a.scale(b);
            let at = |k: usize| j.f1[k].scale(a) + j.f2[k].scale(b) + j.half_cross[k].scale(ab);
            return [at(0), at(1), at(2)];
        }
        #[cfg(not(feature = "wobble"))]
        let _ = (i, c, s);
        [zero; 3]
    }
}

/// `v` turned by the small rotation vector φ, to second order: v + φ × v + ½ φ × (φ × v).
#[inline(always)]
pub fn turn_small<P: Arithmetic, E: Scale<P>>(phi: &Vec3<P::U>, v: Vec3<E>) -> Vec3<E> {
    let cross = |a: &Vec3<P::U>, v: &Vec3<E>| {
        [
            v[2].scale(a[1]) - v[1].scale(a[2]),
            v[0].scale(a[2]) - v[2].scale(a[0]),
            v[1].scale(a[0]) - v[0].scale(a[1]),
        ]
    };
    let c = cross(phi, &v);
    let d = cross(&phi.map(P::half), &c);
    [
        v[0] + (c[0] + d[0]),
        v[1] + (c[1] + d[1]),
        v[2] + (c[2] + d[2]),
    ]
}

/// The unit quaternion of the small rotation vector φ, to second order: (1 − |φ|²/8, φ/2).
#[inline(always)]
pub fn small_quat<P: Arithmetic>(phi: &Vec3<P::U>) -> Quat<P> {
    let h = phi.map(P::half);
    let n = h[0].scale(h[0]) + h[1].scale(h[1]) + h[2].scale(h[2]);
    Quat::new([P::ONE - P::half(n), h[0], h[1], h[2]])
}
