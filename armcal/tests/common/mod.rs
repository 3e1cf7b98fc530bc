//! What the CLI tests share: running the `armcal` binary of this build as a user does, each
//! test in a folder of its own.

use quatarm_ref::arm::Arm;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs `armcal args…` in `dir`.
pub fn armcal(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_armcal"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run armcal")
}

/// Runs `armcal args…` in `dir` and requires it to succeed; a failure shows armcal's stderr.
#[track_caller]
pub fn armcal_ok(args: &[&str], dir: &Path) -> Output {
    let o = armcal(args, dir);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

/// A fresh, empty folder for the test `name` of this test binary (the binary's name and the
/// process id keep suites and concurrent runs apart).
pub fn workdir(name: &str) -> PathBuf {
    let suite = env!("CARGO_CRATE_NAME").replace('_', "-");
    let d = std::env::temp_dir().join(format!("armcal-{suite}-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[allow(dead_code)]
/// Writes `truth` to `dir/truth.toml`, the file the tests' `armcal simulate --truth` reads.
pub fn write_truth(dir: &Path, truth: &Arm) {
    std::fs::write(
        dir.join("truth.toml"),
        quatarm_ref::calfile::write(truth, &["truth"]),
    )
    .unwrap();
}

/// `armcal simulate --truth truth.toml --kind KIND --count COUNT --seed SEED EXTRA… -o OUT` in
/// `dir`, required to succeed.
#[allow(dead_code)]
pub fn simulate(dir: &Path, kind: &str, count: &str, seed: &str, extra: &[&str], out: &str) {
    let mut args = vec![
        "simulate",
        "--truth",
        "truth.toml",
        "--kind",
        kind,
        "--count",
        count,
        "--seed",
        seed,
    ];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["-o", out]);
    armcal_ok(&args, dir);
}

/// The width and height of a PNG file, after checking its signature and header.
#[allow(dead_code)]
pub fn png_size(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(
        &b[..8],
        b"\x89PNG\r\n\x1a\n",
        "{} is not a PNG",
        path.display()
    );
    assert_eq!(&b[12..16], b"IHDR");
    let w = u32::from_be_bytes(b[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(b[20..24].try_into().unwrap());
    (w, h)
}

/// A folder with copies of reproducer inputs: `files` from `tests/data/SET/` (each set a copy
/// of one of `../shared/repro/`'s folders, so the tests do not need `../shared`).
#[allow(dead_code)]
pub fn repro_dir(set: &str, name: &str, files: &[&str]) -> PathBuf {
    let d = workdir(name);
    for f in files {
        std::fs::copy(repro_file(set, f), d.join(f)).unwrap();
    }
    d
}

/// One reproducer input, `tests/data/SET/NAME`.
#[allow(dead_code)]
pub fn repro_file(set: &str, name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(set)
        .join(name)
}

/// armcal's stderr, as text.
#[allow(dead_code)]
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Requires that armcal refused: a non-zero exit that is no panic, nothing on stdout (no
/// partial output), and a message holding every one of `needles` (what looks wrong, the file,
/// the flag to accept it…); returns the message. The one shape of every refusal test.
#[allow(dead_code)]
#[track_caller]
pub fn refused(o: &Output, needles: &[&str]) -> String {
    let e = stderr(o);
    assert!(!o.status.success(), "accepted: {e}");
    assert!(!e.contains("panicked"), "{e}");
    assert!(
        o.stdout.is_empty(),
        "partial output: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    for n in needles {
        assert!(e.contains(n), "`{n}` not in: {e}");
    }
    e
}

/// [`refused`] with exit code `code` (`check`'s errors are 3: its 1 and 2 are verdicts).
#[allow(dead_code)]
#[track_caller]
pub fn refused_with(o: &Output, code: i32, needles: &[&str]) -> String {
    let e = refused(o, needles);
    assert_eq!(o.status.code(), Some(code), "{e}");
    e
}

/// A fresh folder for the test `name` holding copies of `files` from `armcal/tests/data/SET/`
/// and of the project's `data/default-6.toml` as `default-6.toml`.
#[allow(dead_code)]
pub fn with_copies(set: &str, name: &str, files: &[&str]) -> PathBuf {
    let d = workdir(name);
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for f in files {
        std::fs::copy(root.join("tests/data").join(set).join(f), d.join(f))
            .unwrap_or_else(|e| panic!("copy {set}/{f}: {e}"));
    }
    std::fs::copy(
        root.join("../data/default-6.toml"),
        d.join("default-6.toml"),
    )
    .unwrap();
    d
}

/// Simulated `data` cut into `sessions` sessions (row i in group 1 + i mod `sessions`), as a
/// dataset named `name`: the shape the diagnosis and fleet tests hold sessions out of.
#[allow(dead_code)]
pub fn in_sessions(
    data: armcal::data::Dataset,
    sessions: usize,
    name: &str,
) -> armcal::data::Dataset {
    let rows = data
        .rows
        .into_iter()
        .enumerate()
        .map(|(i, mut r)| {
            r.group = 1 + (i % sessions) as i64;
            r
        })
        .collect();
    armcal::data::Dataset::from_rows(rows, 6, false, name).unwrap()
}
