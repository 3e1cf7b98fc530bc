//! The reproducers of issue 27 ("never a false promise") that concern the host tool: F1, F2,
//! F3 and F7 refused with the file and key named, or right. The inputs are copies of
//! `../shared/repro/round2/` in `tests/data/repro27/`.

mod common;

use common::armcal;
use std::path::{Path, PathBuf};

/// A folder with the reproducer files copied in.
fn dir_with(name: &str, files: &[&str]) -> PathBuf {
    common::repro_dir("repro27", name, files)
}

/// Runs armcal, requires a refusal (exit 1 or 2, `check` 3; no panic, nothing on stdout) and returns
/// its stderr.
#[track_caller]
fn refused(args: &[&str], dir: &Path) -> String {
    let o = armcal(args, dir);
    let err = common::refused(&o, &[]);
    // `check`'s 1 and 2 are verdicts: its errors exit 3.
    let error_code = if args.first() == Some(&"check") {
        matches!(o.status.code(), Some(3))
    } else {
        matches!(o.status.code(), Some(1 | 2))
    };
    assert!(error_code, "{:?} {args:?}: {err}", o.status);
    err
}

#[test]
fn f1_a_covariance_that_is_not_semi_definite_is_refused_with_its_key() {
    let d = dir_with("r27-f1", &["f1-indef-cov.toml", "reading.csv"]);
    for args in [
        &[
            "eval",
            "--calib",
            "f1-indef-cov.toml",
            "--uncertainty",
            "reading.csv",
        ][..],
        &[
            "eval",
            "--calib",
            "f1-indef-cov.toml",
            "--uncertainty",
            "--method",
            "monte-carlo",
            "--draws",
            "100",
            "reading.csv",
        ],
        &["table", "build", "f1-indef-cov.toml", "-o", "f1.bin"],
    ] {
        let err = refused(args, &d);
        assert!(
            err.contains("f1-indef-cov.toml")
                && err.contains("uncertainty.covariance[1]")
                && err.contains("positive semi-definite"),
            "{args:?}: {err}"
        );
    }
    assert!(!d.join("f1.bin").exists());
}

#[test]
fn f2_terms_beyond_the_tables_limits_are_refused_never_a_u95_of_0() {
    let d = dir_with(
        "r27-f2",
        &[
            "f2-huge-probing.toml",
            "f2-huge-encoder.toml",
            "reading.csv",
            "f7-data.csv",
            "arm.toml",
        ],
    );
    for (file, key) in [
        ("f2-huge-probing.toml", "uncertainty.probing_mm"),
        ("f2-huge-encoder.toml", "uncertainty.encoder_counts"),
    ] {
        let err = refused(
            &["eval", "--calib", file, "--uncertainty", "reading.csv"],
            &d,
        );
        assert!(
            err.contains(file) && err.contains(key) && err.contains("limit"),
            "{err}"
        );
    }
    let err = refused(
        &[
            "calibrate",
            "f7-data.csv",
            "--arm",
            "arm.toml",
            "--folds",
            "0",
            "--probing-mm",
            "1e200",
            "-o",
            "f2c.toml",
        ],
        &d,
    );
    assert!(
        err.contains("--probing-mm") && err.contains("1e200"),
        "{err}"
    );
    assert!(!d.join("f2c.toml").exists());
}

#[test]
fn f3_check_predict_with_such_a_budget_is_refused_not_a_hang() {
    let d = dir_with("r27-f3", &["f3-sphere.csv", "f2-huge-probing.toml"]);
    let t = std::time::Instant::now();
    let err = refused(
        &[
            "check",
            "f3-sphere.csv",
            "--calib",
            "f2-huge-probing.toml",
            "--predict",
            "--draws",
            "10",
        ],
        &d,
    );
    assert!(err.contains("uncertainty.probing_mm"), "{err}");
    assert!(t.elapsed().as_secs() < 20, "{:?}", t.elapsed());
}

#[test]
fn f7_a_fleet_file_given_twice_is_refused() {
    let d = dir_with("r27-f7", &["f7-data.csv", "arm.toml", "f7-prior1.toml"]);
    let err = refused(
        &[
            "calibrate",
            "f7-data.csv",
            "--arm",
            "arm.toml",
            "--folds",
            "0",
            "-o",
            "f7b.toml",
            "--fleet-prior",
            "f7-prior1.toml",
            "f7-prior1.toml",
            "f7-prior1.toml",
        ],
        &d,
    );
    assert!(
        err.contains("f7-prior1.toml") && err.contains("more than once"),
        "{err}"
    );
    assert!(!d.join("f7b.toml").exists());
}
