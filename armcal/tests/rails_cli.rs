//! Issue 29's safety rails, from copies of the inputs: no command writes over one of its
//! inputs (F4), a private key is its owner's alone, a closed pipe ends quietly, and data
//! that look like a unit mistake are refused before any fit or decision.

#[allow(dead_code)]
mod common;

use common::{armcal, armcal_ok, refused, stderr, workdir};
use std::path::Path;

fn copy_default6(d: &Path, name: &str) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/default-6.toml");
    std::fs::copy(src, d.join(name)).unwrap();
}

/// F4: `table build CAL.toml -o CAL.toml` and `table sign T.bin --key K.pem -o K.pem` are
/// refused, exit non-zero, and leave the input as it was.
#[test]
fn table_build_and_sign_never_write_over_their_inputs() {
    let d = workdir("f4");
    copy_default6(&d, "cal.toml");
    let before = std::fs::read(d.join("cal.toml")).unwrap();
    let o = armcal(&["table", "build", "cal.toml", "-o", "cal.toml"], &d);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("would overwrite the calibration file"),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::read(d.join("cal.toml")).unwrap(), before);
    // Through another name of the same file (a symbolic link) too.
    std::os::unix::fs::symlink(d.join("cal.toml"), d.join("alias.toml")).unwrap();
    let o = armcal(&["table", "build", "cal.toml", "-o", "alias.toml"], &d);
    assert!(!o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read(d.join("cal.toml")).unwrap(), before);

    armcal_ok(&["table", "build", "cal.toml", "-o", "t.bin"], &d);
    armcal_ok(&["table", "keygen", "--out", "maker"], &d);
    let key = std::fs::read(d.join("maker.pem")).unwrap();
    let o = armcal(
        &[
            "table",
            "sign",
            "t.bin",
            "--key",
            "maker.pem",
            "-o",
            "maker.pem",
        ],
        &d,
    );
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("would overwrite the private key"),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::read(d.join("maker.pem")).unwrap(), key);
    let table = std::fs::read(d.join("t.bin")).unwrap();
    let o = armcal(
        &[
            "table",
            "sign",
            "t.bin",
            "--key",
            "maker.pem",
            "-o",
            "t.bin",
        ],
        &d,
    );
    assert!(!o.status.success());
    assert_eq!(std::fs::read(d.join("t.bin")).unwrap(), table);
    // Signing to a new file still works.
    armcal_ok(
        &[
            "table",
            "sign",
            "t.bin",
            "--key",
            "maker.pem",
            "-o",
            "s.bin",
        ],
        &d,
    );
    armcal_ok(&["table", "verify", "s.bin", "--key", "maker.pub"], &d);
}

/// `table keygen` writes the private key 0600 and never overwrites a key.
#[test]
fn keygen_writes_the_private_key_for_its_owner_only_and_keeps_old_keys() {
    use std::os::unix::fs::PermissionsExt;
    let d = workdir("keygen");
    armcal_ok(&["table", "keygen", "--out", "maker"], &d);
    let mode = std::fs::metadata(d.join("maker.pem"))
        .unwrap()
        .permissions()
        .mode();
    assert_eq!(mode & 0o777, 0o600, "private key mode {mode:o}");
    let key = std::fs::read(d.join("maker.pem")).unwrap();
    let o = armcal(&["table", "keygen", "--out", "maker"], &d);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("never overwritten"), "{}", stderr(&o));
    assert_eq!(std::fs::read(d.join("maker.pem")).unwrap(), key);
}

/// `accuracy --write-calib` onto its own `--calib` is refused like every other output.
#[test]
fn accuracy_write_calib_over_its_calib_is_refused() {
    let d = workdir("accuracy");
    copy_default6(&d, "cal.toml");
    let before = std::fs::read(d.join("cal.toml")).unwrap();
    let o = armcal(
        &[
            "accuracy",
            "--calib",
            "cal.toml",
            "--write-calib",
            "cal.toml",
        ],
        &d,
    );
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("would overwrite the calibration"),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::read(d.join("cal.toml")).unwrap(), before);
}

/// `armcal … | head`: a reader that closes the pipe ends armcal quietly, as it does coreutils
/// (no "Broken pipe" error, no panic), with the pipe's status (141, killed by SIGPIPE).
#[test]
fn a_closed_pipe_ends_quietly() {
    use std::process::{Command, Stdio};
    let d = workdir("pipe");
    copy_default6(&d, "cal.toml");
    armcal_ok(
        &[
            "simulate",
            "--truth",
            "cal.toml",
            "--seed",
            "1",
            "--test",
            "iso10360-12",
            "-o",
            "t.csv",
        ],
        &d,
    );
    for args in [
        &["check", "t.csv", "--calib", "cal.toml", "--json"][..],
        &["check", "t.csv", "--calib", "cal.toml"][..],
        &["table", "show", "--help"][..],
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_armcal"))
            .args(args)
            .current_dir(&d)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // The reader goes away before anything is written.
        drop(child.stdout.take());
        let o = child.wait_with_output().unwrap();
        let err = stderr(&o);
        assert!(
            !err.contains("Broken pipe") && !err.contains("panicked"),
            "{args:?}: {err}"
        );
        assert!(err.is_empty(), "{args:?}: {err}");
    }
}

/// A copy of CSV `src` with `f` applied to the cells of the columns `cols` (by header name).
fn rewrite(src: &Path, dst: &Path, cols: &[&str], f: impl Fn(f64) -> f64) {
    let text = std::fs::read_to_string(src).unwrap();
    let mut idx = Vec::new();
    let mut out = String::new();
    for line in text.lines() {
        if line.starts_with('#') {
        } else if idx.is_empty() {
            let names: Vec<&str> = line.split(',').collect();
            idx = cols
                .iter()
                .map(|c| names.iter().position(|n| n == c).unwrap())
                .collect();
        } else {
            let mut cells: Vec<String> = line.split(',').map(str::to_string).collect();
            for &i in &idx {
                if let Ok(x) = cells[i].parse::<f64>() {
                    cells[i] = f(x).to_string();
                }
            }
            out += &cells.join(",");
            out += "\n";
            continue;
        }
        out += line;
        out += "\n";
    }
    std::fs::write(dst, out).unwrap();
}

/// The unit mistakes of issue 29, on copies of simulated data: each refused before any fit
/// with what looks wrong and the `--accept-…` flag; the flag lets it through.
#[test]
fn unit_mistakes_are_refused_before_any_fit() {
    let d = workdir("units");
    copy_default6(&d, "cal.toml");
    armcal_ok(
        &[
            "simulate", "--truth", "cal.toml", "--seed", "2", "--kind", "point", "--count", "120",
            "--temp", "16..28", "-o", "p.csv",
        ],
        &d,
    );
    let cal = |data: &str, extra: &[&str]| {
        let mut args = vec!["calibrate", data, "--folds", "0", "-o", "out.toml"];
        args.extend_from_slice(extra);
        armcal(&args, &d)
    };
    // The data as simulated pass.
    assert!(cal("p.csv", &[]).status.success());
    std::fs::remove_file(d.join("out.toml")).unwrap();

    rewrite(&d.join("p.csv"), &d.join("m.csv"), &["x", "y", "z"], |v| {
        v / 1000.0
    });
    refused(
        &cal("m.csv", &[]),
        &["m.csv", "in metres? multiply by 1000", "--accept-units"],
    );
    assert!(!d.join("out.toml").exists(), "no output when refused");
    rewrite(&d.join("p.csv"), &d.join("in.csv"), &["x", "y", "z"], |v| {
        v / 25.4
    });
    refused(&cal("in.csv", &[]), &["in inches? multiply by 25.4"]);
    let joints = ["j1", "j2", "j3", "j4", "j5", "j6"];
    rewrite(
        &d.join("p.csv"),
        &d.join("deg.csv"),
        &joints,
        f64::to_degrees,
    );
    refused(
        &cal("deg.csv", &[]),
        &["rad on line", "in degrees?", "--accept-units"],
    );
    rewrite(&d.join("p.csv"), &d.join("f.csv"), &["temp_c"], |c| {
        c * 1.8 + 32.0
    });
    refused(
        &cal("f.csv", &[]),
        &["temp_c = ", "in °F?", "--accept-temperature"],
    );
    // Accepted deliberately, the temperature goes on to the fit.
    let o = cal("f.csv", &["--accept-temperature"]);
    assert!(!stderr(&o).contains("in °F"), "{}", stderr(&o));
    // diagnose has the same rails.
    let o = armcal(&["diagnose", "m.csv"], &d);
    refused(&o, &["in metres?"]);
}

/// `check`: an MPE in µm written as mm, and another arm's calibration, refused before any
/// decision.
#[test]
fn check_refuses_mpe_in_the_wrong_unit_and_another_arms_calibration() {
    let d = workdir("checkrails");
    copy_default6(&d, "cal.toml");
    armcal_ok(
        &[
            "simulate",
            "--truth",
            "cal.toml",
            "--seed",
            "1",
            "--test",
            "iso10360-12",
            "-o",
            "t.csv",
        ],
        &d,
    );
    std::fs::write(d.join("mpe.toml"), "P_Size = 20\nP_Form = 0.015\n").unwrap();
    let o = armcal(
        &["check", "t.csv", "--calib", "cal.toml", "--mpe", "mpe.toml"],
        &d,
    );
    refused(
        &o,
        &["mpe.toml", "P_Size = 20 mm", "write 0.02", "--accept-mpe"],
    );
    assert!(o.stdout.is_empty(), "no decision printed");
    // Another arm of six joints (MUKCa's Gen3 lite) as the calibration.
    let other =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/mukca/mukca-gen3lite-dinova_1.toml");
    std::fs::copy(other, d.join("other.toml")).unwrap();
    let o = armcal(&["check", "t.csv", "--calib", "other.toml"], &d);
    refused(&o, &["t.csv", "length group", "this arm", "--accept-units"]);
    let o = armcal(
        &["check", "t.csv", "--calib", "other.toml", "--accept-units"],
        &d,
    );
    refused(
        &o,
        &["other.toml", "this arm's calibration", "--accept-misfit"],
    );
    assert!(o.stdout.is_empty(), "no decision printed");
}

/// MUKCa panda_3 (one arm's real data): the weak results are flagged in the calibration
/// report, the condition number and the link 6 error of +6.3 mm ± 7.7 mm among them.
#[test]
fn weak_results_are_flagged_in_the_calibration_report() {
    let d = workdir("weak");
    let m = Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/mukca");
    for f in ["mukca-panda-panda_3.csv", "mukca-panda-panda_3.toml"] {
        std::fs::copy(m.join(f), d.join(f)).unwrap();
    }
    let o = armcal_ok(
        &[
            "calibrate",
            "mukca-panda-panda_3.csv",
            "--arm",
            "mukca-panda-panda_3.toml",
            "--folds",
            "0",
            "-o",
            "out.toml",
            "--json",
        ],
        &d,
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let weak: Vec<&str> = v["weak"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w.as_str().unwrap())
        .collect();
    assert!(
        weak.iter().any(|w| w.starts_with("condition number")),
        "{weak:?}"
    );
    assert!(
        weak.iter()
            .any(|w| w.starts_with("link 6 error along x") && w.contains("% of the link")),
        "{weak:?}"
    );
    assert!(
        weak.iter()
            .any(|w| w.contains("no larger than their standard uncertainty")),
        "{weak:?}"
    );
}

/// A `;`-separated file (a comma-decimal spreadsheet) reads as the `,` one; a separator the
/// reader does not know is named in the error; a missing file's path is said once.
#[test]
fn separators_are_detected_and_a_missing_file_is_named_once() {
    let d = workdir("sep");
    copy_default6(&d, "cal.toml");
    armcal_ok(
        &[
            "simulate",
            "--truth",
            "cal.toml",
            "--seed",
            "3",
            "--test",
            "iso10360-12",
            "-o",
            "t.csv",
        ],
        &d,
    );
    let text = std::fs::read_to_string(d.join("t.csv")).unwrap();
    std::fs::write(d.join("semi.csv"), text.replace(',', ";")).unwrap();
    std::fs::write(d.join("tab.csv"), text.replace(',', "\t")).unwrap();
    std::fs::write(d.join("bar.csv"), text.replace(',', "|")).unwrap();
    let comma = armcal_ok(&["check", "t.csv", "--calib", "cal.toml", "--json"], &d);
    for f in ["semi.csv", "tab.csv"] {
        let o = armcal_ok(&["check", f, "--calib", "cal.toml", "--json"], &d);
        assert_eq!(o.stdout, comma.stdout, "{f}");
    }
    let o = armcal(&["check", "bar.csv", "--calib", "cal.toml"], &d);
    refused(
        &o,
        &["bar.csv", "one column", "separated by `,`, `;` or tab"],
    );
    for args in [
        &["check", "nosuch.csv", "--calib", "cal.toml"][..],
        &[
            "check",
            "t.csv",
            "--calib",
            "cal.toml",
            "--mpe",
            "nosuch.csv",
        ][..],
        &[
            "table",
            "sign",
            "nosuch.csv",
            "--key",
            "nosuch.pem",
            "-o",
            "x.bin",
        ][..],
    ] {
        let o = armcal(args, &d);
        let err = stderr(&o);
        assert!(!o.status.success());
        assert_eq!(err.matches("nosuch").count(), 1, "{err}");
        assert_eq!(err.matches("No such file").count(), 1, "{err}");
    }
}
