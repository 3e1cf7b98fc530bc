//! Round trips through the virtual arm: simulate an arm with random geometric errors, calibrate
//! from its data alone, and compare the calibrated model with the truth on fresh poses.

use armcal::data::{Dataset, Kind};
use armcal::fit::calib::calibrate;
use armcal::fit::design::poses::{limits, random_pose};
use armcal::fit::finish::Fit;
use armcal::fit::options::Options;
use armcal::fit::residuals::compare_aligned;
use armcal::params::ParamExt as _;
use armcal::rng::rng;
use armcal::sim::{self, perturb, simulate};
use quatarm_ref::arm::Arm;

fn fresh_poses(arm: &Arm, n: usize, seed: u64) -> Vec<(Vec<f64>, f64)> {
    let lim = limits(arm);
    let mut r = rng(seed);
    (0..n).map(|_| (random_pose(&lim, &mut r), 20.0)).collect()
}

fn show(fit: &Fit, nominal: &Arm) {
    println!(
        "iterations {} sigma {:.2} µm kept {} fixed {} cond {:.1} time {:?}",
        fit.iterations,
        fit.sigma_mm * 1e3,
        fit.ident.kept.len(),
        fit.ident.fixed.len(),
        fit.ident.condition_number,
        fit.elapsed
    );
    for f in &fit.ident.fixed {
        let by: Vec<String> = f
            .absorbed_by
            .iter()
            .map(|(k, c)| format!("{} ×{:.4}", fit.params[*k].describe(nominal), c))
            .collect();
        println!(
            "  held {} ({:?}): {}",
            fit.params[f.index].describe(nominal),
            f.why,
            by.join(", ")
        );
    }
}

/// Every identifiable combination of arm parameters against the truth's: `reference` is the
/// same calibration on noise-free data of the truth, i.e. the values of the fitted unknowns
/// that reproduce the truth exactly. Returns the largest |estimate − truth| / uncertainty.
fn worst_z(fit: &Fit, reference: &Fit, nominal: &Arm) -> f64 {
    assert_eq!(fit.ident.kept, reference.ident.kept);
    let mut worst: f64 = 0.0;
    for &k in &fit.ident.kept {
        if fit.params[k].is_frame() {
            continue;
        }
        let want = reference.values[k];
        let u = fit.uncertainty[k].unwrap();
        let z = (fit.values[k] - want) / u;
        println!(
            "  {:<40} {:>13.6e} truth {:>13.6e} ± {:.2e}  z {:+.2}",
            fit.params[k].describe(nominal),
            fit.values[k],
            want,
            u,
            z
        );
        worst = worst.max(z.abs());
    }
    worst
}

fn check(nominal: &Arm, truth: &Arm, data: &Dataset, clean: &Dataset) -> (f64, f64) {
    let fit = calibrate(nominal, data, &Options::default()).unwrap();
    show(&fit, nominal);
    let reference = calibrate(nominal, clean, &Options::default()).unwrap();
    println!("reference fit: sigma {:.3} µm", reference.sigma_mm * 1e3);
    let poses = fresh_poses(nominal, 5000, 13);
    let before = compare_aligned(nominal, truth, &poses);
    let after = compare_aligned(&fit.arm, truth, &poses);
    println!("before {before:?}\nafter {after:?}");
    (after.rms_um, worst_z(&fit, &reference, nominal))
}

fn spat_and_length(truth: &Arm, spat: usize, length: usize, noise_mm: f64, seed: u64) -> Dataset {
    let mut o = sim::Options::new(Kind::Spat, spat);
    o.noise_mm = noise_mm;
    let s = simulate(truth, &o, &mut rng(seed)).unwrap();
    let mut o = sim::Options::new(Kind::Length, length);
    o.noise_mm = noise_mm;
    let l = simulate(truth, &o, &mut rng(seed + 1)).unwrap();
    let mut rows = s.data.rows.clone();
    rows.extend(l.data.rows.iter().map(|r| armcal::data::Row {
        group: r.group + 1000,
        ..r.clone()
    }));
    Dataset::from_rows(rows, truth.dof(), false, "(test)").unwrap()
}

#[test]
fn point_round_trip() {
    let nominal = Arm::default6();
    let truth = perturb(&nominal, 3e-4, 0.3, &mut rng(11));
    let sim = simulate(&truth, &sim::Options::new(Kind::Point, 600), &mut rng(12)).unwrap();
    let mut o = sim::Options::new(Kind::Point, 3000);
    o.noise_mm = 0.0;
    let clean = simulate(&truth, &o, &mut rng(14)).unwrap();
    let (rms, z) = check(&nominal, &truth, &sim.data, &clean.data);
    assert!(rms <= 2.5, "{rms}");
    assert!(z <= 4.0, "{z}");
}

#[test]
fn spat_and_length_round_trip() {
    let nominal = Arm::default6();
    let truth = perturb(&nominal, 3e-4, 0.3, &mut rng(21));
    let data = spat_and_length(&truth, 400, 200, 0.005, 22);
    let clean = spat_and_length(&truth, 1600, 800, 0.0, 32);
    let (rms, z) = check(&nominal, &truth, &data, &clean);
    assert!(rms <= 2.5, "{rms}");
    assert!(z <= 4.0, "{z}");
}

#[test]
fn seven_axis_round_trip() {
    // The MUKCa Panda's nominal model: every axis z, the D-H twists in `tilt`.
    let dir = armcal::mukca::default_dir();
    let nominal = armcal::mukca::load(&dir, "panda_2").unwrap().arm;
    let truth = perturb(&nominal, 3e-4, 0.3, &mut rng(71));
    let data = simulate(&truth, &sim::Options::new(Kind::Point, 600), &mut rng(72))
        .unwrap()
        .data;
    let fit = calibrate(&nominal, &data, &Options::default()).unwrap();
    show(&fit, &nominal);
    let after = compare_aligned(&fit.arm, &truth, &fresh_poses(&nominal, 5000, 17));
    println!("after {after:?}");
    assert!(after.rms_um <= 2.5, "{after:?}");
    // The nominal twists stay in `tilt`; only the identified error is added to them.
    for (a, b) in fit.arm.joints.iter().zip(&nominal.joints) {
        assert_eq!(a.link, b.link);
        for c in 0..2 {
            assert!((a.tilt[c] - b.tilt[c]).abs() < 0.01);
        }
    }
}

fn spat_and_sphere(truth: &Arm, spat: usize, sphere: usize, noise_mm: f64, seed: u64) -> Dataset {
    let mut o = sim::Options::new(Kind::Spat, spat);
    o.noise_mm = noise_mm;
    let s = simulate(truth, &o, &mut rng(seed)).unwrap();
    let mut o = sim::Options::new(Kind::Sphere, sphere);
    o.noise_mm = noise_mm;
    o.group_size = 25;
    o.articulations = Some(5);
    let p = simulate(truth, &o, &mut rng(seed + 1)).unwrap();
    let mut rows = s.data.rows.clone();
    rows.extend(p.data.rows.iter().map(|r| armcal::data::Row {
        group: r.group + 1000,
        ..r.clone()
    }));
    Dataset::from_rows(rows, truth.dof(), false, "(test)").unwrap()
}

/// A test sphere of known diameter is a spat cone with a known radius: spat and sphere data
/// alone calibrate the arm (the sphere's diameter fixes the scale that spat rows cannot), and
/// every identifiable combination lands within its stated uncertainty of the truth's.
#[test]
fn spat_and_sphere_round_trip() {
    let nominal = Arm::default6();
    let truth = perturb(&nominal, 3e-4, 0.3, &mut rng(41));
    let data = spat_and_sphere(&truth, 400, 400, 0.005, 42);
    let clean = spat_and_sphere(&truth, 1600, 1600, 0.0, 52);
    let poses = fresh_poses(&nominal, 5000, 13);
    let before = compare_aligned(&nominal, &truth, &poses).rms_um;
    let (rms, z) = check(&nominal, &truth, &data, &clean);
    println!("nominal {before:.1} µm -> calibrated {rms:.2} µm");
    assert!(rms <= before / 20.0, "{rms} vs {before}");
    assert!(z <= 4.0, "{z}");
}
