//! Coverage benchmark of the uncertainty budget (issue 11): calibrations of random simulated
//! arms (600 `point` readings, 5 µm instrument noise, 1 count of encoder noise), each read
//! afresh 5,000 times with its own noise and quantisation; the fraction of readings whose true
//! point is inside the predicted 95 % region (after one rigid alignment per calibration), and
//! of reading pairs whose true distance is within the distance's 95 % interval. Then first
//! order against Monte Carlo on U95.
//!
//! `cargo bench -p armcal --bench coverage` (release), or, reusing the test profile's build,
//! `cargo test --profile test -p armcal --bench coverage`. Arguments: calibrations, readings.

use armcal::uncertainty::coverage::{self, Setup};
use armcal::uncertainty::{montecarlo, propagate, u95};
use std::time::Instant;

fn main() {
    let mut setup = Setup::BENCHMARK;
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    if let Some(&c) = args.first() {
        setup.calibrations = c;
    }
    if let Some(&r) = args.get(1) {
        setup.readings = r;
    }
    let t0 = Instant::now();
    println!(
        "coverage: {} calibrations × {} fresh readings; {} point rows, {} µm instrument noise, \
         {} count encoder noise",
        setup.calibrations,
        setup.readings,
        setup.point_rows,
        setup.noise_mm * 1e3,
        setup.encoder_noise_counts
    );
    println!("  trial  sphere(U95)  ellipsoid  distance  mean U95 µm  mean |error| µm");
    let mut total = coverage::Tally::default();
    for k in 0..setup.calibrations {
        let t = match coverage::trial(&setup, k) {
            Ok(t) => t,
            Err(e) => {
                println!("  {k:>5}  calibration failed: {e}");
                continue;
            }
        };
        println!(
            "  {k:>5}  {:>11.4}  {:>9.4}  {:>8.4}  {:>11.2}  {:>15.2}",
            t.sphere(),
            t.ellipsoid(),
            t.distance(),
            t.u95_sum / t.points as f64 * 1e3,
            t.error_sum / t.points as f64 * 1e3
        );
        for (a, b) in [
            (&mut total.points, t.points),
            (&mut total.in_sphere, t.in_sphere),
            (&mut total.in_ellipsoid, t.in_ellipsoid),
            (&mut total.pairs, t.pairs),
            (&mut total.in_distance, t.in_distance),
        ] {
            *a += b;
        }
    }
    println!(
        "  all    {:>11.4}  {:>9.4}  {:>8.4}   ({} readings, {} pairs; ideal 0.95)",
        total.sphere(),
        total.ellipsoid(),
        total.distance(),
        total.points,
        total.pairs
    );
    first_order_against_monte_carlo(&setup);
    println!("  took {:.1} s", t0.elapsed().as_secs_f64());
}

/// U95 by both methods at 100 poses of the first calibration, 40,000 draws each (the 95th
/// percentile of 40,000 draws has a relative standard error of about 0.3 %).
fn first_order_against_monte_carlo(setup: &Setup) {
    let Ok(mut c) = coverage::calibrated(setup, 0) else {
        println!("  first order vs Monte Carlo: calibration failed");
        return;
    };
    let root = montecarlo::sqrt_cov(&c.budget.cov);
    let lim = armcal::sim::limits(&c.arm);
    let mut worst: f64 = 0.0;
    let mut sum = 0.0;
    let n = 100;
    for _ in 0..n {
        let th = armcal::sim::random_pose(&lim, &mut c.rng);
        let (_, s) = propagate::point(&c.arm, &c.budget, &th, 20.0);
        let fo = u95::u95(&s);
        let mc = montecarlo::point(&c.arm, &c.budget, &root, &th, 20.0, 40_000, &mut c.rng).u95;
        let rel = mc / fo - 1.0;
        worst = worst.max(rel.abs());
        sum += rel;
    }
    println!(
        "  first order vs Monte Carlo U95 at {n} poses (40,000 draws each): mean MC/FO − 1 = \
         {:+.2} %, largest |difference| {:.2} %",
        sum / n as f64 * 100.0,
        worst * 100.0
    );
}
