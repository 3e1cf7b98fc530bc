//! Cross-building the boards.

use std::process::Command;

use anyhow::{bail, Context, Result};
use host_tests::boards::{board, boards, Board};

use crate::setup;
use crate::toolchain::{self, Toolchain};

/// Runs a command, failing with its description if it fails.
pub fn check(cmd: &mut Command, what: &str) -> Result<()> {
    let status = cmd.status().with_context(|| format!("starting {what}"))?;
    if !status.success() {
        bail!("{what} failed ({status})");
    }
    Ok(())
}

/// Builds one board's release binaries with `tc`.
pub fn build_board_with(b: &Board, tc: &Toolchain) -> Result<()> {
    eprintln!(
        "xtask: building {} ({}) with {}",
        b.name, b.target, tc.version
    );
    let mut cmd = tc.cargo(&b.dir(), b.target, "build");
    cmd.args(["--release", "--locked", "--bins"]);
    check(
        &mut cmd,
        &format!("building {} with {}", b.name, tc.kind.name()),
    )
}

/// Builds one board's release binaries with this machine's primary tool chain.
pub fn build_board(b: &Board) -> Result<()> {
    build_board_with(b, toolchain::survey().primary()?)
}

/// `cargo xtask build [--board NAME]`.
pub fn run(only: Option<&str>) -> Result<()> {
    setup::ensure()?;
    let boards: Vec<Board> = match only {
        Some(name) => vec![board(name)?],
        None => boards()?.to_vec(),
    };
    for b in &boards {
        build_board(b)?;
    }
    Ok(())
}
