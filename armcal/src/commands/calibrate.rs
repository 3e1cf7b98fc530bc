//! `armcal calibrate`: identify an arm's parameters from measured data.

use anyhow::{bail, Context};
use armcal::calib::{self, Prior};
use armcal::holdout;
use armcal::params::Terms;
use armcal::report;
use armcal::residuals::{residuals, summarise};
use quatarm_ref::arm::Arm;
use quatarm_ref::{calfile, forward};
use std::path::{Path, PathBuf};

/// Arguments of `armcal calibrate`.
#[derive(clap::Args)]
pub struct Args {
    /// Measured data (CSV of `spec/measured-data.md`): any mix of point, spat and length rows.
    data: PathBuf,
    /// The arm to start from (its nominal geometry, or an earlier calibration); default the
    /// spec's `default-6`.
    #[arg(long)]
    arm: Option<PathBuf>,
    /// What to fit: `geometric` (the 6N + 3 parameters), plus effects such as
    /// `+encoder_harmonic:2:1,+gravity_compliance:4,+thermal_expansion:probe` (joint numbers
    /// 1-based, `*` for all), or `only,+…` for the effects alone.
    #[arg(long, default_value = "geometric")]
    terms: String,
    /// The calibration file to write; the firmware's binary table goes beside it (`.bin`).
    #[arg(short, long)]
    output: PathBuf,
    /// Print the report as JSON instead of text.
    #[arg(long)]
    json: bool,
    /// Folds of held-out validation (0: none).
    #[arg(long, default_value_t = 5)]
    folds: usize,
    /// Hold out whole groups (sessions, artefact positions) instead of k folds.
    #[arg(long)]
    by_group: bool,
    /// Iterations before a fit is declared not converging.
    #[arg(long, default_value_t = 100)]
    max_iter: usize,
    /// Fit a degenerate pose set anyway, holding what it cannot determine.
    #[arg(long)]
    allow_degenerate: bool,
    /// Keep an extended effect only if it is significant at this many standard
    /// uncertainties (backward elimination; 0 keeps every effect requested).
    #[arg(long, default_value_t = 0.0)]
    significance: f64,
    /// Prior standard deviation of zero offsets and tilts (rad), regularising weak directions.
    #[arg(long, requires = "prior_length")]
    prior_angle: Option<f64>,
    /// Prior standard deviation of link and probe errors (mm).
    #[arg(long, requires = "prior_angle")]
    prior_length: Option<f64>,
    /// MUKCa's regulariser: a ridge λ·Σ Δp² (metres, radians) on every joint's geometric
    /// errors, the probe free: `--ridge` is MUKCa's default λ = 1e-4, `--ridge=3e-5` another. For
    /// data from few artefact positions (one MUKCa session), where some directions are barely
    /// determined.
    #[arg(long, num_args = 0..=1, require_equals = true, default_missing_value = "1e-4", value_name = "LAMBDA")]
    ridge: Option<f64>,
}

/// Reads the start arm: a file, or `default-6`.
pub fn start_arm(path: Option<&Path>) -> anyhow::Result<Arm> {
    match path {
        None => Ok(Arm::default6()),
        Some(p) => {
            let parsed = calfile::read(p)?;
            for k in &parsed.unknown_keys {
                eprintln!("armcal: warning: {}: unknown key {k} ignored", p.display());
            }
            Ok(parsed.arm)
        }
    }
}

/// Runs the subcommand.
pub fn run(a: Args) -> anyhow::Result<()> {
    let start = start_arm(a.arm.as_deref())?;
    let data = armcal::data::read(&a.data, start.dof())?;
    for w in &data.warnings {
        eprintln!("armcal: warning: {w}");
    }
    let terms = Terms::parse(&a.terms, start.dof()).map_err(anyhow::Error::msg)?;
    let mut opts = calib::Options {
        terms: terms.clone(),
        allow_degenerate: a.allow_degenerate,
        significance: a.significance,
        progress: !a.json,
        ..calib::Options::default()
    };
    opts.lm.max_iterations = a.max_iter;
    if let (Some(angle_rad), Some(length_mm)) = (a.prior_angle, a.prior_length) {
        if !(angle_rad > 0.0 && length_mm > 0.0) {
            bail!("prior standard deviations must be positive");
        }
        opts.prior = Some(Prior {
            angle_rad,
            length_mm,
            noise_mm: None,
        });
    }
    if let Some(lambda) = a.ridge {
        if !(lambda > 0.0 && lambda.is_finite()) {
            bail!("the ridge weight must be positive");
        }
        opts.ridge = Some(calib::Ridge { lambda });
    }
    let fit = calib::calibrate(&start, &data, &opts)
        .with_context(|| format!("cannot calibrate from {}", a.data.display()))?;

    let before = summarise(&residuals(&fit.start, &data, None), &data);
    let after = summarise(&residuals(&fit.arm, &data, fit.frame), &data);
    let (folds, method) = if a.by_group {
        (holdout::by_group(&data), "one group at a time".to_string())
    } else {
        (
            holdout::kfold(&data, a.folds, 0x0f01d),
            format!("{}-fold", a.folds),
        )
    };
    let held = (a.folds > 0 || a.by_group) && folds.len() > 1;
    let validation = held.then(|| holdout::validate(&start, &data, &opts, &folds));
    let mut rep = report::build(
        &fit,
        &data,
        before,
        after,
        validation.as_ref().map(|h| (method.as_str(), h)),
    );
    rep.terms = terms.spec();
    if !held && (a.folds > 0 || a.by_group) {
        rep.residuals.holdout_note = Some(
            "none: the data are a single unit (one group) that cannot be split into folds".into(),
        );
    }

    // The calibration file, checked by reading it back and evaluating it.
    let header = [
        format!("calibrated by armcal calibrate from {}", a.data.display()),
        format!(
            "terms {}; {} of {} unknowns fitted; RMS residual {:.2} µm before, {:.2} µm after",
            terms.spec(),
            rep.fitted,
            rep.unknowns,
            rep.residuals.before.all.rms_um,
            rep.residuals.after.all.rms_um
        ),
    ];
    let refs: Vec<&str> = header.iter().map(String::as_str).collect();
    let text = calfile::write(&fit.arm, &refs);
    let back = calfile::parse(&text)
        .map_err(|e| anyhow::anyhow!("the calibration file written does not read back: {e}"))?
        .arm;
    for r in data.rows.iter().take(50) {
        let d = (forward::forward(&back, &r.theta, r.temp_c).p
            - forward::forward(&fit.arm, &r.theta, r.temp_c).p)
            .norm();
        if d > 1e-9 {
            bail!("the calibration file written evaluates {d} mm away from the fit (a bug)");
        }
    }
    std::fs::write(&a.output, &text).with_context(|| a.output.display().to_string())?;
    rep.output.calibration = Some(a.output.display().to_string());
    let table = a.output.with_extension("bin");
    match armcal::tablebuild::build(&fit.arm) {
        Ok(bytes) => {
            std::fs::write(&table, bytes).with_context(|| table.display().to_string())?;
            rep.output.table = Some(table.display().to_string());
        }
        Err(e) => rep.warnings.push(format!("binary table not written: {e}")),
    }
    if a.json {
        println!("{}", rep.json());
    } else {
        print!("{}", rep.text());
    }
    Ok(())
}
