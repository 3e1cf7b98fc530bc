//! `armcal diagnose --fleet`: a cause every unit of a design shows is named for the design,
//! one that a single unit shows is named for that unit only, and bad input is refused with
//! the file named.

mod common;

use armcal::data::{Dataset, Kind};
use armcal::diagnose::fleet::{self, Level, UnitData};
use armcal::params::Effect;
use armcal::sim;
use quatarm_ref::arm::Arm;
use serde_json::Value;

/// Harmonic orders tried: enough for the test's candidates to include the shoulder's
/// first-order wave (a near alias of its compliance) while keeping the run short.
const MAX_ORDER: u32 = 2;

/// A `default-6` unit with its own geometric errors (seed `seed`), a gravity compliance `g`
/// (rad/mm) of joint 2, measured by a tracker: `rows` points, `sessions` sessions of equal
/// size as groups.
fn unit(seed: u64, g: f64, rows: usize, sessions: usize) -> Dataset {
    let mut rng = armcal::rng::rng(seed);
    let mut truth = sim::perturb(&Arm::default6(), 3e-4, 0.3, &mut rng);
    truth.joints[1].gravity = g;
    let d = sim::simulate(&truth, &sim::Options::new(Kind::Point, rows), &mut rng)
        .unwrap()
        .data;
    common::in_sessions(d, sessions, "(simulated unit)")
}

fn options() -> fleet::Options {
    let mut o = fleet::Options::default();
    o.diagnose.max_order = MAX_ORDER;
    o
}

#[test]
fn an_effect_every_unit_has_is_named_for_the_design() {
    // Five units, five geometries, one shoulder compliance at five magnitudes. (Five units
    // test the design's mean gain with 4 degrees of freedom: with Holm over 17 candidates the
    // units' gains must agree to within a spread of about a third of their mean; magnitudes
    // from 2.5e-8 to 5e-8 rad/mm, whose log RMS ratios range 0.47–0.89, gave the compliance
    // p = 7.8e-4 against Holm's 5.9e-4, and its more uniform near alias, the shoulder's
    // first-order wave, was named instead.)
    let gs = [3.0e-8, 3.3e-8, 3.6e-8, 3.9e-8, 4.2e-8];
    let units: Vec<UnitData> = gs
        .iter()
        .enumerate()
        .map(|(k, &g)| UnitData {
            name: format!("unit_{k}"),
            file: format!("unit_{k}.csv"),
            data: unit(100 + k as u64, g, 160, 4),
        })
        .collect();
    let f = fleet::diagnose_fleet(&Arm::default6(), &units, &options()).unwrap();
    assert_eq!(f.tested_units, 5);
    assert_eq!(
        f.design,
        vec![Effect::Gravity(1)],
        "{:?}",
        f.steps[0].pooled
    );
    let (named, significant) = f.steps[0]
        .pooled
        .iter()
        .find(|(p, _)| p.effect == Effect::Gravity(1))
        .unwrap();
    assert!(*significant);
    assert_eq!(named.pooling.units_gaining, 5);
    // Once it is in the model its near alias, the shoulder's first-order wave, has nothing
    // left to explain.
    let last = f.steps.last().unwrap();
    assert!(last.named.is_none());
    assert!(last.pooled.iter().all(|(_, significant)| !significant));
    for (u, &g) in f.units.iter().zip(&gs) {
        let (level, c) = u
            .causes
            .iter()
            .find(|(_, c)| c.effect == Effect::Gravity(1))
            .unwrap_or_else(|| panic!("{}: {:?}", u.name, u.causes));
        assert_eq!(*level, Level::Design);
        // Each unit's own magnitude, not the fleet's mean.
        assert!(
            (c.magnitude - g).abs() < 4.0 * c.magnitude_uncertainty + 0.05 * g,
            "{}: {} ± {} against {g}",
            u.name,
            c.magnitude,
            c.magnitude_uncertainty
        );
        assert!(
            u.causes.iter().all(|(l, _)| *l == Level::Design),
            "{}: unit-level {:?}",
            u.name,
            u.causes
        );
        let before = u.baseline.as_ref().unwrap().summary.all.rms_um;
        let after = u.extended.as_ref().unwrap().summary.all.rms_um;
        assert!(after < 0.7 * before, "{}: {before} → {after}", u.name);
    }
}

/// Writes the units' CSV files into `dir`, named `prefix<name>.csv`.
fn write(dir: &std::path::Path, prefix: &str, units: &[(&str, Dataset)]) -> Vec<String> {
    units
        .iter()
        .map(|(name, d)| {
            let file = format!("{prefix}{name}.csv");
            std::fs::write(dir.join(&file), d.to_csv(&["simulated fleet unit"])).unwrap();
            file
        })
        .collect()
}

#[test]
fn an_effect_of_one_unit_is_named_for_that_unit_only() {
    let dir = common::workdir("one-unit");
    let units = [
        ("a", unit(200, 0.0, 160, 4)),
        ("b", unit(201, 4.0e-8, 160, 4)),
        ("c", unit(202, 0.0, 160, 4)),
        ("d", unit(203, 0.0, 160, 4)),
        ("e", unit(204, 0.0, 60, 2)),
    ];
    let files = write(&dir, "fleet-six-", &units);
    let mut args = vec!["diagnose", "--fleet"];
    args.extend(files.iter().map(String::as_str));
    args.extend(["--json", "--max-order", "2", "--progress"]);
    let out = common::armcal_ok(&args, &dir);
    let j: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["design"]["causes"], Value::Array(Vec::new()), "{j:#}");
    // The pooled stage: one arm's compliance is not made the design's by pooling either (the
    // arms disagree, τ is large, the design's mean does not pass); the arm of two sessions
    // has no jackknife error and is left out, said, naming the option that would join it.
    let pooled = &j["pooled"];
    let g = pooled["effects"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["term"] == "+gravity_compliance:2")
        .unwrap_or_else(|| panic!("{pooled:#}"));
    assert_eq!(g["design"]["arms"], 4, "{g:#}");
    assert_eq!(g["named"], false, "{g:#}");
    assert!(g["design"]["spread"].as_f64().unwrap() > 1e-8, "{g:#}");
    assert_eq!(pooled["left_out"][0][0], "e", "{pooled:#}");
    let why = pooled["left_out"][0][1].as_str().unwrap();
    assert!(why.contains("--join-short"), "{why}");
    // Each arm weighed on the fleet's error scale where Bartlett's test at the fleet's α
    // keeps one scale (the default, `--error-scale fleet`), said with its test; the four
    // arms with a jackknife give φ̂.
    let d = &g["dispersion"];
    let (phi, p) = (d["phi"].as_f64().unwrap(), d["p"].as_f64().unwrap());
    assert!(phi > 0.0 && (0.0..=1.0).contains(&p), "{g:#}");
    assert!(p >= pooled["alpha"].as_f64().unwrap(), "{g:#}");
    assert_eq!(g["fleet_scaled"], true, "{g:#}");
    assert_eq!(d["ratios"].as_array().unwrap().len(), 4, "{g:#}");
    // Piped with --progress: every stage counted, the time left once a step is done.
    let err = String::from_utf8_lossy(&out.stderr);
    for stage in [
        "same-arm test: fit of recording 5 of 5",
        "geometric fit of recording 5 of 5",
        "design step 1: tests of recording 5 of 5",
        "own diagnosis of recording 1 of 4",
        "left",
    ] {
        assert!(err.contains(stage), "no `{stage}` in:\n{err}");
    }
    let units = j["units"].as_array().unwrap();
    let names: Vec<&str> = units.iter().map(|u| u["unit"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        ["a", "b", "c", "d", "e"],
        "the shared prefix is dropped"
    );
    for u in units {
        let name = u["unit"].as_str().unwrap();
        let causes = u["causes"].as_array().unwrap();
        if name == "b" {
            assert_eq!(causes.len(), 1, "{u:#}");
            assert_eq!(causes[0]["level"], "unit");
            assert_eq!(causes[0]["effect"], "gravity_compliance");
            assert_eq!(causes[0]["joint"], 2);
            let g = causes[0]["magnitude"].as_f64().unwrap();
            assert!((g - 4.0e-8).abs() < 0.4e-8, "{g}");
            let (before, after) = (
                u["holdout_rms_um"].as_f64().unwrap(),
                u["holdout_rms_um_after"].as_f64().unwrap(),
            );
            assert!(after < 0.7 * before, "{before} → {after}");
        } else {
            assert!(causes.is_empty(), "{name}: {causes:?}");
        }
        if name == "e" {
            assert_eq!(u["cannot_test"], "cannot test: 2 sessions");
        } else {
            assert!(u.get("cannot_test").is_none(), "{u:#}");
        }
    }
    // With `--join-short` the arm of two sessions (no jackknife error) joins on that scale,
    // last, weighed by √φ̂ times its in-sample error.
    args.push("--join-short");
    let out = common::armcal_ok(&args, &dir);
    let j: Value = serde_json::from_slice(&out.stdout).unwrap();
    let pooled = &j["pooled"];
    let g = &pooled["effects"][0];
    assert_eq!(g["design"]["arms"], 5, "{g:#}");
    let e = &g["arms"][4];
    assert_eq!(
        (&e["arm"], &e["jackknife"]),
        (&Value::from("e"), &Value::from(false))
    );
    let phi = g["dispersion"]["phi"].as_f64().unwrap();
    let want = phi.sqrt() * e["combined"]["model_se"].as_f64().unwrap();
    assert!(
        (e["se"].as_f64().unwrap() - want).abs() <= 1e-9 * want,
        "{e:#}"
    );
    assert!(
        pooled["left_out"].as_array().unwrap().is_empty(),
        "{pooled:#}"
    );
    // On the arms' own errors it has nothing to be weighed by.
    args.extend(["--error-scale", "own"]);
    let out = common::armcal_ok(&args, &dir);
    let j: Value = serde_json::from_slice(&out.stdout).unwrap();
    let pooled = &j["pooled"];
    let g = &pooled["effects"][0];
    assert_eq!(g["design"]["arms"], 4, "{g:#}");
    assert_eq!(pooled["left_out"][0][0], "e", "{pooled:#}");
    let why = pooled["left_out"][0][1].as_str().unwrap();
    assert!(why.contains("--error-scale fleet"), "{why}");
}

#[test]
fn bad_fleets_are_refused_with_the_file_named() {
    let dir = common::workdir("bad");
    let files = write(
        &dir,
        "",
        &[
            ("good", unit(300, 0.0, 30, 3)),
            ("other", unit(301, 0.0, 30, 3)),
        ],
    );
    // A file that does not exist.
    let o = common::armcal(&["diagnose", "--fleet", &files[0], "missing.csv"], &dir);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("missing.csv"), "{err}");
    // A unit of another joint count: a 7-joint file among 6-joint ones.
    let panda = armcal::mukca::default_dir().join("mukca-panda-panda_7.csv");
    let panda = panda.to_str().unwrap();
    let o = common::armcal(&["diagnose", "--fleet", &files[0], &files[1], panda], &dir);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("mukca-panda-panda_7.csv"), "{err}");
    // One file is not a fleet.
    let o = common::armcal(&["diagnose", "--fleet", &files[0]], &dir);
    assert!(!o.status.success());
    // Two paths to one name.
    std::fs::create_dir_all(dir.join("x")).unwrap();
    std::fs::copy(dir.join(&files[0]), dir.join("x").join(&files[0])).unwrap();
    let o = common::armcal(
        &["diagnose", "--fleet", &files[0], &format!("x/{}", files[0])],
        &dir,
    );
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("same unit name"), "{err}");
    // An error scale that is not one, named with the choices.
    let o = common::armcal(
        &[
            "diagnose",
            "--fleet",
            &files[0],
            &files[1],
            "--error-scale",
            "both",
        ],
        &dir,
    );
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--error-scale") && err.contains("own") && err.contains("fleet"),
        "{err}"
    );
}
