//! The compilers that can cross-build the boards on this machine.
//!
//! Two kinds, each used where it is present, both where both are:
//! 1. **rustup** with the thumb targets: plain `cargo build` in the board folder.
//! 2. **Debian's** `rustc-web cargo-web rust-web-src` (1.85 when the project started, 1.96
//!    now): `-Z build-std=core` builds core from the shipped source (`RUSTC_BOOTSTRAP=1`
//!    unlocks the flag on a stable compiler), linked by rust-lld from rustup's host sysroot
//!    (or Debian's `ld.lld`).
//!
//! The two give different images (rustup links its prebuilt `compiler_builtins`, Debian's
//! builds it from source with the board's profile), so a budget that holds with one proves
//! nothing about the other: `cargo xtask test` builds and runs the boards with every kind
//! present and says which it could not have and why. Each builds into its own folder,
//! `boards/<board>/target/<kind>/`.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Result};
pub use host_tests::boards::{Toolchain as Kind, TOOLCHAIN_ENV};

/// The thumb targets the boards need.
pub const TARGETS: [&str; 2] = ["thumbv7em-none-eabihf", "thumbv6m-none-eabi"];

/// Debian's firmware tool chain.
pub const DEBIAN_RUSTC: &str = "/usr/bin/rustc";
/// Debian's cargo.
pub const DEBIAN_CARGO: &str = "/usr/bin/cargo";
const DEBIAN_RUST_SRC: &str = "/usr/lib/rustlib/src/rust/library/core";
/// The oldest Debian rustc the firmware's dependencies are resolved for (`rust-version`).
const DEBIAN_MIN_MINOR: u32 = 85;

/// A compiler that can build the firmware here.
#[derive(Debug, Clone)]
pub struct Toolchain {
    /// Which kind.
    pub kind: Kind,
    /// `rustc --version` of it, e.g. `rustc 1.95.0 (…)`.
    pub version: String,
    /// The linker (Debian's kind only).
    lld: Option<PathBuf>,
}

/// What this machine has: the usable tool chains, and why each missing kind is missing.
#[derive(Debug, Clone, Default)]
pub struct Survey {
    /// Usable, rustup first.
    pub available: Vec<Toolchain>,
    /// Kinds that are not usable here, with the reason.
    pub missing: Vec<(Kind, String)>,
}

fn output(cmd: &mut Command) -> Option<String> {
    let out = cmd.output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_owned())
}

/// The thumb targets rustup lacks (all of them where there is no rustup).
pub fn rustup_missing_targets() -> Vec<&'static str> {
    let list = output(Command::new("rustup").args(["target", "list", "--installed"]));
    TARGETS
        .into_iter()
        .filter(|t| {
            !list
                .as_deref()
                .is_some_and(|l| l.lines().any(|x| x.trim() == *t))
        })
        .collect()
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
        let p = Path::new(&sysroot)
            .join("lib/rustlib")
            .join(host)
            .join("bin/rust-lld");
        if p.exists() {
            return Some(p);
        }
    }
    output(Command::new("which").arg("ld.lld")).map(PathBuf::from)
}

/// Why Debian's tool chain is not usable, or `None` if it is.
pub fn debian_problem() -> Option<String> {
    let Some(v) = output(Command::new(DEBIAN_RUSTC).arg("--version")) else {
        return Some(format!(
            "{DEBIAN_RUSTC} not installed (apt-get install rustc-web cargo-web rust-web-src)"
        ));
    };
    let minor = v
        .split_whitespace()
        .nth(1)
        .and_then(|ver| ver.split('.').nth(1))
        .and_then(|m| m.parse::<u32>().ok());
    if minor.is_none_or(|m| m < DEBIAN_MIN_MINOR) {
        return Some(format!(
            "{DEBIAN_RUSTC} is {v}, older than 1.{DEBIAN_MIN_MINOR}"
        ));
    }
    if !Path::new(DEBIAN_CARGO).exists() {
        return Some(format!(
            "{DEBIAN_CARGO} missing (apt-get install cargo-web)"
        ));
    }
    if !Path::new(DEBIAN_RUST_SRC).exists() {
        return Some("core's source missing (apt-get install rust-web-src)".into());
    }
    if find_lld().is_none() {
        return Some("no rust-lld in rustup's sysroot and no ld.lld (apt-get install lld)".into());
    }
    None
}

/// Every tool chain this machine has, and what it lacks.
pub fn survey() -> Survey {
    let mut s = Survey::default();
    let missing = rustup_missing_targets();
    if missing.is_empty() {
        let version = output(Command::new("rustc").arg("--version")).unwrap_or_default();
        s.available.push(Toolchain {
            kind: Kind::Rustup,
            version,
            lld: None,
        });
    } else {
        s.missing.push((
            Kind::Rustup,
            format!("rustup has no {}", missing.join(", ")),
        ));
    }
    match debian_problem() {
        None => s.available.push(Toolchain {
            kind: Kind::Debian,
            version: output(Command::new(DEBIAN_RUSTC).arg("--version")).unwrap_or_default(),
            lld: find_lld(),
        }),
        Some(why) => s.missing.push((Kind::Debian, why)),
    }
    s
}

impl Survey {
    /// The tool chain single-board commands use: the one named by `QUATARM_FIRMWARE`
    /// (`rustup` or `debian`) if set, else rustup's if present, else Debian's.
    pub fn primary(&self) -> Result<&Toolchain> {
        let wanted = std::env::var(TOOLCHAIN_ENV).ok();
        if let Some(name) = wanted.as_deref() {
            return match self.available.iter().find(|t| t.kind.name() == name) {
                Some(t) => Ok(t),
                None => bail!(
                    "{TOOLCHAIN_ENV}={name}, but that tool chain is not usable here: {}",
                    self.why_missing(name)
                ),
            };
        }
        match self.available.first() {
            Some(t) => Ok(t),
            None => bail!(
                "no firmware tool chain: {} (run `cargo xtask setup`)",
                self.why_missing("")
            ),
        }
    }

    fn why_missing(&self, name: &str) -> String {
        self.missing
            .iter()
            .filter(|(k, _)| name.is_empty() || k.name() == name)
            .map(|(k, why)| format!("{}: {why}", k.name()))
            .collect::<Vec<_>>()
            .join("; ")
    }

    /// One line per kind: used, or skipped and why.
    pub fn describe(&self) -> String {
        let mut lines: Vec<String> = self
            .available
            .iter()
            .map(|t| format!("  {}: {} — used", t.kind.name(), t.version))
            .collect();
        lines.extend(
            self.missing
                .iter()
                .map(|(k, why)| format!("  {}: SKIPPED — {why}", k.name())),
        );
        lines.join("\n")
    }
}

impl Toolchain {
    /// A `cargo <sub>` for the board crate in `dir`, targeting `target`, with the environment
    /// this tool chain needs, building into `dir/target/<kind>/`.
    pub fn cargo(&self, dir: &Path, target: &str, sub: &str) -> Command {
        let mut cmd;
        match self.kind {
            Kind::Rustup => {
                cmd = Command::new("cargo");
                cmd.arg(sub);
            }
            Kind::Debian => {
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
                    .env_remove("RUSTUP_TOOLCHAIN");
                if let Some(lld) = &self.lld {
                    cmd.env(
                        format!(
                            "CARGO_TARGET_{}_LINKER",
                            target.to_uppercase().replace('-', "_")
                        ),
                        lld,
                    );
                }
            }
        }
        cmd.current_dir(dir)
            .env("CARGO_TARGET_DIR", self.kind.target_dir(dir))
            .env_remove("RUSTFLAGS")
            .env_remove("CARGO_ENCODED_RUSTFLAGS")
            .env_remove("CARGO_BUILD_TARGET");
        cmd
    }
}
