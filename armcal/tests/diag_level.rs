//! The base's tilt against level, measured through a gravity compliance
//! ([`armcal::diagnose::level`]): a tilted base is found with the tilt inside its interval and
//! level rejected; a level base is not rejected.

mod common;

use armcal::data::{Dataset, Kind};
use armcal::diagnose::level::test_level;
use armcal::fit::options::Options;
use armcal::params::Effect;
use armcal::sim;
use quatarm_ref::arm::Arm;

/// A `default-6` arm with its own geometric errors, a shoulder compliance of 1 µrad/mm (MUKCa's
/// Pandas: 1.2–1.3) and its base tilted by `tilt` (rad): 160 tracker points in 4 sessions.
fn arm_data(seed: u64, tilt: [f64; 2]) -> Dataset {
    let mut rng = armcal::rng::rng(seed);
    let mut truth = sim::perturb(&Arm::default6(), 3e-4, 0.3, &mut rng);
    truth.joints[1].gravity = 1e-6;
    truth.joints[0].tilt = tilt;
    let d = sim::simulate(&truth, &sim::Options::new(Kind::Point, 160), &mut rng)
        .unwrap()
        .data;
    common::in_sessions(d, 4, "(simulated arm)")
}

fn opts() -> Options {
    Options {
        design_check: false,
        allow_degenerate: true,
        ..Options::default()
    }
}

#[test]
fn a_tilted_base_is_found_and_level_rejected() {
    let tilt = [0.08, -0.05];
    let d = arm_data(71, tilt);
    let l = test_level(&Arm::default6(), &d, &opts(), &[Effect::Gravity(1)]).unwrap();
    assert_eq!(l.sessions, 4);
    for (c, &truth) in tilt.iter().enumerate() {
        let [lo, hi] = l.interval[c];
        assert!(lo < truth && truth < hi, "angle {c}: {l:#?}");
        assert!((l.tilt[c] - truth).abs() < 0.02, "angle {c}: {l:#?}");
    }
    assert!(l.rejects_level && l.p_value < 0.01, "{l:#?}");
    assert!(l.rms_um[1] < l.rms_um[0], "{l:#?}");
    assert!(l.summary().contains("level rejected"), "{}", l.summary());
}

#[test]
fn a_level_base_is_not_rejected() {
    let d = arm_data(72, [0.0, 0.0]);
    let l = test_level(&Arm::default6(), &d, &opts(), &[Effect::Gravity(1)]).unwrap();
    assert!(!l.rejects_level, "{l:#?}");
    for c in 0..2 {
        let [lo, hi] = l.interval[c];
        assert!(lo < 0.0 && 0.0 < hi, "angle {c}: {l:#?}");
        assert!(hi - lo < 0.1, "angle {c}: not determined: {l:#?}");
    }
}

#[test]
fn too_few_sessions_or_no_gravity_term_are_refused() {
    let d = common::in_sessions(arm_data(73, [0.0, 0.0]), 2, "(two sessions)");
    let e = test_level(&Arm::default6(), &d, &opts(), &[Effect::Gravity(1)]).unwrap_err();
    assert!(e.to_string().contains("2 sessions"), "{e}");
    let d = arm_data(73, [0.0, 0.0]);
    let e = test_level(&Arm::default6(), &d, &opts(), &[]).unwrap_err();
    assert!(e.to_string().contains("gravity"), "{e}");
}
