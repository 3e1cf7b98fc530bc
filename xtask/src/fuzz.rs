//! `cargo xtask fuzz`: the libFuzzer targets of `fuzz/` (cargo-fuzz), long runs on demand and
//! a short smoke run of each in `cargo xtask test`.
//!
//! cargo-fuzz passes unstable flags to rustc; `RUSTC_BOOTSTRAP=1` lets the stable compiler
//! take them, so no nightly tool chain is needed. The targets are built without a sanitizer
//! (`-s none`): the fuzzed code is safe Rust, where what a fuzzer can find is a panic or an
//! arithmetic overflow (overflow checks are on, `-a`), and AddressSanitizer would halve the
//! executions for nothing. The committed corpus (`fuzz/corpus/<target>`) is only read; what a
//! run discovers goes to `fuzz/work/` and its crashes to `fuzz/artifacts/` (both ignored by
//! git).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use host_tests::boards::root;

use crate::build::check;

/// Every fuzz target, as `fuzz/Cargo.toml` declares them.
pub const TARGETS: [&str; 9] = [
    "table_parse",
    "hub_frames",
    "host_frames",
    "chain_eval",
    "chain_arm_accuracy",
    "data_csv",
    "calfile_toml",
    "update_session",
    "update_rollback",
];

/// Seconds of each target's smoke run in `cargo xtask test`.
pub const SMOKE_SECONDS: u32 = 5;

fn fuzz_dir() -> PathBuf {
    root().join("fuzz")
}

/// `cargo fuzz <sub>` in `fuzz/`, with the environment the stable compiler needs.
fn cargo_fuzz(sub: &str) -> Command {
    let mut c = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    c.current_dir(fuzz_dir())
        .args(["fuzz", sub])
        .env("RUSTC_BOOTSTRAP", "1")
        .env_remove("RUSTFLAGS")
        .env_remove("CARGO_ENCODED_RUSTFLAGS")
        .env_remove("CARGO_TARGET_DIR");
    c
}

/// Build options, the same for every build so that the smoke run and long runs share one.
const BUILD_FLAGS: [&str; 5] = ["-s", "none", "-a", "--codegen-units", "16"];

/// True if `cargo fuzz` runs.
pub fn cargo_fuzz_present() -> bool {
    cargo_fuzz("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Installs cargo-fuzz from crates.io if `cargo fuzz` does not run.
pub fn ensure_cargo_fuzz() -> Result<()> {
    if cargo_fuzz_present() {
        return Ok(());
    }
    eprintln!(
        "xtask: cargo-fuzz is missing; it builds and runs the libFuzzer targets of fuzz/ (the fuzz smoke run of `cargo xtask test`, `cargo xtask fuzz`): cargo install cargo-fuzz --locked"
    );
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    check(
        Command::new(cargo).args(["install", "cargo-fuzz", "--locked"]),
        "cargo install cargo-fuzz --locked",
    )
}

/// Builds every target.
pub fn build() -> Result<()> {
    ensure_cargo_fuzz()?;
    check(
        cargo_fuzz("build").args(BUILD_FLAGS),
        "cargo fuzz build (fuzz/)",
    )
}

/// One target's run.
pub struct Outcome {
    /// Inputs executed.
    pub executions: u64,
    /// Seconds it ran.
    pub seconds: f64,
    /// The reproducer libFuzzer wrote, if the target failed.
    pub crash: Option<PathBuf>,
}

/// Runs `target` for `seconds`, reading the committed corpus, writing what it finds into
/// `work` (its first corpus directory) and a crash into `artifacts`.
fn run_target(target: &str, seconds: u32, work: &Path, artifacts: &Path) -> Result<Outcome> {
    let corpus = fuzz_dir().join("corpus").join(target);
    std::fs::create_dir_all(&corpus)?;
    std::fs::create_dir_all(work)?;
    std::fs::create_dir_all(artifacts)?;
    let log = work.with_extension("log");
    let start = Instant::now();
    let status = cargo_fuzz("run")
        .args(BUILD_FLAGS)
        .arg(target)
        .arg(work)
        .arg(&corpus)
        .arg("--")
        .arg(format!("-max_total_time={seconds}"))
        .arg(format!("-artifact_prefix={}/", artifacts.display()))
        .arg("-print_final_stats=1")
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(&log)?)
        .status()
        .with_context(|| format!("starting cargo fuzz run {target}"))?;
    let seconds = start.elapsed().as_secs_f64();
    let text = std::fs::read_to_string(&log).unwrap_or_default();
    let executions = text
        .lines()
        .find_map(|l| l.strip_prefix("stat::number_of_executed_units:"))
        .and_then(|n| n.trim().parse().ok())
        .unwrap_or(0);
    let crash = text.lines().find_map(|l| {
        l.split_once("Test unit written to ")
            .map(|(_, p)| PathBuf::from(p.trim()))
    });
    if !status.success() && crash.is_none() {
        bail!(
            "cargo fuzz run {target} failed ({status}) without a reproducer; log: {}",
            log.display()
        );
    }
    Ok(Outcome {
        executions,
        seconds,
        crash,
    })
}

/// Runs `targets` for `seconds` each; fails if any crashed, naming the reproducers.
fn run_all(targets: &[&str], seconds: u32, work_root: &Path) -> Result<()> {
    build()?;
    let mut crashes = Vec::new();
    for t in targets {
        let o = run_target(
            t,
            seconds,
            &work_root.join("corpus").join(t),
            &fuzz_dir().join("artifacts").join(t),
        )?;
        eprintln!(
            "xtask fuzz: {t}: {} executions in {:.0} s ({:.0}/s), {}",
            o.executions,
            o.seconds,
            o.executions as f64 / o.seconds.max(1e-9),
            match &o.crash {
                Some(p) => format!("CRASH, reproducer {}", p.display()),
                None => "0 crashes".into(),
            }
        );
        crashes.extend(o.crash.map(|p| (t, p)));
    }
    if !crashes.is_empty() {
        let list: Vec<String> = crashes
            .iter()
            .map(|(t, p)| {
                format!(
                    "{t}: {} (rerun: cd fuzz && RUSTC_BOOTSTRAP=1 cargo fuzz run {t} {})",
                    p.display(),
                    p.display()
                )
            })
            .collect();
        bail!("fuzz targets crashed:\n  {}", list.join("\n  "));
    }
    Ok(())
}

/// `cargo xtask fuzz [--target NAME] [--seconds N]`: long runs, what they find kept in
/// `fuzz/work/corpus/<target>` for the next run.
pub fn run(target: Option<&str>, seconds: u32) -> Result<()> {
    let targets: Vec<&str> = match target {
        Some(t) if TARGETS.contains(&t) => vec![t],
        Some(t) => bail!("no fuzz target {t}; the targets are {}", TARGETS.join(", ")),
        None => TARGETS.to_vec(),
    };
    run_all(&targets, seconds, &fuzz_dir().join("work"))
}

/// The smoke run of `cargo xtask test`: every target for [`SMOKE_SECONDS`], from the
/// committed corpus, discoveries thrown away.
pub fn smoke() -> Result<()> {
    let tmp = std::env::temp_dir().join(format!("quatarm-fuzz-smoke-{}", std::process::id()));
    let result = run_all(&TARGETS, SMOKE_SECONDS, &tmp);
    let _ = std::fs::remove_dir_all(&tmp);
    result
}
