//! A D–H arm in the spec's model: every axis z, the twist α in the tilt, a and d in the link.
//!
//! The spec (`arm-model.md`, "tilt") says how a twisted arm is written: u_i = z,
//! tilt = [α, 0] (the fixed rotation before the joint, about x), the D–H offset a joining d in
//! the link vector. Worked out for both conventions:
//!
//! **Classic.** `T_i = Rot_z(θ_i) · Trans(a_i, 0, d_i) · Rot_x(α_i)` (the two translations of
//! the definition commute into one). Read left to right, joint i turns about z, then the link
//! runs (a_i, 0, d_i) in the frame *after* that rotation — exactly the spec's v_i — and then
//! `Rot_x(α_i)` is the fixed rotation *before* joint i+1, so α_i becomes joint i+1's tilt. Joint
//! 1's tilt comes from the base transform (zero for an identity base), and the last row's α_N
//! has no joint after it: it turns the tool, so the probe vector is `Rot_x(α_N) · t`.
//!
//! **Modified.** `T_i = Rot_x(α_{i-1}) · Trans_x(a_{i-1}) · Rot_z(θ_i) · Trans_z(d_i)`. Regrouped
//! around the joint rotations, what lies between joint i and joint i+1 is
//! `Trans_z(d_i) · Rot_x(α_i) · Trans_x(a_i) = Trans(a_i, 0, d_i) · Rot_x(α_i)` (a rotation about x
//! and a translation along x commute): the same shape as classic, with link
//! (a_i, 0, d_i) read from rows i (d) and i+1 (a, α) — the spec's own wording, "the D–H offset
//! a_{i-1} joining d_{i-1} in v_{i-1}". Row 1's α_0 and a_0 stand before joint 1, so they join the
//! base transform; the last link is (0, 0, d_N) with no twist after it.
//!
//! **Base.** The spec model has joint 1 at the base-frame origin and its fixed rotation in
//! joint 1's tilt `Rot_x(δα) · Rot_y(δβ)`. Any base *rotation* fits: written as
//! `Rot_x(a) · Rot_y(b) · Rot_z(c)`, a and b are joint 1's tilt and c, a turn about joint 1's own
//! axis, adds to its zero offset. A base *translation* fits only along joint 1's axis, where it
//! lengthens link 1 (the axis does not move as joint 1 turns); a component across the axis would
//! have to stay fixed while joint 1 turns, which no spec parameter does, so it is refused with
//! [`DhError::BaseOffsetAcrossAxis`]. [`to_spec_arm_with_frame`] takes every rigid base by
//! carrying it as the reference-instrument frame of the spec (x_ref = R_T p + t_T) instead.
//!
//! **θ offsets.** A D–H θ offset is the angle the joint stands at when its encoder reads zero:
//! that is the spec's zero offset Δθ, so it goes to `zero_offset`. The converted arm's
//! `zero_offset` is thus a full value (nominal plus error, like `tilt`), and a calibration
//! starting from it estimates the deviation from the table's offset.

use super::{Convention, DhArm, DhError};
use crate::arm::{Arm, Axis, Frame, Joint, Probe};
use nalgebra::{Matrix3, Matrix4, Rotation3, UnitQuaternion, Vector3};

/// Largest base-translation component across joint 1's axis (mm) that is treated as zero.
///
/// Base transforms usually come from products of rotations and translations, whose rounding
/// leaves ~1e-13 mm across the axis where the design has none; 1e-9 mm is the agreement the
/// conversion promises, so what is dropped stays inside it.
pub const BASE_TOLERANCE_MM: f64 = 1e-9;

/// Largest deviation of the base transform from a rigid one (orthonormality, determinant, last
/// row) that is accepted as rounding.
pub const RIGID_TOLERANCE: f64 = 1e-9;

/// The chain in the shape both conventions reduce to:
/// `B' · Π_i [Rot_z(θ_i + offset_i) · Trans(link_i) · Rot_x(twist_i)] · tool`.
struct Normal {
    /// B': the base transform including, for a modified table, row 1's Rot_x(α_0) Trans_x(a_0).
    base: Matrix4<f64>,
    /// Per joint: θ offset, link vector after the joint's rotation, twist after the link.
    joints: Vec<(f64, Vector3<f64>, f64)>,
}

fn normal_form(dh: &DhArm) -> Normal {
    let n = dh.joints.len();
    match dh.convention {
        Convention::Classic => Normal {
            base: dh.base,
            joints: dh
                .joints
                .iter()
                .map(|j| (j.theta_offset, Vector3::new(j.a, 0.0, j.d), j.alpha))
                .collect(),
        },
        Convention::Modified => {
            let first = &dh.joints[0];
            Normal {
                base: dh.base * super::rot_x(first.alpha) * super::trans(first.a, 0.0, 0.0),
                joints: (0..n)
                    .map(|i| {
                        let (a, twist) = match dh.joints.get(i + 1) {
                            Some(next) => (next.a, next.alpha),
                            None => (0.0, 0.0),
                        };
                        (
                            dh.joints[i].theta_offset,
                            Vector3::new(a, 0.0, dh.joints[i].d),
                            twist,
                        )
                    })
                    .collect(),
            }
        }
    }
}

fn check(dh: &DhArm) -> Result<(), DhError> {
    if !crate::arm::JOINT_COUNTS.contains(&dh.joints.len()) {
        return Err(DhError::JointCount(dh.joints.len()));
    }
    let table_finite = dh.joints.iter().all(|j| {
        [j.theta_offset, j.d, j.a, j.alpha]
            .iter()
            .all(|v| v.is_finite())
    });
    if !table_finite {
        return Err(DhError::NonFinite("the D–H table"));
    }
    if !dh.base.iter().all(|v| v.is_finite()) {
        return Err(DhError::NonFinite("the base transform"));
    }
    if !dh.tool.iter().all(|v| v.is_finite()) {
        return Err(DhError::NonFinite("the tool vector"));
    }
    if dh.tool.norm() == 0.0 {
        return Err(DhError::ZeroTool);
    }
    Ok(())
}

/// Splits a homogeneous matrix into rotation and translation, refusing what is not rigid.
fn rigid_parts(t: &Matrix4<f64>) -> Result<(Matrix3<f64>, Vector3<f64>), DhError> {
    let r: Matrix3<f64> = t.fixed_view::<3, 3>(0, 0).into_owned();
    let p: Vector3<f64> = t.fixed_view::<3, 1>(0, 3).into_owned();
    let orth = (r.transpose() * r - Matrix3::identity()).amax();
    let det = (r.determinant() - 1.0).abs();
    let last = (t.fixed_view::<1, 4>(3, 0) - nalgebra::RowVector4::new(0.0, 0.0, 0.0, 1.0)).amax();
    let deviation = orth.max(det).max(last);
    if deviation > RIGID_TOLERANCE {
        return Err(DhError::NotRigid { deviation });
    }
    Ok((r, p))
}

/// The angles (a, b, c) with `r = Rot_x(a) · Rot_y(b) · Rot_z(c)`.
///
/// b comes from the first row (r₀₂ = sin b, |(r₀₀, r₀₁)| = cos b ≥ 0) and c from the same row;
/// a is then read from what remains, `r · Rot_z(−c) · Rot_y(−b)`, so that the product is
/// reproduced to rounding even at b = ±90°, where a and c are not separately defined.
pub fn xyz_angles(r: &Matrix3<f64>) -> (f64, f64, f64) {
    let b = r[(0, 2)].atan2(r[(0, 0)].hypot(r[(0, 1)]));
    let c = (-r[(0, 1)]).atan2(r[(0, 0)]);
    let rest = r
        * Rotation3::from_axis_angle(&Vector3::z_axis(), -c).into_inner()
        * Rotation3::from_axis_angle(&Vector3::y_axis(), -b).into_inner();
    let a = rest[(2, 1)].atan2(rest[(1, 1)]);
    (a, b, c)
}

/// The spec arm of a normal form whose base rotation is `r` and whose base translation has
/// already been checked to lie along joint 1's axis (`along`, mm).
fn build(dh: &DhArm, nf: &Normal, r: &Matrix3<f64>, along: f64) -> Arm {
    let (a, b, c) = xyz_angles(r);
    let mut joints = Vec::with_capacity(nf.joints.len());
    let mut twist_before = 0.0;
    for (i, &(offset, link, twist)) in nf.joints.iter().enumerate() {
        let mut j = Joint::nominal(Axis::Z, link.into());
        if i == 0 {
            j.tilt = [a, b];
            j.zero_offset = offset + c;
            j.link[2] += along;
        } else {
            j.tilt = [twist_before, 0.0];
            j.zero_offset = offset;
        }
        twist_before = twist;
        joints.push(j);
    }
    let probe = super::rot_x(twist_before).fixed_view::<3, 3>(0, 0) * dh.tool;
    Arm {
        name: Some(dh.name.clone()),
        serial: None,
        joints,
        probe: Probe {
            id: 0,
            vector: probe.into(),
            error: [0.0; 3],
            thermal: 0.0,
            ball_diameter: 0.0,
        },
        more_probes: Vec::new(),
        reference_frame: None,
    }
}

/// Converts a D–H arm into the spec's model, evaluated by [`crate::forward::forward`] to the same
/// probe-ball centre and direction (at 20 °C; the converted arm has no error terms).
///
/// Refused: joint counts other than 6 and 7 (the spec model's), non-finite entries, a zero tool
/// vector (the probe direction would be undefined), a base that is not rigid, and a base
/// translation across joint 1's axis (see the module notes; [`to_spec_arm_with_frame`] takes it).
pub fn to_spec_arm(dh: &DhArm) -> Result<Arm, DhError> {
    check(dh)?;
    let nf = normal_form(dh);
    let (r, t) = rigid_parts(&nf.base)?;
    let axis = r.column(2).into_owned();
    let along = t.dot(&axis);
    let across_mm = (t - along * axis).norm();
    if across_mm > BASE_TOLERANCE_MM {
        return Err(DhError::BaseOffsetAcrossAxis { across_mm });
    }
    Ok(build(dh, &nf, &r, along))
}

/// Converts a D–H arm with any rigid base: the arm in its own frame (the table's frame 0 — for a
/// modified table, after row 1's α_0 and a_0) and the base transform as the spec's reference
/// frame, so that world = R_T · p + t_T with p from [`crate::forward::forward`].
///
/// The frame is also stored in the arm's `reference_frame`. quatarm's output stays in the arm's
/// base frame (`docs/spec-reading.md`), so callers who want world coordinates apply it.
pub fn to_spec_arm_with_frame(dh: &DhArm) -> Result<(Arm, Frame), DhError> {
    check(dh)?;
    let nf = normal_form(dh);
    let (r, t) = rigid_parts(&nf.base)?;
    let mut arm = build(dh, &nf, &Matrix3::identity(), 0.0);
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    let q = if q.w < 0.0 {
        -q.into_inner()
    } else {
        q.into_inner()
    };
    let frame = Frame {
        rotation: [q.w, q.i, q.j, q.k],
        translation: t.into(),
    };
    arm.reference_frame = Some(frame.clone());
    Ok((arm, frame))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dh::{agreement, DhJoint};
    use crate::forward::{forward, tilt_matrix};
    use std::f64::consts::{FRAC_PI_2, PI};

    fn some_poses() -> Vec<Vec<f64>> {
        (0..50)
            .map(|k| {
                (0..6)
                    .map(|i| ((k * 7 + i * 13) as f64 * 0.37).sin() * PI)
                    .collect()
            })
            .collect()
    }

    #[test]
    fn xyz_angles_reproduce_the_rotation() {
        for &(a, b, c) in &[
            (0.3, -0.2, 1.4),
            (-2.9, 1.2, -3.0),
            (0.0, FRAC_PI_2, 0.7),
            (1.0, -FRAC_PI_2, 0.0),
            (PI, 0.0, PI),
        ] {
            let r = tilt_matrix(Axis::Z, [a, b])
                * Rotation3::from_axis_angle(&Vector3::z_axis(), c).into_inner();
            let (a2, b2, c2) = xyz_angles(&r);
            let back = tilt_matrix(Axis::Z, [a2, b2])
                * Rotation3::from_axis_angle(&Vector3::z_axis(), c2).into_inner();
            assert!((back - r).amax() < 1e-15, "{a} {b} {c}");
        }
    }

    #[test]
    fn ur5_maps_as_worked_out() {
        // Classic: link_i = (a_i, 0, d_i), tilt_{i+1} = α_i, probe = Rot_x(α_6) t (α_6 = 0).
        let dh = crate::dh::tables::ur5(Vector3::new(0.0, 0.0, 100.0));
        let arm = to_spec_arm(&dh).unwrap();
        assert_eq!(arm.joints[0].tilt, [0.0, 0.0]);
        assert_eq!(arm.joints[1].tilt, [FRAC_PI_2, 0.0]);
        assert_eq!(arm.joints[1].link, [-425.0, 0.0, 0.0]);
        assert_eq!(arm.joints[4].tilt, [FRAC_PI_2, 0.0]);
        assert_eq!(arm.joints[5].tilt, [-FRAC_PI_2, 0.0]);
        assert_eq!(arm.joints[5].link, [0.0, 0.0, 82.3]);
        assert_eq!(arm.probe.vector, [0.0, 0.0, 100.0]);
        assert!(arm.joints.iter().all(|j| j.axis == Axis::Z));
    }

    #[test]
    fn last_twist_turns_the_tool() {
        let mut dh = crate::dh::tables::ur5(Vector3::new(0.0, 10.0, 100.0));
        dh.joints[5].alpha = FRAC_PI_2;
        let arm = to_spec_arm(&dh).unwrap();
        // Rot_x(90°) (0, 10, 100) = (0, -100, 10).
        let v = Vector3::from(arm.probe.vector);
        assert!((v - Vector3::new(0.0, -100.0, 10.0)).norm() < 1e-13);
        let poses = some_poses();
        let agree = agreement(&dh, &arm, &poses).unwrap();
        assert!(agree.max_position_mm < 1e-9, "{agree:?}");
    }

    #[test]
    fn theta_offsets_become_zero_offsets() {
        let mut dh = crate::dh::tables::ur5(Vector3::new(0.0, 0.0, 100.0));
        dh.joints[2].theta_offset = 0.25;
        let arm = to_spec_arm(&dh).unwrap();
        assert_eq!(arm.joints[2].zero_offset, 0.25);
        let poses = some_poses();
        let agree = agreement(&dh, &arm, &poses).unwrap();
        assert!(agree.max_position_mm < 1e-9, "{agree:?}");
    }

    #[test]
    fn base_along_the_axis_lengthens_link_one() {
        // A base raised 150 mm and turned 30° about z: representable.
        let mut dh = crate::dh::tables::ur5(Vector3::new(0.0, 0.0, 100.0));
        dh.base = crate::dh::trans(0.0, 0.0, 150.0) * crate::dh::rot_z(0.5);
        let arm = to_spec_arm(&dh).unwrap();
        assert!((arm.joints[0].link[2] - (89.159 + 150.0)).abs() < 1e-12);
        assert!((arm.joints[0].zero_offset - 0.5).abs() < 1e-15);
        let poses = some_poses();
        let agree = agreement(&dh, &arm, &poses).unwrap();
        assert!(agree.max_position_mm < 1e-9, "{agree:?}");
    }

    #[test]
    fn tilted_base_with_offset_along_its_axis() {
        // Wall mounting: base turned 90° about y, raised along the (now horizontal) joint-1 axis.
        let mut dh = crate::dh::tables::ur5(Vector3::new(5.0, 0.0, 100.0));
        let r = crate::dh::rot_x(0.2)
            * Matrix4::from(Rotation3::from_axis_angle(&Vector3::y_axis(), FRAC_PI_2));
        let axis = r.fixed_view::<3, 1>(0, 2).into_owned();
        dh.base = crate::dh::trans(axis.x * 40.0, axis.y * 40.0, axis.z * 40.0) * r;
        let arm = to_spec_arm(&dh).unwrap();
        let poses = some_poses();
        let agree = agreement(&dh, &arm, &poses).unwrap();
        assert!(agree.max_position_mm < 1e-9, "{agree:?}");
        assert!(agree.max_direction < 1e-12, "{agree:?}");
    }

    #[test]
    fn base_offset_across_the_axis_is_refused_then_carried_as_frame() {
        let mut dh = crate::dh::tables::ur5(Vector3::new(0.0, 0.0, 100.0));
        dh.base = crate::dh::trans(30.0, -40.0, 10.0) * crate::dh::rot_x(0.3);
        match to_spec_arm(&dh) {
            Err(DhError::BaseOffsetAcrossAxis { across_mm }) => {
                assert!(across_mm > 40.0 && across_mm < 60.0, "{across_mm}");
            }
            other => panic!("expected a refusal, got {other:?}"),
        }
        let (arm, frame) = to_spec_arm_with_frame(&dh).unwrap();
        let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            frame.rotation[0],
            frame.rotation[1],
            frame.rotation[2],
            frame.rotation[3],
        ));
        let t = Vector3::from(frame.translation);
        for theta in some_poses() {
            let world = q * forward(&arm, &theta, 20.0).p + t;
            let dhp = dh.pose(&theta).unwrap().p;
            assert!((world - dhp).norm() < 1e-9, "{}", (world - dhp).norm());
        }
    }

    #[test]
    fn modified_first_row_offset_goes_to_the_base() {
        // A modified table whose row 1 has a_0 ≠ 0 puts joint 1 off the base origin: refused,
        // and taken through the frame.
        let mut dh = crate::dh::tables::panda(Vector3::new(0.0, 0.0, 100.0));
        dh.joints[0].a = 25.0;
        assert!(matches!(
            to_spec_arm(&dh),
            Err(DhError::BaseOffsetAcrossAxis { .. })
        ));
        assert!(to_spec_arm_with_frame(&dh).is_ok());
        // α_0 alone is a rotation of the base: representable as joint 1's tilt.
        dh.joints[0].a = 0.0;
        dh.joints[0].alpha = 0.4;
        let arm = to_spec_arm(&dh).unwrap();
        assert!((arm.joints[0].tilt[0] - 0.4).abs() < 1e-15);
        let poses: Vec<Vec<f64>> = some_poses()
            .into_iter()
            .map(|mut p| {
                p.push(p[0] * 0.5);
                p
            })
            .collect();
        let agree = agreement(&dh, &arm, &poses).unwrap();
        assert!(agree.max_position_mm < 1e-9, "{agree:?}");
    }

    #[test]
    fn refusals() {
        let tool = Vector3::new(0.0, 0.0, 100.0);
        let mut dh = crate::dh::tables::ur5(tool);
        dh.joints.pop();
        assert_eq!(to_spec_arm(&dh), Err(DhError::JointCount(5)));

        let mut dh = crate::dh::tables::ur5(Vector3::zeros());
        assert_eq!(to_spec_arm(&dh), Err(DhError::ZeroTool));
        dh.tool = tool;
        dh.joints[3].alpha = f64::NAN;
        assert_eq!(to_spec_arm(&dh), Err(DhError::NonFinite("the D–H table")));

        let mut dh = crate::dh::tables::ur5(tool);
        dh.base[(0, 0)] = 1.1;
        assert!(matches!(to_spec_arm(&dh), Err(DhError::NotRigid { .. })));
        assert!(matches!(
            to_spec_arm_with_frame(&dh),
            Err(DhError::NotRigid { .. })
        ));
        let mut dh = crate::dh::tables::ur5(tool);
        dh.base = Matrix4::identity();
        dh.base[(2, 2)] = -1.0; // a reflection
        assert!(matches!(to_spec_arm(&dh), Err(DhError::NotRigid { .. })));

        let dh = crate::dh::DhArm::new(
            "eight",
            Convention::Classic,
            vec![DhJoint::new(1.0, 1.0, 0.0); 8],
            tool,
        );
        assert_eq!(to_spec_arm(&dh), Err(DhError::JointCount(8)));
    }
}
