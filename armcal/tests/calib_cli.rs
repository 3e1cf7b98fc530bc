//! `armcal simulate` and `armcal calibrate` end to end, as a user runs them.

mod common;

use armcal::fit::design::poses::{limits, random_pose};
use common::{armcal, armcal_ok, simulate, workdir, write_truth};

/// The virtual arm the simulations measure.
fn truth() -> quatarm_ref::Arm {
    armcal::sim::perturb(
        &quatarm_ref::Arm::default6(),
        3e-4,
        0.3,
        &mut armcal::rng::rng(3),
    )
}

#[test]
fn simulate_is_deterministic() {
    let d = workdir("det");
    write_truth(&d, &truth());
    for out in ["a.csv", "b.csv"] {
        armcal_ok(
            &[
                "simulate",
                "--truth",
                "truth.toml",
                "--kind",
                "spat",
                "--count",
                "24",
                "--seed",
                "9",
                "--temp",
                "16..28",
                "-o",
                out,
            ],
            &d,
        );
    }
    let a = std::fs::read(d.join("a.csv")).unwrap();
    assert_eq!(a, std::fs::read(d.join("b.csv")).unwrap());
    let text = String::from_utf8(a).unwrap();
    assert!(text.contains("temp_c"));
    let data = armcal::data::read(&d.join("a.csv"), 6).unwrap();
    assert_eq!(data.rows.len(), 24);
    assert!(data.rows.iter().all(|r| (16.0..28.0).contains(&r.temp_c)));
}

#[test]
fn calibrate_writes_file_table_and_json() {
    let d = workdir("json");
    write_truth(&d, &truth());
    armcal_ok(
        &[
            "simulate",
            "--truth",
            "truth.toml",
            "--kind",
            "point",
            "--count",
            "300",
            "--seed",
            "4",
            "-o",
            "pts.csv",
        ],
        &d,
    );
    let o = armcal_ok(
        &[
            "calibrate",
            "pts.csv",
            "-o",
            "cal.toml",
            "--json",
            "--folds",
            "3",
        ],
        &d,
    );
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON on stdout");
    let after = j["residuals"]["after"]["all"]["rms_um"].as_f64().unwrap();
    let before = j["residuals"]["before"]["all"]["rms_um"].as_f64().unwrap();
    let held_out = j["residuals"]["holdout"]["residuals"]["all"]["rms_um"]
        .as_f64()
        .unwrap();
    assert!(
        before > 100.0 && after < 12.0 && held_out < 14.0,
        "{before} {after} {held_out}"
    );
    assert_eq!(j["fitted"], 27);
    assert!(j["condition_number"].as_f64().unwrap() < 100.0);
    let held = j["not_identifiable"].as_array().unwrap();
    let dz = held
        .iter()
        .find(|h| h["key"] == "joint[1].zero_offset")
        .expect("Δθ1 named");
    assert_eq!(dz["reason"], "inseparable");
    assert_eq!(dz["absorbed_by"][0]["key"], "reference_frame.rotation_z");
    assert!(j["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .all(|p| p["uncertainty"].as_f64().unwrap() > 0.0));
    assert!(
        d.join("cal.bin").exists(),
        "the binary table is written beside the file"
    );

    // The file keeps the nominal values and carries the errors in their keys.
    let cal = quatarm_ref::calfile::read(&d.join("cal.toml")).unwrap();
    assert!(cal.unknown_keys.is_empty());
    let nominal = quatarm_ref::Arm::default6();
    for (a, b) in cal.arm.joints.iter().zip(&nominal.joints) {
        assert_eq!(a.link, b.link);
        assert_eq!(a.axis, b.axis);
    }
    assert_eq!(cal.arm.probe.vector, nominal.probe.vector);
    assert!(cal.arm.reference_frame.is_some());
    assert!(cal.arm.joints[1].zero_offset != 0.0);
}

#[test]
fn bad_data_is_refused_with_file_line_and_column() {
    let d = workdir("bad");
    std::fs::write(
        d.join("bad.csv"),
        "kind,group,j1,j2,j3,j4,j5,j6,x,y,z\npoint,1,0,0,0,0,0,0,1,2,3\npoint,1,0,x,0,0,0,0,1,2,3\n",
    )
    .unwrap();
    let o = armcal(&["calibrate", "bad.csv", "-o", "cal.toml"], &d);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.csv: line 3, column j2"), "{err}");
    assert!(!d.join("cal.toml").exists(), "no partial result");
}

#[test]
fn spat_and_length_calibrate_without_an_instrument() {
    let d = workdir("spat");
    write_truth(&d, &truth());
    for (kind, count, seed, out) in [
        ("spat", "160", "5", "s.csv"),
        ("length", "80", "6", "l.csv"),
    ] {
        simulate(&d, kind, count, seed, &[], out);
    }
    // One file: length groups renumbered after the spat ones, without the second header.
    let s = std::fs::read_to_string(d.join("s.csv")).unwrap();
    let l = std::fs::read_to_string(d.join("l.csv")).unwrap();
    let mut text = String::from("kind,group,j1,j2,j3,j4,j5,j6,end,length_mm\n");
    for line in s.lines().filter(|x| x.starts_with("spat")) {
        text.push_str(&format!("{line},,\n"));
    }
    for line in l.lines().filter(|x| x.starts_with("length")) {
        let mut f: Vec<String> = line.split(',').map(String::from).collect();
        f[1] = (f[1].parse::<i64>().unwrap() + 100).to_string();
        text.push_str(&f.join(","));
        text.push('\n');
    }
    std::fs::write(d.join("sl.csv"), text).unwrap();
    let o = armcal_ok(&["calibrate", "sl.csv", "-o", "cal.toml"], &d);
    let report = String::from_utf8_lossy(&o.stdout);
    assert!(
        report.contains("a rotation of the whole arm about the base z axis"),
        "{report}"
    );
    assert!(report.contains("bar length error"), "{report}");
    let cal = quatarm_ref::calfile::read(&d.join("cal.toml")).unwrap();
    assert!(cal.arm.reference_frame.is_none());
}

/// The rows of several simulated files as one file, each file's groups moved apart.
fn merge(d: &std::path::Path, files: &[&str], out: &str) {
    let mut rows = Vec::new();
    for (k, f) in files.iter().enumerate() {
        let data = armcal::data::read(&d.join(f), 6).unwrap();
        rows.extend(data.rows.into_iter().map(|r| armcal::data::Row {
            group: r.group + 1000 * k as i64,
            ..r
        }));
    }
    let all = armcal::data::Dataset::from_rows(rows, 6, false, out).unwrap();
    std::fs::write(d.join(out), all.to_csv(&[])).unwrap();
}

/// `sphere` rows are calibration data: a sphere of known diameter fixes the scale that spat
/// rows alone cannot, so spat + sphere calibrate an arm that spat alone is refused on.
#[test]
fn sphere_rows_calibrate_with_spat_rows() {
    let d = workdir("sphere");
    write_truth(&d, &truth());
    simulate(&d, "spat", "300", "5", &[], "spat.csv");
    simulate(
        &d,
        "sphere",
        "300",
        "6",
        &["--articulations", "5"],
        "sphere.csv",
    );
    merge(&d, &["spat.csv", "sphere.csv"], "both.csv");
    let refused = armcal(&["calibrate", "spat.csv", "-o", "spat.toml"], &d);
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("the arm's scale"));
    let o = armcal_ok(&["calibrate", "both.csv", "-o", "cal.toml", "--json"], &d);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["data"]["sphere_rows"], 300);
    assert_eq!(v["data"]["sphere_groups"], 12);
    // 300 spat rows give 3 (n − 1) per group, 300 sphere rows n − 3 per group of 25.
    let eq = v["data"]["equations"].as_u64().unwrap();
    assert_eq!(
        eq,
        3 * (300 - v["data"]["spat_groups"].as_u64().unwrap()) + (300 - 36)
    );
    let before = v["residuals"]["before"]["sphere"]["rms_um"]
        .as_f64()
        .unwrap();
    let after = v["residuals"]["after"]["sphere"]["rms_um"]
        .as_f64()
        .unwrap();
    assert!(after < 10.0 && before > 20.0 * after, "{before} -> {after}");
    // The calibrated arm is the truth's to within a tenth of its nominal error over the
    // workspace (71 µm from 1,085: a 25 mm sphere fixes the scale only through its radius, so
    // the scale is the weakest part of such a calibration; a bar fixes it far better).
    let cal = quatarm_ref::calfile::read(&d.join("cal.toml")).unwrap().arm;
    let lim = limits(&cal);
    let mut r = armcal::rng::rng(8);
    let poses: Vec<(Vec<f64>, f64)> = (0..2000)
        .map(|_| (random_pose(&lim, &mut r), 20.0))
        .collect();
    let nominal =
        armcal::fit::residuals::compare_aligned(&quatarm_ref::Arm::default6(), &truth(), &poses);
    let fitted = armcal::fit::residuals::compare_aligned(&cal, &truth(), &poses);
    assert!(
        fitted.rms_um < nominal.rms_um / 10.0,
        "{fitted:?} vs {nominal:?}"
    );
    // And the diagnosis takes them too.
    armcal_ok(&["diagnose", "both.csv", "--folds", "3"], &d);
}

/// A sphere group that fixes no sphere is refused by name and line, before any fit.
#[test]
fn a_sphere_group_of_three_rows_is_refused() {
    let d = workdir("sphere3");
    write_truth(&d, &truth());
    simulate(&d, "point", "100", "5", &[], "pts.csv");
    simulate(&d, "sphere", "25", "6", &[], "sphere.csv");
    let text = std::fs::read_to_string(d.join("sphere.csv")).unwrap();
    let short: Vec<&str> = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .take(4)
        .collect();
    std::fs::write(d.join("short.csv"), short.join("\n") + "\n").unwrap();
    merge(&d, &["pts.csv", "short.csv"], "both.csv");
    let o = armcal(&["calibrate", "both.csv", "-o", "cal.toml"], &d);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("sphere group 1001"), "{err}");
    assert!(err.contains("line"), "{err}");
    assert!(err.contains("a sphere needs 4 or more"), "{err}");
    assert!(!d.join("cal.toml").exists());
}
