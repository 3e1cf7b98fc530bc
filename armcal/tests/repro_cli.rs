//! The reproducers of issue 15 ("never a wrong number") that concern the host tool: each
//! gives a clear error (file, line, column or key named; no partial output) or the right
//! answer. The inputs are copies of `../shared/repro/` in `tests/data/repro/`.

mod common;

use common::{armcal, armcal_ok, workdir, write_truth};
use std::path::{Path, PathBuf};

fn repro(name: &str) -> PathBuf {
    common::repro_file("repro", name)
}

/// A folder with the reproducer files copied in.
fn dir_with(name: &str, files: &[&str]) -> PathBuf {
    common::repro_dir("repro", name, files)
}

/// Runs armcal, requires a refusal (exit 1, no panic) and returns its stderr.
#[track_caller]
fn refused(args: &[&str], dir: &Path) -> String {
    let o = armcal(args, dir);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!err.contains("panicked"), "{err}");
    assert!(!o.status.success(), "accepted: {args:?}\n{err}");
    assert!(
        matches!(o.status.code(), Some(1 | 2)),
        "{:?}: {err}",
        o.status
    );
    err
}

/// The files in `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn d1_terms_only_without_an_effect_is_refused_not_a_panic() {
    let d = dir_with("d1", &["good-spat.csv"]);
    let err = refused(
        &[
            "calibrate",
            "good-spat.csv",
            "--terms",
            "only",
            "-o",
            "x.toml",
        ],
        &d,
    );
    assert!(err.contains("nothing to fit"), "{err}");
    assert_eq!(listing(&d), vec!["good-spat.csv"]);
}

#[test]
fn d2_a_start_arm_with_a_1e300_link_is_refused_with_its_key() {
    let d = dir_with("d2", &["good-point.csv", "c-link1e300.toml"]);
    for cmd in ["calibrate", "diagnose"] {
        let t = std::time::Instant::now();
        let err = refused(
            &[
                cmd,
                "good-point.csv",
                "--arm",
                "c-link1e300.toml",
                "-o",
                "x.toml",
            ],
            &d,
        );
        assert!(t.elapsed().as_secs() < 20, "{cmd} took {:?}", t.elapsed());
        assert!(
            err.contains("c-link1e300.toml: joint[2].link[2]: 1e300 is beyond"),
            "{err}"
        );
    }
}

#[test]
fn d3_spat_data_alone_cannot_fix_the_scale_calibrate_and_diagnose_refuse() {
    let d = dir_with("d3", &["good-spat.csv"]);
    for cmd in ["calibrate", "diagnose"] {
        let err = refused(&[cmd, "good-spat.csv", "-o", "x.toml"], &d);
        assert!(err.contains("cannot fix the arm's scale"), "{cmd}: {err}");
        assert!(err.contains("length"), "says what to record: {err}");
    }
    assert_eq!(listing(&d), vec!["good-spat.csv"], "nothing written");
}

#[test]
fn d3_effects_alone_on_spat_data_still_fit() {
    // A given geometry has its scale: fitting an effect alone is not affected.
    let d = dir_with("d3b", &["good-spat.csv"]);
    let o = armcal_ok(
        &[
            "calibrate",
            "good-spat.csv",
            "--terms",
            "only,+gravity_compliance:2",
            "--folds",
            "0",
            "-o",
            "x.toml",
        ],
        &d,
    );
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("do not fix where the arm stands"), "{text}");
}

#[test]
fn d5_outputs_that_would_overwrite_are_refused_before_the_fit() {
    let d = dir_with("d5", &["good-point.csv"]);
    let err = refused(&["calibrate", "good-point.csv", "-o", "x.bin"], &d);
    assert!(err.contains("would be the same file"), "{err}");
    let before = std::fs::read(d.join("good-point.csv")).unwrap();
    let err = refused(&["calibrate", "good-point.csv", "-o", "good-point.csv"], &d);
    assert!(err.contains("overwrite the data"), "{err}");
    assert_eq!(std::fs::read(d.join("good-point.csv")).unwrap(), before);
    assert_eq!(listing(&d), vec!["good-point.csv"]);
    // diagnose: an -o in a folder that does not exist leaves no figures behind.
    let err = refused(
        &[
            "diagnose",
            "good-point.csv",
            "--plots",
            "figs",
            "-o",
            "missing/x.toml",
        ],
        &d,
    );
    assert!(err.contains("does not exist"), "{err}");
    assert_eq!(listing(&d), vec!["good-point.csv"]);
}

#[test]
fn d6_absurd_finite_values_are_refused_where_they_are() {
    let d = dir_with(
        "d6",
        &["d-length-huge.csv", "c-probe-overflow.toml", "e-good.csv"],
    );
    let err = refused(&["calibrate", "d-length-huge.csv", "-o", "y.toml"], &d);
    assert!(
        err.contains("d-length-huge.csv: line 4, column length_mm: 1e308 is beyond"),
        "{err}"
    );
    let err = refused(
        &["eval", "--calib", "c-probe-overflow.toml", "e-good.csv"],
        &d,
    );
    assert!(
        err.contains("c-probe-overflow.toml: probe.vector[0]: 1e308 is beyond"),
        "{err}"
    );
    let err = refused(
        &[
            "simulate",
            "--truth",
            "c-probe-overflow.toml",
            "--kind",
            "point",
            "--count",
            "10",
            "--seed",
            "1",
            "-o",
            "s.csv",
        ],
        &d,
    );
    assert!(err.contains("probe.vector[0]"), "{err}");
    // A point at 1e308 mm, a reading at 1e300 °C.
    let h = "kind,group,j1,j2,j3,j4,j5,j6,x,y,z,temp_c\n";
    let good = "point,1,0.1,0.2,0.3,0.4,0.5,0.6,1,2,3,20\n";
    for (row, column) in [
        (
            "point,1,0.1,0.2,0.3,0.4,0.5,0.6,1,1e308,3,20\n",
            "column y: 1e308",
        ),
        (
            "point,1,0.1,0.2,0.3,0.4,0.5,0.6,1,2,3,1e300\n",
            "column temp_c: 1e300",
        ),
        (
            "point,1,0.1,0.2,0.3,0.4,5e13,0.6,1,2,3,20\n",
            "column j5: 5e13",
        ),
    ] {
        std::fs::write(d.join("bad.csv"), format!("{h}{good}{row}")).unwrap();
        for cmd in ["calibrate", "diagnose"] {
            let err = refused(&[cmd, "bad.csv", "-o", "z.toml"], &d);
            assert!(err.contains(&format!("bad.csv: line 3, {column}")), "{err}");
        }
    }
}

#[test]
fn d6_zero_offset_1e300_is_refused() {
    let d = workdir("d6z");
    let text = quatarm_ref::calfile::write(&quatarm_ref::Arm::default6(), &[]);
    let text = text.replacen("zero_offset = 0.0", "zero_offset = 1e300", 1);
    std::fs::write(d.join("a.toml"), text).unwrap();
    std::fs::copy(repro("e-good.csv"), d.join("e-good.csv")).unwrap();
    let err = refused(&["eval", "--calib", "a.toml", "e-good.csv"], &d);
    assert!(
        err.contains("joint[1].zero_offset: 1e300 is beyond"),
        "{err}"
    );
}

#[test]
fn d7_line_numbers_count_comment_and_blank_lines() {
    let d = dir_with("d7", &["d-midcomment.csv"]);
    let err = refused(&["calibrate", "d-midcomment.csv", "-o", "z.toml"], &d);
    assert!(
        err.contains("d-midcomment.csv: line 4, column j4: `oops` is not a number"),
        "{err}"
    );
    let text = "kind,group,j1,j2,j3,j4,j5,j6,x,y,z\n\npoint,1,0,0,0,0,0,0,1,2,3\n\n\n# c\npoint,1,0,x,0,0,0,0,1,2,3\n";
    std::fs::write(d.join("b.csv"), text).unwrap();
    let err = refused(&["calibrate", "b.csv", "-o", "z.toml"], &d);
    assert!(err.contains("b.csv: line 7, column j2"), "{err}");
}

#[test]
fn d10_simulate_refuses_a_huge_count_and_a_zero_bar_before_any_work() {
    let d = workdir("d10");
    write_truth(&d, &quatarm_ref::Arm::default6());
    let common = [
        "simulate",
        "--truth",
        "truth.toml",
        "--seed",
        "1",
        "-o",
        "s.csv",
    ];
    let err = refused(
        &[&common[..], &["--kind", "point", "--count", "100000000000"]].concat(),
        &d,
    );
    assert!(err.contains("--count"), "{err}");
    for bar in ["0", "-5", "nan", "1e308"] {
        let arg = format!("--bar-mm={bar}");
        let err = refused(
            &[&common[..], &["--kind", "length", "--count", "20", &arg]].concat(),
            &d,
        );
        assert!(err.contains("--bar-mm"), "{err}");
    }
    let err = refused(
        &[
            &common[..],
            &["--kind", "point", "--count", "20", "--temp", "16..1e300"],
        ]
        .concat(),
        &d,
    );
    assert!(err.contains("-80..120"), "{err}");
    assert_eq!(listing(&d), vec!["truth.toml"]);
}

#[test]
fn arguments_are_checked_before_any_fit() {
    let d = dir_with("args", &["good-point.csv"]);
    for (arg, value) in [
        ("--significance", "nan"),
        ("--significance", "-1"),
        ("--prior-angle", "inf"),
        ("--max-iter", "0"),
    ] {
        let pair = format!("{arg}={value}");
        let mut args = vec!["calibrate", "good-point.csv", "-o", "x.toml", &pair];
        if arg == "--prior-angle" {
            args.extend(["--prior-length", "1"]);
        }
        let err = refused(&args, &d);
        assert!(
            err.contains(&format!("invalid value '{value}' for '{arg}")),
            "{err}"
        );
    }
    let err = refused(
        &[
            "calibrate",
            "good-point.csv",
            "-o",
            "x.toml",
            "--terms",
            "+encoder_harmonic:1:4294967295",
        ],
        &d,
    );
    assert!(err.contains("order 4294967295 is beyond 65535"), "{err}");
    let err = refused(&["diagnose", "good-point.csv", "--alpha", "nan"], &d);
    assert!(err.contains("--alpha"), "{err}");
    assert_eq!(listing(&d), vec!["good-point.csv"]);
}

#[test]
fn eval_reads_its_header_and_numbers_by_the_data_rules() {
    let d = workdir("eval");
    std::fs::write(
        d.join("a.toml"),
        quatarm_ref::calfile::write(&quatarm_ref::Arm::default6(), &[]),
    )
    .unwrap();
    for (csv, want) in [
        ("j1,j2,j3,j4,j5,j6,j7\n0,0,0,0,0,0,0\n", "column j7"),
        (
            "j1,j2,j3,j4,j5,j6,j1\n0,0,0,0,0,0,0\n",
            "column j1: column appears twice",
        ),
        (
            "j1,j2,j3,j4,j5,j6,temp_c\n0,0,0,0,0,0,121\n",
            "line 2, column temp_c: 121 is outside -80..120",
        ),
        (
            "j1,j2,j3,j4,j5,j6\n# c\n0,0,0,1e14,0,0\n",
            "line 3, column j4: 1e14 is beyond",
        ),
    ] {
        std::fs::write(d.join("in.csv"), csv).unwrap();
        for p in ["f64", "f32", "fixed"] {
            let err = refused(
                &["eval", "--calib", "a.toml", "--precision", p, "in.csv"],
                &d,
            );
            assert!(err.contains(want), "{csv}: {err}");
        }
    }
    // The same temperature rule for the measured data.
    std::fs::write(
        d.join("m.csv"),
        "kind,group,j1,j2,j3,j4,j5,j6,x,y,z,temp_c\npoint,1,0,0,0,0,0,0,1,2,3,121\n",
    )
    .unwrap();
    let err = refused(&["calibrate", "m.csv", "-o", "x.toml"], &d);
    assert!(
        err.contains("line 2, column temp_c: 121 is outside -80..120"),
        "{err}"
    );
}

#[test]
fn calibration_file_messages_name_line_joint_and_character() {
    let d = workdir("calmsg");
    std::fs::copy(repro("e-good.csv"), d.join("e-good.csv")).unwrap();
    let base = quatarm_ref::calfile::write(&quatarm_ref::Arm::default6(), &[]);
    // A duplicate key in the third joint.
    let mut parts: Vec<&str> = base.split("[[joint]]").collect();
    let third = parts[3].replacen("axis = \"z\"", "axis = \"z\"\naxis = \"z\"", 1);
    parts[3] = &third;
    std::fs::write(d.join("dup.toml"), parts.join("[[joint]]")).unwrap();
    let err = refused(&["eval", "--calib", "dup.toml", "e-good.csv"], &d);
    assert!(err.contains("dup.toml: line "), "{err}");
    assert!(
        err.contains("duplicate key") && err.contains("(in joint[3])"),
        "{err}"
    );
    std::fs::write(
        d.join("nul.toml"),
        format!("serial = \"AB\\u0000\"\n{base}"),
    )
    .unwrap();
    let err = refused(&["eval", "--calib", "nul.toml", "e-good.csv"], &d);
    assert!(
        err.contains("serial: has a NUL character (byte 3)"),
        "{err}"
    );
}

#[test]
fn a_huge_column_name_is_not_echoed_whole() {
    let d = workdir("longname");
    let name = "q".repeat(1_000_000);
    std::fs::write(
        d.join("w.csv"),
        format!("kind,group,j1,j2,j3,j4,j5,j6,x,y,z,{name},{name}\n"),
    )
    .unwrap();
    let err = refused(&["calibrate", "w.csv", "-o", "x.toml"], &d);
    assert!(err.len() < 1000, "{} bytes of message", err.len());
    assert!(err.contains("(1000000 bytes)"), "{err}");
}

#[test]
fn progress_is_shown_when_asked() {
    let d = dir_with("progress", &["good-point.csv"]);
    let o = armcal_ok(
        &[
            "calibrate",
            "good-point.csv",
            "--folds",
            "2",
            "--progress",
            "-o",
            "x.toml",
        ],
        &d,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("calibrating: identifiability of"), "{err}");
    assert!(err.contains("held-out validation, fold 2 of 2"), "{err}");
    // Not asked, not a terminal: nothing.
    let o = armcal(&["calibrate", "good-point.csv", "-o", "x.toml"], &d);
    assert!(!String::from_utf8_lossy(&o.stderr).contains("calibrating"));
}
