//! Unit quaternions for the chain: the Hamilton product, the product with a joint's rotation
//! about z, and the rotation of a 3-vector (q v q*) with a first-order correction for |q| ≠ 1.
//!
//! Every joint turns about z of its own frame: the model folds each joint's axis into its
//! fixed rotation at boot (see [`crate::model`]), so the per-point code has one shape and no
//! component permutations. Vector functions work on lengths and on dimensionless components
//! alike (through [`Scale`]).

use crate::scalar::{Arithmetic, Scale};

/// A 3-vector (x, y, z).
pub type Vec3<E> = [E; 3];

/// A quaternion (w, x, y, z), Hamilton convention, scalar first.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Quat<P: Arithmetic> {
    /// Scalar part.
    pub w: P::U,
    /// Vector part.
    pub x: P::U,
    /// Vector part.
    pub y: P::U,
    /// Vector part.
    pub z: P::U,
}

impl<P: Arithmetic> Quat<P> {
    /// From (w, x, y, z).
    pub fn new([w, x, y, z]: [P::U; 4]) -> Quat<P> {
        Quat { w, x, y, z }
    }

    /// The Hamilton product self ⊗ o (16 products).
    #[inline(always)]
    pub fn mul(&self, o: &Quat<P>) -> Quat<P> {
        let a = self;
        Quat {
            w: a.w.scale(o.w) - a.x.scale(o.x) - a.y.scale(o.y) - a.z.scale(o.z),
            x: a.w.scale(o.x) + a.x.scale(o.w) + a.y.scale(o.z) - a.z.scale(o.y),
            y: a.w.scale(o.y) - a.x.scale(o.z) + a.y.scale(o.w) + a.z.scale(o.x),
            z: a.w.scale(o.z) + a.x.scale(o.y) - a.y.scale(o.x) + a.z.scale(o.w),
        }
    }

    /// self ⊗ (c, 0, 0, s): a turn about z by the half angle whose cosine and sine are c, s
    /// (8 products).
    #[inline(always)]
    pub fn mul_z(&self, c: P::U, s: P::U) -> Quat<P> {
        Quat {
            w: self.w.scale(c) - self.z.scale(s),
            x: self.x.scale(c) + self.y.scale(s),
            y: self.y.scale(c) - self.x.scale(s),
            z: self.z.scale(c) + self.w.scale(s),
        }
    }

    /// 2/|q|² ≈ 2(2 − |q|²) for |q|² = 1 + ε (error 2ε², 1e-13 for f32 rounding), where
    /// the number format asks for it ([`Arithmetic::DIVIDE_NORM`]); else `None`, taken as 2.
    #[inline(always)]
    pub fn rotation_factor(&self) -> Option<P::U> {
        if !P::DIVIDE_NORM {
            return None;
        }
        let n = self.w.scale(self.w)
            + self.x.scale(self.x)
            + self.y.scale(self.y)
            + self.z.scale(self.z);
        let k = (P::ONE + P::ONE) - n;
        Some(k + k)
    }

    /// q v q* / |q|², with `f` = [`Quat::rotation_factor`].
    ///
    /// With t = q⃗ × v, q v q* = v + 2(w t + q⃗ × t) for a unit q; for any q the correction
    /// w t + q⃗ × t is |q|² times that of q/|q| (it is quadratic in q), so scaling it by
    /// 2/|q|² rotates exactly by q/|q| without normalising q. The correction is small where
    /// the rotation is, and joins v in one rounding.
    #[inline(always)]
    pub fn rotate<E: Scale<P>>(&self, v: &Vec3<E>, f: Option<P::U>) -> Vec3<E> {
        let t = [
            v[2].scale(self.y) - v[1].scale(self.z),
            v[0].scale(self.z) - v[2].scale(self.x),
            v[1].scale(self.x) - v[0].scale(self.y),
        ];
        let c = [
            t[0].scale(self.w) + t[2].scale(self.y) - t[1].scale(self.z),
            t[1].scale(self.w) + t[0].scale(self.z) - t[2].scale(self.x),
            t[2].scale(self.w) + t[1].scale(self.x) - t[0].scale(self.y),
        ];
        match f {
            Some(f) => [
                v[0] + c[0].scale(f),
                v[1] + c[1].scale(f),
                v[2] + c[2].scale(f),
            ],
            None => [
                v[0] + (c[0] + c[0]),
                v[1] + (c[1] + c[1]),
                v[2] + (c[2] + c[2]),
            ],
        }
    }

    /// The products that the third row and column of q's rotation matrix share, each *half*
    /// of its matrix term: z·x, w·y, z·y, w·x and x² + y². The doubling comes after the
    /// product, never before it: a component of a half turn about x or y is ±1, and fixed
    /// point's 2x would wrap at ±2 (I2F30) *before* entering a product, where wrapping is no
    /// longer undone by the sums that follow — on an arm whose joint axis is flipped by π that
    /// turned the gravity deflection's sign on the poses where fixed point rounded |x| to 1
    /// (0.17 µm, issue 15). Sums alone may wrap: they come out right in the end.
    #[inline(always)]
    fn z_halves(&self) -> [P::U; 5] {
        [
            self.z.scale(self.x),
            self.w.scale(self.y),
            self.z.scale(self.y),
            self.w.scale(self.x),
            self.x.scale(self.x) + self.y.scale(self.y),
        ]
    }

    /// q* ẑ q for a unit q: the third row of its rotation matrix (the base frame's vertical
    /// seen from the rotated frame, for gravity).
    #[inline(always)]
    pub fn z_row(&self) -> Vec3<P::U> {
        let [zx, wy, zy, wx, r2] = self.z_halves();
        let (a, b) = (zx - wy, zy + wx);
        [a + a, b + b, P::ONE - r2 - r2]
    }

    /// q ẑ q* for a unit q: the third column of its rotation matrix (the joint axis in the
    /// base frame, for gravity; |q| ≠ 1 scales it by |q|², which gravity does not notice).
    #[inline(always)]
    pub fn z_axis(&self) -> Vec3<P::U> {
        // The same products as `z_row`, so that a caller taking both computes them once.
        let [zx, wy, zy, wx, r2] = self.z_halves();
        let (a, b) = (zx + wy, zy - wx);
        [a + a, b + b, P::ONE - r2 - r2]
    }
}

/// a × b of two dimensionless vectors (small rotation vectors, directions).
#[inline(always)]
pub fn cross<P: Arithmetic>(a: &Vec3<P::U>, b: &Vec3<P::U>) -> Vec3<P::U> {
    [
        a[1].scale(b[2]) - a[2].scale(b[1]),
        a[2].scale(b[0]) - a[0].scale(b[2]),
        a[0].scale(b[1]) - a[1].scale(b[0]),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::F32;

    fn close(a: Vec3<f32>, b: [f64; 3], tol: f64) -> bool {
        (0..3).all(|i| (f64::from(a[i]) - b[i]).abs() < tol)
    }

    #[test]
    fn cross_follows_the_right_hand() {
        let (x, y) = ([1.0f32, 0.0, 0.0], [0.0f32, 1.0, 0.0]);
        assert_eq!(cross::<F32>(&x, &y), [0.0, 0.0, 1.0]);
        assert_eq!(cross::<F32>(&y, &x), [0.0, 0.0, -1.0]);
    }

    #[test]
    fn turn_about_z_follows_the_right_hand() {
        // 90° about z: x → y.
        let h = core::f32::consts::FRAC_1_SQRT_2;
        let q = Quat::<F32>::new([1.0, 0.0, 0.0, 0.0]).mul_z(h, h);
        let r = q.rotate(&[1.0f32, 0.0, 0.0], q.rotation_factor());
        assert!(close(r, [0.0, 1.0, 0.0], 1e-6), "{r:?}");
        assert!(close(q.z_axis(), [0.0, 0.0, 1.0], 1e-6));
    }

    #[test]
    fn product_composes_rotations() {
        // 120° about (1,1,1): x → y → z → x.
        let p = Quat::<F32>::new([0.5, 0.5, 0.5, 0.5]);
        let one = 1.0f32;
        assert!(close(
            p.rotate(&[one, 0.0, 0.0], None),
            [0.0, 1.0, 0.0],
            1e-6
        ));
        assert!(close(p.z_axis(), [1.0, 0.0, 0.0], 1e-6));
        // p ⊗ p: 240°, x → z.
        let pp = p.mul(&p);
        assert!(close(
            pp.rotate(&[one, 0.0, 0.0], None),
            [0.0, 0.0, 1.0],
            1e-6
        ));
        // (p ⊗ p) ⊗ p: identity.
        let ppp = pp.mul(&p);
        assert!((f64::from(ppp.w).abs() - 1.0).abs() < 1e-6);
    }

    /// A half turn about x, a few µrad off, in fixed point with |x| rounded to exactly 1:
    /// the vertical and the axis keep the sign of their small components (2x once wrapped to
    /// −2 here and flipped them: issue 15's flipped vertical joint).
    #[test]
    fn fixed_point_half_turn_keeps_the_small_components() {
        use crate::scalar::{Fixed, Unit};
        let u = |x: f64| Unit::from_bits((x * 1_073_741_824.0).round() as i32);
        for (w, x, y, z) in [
            (3e-6, 1.0, 2e-6, -5e-6),
            (-3e-6, -1.0, 2e-6, 5e-6),
            (4e-6, 1e-6, 1.0, 7e-6),
            (-4e-6, -2e-6, -1.0, -7e-6),
        ] {
            let q = Quat::<Fixed>::new([u(w), u(x), u(y), u(z)]);
            let row = [
                2.0 * (z * x - w * y),
                2.0 * (z * y + w * x),
                1.0 - 2.0 * (x * x + y * y),
            ];
            let axis = [2.0 * (z * x + w * y), 2.0 * (z * y - w * x), row[2]];
            let (gr, ga) = (q.z_row(), q.z_axis());
            for k in 0..3 {
                let (r, a) = (Fixed::u_to_f64(gr[k]), Fixed::u_to_f64(ga[k]));
                assert!((r - row[k]).abs() < 1e-8, "row {k}: {r} vs {}", row[k]);
                assert!((a - axis[k]).abs() < 1e-8, "axis {k}: {a} vs {}", axis[k]);
            }
        }
    }

    #[test]
    fn non_unit_quaternion_rotates_as_its_unit() {
        let s = 1.0 + 3e-7f32;
        let q = Quat::<F32>::new([0.6 * s, 0.0, 0.8 * s, 0.0]);
        let v = [1000.0f32, -200.0, 300.0];
        let unit = Quat::<F32>::new([0.6, 0.0, 0.8, 0.0]);
        let want = unit.rotate(&v, None);
        let got = q.rotate(&v, q.rotation_factor());
        let plain = q.rotate(&v, None);
        let err = |a: Vec3<f32>| (0..3).map(|i| (a[i] - want[i]).abs()).fold(0.0, f32::max);
        assert!(err(got) < 2e-4, "{got:?} vs {want:?}");
        assert!(err(plain) > 5e-4, "the uncorrected rotation should scale");
    }
}
