//! Calibration benchmark: prints the numbers of `docs/results/calibration.md`.
//!
//! `cargo bench -p armcal --bench calibration [-- speed|roundtrip|mukca …]` (all by default).
//! Single-threaded throughout: the times are one core's.

use armcal::data::{Dataset, Kind, Row};
use armcal::fit::calib::calibrate;
use armcal::fit::design::poses::{limits, random_pose};
use armcal::fit::options::Options;
use armcal::fit::priors::Ridge;
use armcal::fit::residuals::compare_aligned;
use armcal::mukca;
use armcal::rng::rng;
use armcal::sim::{self, perturb, simulate};
use quatarm_ref::arm::Arm;
use std::time::{Duration, Instant};

fn fresh_poses(arm: &Arm, n: usize, seed: u64) -> Vec<(Vec<f64>, f64)> {
    let lim = limits(arm);
    let mut r = rng(seed);
    (0..n).map(|_| (random_pose(&lim, &mut r), 20.0)).collect()
}

fn point_data(truth: &Arm, count: usize, seed: u64) -> Dataset {
    simulate(
        truth,
        &sim::Options::new(Kind::Point, count),
        &mut rng(seed),
    )
    .expect("simulate")
    .data
}

fn spat_and_length(truth: &Arm, spat: usize, length: usize, seed: u64) -> Dataset {
    let s = simulate(truth, &sim::Options::new(Kind::Spat, spat), &mut rng(seed)).expect("spat");
    let l = simulate(
        truth,
        &sim::Options::new(Kind::Length, length),
        &mut rng(seed + 1),
    )
    .expect("length");
    let mut rows = s.data.rows;
    rows.extend(l.data.rows.into_iter().map(|r| Row {
        group: r.group + 1000,
        ..r
    }));
    Dataset::from_rows(rows, truth.dof(), false, "(simulated)").expect("rows")
}

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

fn speed() {
    println!("## speed (one core)");
    let nominal = Arm::default6();
    let truth = perturb(&nominal, 3e-4, 0.3, &mut rng(11));
    let data = point_data(&truth, 600, 12);
    let opts = Options::default();
    let mut times = Vec::new();
    let mut iters = 0;
    for _ in 0..31 {
        let t = Instant::now();
        let fit = calibrate(&nominal, &data, &opts).expect("fit");
        times.push(t.elapsed());
        iters = fit.iterations;
    }
    println!(
        "600 point rows, geometric + instrument frame (45 unknowns, 27 identifiable), full pipeline \
         (identifiability, design check, fit, statistical check, uncertainties): median {:.1} ms over 31 runs ({iters} iterations)",
        median(times).as_secs_f64() * 1e3
    );
    let lean = Options {
        design_check: false,
        ..Options::default()
    };
    let times: Vec<Duration> = (0..31)
        .map(|_| {
            let t = Instant::now();
            calibrate(&nominal, &data, &lean).expect("fit");
            t.elapsed()
        })
        .collect();
    println!(
        "  the same without the design check: median {:.1} ms",
        median(times).as_secs_f64() * 1e3
    );
    let big = point_data(&truth, 100_000, 13);
    let t = Instant::now();
    let fit = calibrate(&nominal, &big, &opts).expect("fit");
    println!(
        "100,000 point rows: {:.2} s ({} iterations, noise estimate {:.2} µm)",
        t.elapsed().as_secs_f64(),
        fit.iterations,
        fit.sigma_mm * 1e3
    );
}

fn roundtrip() {
    println!(
        "## round trip (600 readings, 5 µm noise per axis; 5,000 fresh poses, one rigid alignment)"
    );
    let nominal = Arm::default6();
    let poses = fresh_poses(&nominal, 5000, 13);
    for seed in [11u64, 101, 202, 303, 404] {
        let truth = perturb(&nominal, 3e-4, 0.3, &mut rng(seed));
        let data = point_data(&truth, 600, seed + 1);
        let fit = calibrate(&nominal, &data, &Options::default()).expect("fit");
        let before = compare_aligned(&nominal, &truth, &poses);
        let after = compare_aligned(&fit.arm, &truth, &poses);
        let sl = spat_and_length(&truth, 400, 200, seed + 2);
        let fit2 = calibrate(&nominal, &sl, &Options::default()).expect("fit");
        let after2 = compare_aligned(&fit2.arm, &truth, &poses);
        println!(
            "seed {seed:>3}: nominal {:>7.1} µm RMS | point: {:.2} µm RMS (max {:.2}), {} identifiable, {} held | spat 400 + length 200: {:.2} µm RMS (max {:.2}), {} identifiable",
            before.rms_um,
            after.rms_um,
            after.max_um,
            fit.ident.kept.len(),
            fit.ident.fixed.len(),
            after2.rms_um,
            after2.max_um,
            fit2.ident.kept.len()
        );
    }
    // A 7-axis arm (the MUKCa Panda's nominal model) with the same kind of errors.
    let dir = mukca::default_dir();
    let panda = mukca::load(&dir, "panda_2").expect("panda").arm;
    let poses = fresh_poses(&panda, 5000, 17);
    let truth = perturb(&panda, 3e-4, 0.3, &mut rng(71));
    let data = point_data(&truth, 600, 72);
    let fit = calibrate(&panda, &data, &Options::default()).expect("fit");
    let after = compare_aligned(&fit.arm, &truth, &poses);
    println!(
        "7-axis (Panda nominal): point {:.2} µm RMS (max {:.2}), {} of {} unknowns identifiable",
        after.rms_um,
        after.max_um,
        fit.ident.kept.len(),
        fit.params.len()
    );
}

fn mukca_tables() {
    let dir = mukca::default_dir();
    let modes = [
        ("least squares (default)", mukca::options(None)),
        (
            "MUKCa's ridge, lambda 1e-4 (--ridge)",
            mukca::options(Some(Ridge::MUKCA)),
        ),
    ];
    println!("## MUKCa, the authors' protocol (panda_2: fit front_center, score the other sessions but high)");
    for (label, opts) in &modes {
        match mukca::authors_protocol(&dir, opts) {
            Ok(t) => {
                println!(
                    "{label}: train {:.4} -> {:.4} mm (authors 8.28 -> 0.168); test {:.4} -> {:.4} mm (authors 7.79 -> 0.347)",
                    t.train_before, t.train_after, t.test_before, t.test_after
                );
                for (s, b, a) in &t.per_session {
                    println!("  {s:<14} {b:>7.3} -> {a:.3}");
                }
            }
            Err(e) => println!("{label}: failed: {e}"),
        }
    }
    println!("## MUKCa, the ridge's lambda against the test figure (panda_2 protocol; other units: the same one-session protocol)");
    let others: Vec<mukca::Unit> = ["panda_3", "panda_3_bis", "panda_4", "panda_6", "panda_7"]
        .iter()
        .map(|n| mukca::load(&dir, n).expect("unit"))
        .collect();
    let plain: Vec<f64> = others
        .iter()
        .map(|u| one_session(u, &mukca::options(None)).1)
        .collect();
    for lambda in [1e-5, 3e-5, 5e-5, 1e-4, 2e-4] {
        let opts = mukca::options(Some(Ridge { lambda }));
        let t = mukca::authors_protocol(&dir, &opts).expect("protocol");
        let rel: Vec<f64> = others
            .iter()
            .zip(&plain)
            .map(|(u, p)| one_session(u, &opts).1 / p)
            .collect();
        println!(
            "lambda {lambda:.0e}: panda_2 train {:.4} test {:.4} | other Pandas, test relative to least squares: mean {:.4} ({})",
            t.train_after,
            t.test_after,
            rel.iter().sum::<f64>() / rel.len() as f64,
            rel.iter().map(|r| format!("{r:.3}")).collect::<Vec<_>>().join(" ")
        );
    }
    println!("## MUKCa, one session at a time (fit one session, score all the others; mean over the sessions fitted)");
    println!("| unit | sessions | nominal (mm) | least squares (mm) | ridge (mm) |");
    println!("|---|---|---|---|---|");
    for (name, _) in mukca::unit_names(&dir).expect("units") {
        let unit = mukca::load(&dir, &name).expect("unit");
        if unit.groups().len() < 2 {
            continue;
        }
        let (b, a, k) = one_session(&unit, &modes[0].1);
        let (_, r, _) = one_session(&unit, &modes[1].1);
        println!("| {name} | {k} | {b:.3} | {a:.3} | {r:.3} |");
    }
    for (label, opts) in &modes {
        println!("## MUKCa, leave one session out, {label} (fit all other sessions, score the one left out)");
        println!("| unit | sessions | nominal (mm) | calibrated (mm) | per session (nominal -> calibrated) |");
        println!("|---|---|---|---|---|");
        for (name, _) in mukca::unit_names(&dir).expect("units") {
            let unit = mukca::load(&dir, &name).expect("unit");
            let l = mukca::loso(&unit, opts);
            if l.sessions.is_empty() {
                println!(
                    "| {name} | 1 | {:.3} | – | one session only: nothing to leave out |",
                    mukca::score(&unit.arm, &unit, &unit.groups())
                );
                continue;
            }
            let per: Vec<String> = l
                .sessions
                .iter()
                .map(|(s, r)| match r {
                    Ok((b, a)) => format!("{s} {b:.2}→{a:.3}"),
                    Err(e) => format!("{s}: {e}"),
                })
                .collect();
            println!(
                "| {name} | {} | {:.3} | {:.3} | {} |",
                l.sessions.len(),
                l.mean_before,
                l.mean_after,
                per.join(", ")
            );
        }
    }
}

/// Fits each session of a unit alone and scores the unit's other sessions (panda_2 without
/// `high`, as the authors): (mean nominal, mean calibrated) over the sessions fitted.
fn one_session(unit: &mukca::Unit, opts: &Options) -> (f64, f64, usize) {
    let mut groups = unit.groups();
    if unit.name == "panda_2" {
        groups.retain(|g| unit.sessions.get(g).map(String::as_str) != Some("high"));
    }
    let (mut b, mut a, mut k) = (0.0, 0.0, 0);
    for &g in &groups {
        let test: Vec<i64> = groups.iter().copied().filter(|x| *x != g).collect();
        if let Ok((t, _)) = mukca::trial(unit, &[g], &test, opts) {
            b += t.test_before;
            a += t.test_after;
            k += 1;
        }
    }
    (b / k as f64, a / k as f64, k)
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let want = |s: &str| args.is_empty() || args.iter().any(|a| a == s);
    if want("speed") {
        speed();
    }
    if want("roundtrip") {
        roundtrip();
    }
    if want("mukca") {
        mukca_tables();
    }
}
