//! `armcal eval`: joint readings in, probe-ball XYZ and probe direction out.

use anyhow::Context;
use armcal::eval::{evaluate, read_rows, Evaluator};
use armcal::uncertainty::columns::{columns_observed, Method};
use armcal::uncertainty::propagate::Leverage;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `armcal eval`.
#[derive(clap::Args)]
pub struct Args {
    /// Calibration file (TOML).
    #[arg(long)]
    calib: PathBuf,
    /// Evaluator: the f64 reference, or the firmware's f32 or fixed-point chain on the
    /// binary table a board would load.
    #[arg(long, value_enum, default_value_t = Evaluator::F64)]
    precision: Evaluator,
    /// CSV with columns j1..jN (rad) or c1..cN (counts), optional temp_c and probe (the id of
    /// the probe each reading was taken with; the first where absent); stdin if absent.
    input: Option<PathBuf>,
    /// Add each point's covariance and U95 (`cxx,cyy,czz,cxy,cxz,cyz` mm², `U95` mm) from the
    /// calibration's `[uncertainty]` budget, computed on the f64 reference; with a
    /// leverage-scaled pose term (`pose_*` keys) also `leverage`, each reading's ℓ, and with
    /// a joint leverage (`pose_joint_*` keys) `joint_leverage`, its ℓJ.
    #[arg(long)]
    uncertainty: bool,
    /// How the uncertainty is propagated.
    #[arg(long, value_enum, default_value_t = Method::FirstOrder, requires = "uncertainty")]
    method: Method,
    /// Monte Carlo draws per row.
    #[arg(long, default_value_t = 10_000, requires = "uncertainty", value_parser = clap::value_parser!(u64).range(100..=10_000_000))]
    draws: u64,
    /// Seed of the Monte Carlo draws.
    #[arg(long, default_value_t = 0x6c_75_6d, requires = "uncertainty")]
    seed: u64,
    /// The data the calibration was fitted on (measured-data CSV): each reading farther from
    /// every calibration tip than twice their own spacing is flagged as extrapolated, in a
    /// column `far` (1: flagged), and each in a joint configuration outside the calibration's
    /// spread in a column `far_joints`; with `--uncertainty` and a leverage-scaled pose term,
    /// each whose leverage ratio (ℓ, or max(ℓ, ℓJ) with a joint leverage) is above every
    /// calibration row's in a last column `far_leverage`; counts on stderr.
    #[arg(long, value_name = "DATA.csv")]
    seen: Option<PathBuf>,
    /// Show the count of rows done and the time left on stderr even when it is not a terminal
    /// (on a terminal it is always shown for `--uncertainty`).
    #[arg(long)]
    progress: bool,
    #[command(flatten)]
    accept: super::accept::AcceptArgs,
}

/// Runs the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    armcal::plausible::calibration(&args.calib, args.accept.accept())?;
    armcal::load::warn_if_due(&args.calib)?;
    let (arm, budget) = armcal::uncertainty::load::calibration_and_budget(
        &args.calib,
        args.uncertainty.then_some("--uncertainty"),
    )?;
    let (rows, name) = match &args.input {
        Some(p) => {
            let f = std::fs::File::open(p).with_context(|| format!("{}", p.display()))?;
            (read_rows(&arm, f), p.display().to_string())
        }
        None => (
            read_rows(&arm, std::io::stdin().lock()),
            "stdin".to_string(),
        ),
    };
    let rows = rows.map_err(|e| {
        // Another joint count than the calibration's: say whose arm the calibration is.
        let e = format!("{name}: {e:#}");
        if e.contains(" joints") {
            anyhow::anyhow!(
                "{e}; {} ({})",
                armcal::data::whose_arm(&arm),
                args.calib.display()
            )
        } else {
            anyhow::anyhow!(e)
        }
    })?;
    let radians: Vec<Vec<f64>> = rows.iter().map(|r| r.reading.radians(&arm)).collect();
    let placed: Vec<armcal::plausible::Reading> = rows
        .iter()
        .zip(&radians)
        .enumerate()
        .map(|(k, (r, theta))| armcal::plausible::Reading {
            theta,
            temp_c: Some(r.temp_c),
            place: format!("data row {}", k + 1),
        })
        .collect();
    armcal::plausible::readings(&name, &placed, args.accept.accept())?;
    let mut out = evaluate(
        &arm,
        &rows,
        args.precision,
        &args.calib.display().to_string(),
    )?;
    let mut leverage = Vec::new();
    if let Some(b) = &budget {
        let mut counter =
            armcal::progress::Counter::new(args.progress, "eval", "rows", rows.len() as u64);
        let extra = columns_observed(
            &arm,
            b,
            &rows,
            args.method,
            args.draws as usize,
            args.seed,
            &mut || counter.tick(),
        );
        drop(counter);
        let mut joined = String::with_capacity(out.len() * 2);
        let mut lines = out.lines();
        if let Some(h) = lines.next() {
            joined.push_str(&format!("{h},{}\n", extra.header));
        }
        for (l, e) in lines.zip(&extra.lines) {
            joined.push_str(&format!("{l},{e}\n"));
        }
        out = joined;
        note_widened(&extra.leverage);
        leverage = extra.leverage;
    }
    if let Some(seen) = &args.seen {
        out = flag_far(&arm, &rows, seen, &out)?;
        if let (Some(b), true) = (&budget, leverage.iter().any(|l| l.tip.is_some())) {
            out = flag_leverage(&arm, b, seen, &leverage, &out)?;
        }
    }
    let mut stdout = std::io::stdout().lock();
    stdout.write_all(out.as_bytes())?;
    stdout.flush()?;
    Ok(())
}

/// What the factor on the pose part was taken of, for the messages: ℓ, or max(ℓ, ℓJ) where
/// the budget has a joint leverage.
fn ratio_name(leverage: &[Leverage]) -> &'static str {
    if leverage.iter().any(|l| l.joints.is_some()) {
        "max(ℓ, ℓJ) (columns `leverage`, `joint_leverage`)"
    } else {
        "ℓ (column `leverage`)"
    }
}

/// The count of readings whose pose part was widened (ratio above 1), on stderr.
fn note_widened(leverage: &[Leverage]) {
    let l: Vec<f64> = leverage.iter().filter_map(Leverage::ratio).collect();
    let widened = l.iter().filter(|x| **x > 1.0).count();
    if widened > 0 {
        eprintln!(
            "armcal: {widened} of {} readings have a leverage ratio above 1 (largest {:.2}): \
             their pose-dependent term is multiplied by {}",
            leverage.len(),
            l.iter().copied().fold(0.0, f64::max),
            ratio_name(leverage)
        );
    }
}

/// `out` with a last column `far_leverage`: 1 where the reading's leverage ratio (the
/// factor's, [`Leverage::ratio`]: ℓ, or max(ℓ, ℓJ) with a joint leverage; one per row) is
/// above every row's of the calibration data `seen` under the same budget — the
/// parameters' leverage of a placement the calibration did not see, where the budget's
/// pose term is extrapolated; the count goes to stderr.
fn flag_leverage(
    arm: &quatarm_ref::Arm,
    budget: &armcal::uncertainty::Budget,
    seen: &std::path::Path,
    leverage: &[Leverage],
    out: &str,
) -> anyhow::Result<String> {
    let data = armcal::data::read(seen, arm.dof())?;
    let largest = data
        .rows
        .iter()
        .filter_map(|r| {
            let probe = armcal::fit::probes::index(arm, r);
            armcal::uncertainty::propagate::point_with_leverage(
                arm, probe, budget, &r.theta, r.temp_c,
            )
            .2
            .ratio()
        })
        .fold(0.0, f64::max);
    let mut far = 0usize;
    let mut joined = String::with_capacity(out.len() + 2 * leverage.len() + 16);
    let mut lines = out.lines();
    if let Some(h) = lines.next() {
        joined.push_str(&format!("{h},far_leverage\n"));
    }
    for (l, x) in lines.zip(leverage) {
        let f = x.ratio().is_some_and(|x| x > largest);
        far += usize::from(f);
        joined.push_str(&format!("{l},{}\n", u8::from(f)));
    }
    if far > 0 {
        eprintln!(
            "armcal: warning: {far} of {} readings have a leverage ratio {} above every row of \
             {} (> {largest:.2}): the pose term is extrapolated there",
            leverage.len(),
            ratio_name(leverage),
            seen.display()
        );
    }
    Ok(joined)
}

/// `out` with two last columns: `far`, 1 where the reading's tip (the f64 reference's) is far
/// from every tip of the calibration data `seen`, and `far_joints`, 1 where its joint angles
/// are outside their spread
/// ([`armcal::uncertainty::extrapolation`]); the count goes to stderr.
fn flag_far(
    arm: &quatarm_ref::Arm,
    rows: &armcal::eval::Rows,
    seen: &std::path::Path,
    out: &str,
) -> anyhow::Result<String> {
    let data = armcal::data::read(seen, arm.dof())?;
    armcal::fit::probes::check(arm, &data)?;
    let support =
        armcal::uncertainty::extrapolation::Support::of(arm, &data).with_context(|| {
            format!(
                "{}: one unit of evidence (one point or group) gives no spacing to judge \
             extrapolation by",
                seen.display()
            )
        })?;
    let mounted: Vec<_> = (0..arm.probe_count())
        .filter_map(|k| arm.for_probe(k))
        .collect();
    let (mut far, mut new_config) = (0usize, 0usize);
    let mut joined = String::with_capacity(out.len() + 2 * rows.len() + 4);
    let mut lines = out.lines();
    if let Some(h) = lines.next() {
        joined.push_str(&format!("{h},far,far_joints\n"));
    }
    for (l, r) in lines.zip(rows) {
        let with = mounted
            .get(r.probe)
            .context("a row's probe is one of the arm's")?;
        let theta = r.reading.radians(arm);
        let p = quatarm_ref::forward::forward(with, &theta, r.temp_c).p;
        let f = support.far(&p);
        let j = support.joints.as_ref().is_some_and(|s| s.far(&theta));
        far += usize::from(f);
        new_config += usize::from(j);
        joined.push_str(&format!("{l},{},{}\n", u8::from(f), u8::from(j)));
    }
    if new_config > 0 {
        eprintln!(
            "armcal: warning: {new_config} of {} readings are in a joint configuration outside \
             every row of {} (the model's misfit grows there)",
            rows.len(),
            seen.display()
        );
    }
    if far > 0 {
        eprintln!(
            "armcal: warning: {far} of {} readings are extrapolated: farther than {:.1} mm from \
             every tip of {} (the budget has no held-out evidence there)",
            rows.len(),
            support.threshold_mm(),
            seen.display()
        );
    }
    Ok(joined)
}
