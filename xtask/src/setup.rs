//! `cargo xtask setup`: installs what the firmware builds, QEMU runs and fuzz runs need, and
//! the headless browser the HTML reports' test renders them with (Debian's
//! `chromium-headless-shell`), and only that.
//!
//! It asks nothing and removes nothing: every `apt-get install` runs with `--no-remove`, so a
//! package that could only go in by replacing one the machine has (a newer backport of
//! `qemu-utils`, say) is never swapped silently. For QEMU it then looks for the same version
//! in the release's backports suite, the one the installed package came from; failing that it
//! stops and prints the command that would replace the package, for a person to decide.
//! Each install says what it installs and why.

use std::path::Path;
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

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .map(|o| o.stdout.starts_with(b"0\n"))
        .unwrap_or(false)
}

/// `apt-get`, updated once, installing without removing anything.
struct Apt {
    updated: bool,
}

impl Apt {
    fn update(&mut self) -> Result<()> {
        eprintln!("xtask setup: apt-get update");
        let ok = Command::new("apt-get")
            .arg("update")
            .env("DEBIAN_FRONTEND", "noninteractive")
            .status()
            .context("starting apt-get")?
            .success();
        if !ok {
            bail!("apt-get update failed");
        }
        self.updated = true;
        Ok(())
    }

    /// Installs `packages` (with `extra` options such as `-t SUITE`) for `why`; `Ok(false)`
    /// if apt would have to remove a package to do it (nothing is changed then).
    fn install(&mut self, packages: &[&str], extra: &[&str], why: &str) -> Result<bool> {
        if !is_root() {
            bail!(
                "need root to install {} ({why}): run `sudo apt-get install {}`",
                packages.join(" "),
                packages.join(" ")
            );
        }
        if !self.updated {
            self.update()?;
        }
        eprintln!(
            "xtask setup: apt-get install {} {} — {why}",
            extra.join(" "),
            packages.join(" ")
        );
        let ok = Command::new("apt-get")
            .args(["install", "-y", "--no-install-recommends", "--no-remove"])
            .args(extra)
            .args(packages)
            .env("DEBIAN_FRONTEND", "noninteractive")
            .status()
            .context("starting apt-get")?
            .success();
        Ok(ok)
    }

    fn install_or_fail(&mut self, packages: &[&str], why: &str) -> Result<()> {
        if self.install(packages, &[], why)? {
            Ok(())
        } else {
            bail!(
                "apt-get install {} failed (it would remove a package, or the package is not available); nothing was removed",
                packages.join(" ")
            )
        }
    }
}

/// The installed version of a Debian package.
fn installed_version(package: &str) -> Option<String> {
    let out = Command::new("dpkg-query")
        .args(["-W", "-f=${Status} ${Version}", package])
        .output()
        .ok()?;
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    text.strip_prefix("install ok installed ")
        .map(|v| v.trim().to_owned())
}

/// The release's code name (`bookworm`), from `/etc/os-release`.
fn codename() -> Option<String> {
    std::fs::read_to_string("/etc/os-release")
        .ok()?
        .lines()
        .find_map(|l| {
            l.strip_prefix("VERSION_CODENAME=")
                .map(|v| v.trim_matches('"').to_owned())
        })
        .filter(|c| !c.is_empty())
}

const BACKPORTS_SOURCES: &str = "/etc/apt/sources.list.d/quatarm-backports.sources";

/// Adds the release's backports suite with the same mirror and key as the release's own entry
/// in `/etc/apt/sources.list.d/debian.sources`; `false` if there is no such entry to copy.
fn add_backports(code: &str) -> Result<bool> {
    if Path::new(BACKPORTS_SOURCES).exists() {
        return Ok(true);
    }
    let Ok(sources) = std::fs::read_to_string("/etc/apt/sources.list.d/debian.sources") else {
        return Ok(false);
    };
    let Some(entry) = sources.split("\n\n").find(|e| {
        e.lines()
            .any(|l| l.starts_with("Suites:") && l.split_whitespace().any(|s| s == code))
    }) else {
        return Ok(false);
    };
    let text: String = entry
        .lines()
        .map(|l| {
            if l.starts_with("Suites:") {
                format!("Suites: {code}-backports\n")
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    eprintln!(
        "xtask setup: adding {code}-backports (the suite the installed qemu packages come from) as {BACKPORTS_SOURCES}"
    );
    std::fs::write(BACKPORTS_SOURCES, text)
        .with_context(|| format!("writing {BACKPORTS_SOURCES}"))?;
    Ok(true)
}

/// qemu-system-arm, without replacing the machine's other qemu packages.
fn install_qemu(apt: &mut Apt) -> Result<()> {
    const WHY: &str = "runs the QEMU boards (mps2-an386, microbit)";
    if apt.install(&["qemu-system-arm"], &[], WHY)? {
        return Ok(());
    }
    // The usual cause: qemu-utils (or another qemu package) is a newer backport, and the
    // release's qemu-system-arm would replace it. The same version from backports does not.
    let backport = installed_version("qemu-utils")
        .or_else(|| installed_version("qemu-system-common"))
        .filter(|v| v.contains("~bpo"));
    if let (Some(version), Some(code)) = (backport, codename()) {
        if add_backports(&code)? {
            apt.update()?;
            let pinned = format!("qemu-system-arm={version}");
            let suite = format!("{code}-backports");
            if apt.install(
                &[&pinned],
                &["-t", &suite],
                "the same version as the installed qemu-utils",
            )? {
                return Ok(());
            }
        }
    }
    bail!(
        "qemu-system-arm cannot be installed without removing a package this machine has \
         (see apt-get's message above); nothing was removed. To replace it, run as root: \
         `apt-get install qemu-system-arm` and answer apt's question, then `cargo xtask setup` again"
    )
}

/// Makes sure the thumb tool chains and qemu-system-arm are there, installing what is
/// missing. With `every_compiler`, also Debian's tool chain beside rustup's targets, so that
/// the firmware is built and run with both (CI does this).
pub fn run(every_compiler: bool) -> Result<()> {
    let mut apt = Apt { updated: false };
    let missing = toolchain::rustup_missing_targets();
    if !missing.is_empty() && which("rustup") {
        eprintln!(
            "xtask setup: rustup target add {} — the boards' targets (2-minute limit: some machines cannot download)",
            missing.join(" ")
        );
        let ok = run_with_limit(
            Command::new("rustup").args(["target", "add"]).args(TARGETS),
            Duration::from_secs(120),
        );
        if !ok {
            eprintln!("xtask setup: rustup could not add the targets");
        }
    }
    let rustup = toolchain::rustup_missing_targets().is_empty();
    if toolchain::debian_problem().is_some() && (every_compiler || !rustup) {
        let why = if rustup {
            "the second firmware compiler (--every-compiler)"
        } else {
            "the firmware compiler (rustup has no thumb targets here), with core's source for -Z build-std"
        };
        if installed_version("rustc-web").is_none() || installed_version("rust-web-src").is_none() {
            apt.install_or_fail(&["rustc-web", "cargo-web", "rust-web-src"], why)?;
        }
        if toolchain::find_lld().is_none() {
            apt.install_or_fail(&["lld"], "the linker for Debian's rustc, which ships none")?;
        }
    }
    if !which("qemu-system-arm") {
        install_qemu(&mut apt)?;
    }
    install_c_compiler(&mut apt)?;
    if !has_browser() {
        apt.install_or_fail(
            &["chromium-headless-shell"],
            "renders armcal's HTML reports in the tests (armcal/tests/report_browser.rs)",
        )?;
    }
    crate::fuzz::ensure_cargo_fuzz()?;
    let survey = toolchain::survey();
    survey.primary()?;
    eprintln!(
        "xtask setup: firmware tool chains:\n{}\nxtask setup: qemu-system-arm, chromium and cargo-fuzz present",
        survey.describe()
    );
    Ok(())
}

/// The C baselines' compiler (`bench/c/`, measured by `bench-target`) where it is missing.
/// Optional: without it (no root, or apt cannot) setup goes on and the C baselines are
/// reported as skipped, never as measured.
fn install_c_compiler(apt: &mut Apt) -> Result<()> {
    if crate::cbase::image::gcc().is_some() {
        return Ok(());
    }
    const PACKAGES: [&str; 2] = ["gcc-arm-none-eabi", "libnewlib-arm-none-eabi"];
    let why = "the C baselines of `cargo xtask bench-target` (bench/c/), optional";
    if !is_root() {
        eprintln!(
            "xtask setup: {} not installed ({why}; needs root: `sudo apt-get install {}`)",
            crate::cbase::image::GCC,
            PACKAGES.join(" ")
        );
        return Ok(());
    }
    match apt.install(&PACKAGES, &[], why) {
        Ok(true) => {}
        Ok(false) => eprintln!(
            "xtask setup: apt-get install {} failed; the C baselines will be skipped",
            PACKAGES.join(" ")
        ),
        Err(e) => eprintln!("xtask setup: {e:#}; the C baselines will be skipped"),
    }
    Ok(())
}

/// Whether a headless Chromium is there (the shell, or the full browser).
pub fn has_browser() -> bool {
    which("chromium-headless-shell") || which("chromium")
}

/// Runs [`run`] only if a firmware tool chain or QEMU is missing (the other commands call
/// this first; cargo-fuzz is installed by the fuzz commands themselves when they need it, so
/// that `cargo xtask demo` does not wait for it).
pub fn ensure() -> Result<()> {
    if toolchain::survey().primary().is_ok() && which("qemu-system-arm") && has_browser() {
        return Ok(());
    }
    run(false)
}
