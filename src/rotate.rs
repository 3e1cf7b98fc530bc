//! Rotations of 3-vectors: the unit quaternion sandwich q v q*, specialised for the three
//! kinds of rotation a joint makes (exact quarter turns, a half-angle axis quaternion, a small
//! correction angle).
//!
//! Every function works on vectors of lengths or of dimensionless components alike (through
//! [`Scale`]), so the probe position and the probe direction share one implementation.

use crate::scalar::{Precision, Scale};

/// A 3-vector (x, y, z).
pub type Vec3<E> = [E; 3];

/// The two axes after `axis` in cyclic order: (axis + 1, axis + 2) mod 3, without a division
/// (there is no divider on a Cortex-M0).
#[inline(always)]
pub fn cyclic(axis: u8) -> (usize, usize) {
    match axis {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    }
}

/// A unit quaternion (w, x, y, z), Hamilton convention, scalar first.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Quat<P: Precision> {
    /// Scalar part.
    pub w: P::U,
    /// Vector part.
    pub v: Vec3<P::U>,
}

#[inline(always)]
fn cross<P: Precision, E: Scale<P>>(a: &Vec3<P::U>, b: &Vec3<E>) -> Vec3<E> {
    [
        b[2].scale(a[1]) - b[1].scale(a[2]),
        b[0].scale(a[2]) - b[2].scale(a[0]),
        b[1].scale(a[0]) - b[0].scale(a[1]),
    ]
}

impl<P: Precision> Quat<P> {
    /// q v q*: with t = 2 (q⃗ × v), v' = v + (w t + q⃗ × t) (15 products, exact algebra for a
    /// unit q). For a q near the identity the correction is small, so its rounding is small
    /// too, and it joins v in one addition: the result rounds little more than v itself.
    #[inline(always)]
    pub fn rotate<E: Scale<P>>(&self, v: Vec3<E>) -> Vec3<E> {
        let t = cross::<P, E>(&self.v, &v);
        let t = [t[0] + t[0], t[1] + t[1], t[2] + t[2]];
        let u = cross::<P, E>(&self.v, &t);
        [
            v[0] + (t[0].scale(self.w) + u[0]),
            v[1] + (t[1].scale(self.w) + u[1]),
            v[2] + (t[2].scale(self.w) + u[2]),
        ]
    }

    /// q* v q: the inverse rotation.
    #[inline(always)]
    pub fn rotate_inverse<E: Scale<P>>(&self, v: Vec3<E>) -> Vec3<E> {
        Quat::<P> {
            w: self.w,
            v: [-self.v[0], -self.v[1], -self.v[2]],
        }
        .rotate(v)
    }
}

/// Rotation by a quaternion (c, s·u) about the coordinate axis u = `axis` (half angle x with
/// c = cos x, s = sin x): the sandwich product with the zero components dropped,
/// v_b' = v_b − 2(c·s·v_d + s·s·v_b), v_d' = v_d + 2(c·s·v_b − s·s·v_d).
#[inline(always)]
pub fn axis_rotate<P: Precision, E: Scale<P>>(axis: u8, c: P::U, s: P::U, v: Vec3<E>) -> Vec3<E> {
    let (b, d) = cyclic(axis);
    let tb = v[b].scale(s);
    let td = v[d].scale(s);
    let db = td.scale(c) + tb.scale(s);
    let dd = tb.scale(c) - td.scale(s);
    let mut r = v;
    r[b] = v[b] - (db + db);
    r[d] = v[d] + (dd + dd);
    r
}

/// Rotation by `quadrant` quarter turns about the coordinate axis `axis`: exact.
#[inline(always)]
pub fn quadrant_rotate<E: Copy + core::ops::Neg<Output = E>>(
    axis: u8,
    quadrant: u8,
    v: Vec3<E>,
) -> Vec3<E> {
    let (b, d) = cyclic(axis);
    let mut r = v;
    match quadrant & 3 {
        0 => {}
        1 => {
            r[b] = -v[d];
            r[d] = v[b];
        }
        2 => {
            r[b] = -v[b];
            r[d] = -v[d];
        }
        _ => {
            r[b] = v[d];
            r[d] = -v[b];
        }
    }
    r
}

/// Rotation by a small angle e about the coordinate axis `axis`, to second order
/// (h = e²/2): v_b' = v_b − e·v_d − h·v_b, v_d' = v_d + e·v_b − h·v_d. For |e| ≤ 1e-3 the
/// neglected third-order term is below 1.7e-10 rad.
#[inline(always)]
pub fn small_rotate<P: Precision, E: Scale<P>>(axis: u8, e: P::U, h: P::U, v: Vec3<E>) -> Vec3<E> {
    let (b, d) = cyclic(axis);
    let mut r = v;
    r[b] = v[b] - (v[d].scale(e) + v[b].scale(h));
    r[d] = v[d] + (v[b].scale(e) - v[d].scale(h));
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::F32;

    fn close(a: Vec3<f32>, b: [f64; 3], tol: f64) -> bool {
        (0..3).all(|i| (f64::from(a[i]) - b[i]).abs() < tol)
    }

    #[test]
    fn quarter_turns_follow_the_right_hand() {
        // About z: x → y.
        assert_eq!(quadrant_rotate(2, 1, [1.0f32, 0.0, 0.0]), [0.0, 1.0, 0.0]);
        // About x: y → z.
        assert_eq!(quadrant_rotate(0, 1, [0.0f32, 1.0, 0.0]), [0.0, 0.0, 1.0]);
        // About y: z → x.
        assert_eq!(quadrant_rotate(1, 1, [0.0f32, 0.0, 1.0]), [1.0, 0.0, 0.0]);
        assert_eq!(quadrant_rotate(1, 3, [1.0f32, 0.0, 0.0]), [0.0, 0.0, 1.0]);
    }

    #[test]
    fn axis_rotation_matches_quaternion_rotation() {
        let x = 0.3f64; // half angle
        let (c, s) = (x.cos() as f32, x.sin() as f32);
        let v = [1.0f32, 2.0, 3.0];
        for axis in 0..3u8 {
            let mut q = Quat::<F32> { w: c, v: [0.0; 3] };
            q.v[axis as usize] = s;
            let a = axis_rotate::<F32, f32>(axis, c, s, v);
            let b = q.rotate(v);
            let b64 = [f64::from(b[0]), f64::from(b[1]), f64::from(b[2])];
            assert!(close(a, b64, 1e-5), "{a:?} {b:?}");
        }
        // About z by 0.6 rad.
        let r = axis_rotate::<F32, f32>(2, c, s, [1.0, 0.0, 0.0]);
        assert!(close(r, [0.6f64.cos(), 0.6f64.sin(), 0.0], 1e-6));
    }

    #[test]
    fn small_rotation_is_second_order_accurate() {
        let e = 1e-3f64;
        let r = small_rotate::<F32, f32>(0, e as f32, (e * e / 2.0) as f32, [0.0, 1000.0, 0.0]);
        assert!(
            close(r, [0.0, 1000.0 * e.cos(), 1000.0 * e.sin()], 1e-4),
            "{r:?}"
        );
    }

    #[test]
    fn inverse_undoes_rotation() {
        let q = Quat::<F32> {
            w: 0.5,
            v: [0.5, -0.5, 0.5],
        };
        let v = [3.0f32, -1.0, 2.0];
        let back = q.rotate_inverse(q.rotate(v));
        assert!(close(back, [3.0, -1.0, 2.0], 1e-6));
        // First column of q's rotation matrix: (1 − 2(y²+z²), 2(xy + wz), 2(xz − wy)) = z.
        let r = q.rotate([1.0f32, 0.0, 0.0]);
        assert!(close(r, [0.0, 0.0, 1.0], 1e-6), "{r:?}");
    }
}
