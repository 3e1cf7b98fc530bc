//! Bad data gets a plain error, never a silent wrong fit.

use armcal::data::{Dataset, Kind, Row};
use armcal::fit::calib::calibrate;
use armcal::fit::design::poses::{limits, random_pose};
use armcal::fit::error::CalibError;
use armcal::fit::options::Options;
use armcal::rng::rng;
use armcal::sim::{self, perturb, simulate};
use quatarm_ref::arm::Arm;
use quatarm_ref::forward;

fn truth() -> Arm {
    perturb(&Arm::default6(), 3e-4, 0.3, &mut rng(5))
}

#[test]
fn too_few_rows_for_the_parameters() {
    let data = simulate(&truth(), &sim::Options::new(Kind::Point, 8), &mut rng(6))
        .unwrap()
        .data;
    let e = calibrate(&Arm::default6(), &data, &Options::default()).unwrap_err();
    match &e {
        CalibError::TooFewRows {
            equations,
            parameters,
            ..
        } => {
            assert_eq!(*equations, 24);
            assert_eq!(*parameters, 27, "the identifiable count of good point data");
        }
        other => panic!("{other}"),
    }
    assert!(
        e.to_string().starts_with("too few rows for the parameters"),
        "{e}"
    );
}

/// Point rows from poses where joint 3 never turns.
fn joint3_still(n: usize) -> Dataset {
    let t = truth();
    let lim = limits(&t);
    let mut r = rng(7);
    let rows = (0..n)
        .map(|_| {
            let mut th = random_pose(&lim, &mut r);
            th[2] = 0.4;
            let p = forward::forward(&t, &th, 20.0).p;
            Row {
                kind: Kind::Point,
                group: 1,
                theta: th,
                xyz: Some([p.x, p.y, p.z]),
                end: None,
                length_mm: None,
                sphere: None,
                temp_c: 20.0,
                probe: None,
                line: 0,
                file: None,
            }
        })
        .collect();
    Dataset::from_rows(rows, 6, false, "still.csv").unwrap()
}

#[test]
fn a_degenerate_pose_set_is_refused_and_says_why() {
    let data = joint3_still(300);
    let e = calibrate(&Arm::default6(), &data, &Options::default()).unwrap_err();
    let CalibError::Degenerate { lost, hint } = &e else {
        panic!("{e}")
    };
    assert!(!lost.is_empty());
    assert!(hint.contains("joint 3 hardly moves"), "{hint}");
    assert!(e.to_string().starts_with("degenerate pose set"), "{e}");
    // On request it fits what the poses determine, and reports the rest as held.
    let opts = Options {
        allow_degenerate: true,
        ..Options::default()
    };
    let fit = calibrate(&Arm::default6(), &data, &opts).unwrap();
    assert!(fit.ident.kept.len() < 27);
    assert!(
        fit.sigma_mm < 1e-3,
        "noise-free data fit to rounding: {}",
        fit.sigma_mm
    );
}

#[test]
fn a_fit_that_does_not_converge_says_so() {
    let data = simulate(&truth(), &sim::Options::new(Kind::Point, 300), &mut rng(8))
        .unwrap()
        .data;
    // A start far from the data (zero offsets off by 0.2 rad), with too few iterations.
    let mut start = Arm::default6();
    for j in &mut start.joints {
        j.zero_offset = 0.2;
    }
    let mut opts = Options::default();
    opts.lm.max_iterations = 3;
    let e = calibrate(&start, &data, &opts).unwrap_err();
    assert!(
        matches!(e, CalibError::NotConverged { iterations: 3, .. }),
        "{e}"
    );
    assert!(e.to_string().starts_with("the fit did not converge"), "{e}");
    // Given the iterations, the same bad start converges to the truth's fit.
    let fit = calibrate(&start, &data, &Options::default()).unwrap();
    assert!(fit.sigma_mm < 0.006, "{}", fit.sigma_mm);
}

#[test]
fn a_bad_start_still_converges() {
    // Link errors of 5 mm and zero offsets of 0.05 rad in the start arm.
    let t = truth();
    let data = simulate(&t, &sim::Options::new(Kind::Point, 600), &mut rng(9))
        .unwrap()
        .data;
    let mut start = Arm::default6();
    for (k, j) in start.joints.iter_mut().enumerate() {
        j.zero_offset = if k % 2 == 0 { 0.05 } else { -0.05 };
        j.link_error = [5.0, -5.0, 5.0];
    }
    let fit = calibrate(&start, &data, &Options::default()).unwrap();
    assert!(fit.sigma_mm < 0.006, "{}", fit.sigma_mm);
}
