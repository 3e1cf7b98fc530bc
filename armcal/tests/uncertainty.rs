//! The uncertainty of every point (issue 11): coverage on simulated arms, first order against
//! Monte Carlo, and the commands end to end.

mod common;

use armcal::fit::design::poses::{limits, random_pose};
use armcal::uncertainty::coverage::{self, Setup};
use armcal::uncertainty::{montecarlo, propagate, u95};
use common::{armcal, armcal_ok, workdir, write_truth};

/// A looser run of the benchmark (`benches/coverage.rs`): 2 calibrations × 500 readings. The
/// binomial spread of 1,000 readings at 95 % is ±0.7 %; the bound leaves room for what one
/// calibration's luck does to all its readings.
#[test]
fn coverage_of_points_and_distances_is_about_95_percent() {
    let setup = Setup {
        calibrations: 2,
        readings: 500,
        ..Setup::BENCHMARK
    };
    let (_, total) = coverage::run(&setup).unwrap();
    assert_eq!(total.points, 1000);
    for (what, f) in [("sphere", total.sphere()), ("distance", total.distance())] {
        assert!((0.88..=0.99).contains(&f), "{what} coverage {f}");
    }
}

/// With a budget ten times too small the same check fails: the coverage test can tell.
#[test]
fn a_too_small_budget_is_caught() {
    let setup = Setup {
        calibrations: 1,
        readings: 300,
        ..Setup::BENCHMARK
    };
    let mut c = coverage::calibrated(&setup, 0).unwrap();
    c.budget.encoder_counts.iter_mut().for_each(|e| *e *= 0.1);
    c.budget.cov *= 0.01;
    let t = coverage::fresh(&c.truth, &c.arm, &c.budget, &setup, &mut c.rng);
    assert!(t.sphere() < 0.5, "{}", t.sphere());
}

#[test]
fn first_order_and_monte_carlo_agree_on_u95() {
    let setup = Setup::BENCHMARK;
    let mut c = coverage::calibrated(&setup, 3).unwrap();
    let root = montecarlo::sqrt_cov(&c.budget.cov);
    let lim = limits(&c.arm);
    for _ in 0..6 {
        let th = random_pose(&lim, &mut c.rng);
        let (p, s) = propagate::point(&c.arm, 0, &c.budget, &th, 20.0);
        let fo = u95::u95(&s);
        let mc = montecarlo::point(&c.arm, 0, &c.budget, &root, &th, 20.0, 40_000, &mut c.rng);
        assert!((mc.p - p).norm() < 1e-12);
        assert!((mc.u95 / fo - 1.0).abs() < 0.03, "FO {fo} MC {}", mc.u95);
        for k in 0..3 {
            let r = mc.cov[(k, k)] / s[(k, k)];
            assert!((r - 1.0).abs() < 0.05, "variance {k}: MC/FO {r}");
        }
    }
}

/// `calibrate` writes the budget, `eval --uncertainty` reads it by both methods, and a file
/// without one is refused rather than given a zero uncertainty.
#[test]
fn calibrate_writes_the_budget_and_eval_uses_it() {
    let d = workdir("cli");
    let truth = armcal::sim::perturb(
        &quatarm_ref::Arm::default6(),
        3e-4,
        0.3,
        &mut armcal::rng::rng(5),
    );
    write_truth(&d, &truth);
    #[rustfmt::skip]
    armcal_ok(&["simulate", "--truth", "truth.toml", "--kind", "point", "--count", "300",
        "--seed", "2", "--encoder-noise-counts", "1", "-o", "p.csv"], &d);
    let o = armcal_ok(
        &[
            "calibrate",
            "p.csv",
            "-o",
            "cal.toml",
            "--encoder-counts",
            "1.04",
            "--folds",
            "0",
        ],
        &d,
    );
    let report = String::from_utf8_lossy(&o.stdout);
    assert!(report.contains("uncertainty budget"), "{report}");
    assert!(report.contains("probing: 0, assumed"), "{report}");
    let parsed = quatarm_ref::calfile::read(&d.join("cal.toml")).unwrap();
    let u = parsed.uncertainty.unwrap();
    assert!(!u.parameters.is_empty());
    assert_eq!(u.encoder_counts, vec![1.04; 6]);
    std::fs::write(
        d.join("q.csv"),
        "j1,j2,j3,j4,j5,j6\n0.3,0.5,-0.4,1.0,0.2,0.7\n",
    )
    .unwrap();
    let mut u95s = Vec::new();
    for method in ["first-order", "monte-carlo"] {
        #[rustfmt::skip]
        let o = armcal_ok(&["eval", "--calib", "cal.toml", "--uncertainty", "--method", method,
            "--draws", "20000", "q.csv"], &d);
        let out = String::from_utf8_lossy(&o.stdout).to_string();
        let mut lines = out.lines();
        assert_eq!(
            lines.next(),
            Some("x,y,z,nx,ny,nz,cxx,cyy,czz,cxy,cxz,cyz,U95")
        );
        let row: Vec<f64> = lines
            .next()
            .unwrap()
            .split(',')
            .map(|v| v.parse().unwrap())
            .collect();
        assert_eq!(row.len(), 13);
        u95s.push(row[12]);
    }
    assert!((u95s[1] / u95s[0] - 1.0).abs() < 0.03, "{u95s:?}");
    // 1 count at 2^20 per turn is 6 µrad: over a metre of lever, several µm per joint.
    assert!((0.005..0.05).contains(&u95s[0]), "{u95s:?}");
    let o = armcal(
        &["eval", "--calib", "truth.toml", "--uncertainty", "q.csv"],
        &d,
    );
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("no [uncertainty]"));
}

/// Length data with 5 µm seating noise and 1 count of encoder noise: the probing term the
/// budget estimates from the bar ends' scatter is the seating noise (the reading's own part
/// taken out), and without such rows it is assumed, not invented.
#[test]
fn probing_is_estimated_from_the_scatter_of_repeated_probings() {
    use armcal::data::Kind;
    use armcal::uncertainty::estimate::{from_fit, Settings};
    let nominal = quatarm_ref::Arm::default6();
    let mut rng = armcal::rng::rng(8);
    let truth = armcal::sim::perturb(&nominal, 3e-4, 0.3, &mut rng);
    let mut o = armcal::sim::Options::new(Kind::Length, 600);
    o.encoder_noise_counts = 1.0;
    let data = armcal::sim::simulate(&truth, &o, &mut rng).unwrap().data;
    let fit = armcal::fit::calib::calibrate(&nominal, &data, &Default::default()).unwrap();
    let s = Settings {
        encoder_counts: coverage::reading_sd(1.0),
        ..Settings::default()
    };
    let est = from_fit(&fit, &data, None, 0.0, &s).unwrap();
    let p = est.budget.probing_mm;
    assert!((p - 0.005).abs() < 0.0005, "probing {p}");
    assert!(est
        .notes
        .iter()
        .any(|n| n.contains("estimated from the scatter")));
    // Counted as quantisation alone, the encoder noise lands in the probing term instead.
    let est = from_fit(&fit, &data, None, 0.0, &Settings::default()).unwrap();
    assert!(
        est.budget.probing_mm > p + 0.0005,
        "{}",
        est.budget.probing_mm
    );
}
