//! The fleet prior (`armcal::fit::fleet_prior`, `armcal calibrate --fleet-prior`): a design whose
//! units share a systematic error and scatter about it; five units calibrated from plenty of
//! data give the prior of the sixth, calibrated from few rows.

mod common;

use armcal::data::{Dataset, Kind};
use armcal::fit::calib;
use armcal::fit::design::poses::{limits, random_pose};
use armcal::fit::fleet_prior::{self, Fallback};
use armcal::fit::options::Options;
use armcal::fit::priors;
use armcal::fit::priors::Prior;
use armcal::fit::residuals::compare_aligned;
use armcal::params::ParamExt as _;
use armcal::rng::rng;
use armcal::sim::{self, perturb, simulate};
use quatarm_ref::arm::{Arm, Axis};
use quatarm_ref::calfile;
use std::path::{Path, PathBuf};

/// The design's shared error (every unit has it): 1 mrad and 0.5 mm per component.
fn design(nominal: &Arm) -> Arm {
    perturb(nominal, 1e-3, 0.5, &mut rng(7))
}

/// Unit `k` of the design: the shared error plus its own scatter (20 µrad, 10 µm).
fn unit(nominal: &Arm, k: u64) -> Arm {
    perturb(&design(nominal), 2e-5, 0.01, &mut rng(100 + k))
}

fn points(truth: &Arm, count: usize, noise_mm: f64, seed: u64) -> Dataset {
    let mut o = sim::Options::new(Kind::Point, count);
    o.noise_mm = noise_mm;
    simulate(truth, &o, &mut rng(seed)).unwrap().data
}

/// The fleet: units 1–5 calibrated from 400 point rows each, their files written to `dir`.
fn fleet_files(nominal: &Arm, dir: &Path) -> Vec<PathBuf> {
    (1..=5)
        .map(|k| {
            let data = points(&unit(nominal, k), 400, 0.005, 200 + k);
            let fit = calib::calibrate(nominal, &data, &Options::default()).unwrap();
            let path = dir.join(format!("unit{k}.toml"));
            std::fs::write(&path, calfile::write(&fit.arm, &["fleet unit"])).unwrap();
            path
        })
        .collect()
}

/// RMS distance (µm) of a model's ball from the truth's on fresh poses, after alignment.
fn fresh_error(model: &Arm, truth: &Arm) -> f64 {
    let lim = limits(truth);
    let mut r = rng(999);
    let poses: Vec<(Vec<f64>, f64)> = (0..2000)
        .map(|_| (random_pose(&lim, &mut r), 20.0))
        .collect();
    compare_aligned(model, truth, &poses).rms_um
}

fn with_prior(unknowns: Vec<(armcal::params::Param, priors::Gaussian)>) -> Options {
    Options {
        prior: Some(Prior {
            unknowns,
            ..Prior::default()
        }),
        ..Options::default()
    }
}

#[test]
fn the_fleet_prior_calibrates_a_unit_from_few_rows_better() {
    let nominal = Arm::default6();
    let dir = common::workdir("few-rows");
    let files = fleet_files(&nominal, &dir);
    let fleet = fleet_prior::from_files(&nominal, &files).unwrap();
    assert_eq!(fleet.units.len(), 5);
    // What point data cannot separate is held in every unit's calibration: no spread, no
    // Gaussian (the calibration's own rule applies to it).
    let held = fleet
        .entries
        .iter()
        .find(|e| e.key == "joint[1].zero_offset")
        .unwrap();
    assert_eq!(
        (held.units, held.fallback),
        (0, Some(Fallback::TooFewUnits))
    );
    let gaussians = fleet.gaussians();
    assert!(gaussians.len() >= 20, "{}", gaussians.len());

    // The sixth unit, from 16 rows of a coarse instrument (50 µm; 48 equations for 33
    // unknowns).
    let truth = unit(&nominal, 6);
    let data = points(&truth, 16, 0.05, 306);
    let plain = calib::calibrate(&nominal, &data, &Options::default()).unwrap();
    let fit = calib::calibrate(&nominal, &data, &with_prior(gaussians.clone())).unwrap();
    // The same spreads centred on the nominal arm: what the mean adds.
    let centred: Vec<_> = gaussians
        .iter()
        .map(|(p, g)| (*p, priors::Gaussian { mean: 0.0, ..*g }))
        .collect();
    let at_nominal = calib::calibrate(&nominal, &data, &with_prior(centred)).unwrap();
    let (e_plain, e_fleet, e_nominal) = (
        fresh_error(&plain.arm, &truth),
        fresh_error(&fit.arm, &truth),
        fresh_error(&at_nominal.arm, &truth),
    );
    let mut mean_arm = nominal.clone();
    for (p, g) in &gaussians {
        p.add_to(&mut mean_arm, g.mean);
    }
    println!(
        "fresh poses, RMS µm: least squares {e_plain:.1}, fleet prior {e_fleet:.1}, \
         fleet spreads centred on nominal {e_nominal:.1}; nominal arm {:.1}, fleet mean arm {:.1}",
        fresh_error(&nominal, &truth),
        fresh_error(&mean_arm, &truth)
    );
    let e_mean = fresh_error(&mean_arm, &truth);
    // Measured: least squares 72.7 µm, the fleet's mean arm alone 57.7, the fit with the
    // fleet prior 41.5 (as the two combined should: 1/√(1/57.7² + 1/72.7²) = 45), the same
    // spreads pulling towards the nominal arm 1228.
    assert!(e_fleet < 0.7 * e_plain, "{e_fleet} {e_plain}");
    assert!(e_fleet < 0.85 * e_mean, "{e_fleet} {e_mean}");
    assert!(e_fleet < 0.1 * e_nominal, "{e_fleet} {e_nominal}");
    // The fleet's errors agree with this unit's: no prior was dropped as contradicted.
    assert!(fit.prior_conflicts.is_empty(), "{:?}", fit.prior_conflicts);
}

#[test]
fn a_prior_the_data_contradict_is_dropped() {
    let nominal = Arm::default6();
    let truth = unit(&nominal, 6);
    let data = points(&truth, 200, 0.005, 307);
    // A prior 3 mm off on the probe's x, with a 0.01 mm spread: the data fix it to microns.
    let wrong = priors::Gaussian {
        mean: truth.probe.error[0] + 3.0,
        sd: 0.01,
    };
    let probe_x = armcal::params::Param::ProbeError(0, 0);
    let fit = calib::calibrate(&nominal, &data, &with_prior(vec![(probe_x, wrong)])).unwrap();
    assert_eq!(fit.prior_conflicts.len(), 1);
    let c = fit.prior_conflicts[0];
    assert_eq!(fit.params[c.index], probe_x);
    assert!(c.sigmas() > 100.0, "{}", c.sigmas());
    assert!(fresh_error(&fit.arm, &truth) < 10.0);
}

#[test]
fn a_unit_of_another_design_is_refused_naming_its_file() {
    let nominal = Arm::default6();
    let dir = common::workdir("other-design");
    let mut files = fleet_files(&nominal, &dir)[..2].to_vec();
    // A 7-joint arm.
    let seven = dir.join("seven.toml");
    let mut a = nominal.clone();
    a.joints.push(a.joints[5].clone());
    std::fs::write(&seven, calfile::write(&a, &["7 joints"])).unwrap();
    files.push(seven.clone());
    let e = fleet_prior::from_files(&nominal, &files)
        .unwrap_err()
        .to_string();
    assert!(e.contains("seven.toml") && e.contains("7 joints"), "{e}");
    // Another axis.
    let turned = dir.join("turned.toml");
    let mut b = nominal.clone();
    b.joints[2].axis = if b.joints[2].axis == Axis::X {
        Axis::Y
    } else {
        Axis::X
    };
    std::fs::write(&turned, calfile::write(&b, &["axis"])).unwrap();
    let e = fleet_prior::from_files(&nominal, &[turned])
        .unwrap_err()
        .to_string();
    assert!(e.contains("turned.toml") && e.contains("joint 3"), "{e}");
    // The same joints, a link 50 mm longer: another arm.
    let longer = dir.join("longer.toml");
    let mut c = nominal.clone();
    c.joints[1].link[0] += 50.0;
    std::fs::write(&longer, calfile::write(&c, &["longer"])).unwrap();
    let e = fleet_prior::from_files(&nominal, &[longer])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("longer.toml") && e.contains("joint[2].link_error[0]"),
        "{e}"
    );
}

#[test]
fn the_cli_says_which_prior_it_used() {
    let nominal = Arm::default6();
    let dir = common::workdir("cli");
    let files = fleet_files(&nominal, &dir);
    std::fs::write(
        dir.join("nominal.toml"),
        calfile::write(&nominal, &["nominal"]),
    )
    .unwrap();
    let data = points(&unit(&nominal, 6), 16, 0.05, 306);
    std::fs::write(dir.join("few.csv"), data.to_csv(&["16 rows of unit 6"])).unwrap();
    let names: Vec<String> = files
        .iter()
        .map(|f| f.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    let mut args = vec![
        "calibrate",
        "few.csv",
        "--arm",
        "nominal.toml",
        "-o",
        "cal.toml",
        "--folds",
        "0",
        "--json",
        "--fleet-prior",
    ];
    args.extend(names.iter().map(String::as_str));
    let out = common::armcal_ok(&args, &dir);
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let fleet = &j["prior"]["fleet"];
    assert_eq!(fleet["units"].as_array().unwrap().len(), 5);
    let probe = fleet["entries"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["key"] == "probe.error[0]")
        .unwrap();
    assert_eq!(probe["units"], 5);
    assert!(probe["fallback"].is_null());
    assert!(probe["sd"].as_f64().unwrap() > 0.0);
    assert!(j["prior"]["rule"]
        .as_str()
        .unwrap()
        .contains("least squares"));
    // The text report lists it too, with the rule left to the others.
    let mut targs: Vec<&str> = args.iter().copied().filter(|a| *a != "--json").collect();
    targs.push("--ridge");
    let text = common::armcal_ok(&targs, &dir);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(text.contains("fleet prior from 5 units"), "{text}");
    assert!(
        text.contains("left to the rule `ridge λ = 0.0001`"),
        "{text}"
    );
    // A bad unit file: refused before any fit, named.
    std::fs::write(dir.join("bad.toml"), "[[joint]]\naxis = \"q\"\n").unwrap();
    let o = common::armcal(
        &[
            "calibrate",
            "few.csv",
            "--arm",
            "nominal.toml",
            "-o",
            "cal2.toml",
            "--fleet-prior",
            "bad.toml",
        ],
        &dir,
    );
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("bad.toml"));
    assert!(!dir.join("cal2.toml").exists());
}
