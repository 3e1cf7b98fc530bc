//! `armcal check` as a metrologist runs it: simulated sphere, bar and SPAT tests of a known
//! arm, checked with the right calibration, with a wrong ball diameter, and against MPEs.

mod common;

use common::{armcal, armcal_ok, png_size, workdir, write_truth};
use quatarm_ref::arm::Arm;
use std::path::Path;

fn truth() -> Arm {
    let mut a = Arm::default6();
    a.probe.ball_diameter = 3.0;
    a
}

/// Noise-free simulated rows of `truth.toml` (seed 7).
fn simulate(dir: &Path, kind: &str, count: &str, extra: &[&str], out: &str) {
    let extra = [&["--noise-um", "0"][..], extra].concat();
    common::simulate(dir, kind, count, "7", &extra, out);
}

fn json(dir: &Path, args: &[&str]) -> serde_json::Value {
    let o = armcal_ok(args, dir);
    serde_json::from_slice(&o.stdout).expect("check --json prints JSON")
}

#[test]
fn the_true_arm_passes_and_a_wrong_ball_diameter_shows_in_p_size() {
    let dir = workdir("true-arm");
    write_truth(&dir, &truth());
    simulate(&dir, "sphere", "50", &[], "sphere.csv");
    simulate(&dir, "sphere", "25", &["--articulations", "5"], "ldia.csv");
    simulate(&dir, "length", "20", &[], "bar.csv");
    simulate(&dir, "spat", "16", &[], "spat.csv");
    let v = json(
        &dir,
        &["check", "sphere.csv", "--calib", "truth.toml", "--json"],
    );
    // Noise-free rows, quantised to 2^20 counts a turn: a few µm at most.
    let p_size = v["results"]["P_Size"].as_f64().unwrap();
    let p_form = v["results"]["P_Form"].as_f64().unwrap();
    assert!(p_size.abs() < 5.0 && p_form < 15.0, "{v}");
    assert_eq!(
        v["tests"].as_array().unwrap().len(),
        4,
        "two groups, two tests each"
    );
    assert_eq!(v["tests"][0]["test"], "P_Size");
    for (file, key, bound) in [
        ("ldia.csv", "L_Dia", 15.0),
        ("bar.csv", "E_Uni", 5.0),
        ("spat.csv", "SPAT_max", 15.0),
    ] {
        let v = json(&dir, &["check", file, "--calib", "truth.toml", "--json"]);
        let x = v["results"][key].as_f64().unwrap();
        assert!(x.abs() < bound, "{file}: {key} = {x} µm");
    }
    // The same data checked with a calibration that says the ball has no diameter: the
    // fitted sphere is the ball's 3 mm larger.
    let mut wrong = truth();
    wrong.probe.ball_diameter = 0.0;
    std::fs::write(
        dir.join("wrong.toml"),
        quatarm_ref::calfile::write(&wrong, &["no ball"]),
    )
    .unwrap();
    let v = json(
        &dir,
        &["check", "sphere.csv", "--calib", "wrong.toml", "--json"],
    );
    let p = v["results"]["P_Size"].as_f64().unwrap();
    assert!((p - 3000.0).abs() < 5.0, "P_Size {p} µm");
    // The effective diameter test measures the ball the wrong file lost: 3 mm, per group.
    let eff = v["effective_ball_diameter"].as_array().unwrap();
    assert_eq!(eff.len(), 2, "{v}");
    for e in eff {
        let d = e["diameter_mm"].as_f64().unwrap();
        assert!((d - truth().probe.ball_diameter).abs() < 0.005, "{e}");
    }
    let text = armcal_ok(&["check", "sphere.csv", "--calib", "wrong.toml"], &dir);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(
        text.contains("effective stylus ball diameter (B89.4.22): ")
            && text.contains("mm (group 2)"),
        "{text}"
    );
}

#[test]
fn decisions_follow_iso_14253_1() {
    let dir = workdir("decisions");
    write_truth(&dir, &truth());
    simulate(&dir, "length", "20", &[], "bar.csv");
    let decide = |mpe: &str| -> Vec<String> {
        std::fs::write(dir.join("mpe.toml"), mpe).unwrap();
        let o = armcal(
            &[
                "check",
                "bar.csv",
                "--calib",
                "truth.toml",
                "--mpe",
                "mpe.toml",
                "--json",
            ],
            &dir,
        );
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
        // The exit code is the verdict's, which the JSON states too.
        assert_eq!(
            o.status.code(),
            v["verdict"]["exit_code"].as_i64().map(|c| c as i32),
            "{v}"
        );
        v["tests"]
            .as_array()
            .unwrap()
            .iter()
            .map(|t| t["decision"].as_str().unwrap().to_string())
            .collect()
    };
    assert!(decide("E_Uni = { a = 0.010, per_m = 0.005 }\n")
        .iter()
        .all(|d| d == "pass"));
    assert!(decide("E_Uni = 0.0\ntest_uncertainty = { E_Uni = 0.0 }\n")
        .iter()
        .all(|d| d == "fail"));
    assert!(
        decide("E_Uni = 0.010\ntest_uncertainty = { E_Uni = 0.020 }\n")
            .iter()
            .all(|d| d == "cannot decide")
    );
}

#[test]
fn bad_input_is_refused_with_its_place() {
    let dir = workdir("bad");
    write_truth(&dir, &truth());
    simulate(&dir, "sphere", "25", &[], "sphere.csv");
    std::fs::write(dir.join("mpe.toml"), "P_Size = 0.016\nP_Sise = 0.1\n").unwrap();
    let o = armcal(
        &[
            "check",
            "sphere.csv",
            "--calib",
            "truth.toml",
            "--mpe",
            "mpe.toml",
        ],
        &dir,
    );
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.code() == Some(3) && o.stdout.is_empty(), "{o:?}");
    assert!(e.contains("mpe.toml") && e.contains("P_Sise"), "{e}");
    // 24 points where P_Size needs 25: refused, naming the group.
    let text = std::fs::read_to_string(dir.join("sphere.csv")).unwrap();
    let short: Vec<&str> = text.lines().take(text.lines().count() - 1).collect();
    std::fs::write(dir.join("short.csv"), short.join("\n")).unwrap();
    let o = armcal(&["check", "short.csv", "--calib", "truth.toml"], &dir);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && o.stdout.is_empty());
    assert!(
        e.contains("short.csv") && e.contains("group 1") && e.contains("24 points"),
        "{e}"
    );
    // Sphere rows are calibration data, but one sphere position (22 equations) cannot
    // calibrate an arm: refused, naming the file, and nothing written.
    let o = armcal(&["calibrate", "sphere.csv", "-o", "cal.toml"], &dir);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("sphere.csv"), "{e}");
    assert!(!dir.join("cal.toml").exists());
}

#[test]
fn the_virtual_test_needs_a_budget_and_gives_u_from_it() {
    let dir = workdir("predict");
    write_truth(&dir, &truth());
    simulate(&dir, "length", "20", &[], "bar.csv");
    let o = armcal(
        &["check", "bar.csv", "--calib", "truth.toml", "--predict"],
        &dir,
    );
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("[uncertainty]"), "{e}");
    let mut text = std::fs::read_to_string(dir.join("truth.toml")).unwrap();
    text.push_str("\n[uncertainty]\nprobing_mm = 0.002\n");
    std::fs::write(dir.join("budget.toml"), text).unwrap();
    std::fs::write(dir.join("mpe.toml"), "E_Uni = 0.030\n").unwrap();
    let v = json(
        &dir,
        &[
            "check",
            "bar.csv",
            "--calib",
            "budget.toml",
            "--mpe",
            "mpe.toml",
            "--predict",
            "--json",
        ],
    );
    for t in v["tests"].as_array().unwrap() {
        // Two means of five probings each, 2 µm per axis: sd 1.26 µm, U = 2 sd.
        let u = t["U_um"].as_f64().unwrap();
        assert!((u - 2.53).abs() < 0.5, "{t}");
        let p = &t["predicted_um"];
        assert!(
            p["lo"].as_f64().unwrap() < 0.0 && p["hi"].as_f64().unwrap() > 0.0,
            "{t}"
        );
    }
}

/// Issue 27: without `test_uncertainty`, U is propagated from the calibration's budget
/// (without `--predict` too), printed with its source and used by the decision; with it, the
/// MPE file's value.
#[test]
fn u_comes_from_the_budget_unless_the_mpe_file_gives_it() {
    let dir = workdir("u-from-budget");
    write_truth(&dir, &truth());
    simulate(&dir, "length", "20", &[], "bar.csv");
    let mut text = std::fs::read_to_string(dir.join("truth.toml")).unwrap();
    text.push_str("\n[uncertainty]\nprobing_mm = 0.002\n");
    std::fs::write(dir.join("budget.toml"), text).unwrap();
    // The verdict is the exit code: 2 (cannot decide) with the budget's U, 0 with the file's.
    let run = |mpe: &str, code: i32| {
        std::fs::write(dir.join("mpe.toml"), mpe).unwrap();
        let args = [
            "check",
            "bar.csv",
            "--calib",
            "budget.toml",
            "--mpe",
            "mpe.toml",
        ];
        let o = armcal(&[&args[..], &["--json"]].concat(), &dir);
        assert_eq!(
            o.status.code(),
            Some(code),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
        let o = armcal(&args, &dir);
        assert_eq!(
            o.status.code(),
            Some(code),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        (v, String::from_utf8_lossy(&o.stdout).into_owned())
    };
    // The noise-free bar's error is 0; U (2 sd of two means of five 2 µm probings) is
    // 2.5 µm: against an MPE of 2 µm only U keeps the decision from a pass.
    let (v, text) = run("E_Uni = 0.002\n", 2);
    for t in v["tests"].as_array().unwrap() {
        let u = t["U_um"].as_f64().unwrap();
        assert!((u - 2.53).abs() < 0.5, "{t}");
        assert_eq!(t["u_source"], "budget", "{t}");
        assert_eq!(t["decision"], "cannot decide", "{t}");
        assert!(t.get("predicted_um").is_none(), "{t}");
    }
    assert!(text.contains("from the budget"), "{text}");
    assert!(!text.contains("U = 0"), "{text}");
    let (v, text) = run("E_Uni = 0.002\ntest_uncertainty = { E_Uni = 0.0005 }\n", 0);
    for t in v["tests"].as_array().unwrap() {
        assert_eq!(t["U_um"].as_f64().unwrap(), 0.5, "{t}");
        assert_eq!(t["u_source"], "mpe_file", "{t}");
        assert_eq!(t["decision"], "pass", "{t}");
    }
    assert!(text.contains("from the MPE file"), "{text}");
}

/// `--plots`: the three pictures of a complete ISO 10360-12 test set, valid PNGs; a folder that
/// is a file is refused and nothing is written.
#[test]
fn plots_are_written_for_a_complete_test_set() {
    let d = workdir("plots");
    write_truth(&d, &truth());
    armcal_ok(
        &[
            "simulate",
            "--truth",
            "truth.toml",
            "--test",
            "iso10360-12",
            "--seed",
            "5",
            "-o",
            "iso.csv",
        ],
        &d,
    );
    armcal_ok(
        &[
            "check",
            "iso.csv",
            "--calib",
            "truth.toml",
            "--plots",
            "figs",
        ],
        &d,
    );
    for f in [
        "sphere_deviations.png",
        "length_errors.png",
        "spat_scatter.png",
    ] {
        let (w, h) = png_size(&d.join("figs").join(f));
        assert!(w >= 1000 && h >= 300, "{f}: {w}×{h}");
    }
    std::fs::write(d.join("afile"), "x").unwrap();
    let o = armcal(
        &[
            "check",
            "iso.csv",
            "--calib",
            "truth.toml",
            "--plots",
            "afile",
        ],
        &d,
    );
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("afile"));
    assert!(o.stdout.is_empty(), "no partial output");
}

/// The exit code is the verdict (0 conforms, 1 does not, 2 cannot decide) and an error is 3,
/// never one of them: the true arm checked with its own calibration conforms, an arm whose
/// calibration has link 3 150 µm short fails E_Uni, and the same arm with a test uncertainty
/// as large as its error cannot be decided.
#[test]
fn exit_codes_are_the_verdict_and_errors_are_3() {
    let dir = workdir("exit-codes");
    write_truth(&dir, &truth());
    simulate(&dir, "length", "20", &[], "bar.csv");
    let mut short = truth();
    short.joints[2].link[2] -= 0.150;
    std::fs::write(
        dir.join("short.toml"),
        quatarm_ref::calfile::write(&short, &["link 3 150 µm short"]),
    )
    .unwrap();
    std::fs::write(
        dir.join("mpe.toml"),
        "E_Uni = { a = 0.010, per_m = 0.005 }\ntest_uncertainty = { E_Uni = 0.002 }\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("wide.toml"),
        "E_Uni = { a = 0.010, per_m = 0.005 }\ntest_uncertainty = { E_Uni = 0.500 }\n",
    )
    .unwrap();
    let run = |calib: &str, mpe: &str| {
        let o = armcal(&["check", "bar.csv", "--calib", calib, "--mpe", mpe], &dir);
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        (o.status.code(), text)
    };
    let (code, text) = run("truth.toml", "mpe.toml");
    assert_eq!(code, Some(0), "{text}");
    let verdict = text.lines().last().unwrap();
    assert!(
        verdict.starts_with("verdict: conforms (exit 0)")
            && verdict.contains("MPE file mpe.toml")
            && verdict.contains("ISO 14253-1"),
        "{verdict}"
    );
    // The E_Uni rows carry their bar's length.
    let row = text.lines().find(|l| l.starts_with("E_Uni")).unwrap();
    let bar: f64 = row.split_whitespace().nth(2).unwrap().parse().unwrap();
    assert!((200.0..=3000.0).contains(&bar), "{row}");
    let (code, text) = run("short.toml", "mpe.toml");
    assert_eq!(code, Some(1), "{text}");
    assert!(
        text.contains("verdict: does not conform (exit 1)"),
        "{text}"
    );
    let (code, text) = run("short.toml", "wide.toml");
    assert_eq!(code, Some(2), "{text}");
    assert!(text.contains("verdict: cannot decide (exit 2)"), "{text}");
    // Errors: a missing file, a bad argument. Never 1 or 2.
    let (code, _) = run("missing.toml", "mpe.toml");
    assert_eq!(code, Some(3));
    let o = armcal(
        &["check", "bar.csv", "--calib", "truth.toml", "--draws", "x"],
        &dir,
    );
    assert_eq!(o.status.code(), Some(3));
    // No MPE file: values only, exit 0, and the verdict line says nothing was decided.
    let o = armcal_ok(&["check", "bar.csv", "--calib", "truth.toml"], &dir);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("verdict: no decision (exit 0)"), "{text}");
    // --help lists the codes.
    let o = armcal_ok(&["check", "--help"], &dir);
    let help = String::from_utf8_lossy(&o.stdout);
    assert!(
        help.contains("3  error") && help.contains("2  cannot decide"),
        "{help}"
    );
}

/// `--predict`: a measured value outside its predicted 95 % interval is flagged, in the text
/// and the JSON: data of an arm with link 3 40 µm short, predicted by a calibration of the
/// nominal link with a 2 µm probing budget.
#[test]
fn a_value_outside_its_prediction_is_flagged() {
    let dir = workdir("outside");
    let mut short = truth();
    short.joints[2].link[2] -= 0.040;
    write_truth(&dir, &short);
    simulate(&dir, "length", "20", &[], "bar.csv");
    let mut text = quatarm_ref::calfile::write(&truth(), &["nominal"]);
    text.push_str("\n[uncertainty]\nprobing_mm = 0.002\n");
    std::fs::write(dir.join("budget.toml"), text).unwrap();
    let args = ["check", "bar.csv", "--calib", "budget.toml", "--predict"];
    let v = json(&dir, &[&args[..], &["--json"]].concat());
    let rows = v["tests"].as_array().unwrap();
    let outside = rows
        .iter()
        .filter(|t| t["outside_predicted"] == true)
        .count();
    // The bars not along link 3 may not change; most do, by far more than 2 µm.
    assert!(outside >= rows.len() / 2, "{v}");
    for t in rows {
        let (x, p) = (t["value_um"].as_f64().unwrap(), &t["predicted_um"]);
        let inside = x >= p["lo"].as_f64().unwrap() && x <= p["hi"].as_f64().unwrap();
        assert_eq!(t["outside_predicted"] == true, !inside, "{t}");
    }
    let o = armcal_ok(&args, &dir);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("OUTSIDE the predicted interval")
            && text.contains("outside the 95 % interval the calibration's budget predicts"),
        "{text}"
    );
}
