//! How to cross-compile a board on this machine.
//!
//! Two ways, tried in this order:
//! 1. rustup has the thumb targets: plain `cargo build` in the board folder.
//! 2. Debian's `rustc-web cargo-web rust-web-src` (rustc 1.85): `-Z build-std=core` builds core
//!    from the shipped source (`RUSTC_BOOTSTRAP=1` unlocks the flag on a stable compiler), and
//!    the linker is rust-lld from rustup's own host sysroot (or Debian's `ld.lld`).
//!
//! Rustup here (and on a fresh CI machine) has only the host target and cannot download
//! others, so CI takes the second way; `cargo xtask setup` installs what it needs.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context, Result};

/// The thumb targets the boards need.
pub const TARGETS: [&str; 2] = ["thumbv7em-none-eabihf", "thumbv6m-none-eabi"];

/// Debian's firmware tool chain.
pub const DEBIAN_RUSTC: &str = "/usr/bin/rustc";
/// Debian's cargo.
pub const DEBIAN_CARGO: &str = "/usr/bin/cargo";
const DEBIAN_RUST_SRC: &str = "/usr/lib/rustlib/src/rust/library/core";

/// A way to build firmware.
#[derive(Debug, Clone)]
pub enum Toolchain {
    /// rustup with the thumb targets installed.
    Rustup,
    /// Debian's rustc with build-std, linking with `lld`.
    Debian {
        /// The linker binary (rust-lld or ld.lld).
        lld: PathBuf,
    },
}

fn output(cmd: &mut Command) -> Option<String> {
    let out = cmd.output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).into_owned())
}

/// True if rustup has every thumb target.
pub fn rustup_has_targets() -> bool {
    match output(Command::new("rustup").args(["target", "list", "--installed"])) {
        Some(list) => TARGETS.iter().all(|t| list.lines().any(|l| l.trim() == *t)),
        None => false,
    }
}

/// An lld to link thumb binaries with: rustup's rust-lld, else `ld.lld` on the PATH.
pub fn find_lld() -> Option<PathBuf> {
    if let Some(sysroot) = output(Command::new("rustc").args(["--print", "sysroot"])) {
        let host = output(Command::new("rustc").args(["--print", "host-tuple"]))
            .or_else(|| {
                output(Command::new("rustc").arg("-vV")).and_then(|v| {
                    v.lines()
                        .find_map(|l| l.strip_prefix("host: ").map(str::to_owned))
                })
            })
            .unwrap_or_else(|| "x86_64-unknown-linux-gnu".into());
        let p = Path::new(sysroot.trim())
            .join("lib/rustlib")
            .join(host.trim())
            .join("bin/rust-lld");
        if p.exists() {
            return Some(p);
        }
    }
    output(Command::new("which").arg("ld.lld")).map(|s| PathBuf::from(s.trim()))
}

/// Debian's rustc, if installed and new enough (1.85) with its source.
pub fn debian_ready() -> bool {
    let Some(v) = output(Command::new(DEBIAN_RUSTC).arg("--version")) else {
        return false;
    };
    let minor = v
        .split_whitespace()
        .nth(1)
        .and_then(|ver| ver.split('.').nth(1))
        .and_then(|m| m.parse::<u32>().ok());
    minor.is_some_and(|m| m >= 85)
        && Path::new(DEBIAN_CARGO).exists()
        && Path::new(DEBIAN_RUST_SRC).exists()
}

/// The tool chain to use, or what is missing.
pub fn detect() -> Result<Toolchain> {
    if rustup_has_targets() {
        return Ok(Toolchain::Rustup);
    }
    if !debian_ready() {
        bail!("no thumb tool chain: rustup lacks {TARGETS:?} and Debian's rustc-web 1.85 with rust-web-src is not installed (run `cargo xtask setup`)");
    }
    let lld = find_lld().context("no rust-lld in rustup's sysroot and no ld.lld on the PATH")?;
    Ok(Toolchain::Debian { lld })
}

impl Toolchain {
    /// A `cargo <sub>` for the board crate in `dir`, targeting `target`, with the environment
    /// this tool chain needs. The board's own `target/` is always used.
    pub fn cargo(&self, dir: &Path, target: &str, sub: &str) -> Command {
        let mut cmd;
        match self {
            Toolchain::Rustup => {
                cmd = Command::new("cargo");
                cmd.arg(sub);
            }
            Toolchain::Debian { lld } => {
                cmd = Command::new(DEBIAN_CARGO);
                cmd.arg(sub)
                    .args([
                        "-Z",
                        "build-std=core",
                        "-Z",
                        "build-std-features=compiler-builtins-mem",
                    ])
                    .env("RUSTC", DEBIAN_RUSTC)
                    .env("RUSTC_BOOTSTRAP", "1")
                    .env(
                        format!(
                            "CARGO_TARGET_{}_LINKER",
                            target.to_uppercase().replace('-', "_")
                        ),
                        lld,
                    )
                    .env_remove("RUSTUP_TOOLCHAIN");
            }
        }
        cmd.current_dir(dir)
            .env("CARGO_TARGET_DIR", dir.join("target"))
            .env_remove("RUSTFLAGS")
            .env_remove("CARGO_ENCODED_RUSTFLAGS")
            .env_remove("CARGO_BUILD_TARGET");
        cmd
    }
}
