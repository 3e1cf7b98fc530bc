//! The HTML reports rendered by a real browser (headless Chromium from Debian, which
//! `cargo xtask setup` installs): the `check` report of the shipped ISO 10360-12 test set and
//! the `diagnose` report of a shipped MUKCa recording are loaded, their DOM read back for the
//! verdict, a screenshot taken and checked to be a real page, and each printed to PDF.
//!
//! Without a browser the test fails under `CI=true` and says so loudly otherwise: it is never
//! a silent pass.

mod common;

use common::{armcal, armcal_ok, png_size, workdir};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The browser: `chromium-headless-shell` or `chromium`, where installed.
fn browser() -> Option<PathBuf> {
    ["chromium-headless-shell", "chromium", "chromium-browser"]
        .iter()
        .find_map(|name| {
            std::env::var_os("PATH").and_then(|paths| {
                std::env::split_paths(&paths)
                    .map(|d| d.join(name))
                    .find(|p| p.is_file())
            })
        })
}

/// Runs the browser headless on `page` with `args` (a fresh profile in `dir`), returning its
/// stdout.
fn render(browser: &Path, dir: &Path, page: &Path, args: &[&str]) -> String {
    let o = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            // No network at all: the page must be self-contained.
            "--proxy-server=127.0.0.1:9",
            "--window-size=1200,1600",
        ])
        .arg(format!("--user-data-dir={}", dir.join("profile").display()))
        .args(args)
        .arg(page)
        .output()
        .expect("run the browser");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The screenshot, DOM and PDF of `page`: the DOM holds `expect`, the PNG is the window's
/// size and far from blank, the PDF is one.
fn check_page(browser: &Path, dir: &Path, page: &Path, expect: &str) {
    let dom = render(browser, dir, page, &["--dump-dom"]);
    assert!(
        dom.contains(r#"id="verdict""#) && dom.contains(expect),
        "{dom}"
    );
    let png = dir.join(page.with_extension("png").file_name().unwrap());
    render(
        browser,
        dir,
        page,
        &[&format!("--screenshot={}", png.display())],
    );
    let (w, h) = png_size(&png);
    assert_eq!((w, h), (1200, 1600));
    // A blank or error page compresses to a few kB; text, tables and plots do not.
    let bytes = std::fs::metadata(&png).unwrap().len();
    assert!(bytes > 60_000, "{}: {bytes} B", png.display());
    let pdf = dir.join(page.with_extension("pdf").file_name().unwrap());
    render(
        browser,
        dir,
        page,
        &[
            &format!("--print-to-pdf={}", pdf.display()),
            "--no-pdf-header-footer",
        ],
    );
    let b = std::fs::read(&pdf).unwrap();
    assert!(b.starts_with(b"%PDF-") && b.len() > 20_000, "{} B", b.len());
}

#[test]
fn check_and_diagnose_reports_render_in_chromium() {
    let Some(browser) = browser() else {
        let ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
        assert!(
            !ci,
            "no chromium-headless-shell or chromium on PATH: `cargo xtask setup` installs it"
        );
        eprintln!(
            "report_browser: NOT RUN: no chromium-headless-shell or chromium on PATH \
             (`cargo xtask setup` installs it; under CI=true this fails)"
        );
        return;
    };
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../data");
    let dir = workdir("browser");
    let o = armcal(
        &[
            "check",
            data.join("acceptance/iso10360-12.csv").to_str().unwrap(),
            "--calib",
            data.join("default-6.toml").to_str().unwrap(),
            "--mpe",
            data.join("mpe-example.toml").to_str().unwrap(),
            "--report",
            "check.html",
        ],
        &dir,
    );
    // The shipped test set: P_Form of sphere 2 is 28.26 µm against 30 µm with U = 3 µm.
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let html = std::fs::read_to_string(dir.join("check.html")).unwrap();
    assert!(
        !html.contains("https://") && !html.contains(" src="),
        "self-contained"
    );
    check_page(
        &browser,
        &dir,
        &dir.join("check.html"),
        "Verdict: CANNOT DECIDE (exit 2)",
    );
    let mukca = data.join("mukca");
    armcal_ok(
        &[
            "diagnose",
            mukca.join("mukca-gen3lite-dinova_1.csv").to_str().unwrap(),
            "--arm",
            mukca.join("mukca-gen3lite-dinova_1.toml").to_str().unwrap(),
            "--report",
            "diagnose.html",
        ],
        &dir,
    );
    check_page(&browser, &dir, &dir.join("diagnose.html"), "Held-out RMS");
}

/// `calibrate --report`: the certificate names the data file with its SHA-256, holds the
/// plots and the full report, escapes what it quotes; a report over an input is refused and
/// nothing is written.
#[test]
fn calibrate_writes_a_certificate_and_never_over_an_input() {
    let dir = workdir("certificate");
    common::write_truth(&dir, &quatarm_ref::arm::Arm::default6());
    common::simulate(&dir, "point", "80", "3", &[], "p<1>.csv");
    armcal_ok(
        &[
            "calibrate",
            "p<1>.csv",
            "-o",
            "cal.toml",
            "--report",
            "cal.html",
        ],
        &dir,
    );
    let html = std::fs::read_to_string(dir.join("cal.html")).unwrap();
    let sha = armcal::html::header::sha256_hex(&std::fs::read(dir.join("p<1>.csv")).unwrap());
    assert!(html.contains("Calibration certificate") && html.contains(&sha));
    assert!(html.contains("p&lt;1&gt;.csv") && !html.contains("p<1>.csv"));
    assert!(
        html.matches("<svg").count() >= 3,
        "vectors, before/after, held out"
    );
    assert!(html.contains("Residual vectors after the fit") && html.contains("<pre>"));
    let o = armcal(
        &[
            "calibrate",
            "p<1>.csv",
            "-o",
            "c2.toml",
            "--report",
            "p<1>.csv",
        ],
        &dir,
    );
    assert!(!o.status.success() && !dir.join("c2.toml").exists());
    let o = armcal(
        &[
            "check", "p<1>.csv", "--calib", "cal.toml", "--report", "cal.toml",
        ],
        &dir,
    );
    assert_eq!(o.status.code(), Some(3));
}
