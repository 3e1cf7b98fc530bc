//! `armcal diagnose` end to end, as a user runs it: JSON of the issue's shape, the text
//! report, the figures, the extended calibration file and its table, and clear refusals.

use quatarm_ref::arm::{Arm, Harmonic};
use serde_json::Value;
use std::path::Path;

mod common;

use common::{armcal, armcal_ok, png_size, workdir, write_truth};

/// Writes a truth file and simulates 600 point readings of it at 16–28 °C into `points.csv`.
fn simulate(dir: &Path, truth: &Arm, seed: &str) {
    write_truth(dir, truth);
    armcal_ok(
        &[
            "simulate",
            "--truth",
            "truth.toml",
            "--kind",
            "point",
            "--count",
            "600",
            "--seed",
            seed,
            "--temp",
            "16..28",
            "-o",
            "points.csv",
        ],
        dir,
    );
}

fn truth() -> Arm {
    let mut t = armcal::sim::perturb(&Arm::default6(), 3e-4, 0.3, &mut armcal::rng::rng(21));
    t.joints[1].harmonics.push(Harmonic {
        order: 1,
        sin: 5e-5,
        cos: -4e-5,
    });
    t.joints[4].thermal = 2e-5;
    t
}

/// Width and height from a PNG's IHDR, after checking the signature.
#[test]
fn diagnose_prints_the_issue_json_and_writes_file_table_and_figures() {
    let d = workdir("json");
    simulate(&d, &truth(), "22");
    let o = armcal_ok(
        &[
            "diagnose",
            "points.csv",
            "--json",
            "--plots",
            "figs",
            "-o",
            "ext.toml",
        ],
        &d,
    );
    let j: Value = serde_json::from_slice(&o.stdout).expect("JSON on stdout");
    // The issue's shape.
    assert_eq!(j["baseline"]["model"], "geometric");
    for k in ["rms_um", "holdout_rms_um", "max_um"] {
        assert!(j["baseline"][k].as_f64().unwrap() > 0.0, "baseline.{k}");
        assert!(j["extended"][k].as_f64().unwrap() > 0.0, "extended.{k}");
    }
    let causes = j["causes"].as_array().unwrap();
    assert_eq!(causes.len(), 2, "{causes:#?}");
    let harmonic = causes
        .iter()
        .find(|c| c["effect"] == "encoder_harmonic")
        .expect("the harmonic is named");
    assert_eq!(harmonic["joint"], 2);
    assert_eq!(harmonic["order"], 1);
    assert_eq!(harmonic["unit"], "rad");
    let amp = harmonic["magnitude"].as_f64().unwrap();
    assert!((amp - 5e-5f64.hypot(4e-5)).abs() < 3e-6, "{amp}");
    let thermal = causes
        .iter()
        .find(|c| c["effect"] == "thermal_expansion")
        .expect("the thermal expansion is named");
    // Link 5's expansion is named as the pair's lower link, 4, with 5 listed.
    assert_eq!(thermal["joint"], 4);
    assert_eq!(thermal["indistinguishable_from"], serde_json::json!([5]));
    assert_eq!(thermal["unit"], "1/°C");
    assert!(thermal.get("order").is_none());
    for c in causes {
        assert!(c["holdout_rms_um_after"].as_f64().unwrap() > 0.0);
    }
    let base = j["baseline"]["holdout_rms_um"].as_f64().unwrap();
    let ext = j["extended"]["holdout_rms_um"].as_f64().unwrap();
    let gain = j["gain_percent"].as_f64().unwrap();
    assert!((gain - 100.0 * (1.0 - ext / base)).abs() < 1e-9);
    assert!(gain > 40.0, "{gain}");
    assert!(
        j["extended"]["model"]
            .as_str()
            .unwrap()
            .contains("encoder_harmonic:2:1"),
        "{}",
        j["extended"]["model"]
    );
    // The files.
    let back = quatarm_ref::calfile::read(&d.join("ext.toml")).unwrap().arm;
    assert_eq!(back.joints[1].harmonics.len(), 1);
    assert!(
        back.joints[3].thermal > 1.5e-5,
        "{}",
        back.joints[3].thermal
    );
    assert!(d.join("ext.bin").exists());
    assert_eq!(j["output"]["table"], "ext.bin");
    assert_eq!(j["output"]["calibration"], "ext.toml");
    for f in [
        "residuals_vs_joint_angle.png",
        "residuals_vs_gravity_lever.png",
        "residuals_vs_temperature.png",
    ] {
        let (w, h) = png_size(&d.join("figs").join(f));
        assert!(w >= 1000 && h >= 400, "{f}: {w}×{h}");
    }
}

#[test]
fn the_text_report_says_what_it_found() {
    let d = workdir("text");
    simulate(&d, &truth(), "23");
    let o = armcal_ok(&["diagnose", "points.csv"], &d);
    let text = String::from_utf8(o.stdout).unwrap();
    for want in [
        "what the model gets wrong",
        "joint 2 encoder harmonic of order 1",
        "link 4 thermal expansion",
        "indistinguishable from link 5",
        "2 causes named",
        "gain on held-out data",
        "not testable on these data",
        "joint 1 has no gravity lever",
    ] {
        assert!(text.contains(want), "missing `{want}` in:\n{text}");
    }
}

#[test]
fn noise_alone_is_reported_as_none() {
    let d = workdir("none");
    let t = armcal::sim::perturb(&Arm::default6(), 3e-4, 0.3, &mut armcal::rng::rng(24));
    simulate(&d, &t, "25");
    let o = armcal_ok(&["diagnose", "points.csv", "--json", "-o", "ext.toml"], &d);
    let j: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["causes"], serde_json::json!([]));
    assert_eq!(j["gain_percent"], 0.0);
    assert_eq!(j["extended"]["model"], "geometric");
    assert!(j["verdict"].as_str().unwrap().starts_with("none"));
    // The extended calibration is then the geometric one, still written with its table.
    assert!(d.join("ext.bin").exists());
}

#[test]
fn a_term_beyond_the_table_is_reported_and_no_table_is_written() {
    let d = workdir("table");
    let mut t = armcal::sim::perturb(&Arm::default6(), 3e-4, 0.3, &mut armcal::rng::rng(26));
    t.joints[1].gravity = 8e-6; // beyond the table's 3e-6 rad/mm
    simulate(&d, &t, "27");
    std::fs::write(d.join("ext.bin"), b"stale").unwrap();
    let o = armcal_ok(&["diagnose", "points.csv", "--json", "-o", "ext.toml"], &d);
    let j: Value = serde_json::from_slice(&o.stdout).unwrap();
    let causes = j["causes"].as_array().unwrap();
    assert!(
        causes
            .iter()
            .any(|c| c["effect"] == "gravity_compliance" && c["joint"] == 2),
        "{causes:#?}"
    );
    let err = j["output"]["table_error"].as_str().expect("table_error");
    assert!(err.contains("joint 2 gravity compliance"), "{err}");
    assert!(err.contains("≤ 3e-6 rad/mm"), "{err}");
    assert!(j["output"]["table"].is_null());
    assert!(!d.join("ext.bin").exists(), "a stale table must not stay");
    assert!(d.join("ext.toml").exists());
}

#[test]
fn data_without_held_out_units_are_refused_plainly() {
    let d = workdir("single");
    let dir = armcal::mukca::default_dir();
    let o = armcal(
        &[
            "diagnose",
            dir.join("mukca-panda-panda_left.csv").to_str().unwrap(),
            "--arm",
            dir.join("mukca-panda-panda_left.toml").to_str().unwrap(),
            "--by-group",
        ],
        &d,
    );
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("held-out"), "{err}");
    let o = armcal(&["diagnose", "nothing.csv"], &d);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("nothing.csv"));
}

/// Two sessions cannot confirm or rule out any cause: the report says so, never "none".
#[test]
fn two_sessions_are_reported_as_cannot_test() {
    let d = workdir("two-sessions");
    let mukca = Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/mukca");
    let data = mukca.join("mukca-panda-panda_7.csv");
    let arm = mukca.join("mukca-panda-panda_7.toml");
    let args = [
        "diagnose",
        data.to_str().unwrap(),
        "--arm",
        arm.to_str().unwrap(),
    ];
    let o = armcal_ok(&[&args[..], &["--by-group", "--json"]].concat(), &d);
    let j: Value = serde_json::from_slice(&o.stdout).unwrap();
    let verdict = j["verdict"].as_str().unwrap();
    assert!(
        verdict.starts_with("cannot test: 2 held-out units"),
        "{verdict}"
    );
    assert!(verdict.contains("record 1 more session"), "{verdict}");
    let o = armcal_ok(&[&args[..], &["--by-group"]].concat(), &d);
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(!text.contains("\n  none\n"), "{text}");
    // Nor can the selection be rerun without a session: one session left cannot be diagnosed.
    assert!(text.contains("no session could be scored"), "{text}");
}
