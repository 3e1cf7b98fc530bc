//! The firmware chains against the f64 reference, on every run: the accuracy bounds of issue 2
//! over random readings of `default-6` with a calibration that uses every term, plus
//! randomised calibrations; arbitrary counts never panic. (The million-pose figures come from
//! `armcal accuracy`; these tests hold the same bounds on fewer poses, in seconds.)

use armcal::accuracy::{full_calibration, measure, random_reading, Paths, Report};
use proptest::prelude::*;
use quatarm::{Chain, ChainError, Fixed, Table, F32};
use quatarm_ref::{Arm, Harmonic};

/// Issue 2's bounds: tip (µm) and direction, f32 and fixed point.
const F32_TIP_UM: f64 = 1.0;
const FIXED_TIP_UM: f64 = 0.1;
const F32_DIR: f64 = 1e-6;
const FIXED_DIR: f64 = 1e-7;

fn check(rep: &Report) {
    let [qf, qx, mf, mx, _] = rep.stats;
    assert!(
        qf.max_um <= F32_TIP_UM,
        "f32 quaternion tip {} um",
        qf.max_um
    );
    assert!(qf.max_dir <= F32_DIR, "f32 quaternion dir {}", qf.max_dir);
    assert!(
        qx.max_um <= FIXED_TIP_UM,
        "fixed quaternion tip {} um",
        qx.max_um
    );
    assert!(
        qx.max_dir <= FIXED_DIR,
        "fixed quaternion dir {}",
        qx.max_dir
    );
    assert!(mf.max_um <= F32_TIP_UM, "f32 matrix tip {} um", mf.max_um);
    assert!(
        mx.max_um <= FIXED_TIP_UM,
        "fixed matrix tip {} um",
        mx.max_um
    );
}

#[test]
fn full_calibration_within_bounds_over_100k_poses() {
    let rep = measure(&full_calibration(), 100_000, 7, 2, &|_| {}).unwrap();
    check(&rep);
    // The quaternion chain is at least as accurate as the matrix chain in f32 (RMS: the
    // maximum of 1e5 samples is itself noisy; `armcal accuracy` compares maxima over 1e6).
    assert!(rep.stats[0].rms_um() <= rep.stats[2].rms_um());
}

#[test]
fn the_shipped_calibration_file_is_the_built_in_one() {
    let parsed = quatarm_ref::calfile::read(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../data/default-6-full.toml"
    )))
    .unwrap();
    assert_eq!(parsed.arm, full_calibration());
}

/// The quaternion chains' bounds (the matrix chain takes the spec's first-order gravity sum,
/// which is micrometres off at such compliances: a comparison, not a firmware path).
fn check_quaternion(rep: &Report) {
    let [qf, qx, ..] = rep.stats;
    assert!(qf.max_um <= F32_TIP_UM, "f32 tip {} um", qf.max_um);
    assert!(qf.max_dir <= F32_DIR, "f32 dir {}", qf.max_dir);
    assert!(qx.max_um <= FIXED_TIP_UM, "fixed tip {} um", qx.max_um);
    assert!(qx.max_dir <= FIXED_DIR, "fixed dir {}", qx.max_dir);
}

/// Large gravity compliances on every hinge, with the full calibration: the largest a table
/// holds (deflections of several mrad, where first-order gravity would miss by micrometres
/// and 1e-5), and the largest for which the chain leaves the second-order terms out.
#[test]
fn large_gravity_compliance_within_bounds() {
    for g in [
        quatarm::table::limits::GRAVITY,
        quatarm::chain::SECOND_ORDER_GRAVITY,
    ] {
        for signs in [[1.0, 1.0, 1.0], [1.0, -1.0, 1.0]] {
            let mut arm = full_calibration();
            for (k, sign) in [1, 3, 5].into_iter().zip(signs) {
                arm.joints[k].gravity = sign * g;
            }
            let rep = measure(&arm, 20_000, 11, 2, &|_| {}).unwrap();
            check_quaternion(&rep);
        }
    }
}

fn arm_strategy() -> impl Strategy<Value = Arm> {
    let joint = (
        -5e-3..5e-3f64,
        prop::array::uniform2(-5e-3..5e-3f64),
        prop::array::uniform3(-2.0..2.0f64),
        prop::array::uniform4(-1.5e-4..1.5e-4f64),
        1u32..5,
        0.0..5e-8f64,
        0.0..3e-5f64,
    );
    (
        prop::collection::vec(joint, 6),
        prop::array::uniform3(-0.5..0.5f64),
        0.0..2e-5f64,
    )
        .prop_map(|(joints, probe_err, probe_k)| {
            let mut arm = Arm::default6();
            for (k, (j, (dz, tilt, dv, h, order2, g, kappa))) in
                arm.joints.iter_mut().zip(joints).enumerate()
            {
                j.zero_offset = dz;
                j.tilt = tilt;
                j.link_error = dv;
                j.harmonics = vec![
                    Harmonic {
                        order: 1,
                        sin: h[0],
                        cos: h[1],
                    },
                    Harmonic {
                        order: 1 + order2,
                        sin: h[2],
                        cos: h[3],
                    },
                ];
                j.gravity = if k % 2 == 1 { g } else { 0.0 };
                j.thermal = kappa;
            }
            arm.probe.error = probe_err;
            arm.probe.thermal = probe_k;
            arm
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn random_calibrations_within_bounds(arm in arm_strategy(), seed in any::<u64>()) {
        let rep = measure(&arm, 2_000, seed, 1, &|_| {}).unwrap();
        check(&rep);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2_000, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_counts_never_panic(
        counts in prop::collection::vec(any::<u32>(), 0..9),
        temp in any::<i32>(),
    ) {
        let bytes = armcal::tablebuild::build(&full_calibration()).unwrap();
        let t = Table::parse(&bytes).unwrap();
        let qf = Chain::<F32>::new(&t).unwrap();
        let qx = Chain::<Fixed>::new(&t).unwrap();
        let a = qf.eval(&counts, temp);
        let b = qx.eval(&counts, temp);
        let valid = counts.len() == 6
            && counts.iter().all(|&c| c < 1 << 20)
            && (temp - 20_000).unsigned_abs() <= 100_000;
        prop_assert_eq!(a.is_ok(), valid);
        prop_assert_eq!(b.is_ok(), valid);
        if counts.len() != 6 {
            prop_assert!(
                matches!(a, Err(ChainError::JointCount { expected: 6, .. })),
                "joint count error expected"
            );
        }
    }

    #[test]
    fn extreme_readings_stay_in_bounds(seed in any::<u64>()) {
        // Readings at the temperature limits (−80 °C, 120 °C) and random poses.
        use rand::SeedableRng;
        let arm = full_calibration();
        let paths = Paths::new(&arm).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let (counts, _) = random_reading(&mut rng, &arm);
        let mut rep = Report::default();
        for temp in [-80_000, 120_000] {
            armcal::accuracy::one(&arm, &paths, &counts, temp, &mut rep).unwrap();
        }
        check(&rep);
    }
}

#[test]
fn nominal_arm_straight_up_is_exact() {
    let bytes = armcal::tablebuild::build(&Arm::default6()).unwrap();
    let t = Table::parse(&bytes).unwrap();
    let p = Chain::<Fixed>::new(&t)
        .unwrap()
        .eval(&[0; 6], 20_000)
        .unwrap();
    assert_eq!(p.xyz_nm(), [0, 0, 1_500_000_000]);
    assert_eq!(p.dir_e9(), [0, 0, 1_000_000_000]);
    let p = Chain::<F32>::new(&t)
        .unwrap()
        .eval(&[0; 6], 20_000)
        .unwrap();
    assert_eq!(p.xyz_nm(), [0, 0, 1_500_000_000]);
    // Shoulder a quarter turn: everything above swings to −y.
    let p = Chain::<F32>::new(&t)
        .unwrap()
        .eval(&[0, 1 << 18, 0, 0, 0, 0], 20_000)
        .unwrap();
    assert_eq!(p.xyz_nm(), [0, -1_300_000_000, 200_000_000]);
}

#[test]
fn a_table_too_long_for_fixed_point_is_refused_not_wrapped() {
    let mut arm = Arm::default6();
    arm.joints[2].link = [0.0, 0.0, 900.0];
    let bytes = armcal::tablebuild::build(&arm).unwrap();
    let t = Table::parse(&bytes).unwrap();
    assert_eq!(
        Chain::<Fixed>::new(&t).unwrap_err(),
        ChainError::Range { joint: 0 }
    );
    assert!(Chain::<F32>::new(&t).is_ok());
}
