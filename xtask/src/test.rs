//! `cargo xtask test`: the README's test command and what `.ci/run` runs.

use std::process::Command;
use std::time::Instant;

use anyhow::Result;
use host_tests::boards::{boards, root};

use crate::build::{build_board_with, check};
use crate::toolchain::{self, TOOLCHAIN_ENV};
use crate::{fuzz, setup};

fn cargo() -> Command {
    let mut c = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    c.current_dir(root());
    c
}

/// ", N.N GB free" on the disk the build writes to (empty where `df` cannot say): a run
/// that fills the disk shows where, as one did on a CI machine.
fn free_disk() -> String {
    let Ok(out) = Command::new("df").arg("-Pk").arg(root()).output() else {
        return String::new();
    };
    let text = String::from_utf8_lossy(&out.stdout);
    text.lines()
        .nth(1)
        .and_then(|l| l.split_whitespace().nth(3))
        .and_then(|kib| kib.parse::<f64>().ok())
        .map(|kib| format!(", {:.1} GB free", kib / 1_048_576.0))
        .unwrap_or_default()
}

/// Runs every check in order, stopping at the first failure: each stage below is one step
/// of the log, timed from the start with the disk's free space.
pub fn run() -> Result<()> {
    let start = Instant::now();
    let step = |name: &str| {
        eprintln!(
            "\nxtask test: {name} [{:.0?}{}]",
            start.elapsed(),
            free_disk()
        )
    };
    setup::ensure()?;
    step("rustfmt");
    formatting()?;
    step("clippy");
    check(
        cargo().args([
            "clippy",
            "--workspace",
            "--all-targets",
            "--",
            "-D",
            "warnings",
        ]),
        "cargo clippy",
    )?;
    host_tests(&step)?;
    step("fuzz smoke run");
    // Each target for a few seconds from the committed corpus: a target that no longer builds
    // or an input of the corpus that now crashes fails the run. Long runs: `cargo xtask fuzz`.
    check(
        cargo()
            .args(["fmt", "--manifest-path"])
            .arg(root().join("fuzz/Cargo.toml"))
            .args(["--", "--check"]),
        "cargo fmt --check in fuzz",
    )?;
    fuzz::smoke()?;
    // Every firmware tool chain this machine has: the images differ (rustup links a prebuilt
    // compiler_builtins, Debian's builds it from source), so each must meet the budgets.
    let survey = toolchain::survey();
    survey.primary()?;
    eprintln!("\nxtask test: firmware tool chains\n{}", survey.describe());
    boards_built_and_linted(&survey, &step)?;
    qemu_end_to_end(&survey, &step)?;
    eprintln!(
        "\nxtask test: all passed in {:.0?}{}; firmware tool chains:\n{}",
        start.elapsed(),
        free_disk(),
        survey.describe()
    );
    Ok(())
}

/// `cargo fmt --check` in the workspace, in each board's crate and in the boards' shared
/// crate (neither is in the workspace: they build for the targets).
fn formatting() -> Result<()> {
    check(
        cargo().args(["fmt", "--all", "--", "--check"]),
        "cargo fmt --check",
    )?;
    for b in boards()?
        .iter()
        .map(|b| b.dir())
        .chain([root().join("boards/common")])
    {
        check(
            cargo()
                .args(["fmt", "--manifest-path"])
                .arg(b.join("Cargo.toml"))
                .args(["--", "--check"]),
            &format!("cargo fmt --check in {}", b.display()),
        )?;
    }
    Ok(())
}

/// The tests that run on the host: the workspace's, the boards' shared crate's, and the
/// docs (rustdoc's warnings denied).
fn host_tests(step: &dyn Fn(&str)) -> Result<()> {
    step("workspace tests");
    check(
        cargo().args(["test", "--workspace"]),
        "cargo test --workspace",
    )?;

    step("the Pico's U95 (quatarm feature fixed-u95)");
    // The workspace builds quatarm without `fixed-u95` (no member asks for it): the Pico's
    // integer product is tested on its own, against f64 and against the host's U95.
    check(
        cargo().args([
            "test",
            "-p",
            "quatarm",
            "--features",
            "fixed-u95",
            "--lib",
            "uncertainty",
        ]),
        "cargo test -p quatarm --features fixed-u95 --lib uncertainty",
    )?;
    check(
        cargo().args([
            "test",
            "-p",
            "armcal",
            "--features",
            "quatarm/fixed-u95",
            "--test",
            "hub_u95",
        ]),
        "cargo test -p armcal --features quatarm/fixed-u95 --test hub_u95",
    )?;

    step("board-common unit tests (host)");
    // The boards' shared crate is in no workspace (it builds for the targets); its pure parts
    // (the boot check, the flash map and window, the update port) are tested on the host,
    // with the features of the full profile (qemu-m4f, nucleo-f446re, rp-pico: U95 with the
    // parameter block, the wobble) and without (qemu-m0's minimal profile).
    for features in [&[][..], &["--features", "u95 wobble"][..]] {
        check(
            cargo()
                .args(["test", "--lib", "--manifest-path"])
                .arg(root().join("boards/common/Cargo.toml"))
                .args(features),
            "cargo test --manifest-path boards/common/Cargo.toml",
        )?;
    }

    step("rustdoc");
    // Broken intra-doc links, private items linked from public docs, bad code-block syntax:
    // rustdoc only warns, so a warning fails here. (The doctests ran with the tests above.)
    check(
        cargo()
            .env("RUSTDOCFLAGS", "-D warnings")
            .args(["doc", "--workspace", "--no-deps"]),
        "RUSTDOCFLAGS=\"-D warnings\" cargo doc --workspace --no-deps",
    )
}

/// Every board built with every tool chain of `survey` (each must meet the budgets), then
/// clippy on the boards with rustup's, where there is one.
fn boards_built_and_linted(survey: &toolchain::Survey, step: &dyn Fn(&str)) -> Result<()> {
    for tc in &survey.available {
        step(&format!("board builds ({})", tc.version));
        for b in boards()? {
            build_board_with(b, tc)?;
        }
    }
    // Clippy needs rustup's: Debian's Rust ships none. The boards are clippy-clean with it.
    match survey
        .available
        .iter()
        .find(|tc| tc.kind == toolchain::Kind::Rustup)
    {
        Some(tc) => {
            step(&format!("clippy on the boards ({})", tc.version));
            for b in boards()? {
                let mut cmd = tc.cargo(&b.dir(), b.target, "clippy");
                cmd.args(["--release", "--locked", "--bins", "--", "-D", "warnings"]);
                check(&mut cmd, &format!("cargo clippy in {}", b.dir().display()))?;
            }
        }
        None => eprintln!(
            "\nxtask test: clippy on the boards skipped: it needs rustup's thumb targets \
             (Debian's Rust ships no clippy)"
        ),
    }
    Ok(())
}

/// The QEMU hubs driven end to end with each tool chain's images: the tests compare the
/// stream with what the `armcal` binary prints, and drive the hubs with it through a
/// pseudo-terminal (`armcal table send`, `armcal decode --port`).
fn qemu_end_to_end(survey: &toolchain::Survey, step: &dyn Fn(&str)) -> Result<()> {
    step("QEMU end-to-end");
    check(
        cargo().args(["build", "-p", "armcal"]),
        "cargo build -p armcal",
    )?;
    for tc in &survey.available {
        step(&format!("QEMU end-to-end ({})", tc.version));
        let mut e2e = cargo();
        e2e.env(TOOLCHAIN_ENV, tc.kind.name())
            .args(["test", "-p", "host-tests"]);
        for b in boards()?.iter().filter(|b| b.qemu.is_some()) {
            e2e.args([
                "--test",
                &format!("qemu_{}", b.name.trim_start_matches("qemu-")),
            ]);
        }
        e2e.args(["--", "--include-ignored"]);
        check(
            &mut e2e,
            &format!("QEMU end-to-end tests ({})", tc.kind.name()),
        )?;
    }
    Ok(())
}
