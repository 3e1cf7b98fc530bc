//! `armcal check`: the acceptance and reverification tests of `spec/acceptance-tests.md` on
//! measured data, with the calibrated model, and the ISO 14253-1 decision against an MPE file.

use anyhow::Context;
use armcal::acceptance::{self, mpe::Mpe, virtual_test};
use std::path::PathBuf;

/// Arguments of `armcal check`.
#[derive(clap::Args)]
#[command(after_help = EXIT_CODES)]
pub struct Args {
    /// Measured data (`sphere`, `length` and `spat` groups; spec/measured-data.md), in one file
    /// or several (each file's groups kept apart), joint readings in radians (`j1..jN`) or
    /// encoder counts (`c1..cN`).
    #[arg(required = true, num_args = 1..)]
    data: Vec<PathBuf>,
    /// The calibration the ball centres are evaluated with.
    #[arg(long)]
    calib: PathBuf,
    /// Maximum permissible errors (TOML, spec/acceptance-tests.md): adds the decision.
    #[arg(long)]
    mpe: Option<PathBuf>,
    /// Print the result as JSON instead of the text report.
    #[arg(long)]
    json: bool,
    /// The virtual test: predict each statistic (mean and 95 % interval) by Monte Carlo over
    /// the calibration's `[uncertainty]` budget at the data's readings, beside the measured
    /// value; the budget also gives U where the MPE file has no `test_uncertainty`.
    #[arg(long)]
    predict: bool,
    /// Monte Carlo draws of the virtual test.
    #[arg(long, default_value_t = 2000, value_parser = clap::value_parser!(u64).range(10..=1_000_000))]
    draws: u64,
    /// Seed of the virtual test's draws.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Write the pictures into this folder (created if needed): `sphere_deviations.png`
    /// (radial deviations against azimuth, per sphere group), `length_errors.png` (each bar
    /// position's error against length, height and reach), `spat_scatter.png` (each SPAT
    /// cone's centres about their mean, from above); each only where the data has its groups.
    #[arg(long, value_name = "DIR")]
    plots: Option<PathBuf>,
    /// Write the test report here: one self-contained HTML page (header with the arm's serial,
    /// the files and their SHA-256, the verdict, every value with its U and decision, the
    /// plots), which a browser shows and prints to PDF.
    #[arg(long, value_name = "FILE.html")]
    report: Option<PathBuf>,
    #[command(flatten)]
    accept: super::accept::AcceptArgs,
    /// Accept MPE values outside 0.0005..1 mm (refused as µm or metres written as mm).
    #[arg(long)]
    accept_mpe: bool,
    /// Accept a calibration whose test values on the data exceed 5 mm (refused as another
    /// arm's calibration).
    #[arg(long)]
    accept_misfit: bool,
}

/// The exit codes, as `armcal check --help` lists them.
pub const EXIT_CODES: &str = "Exit codes (ISO 14253-1 with each value's U, against --mpe):
  0  conforms: every value with an MPE is proven within it (also: no --mpe given, values only)
  1  does not conform: at least one value is proven beyond its MPE
  2  cannot decide: none proven beyond, at least one not proven within (value ± U straddles
     the MPE), or the MPE file limits none of the data's tests
  3  error: bad arguments, or a file that cannot be read or is refused; no verdict";

/// Runs the subcommand: everything is read and checked before anything is printed. Returns
/// the exit code of the verdict (errors are `acceptance::verdict::EXIT_ERROR`, by the caller).
pub fn run(a: Args) -> anyhow::Result<i32> {
    let mut inputs = super::data_in::inputs(&a.data);
    inputs.push((a.calib.as_path(), "calibration"));
    if let Some(m) = &a.mpe {
        inputs.push((m.as_path(), "MPE file"));
    }
    if let Some(r) = &a.report {
        armcal::output::check(&[(r.as_path(), "report")], &inputs)?;
    }
    armcal::plausible::calibration(&a.calib, a.accept.accept())?;
    // The budget, where the file has one, gives U where the MPE file has none.
    let (arm, budget) = armcal::uncertainty::load::calibration_with_budget(
        &a.calib,
        a.predict.then_some("--predict"),
    )?;
    let accept = armcal::plausible::Accept {
        mpe: a.accept_mpe,
        misfit: a.accept_misfit,
        ..a.accept.accept()
    };
    let mpe = a.mpe.as_deref().map(Mpe::read).transpose()?;
    if let (Some(m), Some(p)) = (&mpe, &a.mpe) {
        armcal::plausible::mpe(m, &p.display().to_string(), accept)?;
    }
    let data = super::data_in::read(&a.data, &arm, accept)?;
    let names = super::data_in::names(&a.data);
    // The values once: another arm's calibration is refused on them before any prediction or
    // decision, and the decision below reuses them.
    // Named by the group's own file and line, not by all the files given.
    let values = acceptance::measure(&arm, &data).map_err(|e| {
        let at = data.group_place(e.group()).unwrap_or_else(|| names.clone());
        anyhow::anyhow!("{at}: {e}")
    })?;
    armcal::plausible::misfit(
        acceptance::statistics::Test::ALL.iter().filter_map(|&t| {
            acceptance::statistics::result(&values, t).map(|v| (t.key(), v.value_mm * 1e3))
        }),
        &names,
        &a.calib.display().to_string(),
        accept,
    )?;
    let prediction = budget
        .as_ref()
        .map(|b| virtual_test::predict(&arm, b, &data, a.draws as usize, a.seed))
        .transpose()
        .with_context(|| names.clone())?;
    let c = acceptance::decide(
        &arm,
        &data,
        &values,
        mpe.as_ref(),
        prediction.as_ref(),
        a.predict,
    );
    if c.tests.is_empty() {
        anyhow::bail!("{names}: no sphere, length or spat group: no acceptance test to run");
    }
    let mut files = armcal::output::Staged::guarding(&inputs);
    let written = match &a.plots {
        Some(dir) => {
            let figures = acceptance::plots::figures(&data, &acceptance::centres(&arm, &data));
            armcal::diagnose::plots::write_all(&figures, dir, &mut files)?
        }
        None => Vec::new(),
    };
    if let Some(r) = &a.report {
        let prov = armcal::html::header::Provenance {
            arm: &arm,
            arm_file: Some(("calibration file", &a.calib)),
            data_files: a.data.iter().map(PathBuf::as_path).collect(),
            data: &data,
            mpe: a.mpe.as_deref(),
            rule: a.mpe.is_some().then_some(acceptance::verdict::RULE),
        };
        let page = armcal::html::check::page(&c, &arm, &data, mpe.as_ref(), &prov);
        files.write(r, page.as_bytes())?;
    }
    files.commit()?;
    for f in written.iter().chain(&a.report) {
        eprintln!("armcal: wrote {}", f.display());
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&c)?);
    } else {
        print!("{}", c.text());
    }
    Ok(c.verdict.exit_code)
}
