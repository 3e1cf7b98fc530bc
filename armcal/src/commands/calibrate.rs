//! `armcal calibrate`: identify an arm's parameters from measured data.

use anyhow::Context;
use armcal::data::Dataset;
use armcal::fit::calib;
use armcal::fit::finish::Fit;
use armcal::fit::holdout::{self, Holdout};
use armcal::fit::options::Options;
use armcal::fit::priors::{Prior, Ridge};
use armcal::fit::report;
use armcal::fit::residuals::{residuals, summarise};
use armcal::html::header::Provenance;
use armcal::output::Staged;
use armcal::params::Terms;
use armcal::uncertainty::report::BudgetReport;
use quatarm_ref::arm::Arm;
use std::path::{Path, PathBuf};

/// Arguments of `armcal calibrate`.
#[derive(clap::Args)]
pub struct Args {
    /// Measured data (CSV of `spec/measured-data.md`): any mix of point, spat and length rows,
    /// in one file or several (`simulate` writes one kind per file); each file's groups are
    /// kept apart, joint readings in radians (`j1..jN`) or encoder counts (`c1..cN`).
    #[arg(required = true, num_args = 1..)]
    data: Vec<PathBuf>,
    /// The arm to start from (its nominal geometry, or an earlier calibration); default the
    /// spec's `default-6`.
    #[arg(long)]
    arm: Option<PathBuf>,
    #[arg(long, default_value = "geometric", help = terms_help())]
    terms: String,
    /// The calibration file to write; the firmware's binary table goes beside it (`.bin`).
    #[arg(short, long)]
    output: PathBuf,
    /// Print the report as JSON instead of text.
    #[arg(long)]
    json: bool,
    /// Folds of held-out validation (0: none).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(0..=1000))]
    folds: u32,
    /// Hold out whole groups (sessions, artefact positions) instead of k folds.
    #[arg(long)]
    by_group: bool,
    /// Iterations before a fit is declared not converging.
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    max_iter: u32,
    /// Fit a degenerate pose set anyway, holding what it cannot determine.
    #[arg(long)]
    allow_degenerate: bool,
    /// Keep an extended effect only if it is significant at this many standard
    /// uncertainties (backward elimination; 0 keeps every effect requested).
    #[arg(long, default_value_t = 0.0, value_parser = super::args::non_negative)]
    significance: f64,
    /// Prior standard deviation of zero offsets and tilts (rad), regularising weak directions.
    #[arg(long, requires = "prior_length", value_parser = super::args::positive)]
    prior_angle: Option<f64>,
    /// Prior standard deviation of link and probe errors (mm).
    #[arg(long, requires = "prior_angle", value_parser = super::args::positive)]
    prior_length: Option<f64>,
    /// MUKCa's regulariser: a ridge λ·Σ Δp² (metres, radians) on every joint's geometric
    /// errors, the probe free: `--ridge` is MUKCa's default λ = 1e-4, `--ridge=3e-5` another. For
    /// data from few artefact positions (one MUKCa session), where some directions are barely
    /// determined.
    #[arg(long, num_args = 0..=1, require_equals = true, default_missing_value = "1e-4", value_name = "LAMBDA", value_parser = super::args::positive)]
    ridge: Option<f64>,
    /// A fleet prior: calibration files of other units of the same design as `--arm` (its
    /// nominal arm). Each geometric error is pulled towards the units' mean error, weighed by
    /// their spread, in place of the ridge or `--prior-angle/--prior-length`, which still apply
    /// to errors fewer than 3 units determined. Give the data file before this list.
    #[arg(long, num_args = 1.., value_name = "CAL.toml")]
    fleet_prior: Vec<PathBuf>,
    /// Show progress on stderr even when it is not a terminal.
    #[arg(long)]
    progress: bool,
    /// Write the calibration certificate here: one self-contained HTML page (header with the
    /// arm's serial, the data file and its SHA-256, the residuals before, after and held out,
    /// residual vectors against position, every parameter), which a browser prints to PDF.
    #[arg(long, value_name = "FILE.html")]
    report: Option<PathBuf>,
    #[command(flatten)]
    budget: super::budget::BudgetArgs,
    #[command(flatten)]
    accept: super::accept::AcceptArgs,
}

/// Reads the start arm: a file (its angles in radians unless `accept.units`), or `default-6`.
pub fn start_arm(path: Option<&Path>, accept: armcal::plausible::Accept) -> anyhow::Result<Arm> {
    match path {
        None => Ok(Arm::default6()),
        Some(p) => {
            armcal::plausible::calibration(p, accept)?;
            Ok(armcal::load::arm(p)?)
        }
    }
}

/// Runs the subcommand. Everything that can be refused without a fit (the start arm, the
/// terms, the output's name, the data) is checked before the fit; the files are written
/// together at the end, or none of them.
pub fn run(a: Args) -> anyhow::Result<()> {
    let start = start_arm(a.arm.as_deref(), a.accept.accept())?;
    let terms = Terms::parse(&a.terms, start.dof())?;
    let table = a.output.with_extension("bin");
    let inputs = inputs(&a);
    let mut outputs = vec![
        (a.output.as_path(), "calibration file"),
        (&table, "binary table"),
    ];
    if let Some(r) = &a.report {
        outputs.push((r.as_path(), "report"));
    }
    armcal::output::check(&outputs, &inputs)?;
    let data = super::data_in::read(&a.data, &start, a.accept.accept())?;
    let fleet = if a.fleet_prior.is_empty() {
        None
    } else {
        Some(armcal::fit::fleet_prior::from_files(
            &start,
            &a.fleet_prior,
        )?)
    };
    let opts = options(&a, &terms, fleet.as_ref());
    let mut observer = armcal::progress::for_command(a.progress, "calibrating");
    let fit = calib::calibrate_observed(&start, &data, &opts, observer.as_mut())
        .with_context(|| format!("cannot calibrate from {}", super::data_in::names(&a.data)))?;
    let (method, validation) = validate(&a, &start, &data, &opts, observer.as_mut());
    drop(observer);
    let before = summarise(&residuals(&fit.start, &data, None), &data);
    let after = summarise(&residuals(&fit.arm, &data, fit.frame), &data);
    let mut rep = report::build(
        &fit,
        &data,
        before,
        after,
        validation.as_ref().map(|h| (method.as_str(), h)),
    );
    rep.terms = terms.spec();
    rep.prior = prior_report(&a, fleet, &fit);
    if validation.is_none() && (a.folds > 0 || a.by_group) {
        rep.residuals.holdout_note = Some(
            "none: the data are a single unit (one group) that cannot be split into folds".into(),
        );
    }
    let mut files = Staged::guarding(&inputs);
    stage(
        &a,
        &terms,
        &fit,
        &data,
        validation.as_ref(),
        &mut rep,
        &mut files,
    )?;
    files.commit()?;
    super::print_report(a.json, || rep.json(), || rep.text());
    Ok(())
}

/// The files no output may overwrite: the data, the start arm, the fleet prior's
/// calibrations.
fn inputs(a: &Args) -> Vec<(&Path, &'static str)> {
    let mut inputs = super::data_in::inputs(&a.data);
    if let Some(arm) = &a.arm {
        inputs.push((arm.as_path(), "start arm"));
    }
    for f in &a.fleet_prior {
        inputs.push((f.as_path(), "fleet prior's calibration"));
    }
    inputs
}

/// The held-out validation the arguments ask for (`--folds`, `--by-group`): its method in
/// words and its result, `None` where none is asked or the data are one unit that cannot be
/// split.
fn validate(
    a: &Args,
    start: &Arm,
    data: &Dataset,
    opts: &Options,
    observer: &mut dyn armcal::progress::Observer,
) -> (String, Option<Holdout>) {
    let k = a.folds as usize;
    let (folds, method) = if a.by_group {
        (holdout::by_group(data), "one group at a time".to_string())
    } else {
        (holdout::kfold(data, k, 0x0f01d), format!("{k}-fold"))
    };
    let held = (k > 0 || a.by_group) && folds.len() > 1;
    let validation = held.then(|| holdout::validate_observed(start, data, opts, &folds, observer));
    (method, validation)
}

/// Stages the outputs: the calibration file (checked by reading it back and evaluating it),
/// with its uncertainty budget, its binary table where the firmware can hold the model, and
/// the HTML report if asked; the report says what was written.
fn stage(
    a: &Args,
    terms: &Terms,
    fit: &Fit,
    data: &Dataset,
    validation: Option<&Holdout>,
    rep: &mut report::Report<BudgetReport>,
    files: &mut Staged,
) -> anyhow::Result<()> {
    let header = [
        format!(
            "calibrated by armcal calibrate from {}",
            super::data_in::names(&a.data)
        ),
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
    let made = a
        .budget
        .budget(fit, data, validation, rep.residuals.after.all.rms_um);
    let budget = super::budget::or_warning(made, &mut rep.uncertainty, &mut rep.warnings);
    let text = super::written::checked_text(&fit.arm, budget.as_ref(), &refs, data)?;
    let table =
        super::written::stage_with_table(files, &a.output, &text, &fit.arm, budget.as_ref())?;
    rep.output.calibration = Some(a.output.display().to_string());
    match table {
        Ok(table) => rep.output.table = Some(table.display().to_string()),
        Err(e) => rep.warnings.push(format!("binary table not written: {e}")),
    }
    if let Some(r) = &a.report {
        let prov = Provenance::of_fit(&fit.arm, a.arm.as_deref(), &a.data, data);
        let page = armcal::html::calibration::page(rep, fit, data, validation, &prov);
        files.write(r, page.as_bytes())?;
    }
    Ok(())
}

/// The fit's options from the arguments.
fn options(
    a: &Args,
    terms: &Terms,
    fleet: Option<&armcal::fit::fleet_prior::FleetPrior>,
) -> Options {
    let mut opts = Options {
        terms: terms.clone(),
        allow_degenerate: a.allow_degenerate,
        significance: a.significance,
        ..Options::default()
    };
    opts.lm.max_iterations = a.max_iter as usize;
    if a.prior_angle.is_some() || fleet.is_some() {
        opts.prior = Some(Prior {
            angle_rad: a.prior_angle,
            length_mm: a.prior_length,
            unknowns: fleet.map(|f| f.gaussians()).unwrap_or_default(),
            ..Prior::default()
        });
    }
    if let Some(lambda) = a.ridge {
        opts.ridge = Some(Ridge { lambda });
    }
    opts
}

/// What the report says of the prior: the rule of the unknowns without a fleet Gaussian, and
/// the fleet's statistics (`None`: plain least squares).
fn prior_report(
    a: &Args,
    fleet: Option<armcal::fit::fleet_prior::FleetPrior>,
    fit: &Fit,
) -> Option<report::PriorReport> {
    let mut rule = Vec::new();
    if let (Some(angle), Some(length)) = (a.prior_angle, a.prior_length) {
        rule.push(format!("Gaussian 0 ± {angle} rad, 0 ± {length} mm"));
    }
    if let Some(lambda) = a.ridge {
        rule.push(format!("ridge λ = {lambda}"));
    }
    if rule.is_empty() && fleet.is_none() {
        return None;
    }
    let rule = if rule.is_empty() {
        "none: least squares, held where the data cannot determine it".to_string()
    } else {
        rule.join(" and ")
    };
    Some(report::PriorReport {
        rule,
        fleet,
        dropped: report::DroppedPrior::of(fit),
    })
}

/// The help of `--terms`, with an example of every effect from the registry.
fn terms_help() -> String {
    use armcal::params::{Effect, Link};
    let example = [
        Effect::Harmonic { joint: 1, order: 1 },
        Effect::Gravity(3),
        Effect::Thermal(Link::Probe),
    ];
    format!(
        "What to fit: `geometric` (the 6N + 3 parameters), plus effects such as `{}` (joint \
         numbers 1-based, `*` for all), or `only,+…` for the effects alone",
        example.map(|e| e.spec()).join(",")
    )
}
