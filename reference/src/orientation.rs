//! Orientation quantities of the classic formulation (Sładek et al.): the axis–angle pair of a
//! rotation matrix and the orientation error of the probe direction.
//!
//! Sign convention, used everywhere in quatarm (also written in `docs/spec-reading.md`):
//! **n is the model's direction, n_m the measured one, and an orientation error is the rotation
//! that takes the model onto the measurement** — positive where the measured direction lies
//! turned, in the right-hand sense about e, from the modelled one. That is the sense of a
//! residual "measured minus model": turning the model by the error moves it towards the
//! measurement.

use nalgebra::{Matrix3, Unit, Vector3};

/// Axis and angle of a rotation matrix: `r = Rot(axis, angle)` with angle in [0, π].
///
/// Robust over the whole range, which the textbook `acos((tr R − 1)/2)` is not (it loses half
/// the digits near 0 and near π, and its axis `(R − Rᵀ)/(2 sin φ)` fails near π):
/// - the angle is `atan2(sin φ, cos φ)` with sin φ = |vee(R − Rᵀ)|/2 and cos φ = (tr R − 1)/2, so
///   it keeps full relative precision near 0 and absolute precision ~1e-16 near π;
/// - for φ ≤ π/2 the axis is vee(R − Rᵀ) normalised (well conditioned there);
/// - for φ > π/2 it comes from the symmetric part, (R + Rᵀ)/2 − cos φ·I = (1 − cos φ) u uᵀ, taking
///   its largest column (never small: 1 − cos φ ≥ 1), with the sign chosen so that
///   u · vee(R − Rᵀ) ≥ 0. At φ = π exactly both signs describe the same rotation.
///
/// At φ = 0 the axis is undefined; z is returned. `r` is assumed orthonormal (a rotation
/// matrix); for any finite input the result is finite.
pub fn axis_angle(r: &Matrix3<f64>) -> (Unit<Vector3<f64>>, f64) {
    let w = Vector3::new(
        r[(2, 1)] - r[(1, 2)],
        r[(0, 2)] - r[(2, 0)],
        r[(1, 0)] - r[(0, 1)],
    );
    let sin = 0.5 * w.norm();
    let cos = 0.5 * (r.trace() - 1.0);
    let angle = sin.atan2(cos);
    let axis = if cos >= 0.0 {
        w
    } else {
        let b = 0.5 * (r + r.transpose()) - Matrix3::from_diagonal_element(cos);
        let k = (0..3)
            .max_by(|&i, &j| b[(i, i)].total_cmp(&b[(j, j)]))
            .unwrap_or(2);
        let u = b.column(k).into_owned();
        if u.dot(&w) < 0.0 {
            -u
        } else {
            u
        }
    };
    match Unit::try_new(axis, 0.0) {
        Some(u) if u.iter().all(|v| v.is_finite()) => (u, angle),
        _ => (Vector3::z_axis(), angle),
    }
}

/// The rotation vector (axis × angle, |·| ≤ π) of a rotation matrix.
pub fn rotation_vector(r: &Matrix3<f64>) -> Vector3<f64> {
    let (u, angle) = axis_angle(r);
    u.into_inner() * angle
}

/// Orientation error of the probe direction, Sładek et al. eq. 22: e = ½ (n × n_m).
///
/// `model` is n, the direction the arm model predicts; `measured` is n_m, the direction
/// observed (both unit vectors). e points along the axis of the smallest rotation that takes
/// n onto n_m, with |e| = ½ sin γ, γ the angle between them. For a small rotation
/// n_m = R(ω) n it is e = ½ ω⊥ + O(|ω|²), ω⊥ the part of ω across n (the part along n turns
/// nothing and cannot be seen in a direction).
///
/// Why ½: the formula is the one-vector case of the orientation error of Luh, Walker & Paul
/// (1980), e = ½ Σ_k (r_k × r_mk) over the three axes of a frame, where the three terms add up to
/// 2ω (see [`frame_orientation_error`]). With a single direction only one term is present, so e
/// is *half* the small rotation — keep the factor in mind when comparing e with angles, or use
/// [`direction_rotation`] for the rotation itself.
pub fn probe_direction_error(model: &Vector3<f64>, measured: &Vector3<f64>) -> Vector3<f64> {
    0.5 * model.cross(measured)
}

/// The smallest rotation taking direction `model` onto direction `measured`, as a rotation
/// vector: axis n × n_m, angle γ = atan2(|n × n_m|, n · n_m) ∈ [0, π].
///
/// This is the exact counterpart of [`probe_direction_error`] (e = ½ sin γ · axis). For
/// opposite directions the axis is undefined; any axis across `model` is then returned.
pub fn direction_rotation(model: &Vector3<f64>, measured: &Vector3<f64>) -> Vector3<f64> {
    let c = model.cross(measured);
    let angle = c.norm().atan2(model.dot(measured));
    match Unit::try_new(c, 0.0) {
        Some(u) => u.into_inner() * angle,
        None if angle == 0.0 => Vector3::zeros(),
        None => {
            // Antiparallel: any perpendicular axis; take the one from the smallest component.
            let k = model.iamin();
            let mut e = Vector3::zeros();
            e[k] = 1.0;
            model.cross(&e).normalize() * angle
        }
    }
}

/// Orientation error of a whole frame (Luh, Walker & Paul 1980): e = ½ Σ_k r_k × r_mk over the
/// columns of the model orientation `model` and the measured one `measured`.
///
/// For `measured = R(ω) · model` with small ω this is ω + O(|ω|²): the rotation, in the base
/// frame, that takes the model frame onto the measured one — the same sign convention as
/// [`probe_direction_error`], of which it is the three-direction sum.
pub fn frame_orientation_error(model: &Matrix3<f64>, measured: &Matrix3<f64>) -> Vector3<f64> {
    (0..3)
        .map(|k| model.column(k).cross(&measured.column(k)))
        .fold(Vector3::zeros(), |acc, c| acc + c)
        * 0.5
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::f64::consts::{FRAC_PI_2, PI};

    fn unit(rng: &mut ChaCha8Rng) -> Unit<Vector3<f64>> {
        loop {
            let v = Vector3::new(
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
            );
            let n = v.norm();
            if n > 0.1 && n <= 1.0 {
                return Unit::new_normalize(v);
            }
        }
    }

    /// The angles the round trip must survive: exact and near 0, near the branch switch at π/2,
    /// near and at π.
    const EDGE_ANGLES: [f64; 16] = [
        0.0,
        1e-300,
        1e-15,
        1e-10,
        1e-6,
        0.3,
        FRAC_PI_2 - 1e-12,
        FRAC_PI_2,
        FRAC_PI_2 + 1e-12,
        2.5,
        PI - 1e-4,
        PI - 1e-8,
        PI - 1e-12,
        PI - 1e-15,
        PI - 4e-16,
        PI,
    ];

    fn axes(rng: &mut ChaCha8Rng) -> Vec<Unit<Vector3<f64>>> {
        let mut v: Vec<Unit<Vector3<f64>>> = vec![
            Vector3::x_axis(),
            Vector3::y_axis(),
            Vector3::z_axis(),
            -Vector3::x_axis(),
            -Vector3::z_axis(),
            Unit::new_normalize(Vector3::new(1.0, 1.0, 1.0)),
            Unit::new_normalize(Vector3::new(1.0, -1.0, 0.0)),
            Unit::new_normalize(Vector3::new(1e-9, 0.0, 1.0)),
        ];
        v.extend((0..200).map(|_| unit(rng)));
        v
    }

    /// Checks one round trip and returns (rotation-matrix error, angle error).
    fn round_trip(u: &Unit<Vector3<f64>>, phi: f64) -> (f64, f64) {
        let r = Rotation3::from_axis_angle(u, phi).into_inner();
        let (u2, phi2) = axis_angle(&r);
        assert!((0.0..=PI).contains(&phi2), "angle {phi2} out of [0, π]");
        assert!((u2.norm() - 1.0).abs() < 1e-15);
        let back = Rotation3::from_axis_angle(&u2, phi2).into_inner();
        let r_err = (back - r).amax();
        let a_err = (phi2 - phi).abs();
        // Where the axis is defined to better than rounding, it must be the one put in.
        if (1e-6..=PI - 1e-6).contains(&phi) {
            assert!(
                (u2.into_inner() - u.into_inner()).norm() < 1e-9,
                "axis {u2:?} for {u:?} at {phi}"
            );
        }
        if phi > PI - 1e-6 {
            // Near π the sign is fixed by a tiny antisymmetric part; the line must be right.
            let d = (u2.into_inner() - u.into_inner())
                .norm()
                .min((u2.into_inner() + u.into_inner()).norm());
            assert!(d < 1e-12, "axis line {u2:?} for {u:?} at {phi}");
        }
        (r_err, a_err)
    }

    #[test]
    fn axis_angle_round_trip_edge_cases() {
        let mut rng = ChaCha8Rng::seed_from_u64(22);
        let mut worst = (0.0f64, 0.0f64);
        for u in axes(&mut rng) {
            for &phi in &EDGE_ANGLES {
                let (r, a) = round_trip(&u, phi);
                worst = (worst.0.max(r), worst.1.max(a));
            }
        }
        println!("edges: rotation {:e}, angle {:e}", worst.0, worst.1);
        assert!(worst.0 < 4e-15, "rotation error {:e}", worst.0);
        assert!(worst.1 < 4e-15, "angle error {:e}", worst.1);
    }

    #[test]
    fn axis_angle_round_trip_random() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut worst = (0.0f64, 0.0f64);
        for _ in 0..20_000 {
            let u = unit(&mut rng);
            let phi = rng.gen_range(0.0..=PI);
            let (r, a) = round_trip(&u, phi);
            worst = (worst.0.max(r), worst.1.max(a));
        }
        // A few units in the last place of entries of size 1 (ulp 2.2e-16).
        println!("random: rotation {:e}, angle {:e}", worst.0, worst.1);
        assert!(worst.0 < 4e-15, "rotation error {:e}", worst.0);
        assert!(worst.1 < 4e-15, "angle error {:e}", worst.1);
    }

    #[test]
    fn angles_beyond_pi_come_back_with_the_opposite_axis() {
        let u = Unit::new_normalize(Vector3::new(0.2, -0.5, 0.7));
        let r = Rotation3::from_axis_angle(&u, 4.0).into_inner();
        let (u2, phi2) = axis_angle(&r);
        assert!((phi2 - (2.0 * PI - 4.0)).abs() < 1e-14);
        assert!((u2.into_inner() + u.into_inner()).norm() < 1e-14);
    }

    #[test]
    fn identity_is_zero_angle() {
        let (u, phi) = axis_angle(&Matrix3::identity());
        assert_eq!(phi, 0.0);
        assert_eq!(u, Vector3::z_axis());
        assert_eq!(rotation_vector(&Matrix3::identity()), Vector3::zeros());
    }

    #[test]
    fn non_rotation_input_stays_finite() {
        let (u, phi) = axis_angle(&Matrix3::zeros());
        assert!(phi.is_finite() && u.iter().all(|v| v.is_finite()));
        let (u, phi) = axis_angle(&Matrix3::from_element(3.0));
        assert!(phi.is_finite() && u.iter().all(|v| v.is_finite()));
    }

    #[test]
    fn probe_error_is_half_the_perpendicular_rotation() {
        // n_m = R(ω) n: e = ½ (n × n_m) = +½ ω⊥ to first order, with the documented sign.
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..5_000 {
            let n = unit(&mut rng).into_inner();
            let size = 10f64.powf(rng.gen_range(-8.0..-2.0));
            let omega = unit(&mut rng).into_inner() * size;
            let n_m = Rotation3::new(omega) * n;
            let e = probe_direction_error(&n, &n_m);
            let omega_perp = omega - n * n.dot(&omega);
            // Second-order remainder: |e − ½ ω⊥| ≤ |ω|² (a loose bound on ¼|ω|²-type terms).
            assert!(
                (e - 0.5 * omega_perp).norm() <= size * size + 1e-17,
                "|ω| = {size:e}: e = {e}, ½ω⊥ = {}",
                0.5 * omega_perp
            );
            // Swapping model and measurement flips the sign: the convention is not symmetric.
            assert_eq!(probe_direction_error(&n_m, &n), -e);
            // And the exact rotation is twice e to first order.
            let rot = direction_rotation(&n, &n_m);
            assert!((rot - omega_perp).norm() <= size * size + 1e-15);
        }
    }

    #[test]
    fn probe_error_magnitude_is_half_sine() {
        let n = Vector3::z();
        for &g in &[0.0, 1e-9, 0.1, 1.0, FRAC_PI_2, 3.0] {
            let n_m = Vector3::new(g.sin(), 0.0, g.cos());
            let e = probe_direction_error(&n, &n_m);
            assert!((e.norm() - 0.5 * g.sin()).abs() < 1e-16);
            // n turned about +y by γ reaches n_m, so e points along +y.
            assert!(g == 0.0 || e.y > 0.0);
        }
    }

    #[test]
    fn direction_rotation_is_exact() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..2_000 {
            let n = unit(&mut rng).into_inner();
            let n_m = unit(&mut rng).into_inner();
            let v = direction_rotation(&n, &n_m);
            assert!((Rotation3::new(v) * n - n_m).norm() < 1e-14);
            assert!(v.dot(&n).abs() < 1e-14, "smallest rotation is across n");
        }
        let n = Vector3::new(0.0, 0.6, 0.8);
        assert_eq!(direction_rotation(&n, &n), Vector3::zeros());
        let v = direction_rotation(&n, &-n);
        assert!((v.norm() - PI).abs() < 1e-15);
        assert!((Rotation3::new(v) * n + n).norm() < 1e-15);
    }

    #[test]
    fn frame_error_is_the_small_rotation() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for _ in 0..2_000 {
            let model = Rotation3::from_axis_angle(&unit(&mut rng), rng.gen_range(0.0..PI));
            let size = 10f64.powf(rng.gen_range(-8.0..-2.0));
            let omega = unit(&mut rng).into_inner() * size;
            let measured = Rotation3::new(omega) * model;
            let e = frame_orientation_error(model.matrix(), measured.matrix());
            assert!((e - omega).norm() <= size * size + 1e-15, "{e} vs {omega}");
        }
    }
}
