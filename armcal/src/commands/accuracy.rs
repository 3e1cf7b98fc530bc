//! `armcal accuracy`: the firmware paths against the f64 reference over random poses.

use anyhow::Context;
use armcal::accuracy::{full_calibration, measure, with_wobble, PATHS, SEED};
use std::path::PathBuf;

/// Arguments of `armcal accuracy`.
#[derive(clap::Args)]
pub struct Args {
    /// Calibration file; default: `default-6` with the built-in full calibration (every term).
    #[arg(long)]
    calib: Option<PathBuf>,
    /// Number of random poses.
    #[arg(long, default_value_t = 1_000_000)]
    poses: u64,
    /// Seed of the random poses.
    #[arg(long, default_value_t = SEED)]
    seed: u64,
    /// Write the built-in full calibration (with `--wobble`, the wobble too) to this TOML
    /// file and stop (how `data/default-6-full.toml` and `data/default-6-wobble.toml` were
    /// made).
    #[arg(long)]
    write_calib: Option<PathBuf>,
    /// Add an axis wobble to every joint of the arm (`armcal::accuracy::with_wobble`: orders
    /// 1-3, and 4 on the hinges, each coefficient up to this many rad; 1e-4 is a worn
    /// bearing's).
    #[arg(long, value_name = "RAD")]
    wobble: Option<f64>,
    /// Worker threads (the result does not depend on it).
    #[arg(long, default_value_t = 2)]
    threads: usize,
}

/// `--wobble`'s size, checked.
fn wobble_size(size: f64) -> anyhow::Result<f64> {
    anyhow::ensure!(
        size.is_finite() && size > 0.0,
        "--wobble: {size}: give a positive size in rad (1e-4 is a worn bearing's)"
    );
    Ok(size)
}

/// Runs the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(path) = &args.write_calib {
        let arm = match args.wobble {
            Some(size) => with_wobble(&full_calibration(), wobble_size(size)?),
            None => full_calibration(),
        };
        let mut header = vec![
            "default-6 with a realistic calibration that uses every term of the model:",
            "zero offsets and tilts of a few mrad, link errors up to 1 mm, two encoder",
            "harmonics per joint, gravity compliance on the hinges, thermal expansion",
            "(aluminium links 1, 3, 5; carbon-fibre links 2, 4, 6; steel probe).",
            "Written by `armcal accuracy --write-calib` (armcal::accuracy::full_calibration).",
        ];
        let wobble_line;
        if let Some(size) = args.wobble {
            wobble_line = format!(
                "With an axis wobble on every joint: `--wobble {size:e}` \
                 (armcal::accuracy::with_wobble)."
            );
            header.push(&wobble_line);
        }
        let inputs: Vec<(&std::path::Path, &str)> = args
            .calib
            .iter()
            .map(|c| (c.as_path(), "calibration"))
            .collect();
        armcal::output::check(&[(path, "calibration file")], &inputs)?;
        let text = quatarm_ref::calfile::write(&arm, &header);
        let mut files = armcal::output::Staged::guarding(&inputs);
        files.write(path, text.as_bytes())?;
        files.commit()?;
        return Ok(());
    }
    let arm = match &args.calib {
        Some(p) => armcal::load::arm(p)?,
        None => full_calibration(),
    };
    let arm = match args.wobble {
        Some(size) => with_wobble(&arm, wobble_size(size)?),
        None => arm,
    };
    let bar = indicatif::ProgressBar::new(args.poses);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} poses {eta}")
            .context("progress style")?,
    );
    let start = std::time::Instant::now();
    let report = measure(&arm, args.poses, args.seed, args.threads, &|k| bar.inc(k))?;
    bar.finish_and_clear();
    println!(
        "arm: {}, {} random poses (seed {}), temperatures 10-35 degC, {:.1} s",
        arm.name.as_deref().unwrap_or("(unnamed)"),
        args.poses,
        args.seed,
        start.elapsed().as_secs_f64()
    );
    println!("errors against the f64 reference (exact gravity):");
    println!(
        "{:<26} {:>12} {:>12} {:>14} {:>14}",
        "path", "tip max um", "tip RMS um", "dir max", "dir RMS"
    );
    for (i, (name, s)) in PATHS.iter().zip(&report.stats).enumerate() {
        if let Some(e) = report.refused.get(i).copied().flatten() {
            println!("{name:<26} refused: {e}");
            continue;
        }
        println!(
            "{:<26} {:>12.4} {:>12.4} {:>14.3e} {:>14.3e}",
            name,
            s.max_um,
            s.rms_um(),
            s.max_dir,
            s.rms_dir()
        );
    }
    Ok(())
}
