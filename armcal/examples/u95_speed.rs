//! The host's U95 radius, measured in one run (issue 27):
//!
//! 1. the one-dimensional form (`armcal::uncertainty::u95::u95`) against the nested quadrature
//!    it replaced (`u95::quadrature`), over random covariances from a line (rank 1) through
//!    flat discs to a round ball, rotated, at scales from 1e-12 to 1e2 mm²: the worst relative
//!    error and the speed-up;
//! 2. `armcal calibrate` of 600 simulated `point` rows (truth `data/default-6-full.toml`,
//!    nominal `data/default-6.toml`, the default model), timed as a command;
//! 3. `armcal eval --uncertainty` of `data/recordings/default-6-session.csv` (12,000 rows)
//!    with that calibration, timed as a command.
//!
//! `cargo build --release -p armcal && cargo run --release -p armcal --example u95_speed [N]`
//! (N covariances, default 100,000: the quadrature's radius on the first 2,000 for the
//! speed-up, its probability at the fast radius on all N for the error; about a minute and a
//! half; `ARMCAL` names another binary).

use armcal::uncertainty::u95::{eigenvalues, probability_within, quadrature, u95, LEVEL};

/// Covariances whose radius the quadrature also finds (4.5 ms each).
const SUBSET: usize = 2000;
use nalgebra::{Matrix3, Rotation3, Vector3};
use rand::{Rng, SeedableRng};
use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

/// Eigenvalues (largest 1) of a random shape: each ratio uniform, or log-uniform down to 1e-8,
/// or exactly 0 or 1 (a line, a disc, a ball and their neighbours all drawn).
fn shape(rng: &mut impl Rng) -> [f64; 3] {
    let ratio = |rng: &mut dyn rand::RngCore| match rng.gen_range(0..8) {
        0 => 0.0,
        1 => 1.0,
        2..=4 => rng.gen::<f64>(),
        _ => 10f64.powf(rng.gen_range(-8.0..0.0)),
    };
    let a = ratio(rng);
    let b = ratio(rng);
    [1.0, a, a * b]
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(100_000);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(27);
    let cases: Vec<(Matrix3<f64>, [f64; 3])> = (0..n)
        .map(|_| {
            let l = shape(&mut rng);
            let scale = 10f64.powf(rng.gen_range(-12.0..2.0));
            let axis = Vector3::new(
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
            );
            let r = Rotation3::new(axis * 3.0);
            let lam = l.map(|x| x * scale);
            let s =
                r.matrix() * Matrix3::from_diagonal(&Vector3::from(lam)) * r.matrix().transpose();
            (s, lam)
        })
        .collect();

    // The fast form, timed on every case (eigenvalues included: it is what a caller pays).
    let t = Instant::now();
    let fast: Vec<f64> = cases.iter().map(|(s, _)| u95(s)).collect();
    let fast_s = t.elapsed().as_secs_f64();
    // The quadrature's radius (regula falsi, ~10 quadratures each, 4.5 ms) on the first
    // SUBSET: the speed-up, and the difference of the two radii.
    let m = n.min(SUBSET);
    let t = Instant::now();
    let slow: Vec<f64> = cases[..m]
        .iter()
        .map(|(s, _)| quadrature::radius(eigenvalues(s), LEVEL))
        .collect();
    let slow_s = t.elapsed().as_secs_f64();
    let direct = fast[..m]
        .iter()
        .zip(&slow)
        .map(|(f, q)| (f / q - 1.0).abs())
        .fold(0.0f64, f64::max);
    // Every case: the quadrature's probability at the fast radius r, one quadrature each;
    // its miss of 95 % over r·dP/dr is the relative error of r (to first order, which at
    // 1e-8 is exact enough).
    let (mut worst, mut at) = (0.0f64, 0);
    for (k, ((s, _), r)) in cases.iter().zip(&fast).enumerate() {
        let l = eigenvalues(s);
        let miss = quadrature::probability_within(l, *r) - LEVEL;
        let h = 1e-4;
        let slope = (probability_within(l, r * (1.0 + h)) - probability_within(l, r * (1.0 - h)))
            / (2.0 * h);
        let e = (miss / slope).abs();
        if e > worst || e.is_nan() {
            worst = e;
            at = k;
        }
    }
    println!("U95 radius over {n} random covariances (line to ball, 1e-12..1e2 mm²):");
    println!(
        "  one-dimensional form: {:.2} µs each; nested quadrature: {:.1} µs each (first {m}); \
         speed-up {:.0}×",
        fast_s / n as f64 * 1e6,
        slow_s / m as f64 * 1e6,
        (slow_s / m as f64) / (fast_s / n as f64)
    );
    println!("  worst relative difference of the two radii (first {m}): {direct:.2e}");
    println!(
        "  worst relative error over all {n} (quadrature's P at the fast radius): {worst:.2e} \
         (eigenvalues {:?})",
        cases[at].1
    );

    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let armcal = std::env::var_os("ARMCAL")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target/release/armcal"));
    let dir = std::env::temp_dir().join(format!("u95_speed_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    let run = |what: &str, args: &[&str]| -> f64 {
        let t = Instant::now();
        let out = Command::new(&armcal)
            .args(args)
            .current_dir(&root)
            .output()
            .unwrap_or_else(|e| panic!("{}: {e}", armcal.display()));
        let secs = t.elapsed().as_secs_f64();
        assert!(
            out.status.success(),
            "{what}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        secs
    };
    let data = dir.join("points.csv");
    let cal = dir.join("cal.toml");
    let (data_s, cal_s) = (data.display().to_string(), cal.display().to_string());
    run(
        "simulate",
        &[
            "simulate",
            "--truth",
            "data/default-6-full.toml",
            "--arm",
            "data/default-6.toml",
            "--kind",
            "point",
            "--count",
            "600",
            "--seed",
            "1",
            "-o",
            &data_s,
        ],
    );
    let c = run(
        "calibrate",
        &[
            "calibrate",
            &data_s,
            "--arm",
            "data/default-6.toml",
            "-o",
            &cal_s,
        ],
    );
    println!("armcal calibrate of 600 point rows: {c:.2} s");
    let e = run(
        "eval",
        &[
            "eval",
            "--calib",
            &cal_s,
            "--uncertainty",
            "data/recordings/default-6-session.csv",
        ],
    );
    println!("armcal eval --uncertainty of the 12,000-row recording: {e:.2} s");
    let _ = std::fs::remove_dir_all(&dir);
}
