//! `armcal eval`: joint readings in, probe-ball XYZ and probe direction out.

use anyhow::Context;
use armcal::eval::{evaluate, read_rows, Evaluator};
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
    /// CSV with columns j1..jN (rad) or c1..cN (counts) and optional temp_c; stdin if absent.
    input: Option<PathBuf>,
}

/// Runs the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    let arm = armcal::load::arm(&args.calib)?;
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
    let rows = rows.with_context(|| name.clone())?;
    let out = evaluate(
        &arm,
        &rows,
        args.precision,
        &args.calib.display().to_string(),
    )?;
    let mut stdout = std::io::stdout().lock();
    stdout.write_all(out.as_bytes())?;
    stdout.flush()?;
    Ok(())
}
