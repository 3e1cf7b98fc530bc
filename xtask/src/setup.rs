//! `cargo xtask setup`: installs what the firmware builds, QEMU runs and fuzz runs need, and only
//! that.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};

use crate::toolchain::{self, TARGETS};

fn which(bin: &str) -> bool {
    Command::new("which")
        .arg(bin)
        .stdout(Stdio::null())
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
}

/// Runs `cmd`, killing it after `limit` (a download that hangs must not hang CI).
fn run_with_limit(cmd: &mut Command, limit: Duration) -> bool {
    let Ok(mut child) = cmd.stdout(Stdio::null()).stderr(Stdio::null()).spawn() else {
        return false;
    };
    let start = Instant::now();
    loop {
        match child.try_wait() {
            Ok(Some(status)) => return status.success(),
            Ok(None) if start.elapsed() < limit => std::thread::sleep(Duration::from_millis(200)),
            _ => {
                let _ = child.kill();
                let _ = child.wait();
                return false;
            }
        }
    }
}

struct Apt {
    updated: bool,
}

impl Apt {
    fn install(&mut self, packages: &[&str]) -> Result<()> {
        let root = Command::new("id")
            .arg("-u")
            .output()
            .map(|o| o.stdout.starts_with(b"0"))
            .unwrap_or(false);
        if !root {
            bail!(
                "need root to install {packages:?}: run `sudo apt-get install -y {}`",
                packages.join(" ")
            );
        }
        if !self.updated {
            eprintln!("xtask setup: apt-get update");
            let ok = Command::new("apt-get")
                .arg("update")
                .env("DEBIAN_FRONTEND", "noninteractive")
                .status()
                .context("apt-get")?
                .success();
            if !ok {
                bail!("apt-get update failed");
            }
            self.updated = true;
        }
        eprintln!("xtask setup: apt-get install {}", packages.join(" "));
        let ok = Command::new("apt-get")
            .args(["install", "-y", "--no-install-recommends"])
            .args(packages)
            .env("DEBIAN_FRONTEND", "noninteractive")
            .status()
            .context("apt-get")?
            .success();
        if !ok {
            bail!("apt-get install {packages:?} failed");
        }
        Ok(())
    }
}

/// Makes sure a thumb tool chain and qemu-system-arm are there; installs what is missing.
pub fn run() -> Result<()> {
    let mut apt = Apt { updated: false };
    if toolchain::detect().is_err() {
        let rustup = which("rustup")
            && run_with_limit(
                Command::new("rustup").args(["target", "add"]).args(TARGETS),
                Duration::from_secs(120),
            );
        if !rustup || !toolchain::rustup_has_targets() {
            eprintln!("xtask setup: rustup cannot add {TARGETS:?}; using Debian's rustc-web with build-std");
            if !toolchain::debian_ready() {
                apt.install(&["rustc-web", "cargo-web", "rust-web-src"])?;
            }
            if toolchain::find_lld().is_none() {
                apt.install(&["lld"])?;
            }
        }
    }
    let tc = toolchain::detect()?;
    if !which("qemu-system-arm") {
        apt.install(&["qemu-system-arm"])?;
    }
    crate::fuzz::ensure_cargo_fuzz()?;
    eprintln!("xtask setup: firmware tool chain {tc:?}; qemu-system-arm and cargo-fuzz present");
    Ok(())
}

/// Runs [`run`] only if something is missing (the other commands call this first).
pub fn ensure() -> Result<()> {
    if toolchain::detect().is_ok() && which("qemu-system-arm") && crate::fuzz::cargo_fuzz_present()
    {
        return Ok(());
    }
    run()
}
