//! Issue 29's safety rails, from copies of the inputs: no command writes over one of its
//! inputs (F4), a private key is its owner's alone, a closed pipe ends quietly, and data
//! that look like a unit mistake are refused before any fit or decision.

#[allow(dead_code)]
mod common;

use common::{armcal, armcal_ok, workdir};
use std::path::Path;

fn copy_default6(d: &Path, name: &str) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/default-6.toml");
    std::fs::copy(src, d.join(name)).unwrap();
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
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
