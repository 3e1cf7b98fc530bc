//! `armcal check`: the acceptance and reverification tests of `spec/acceptance-tests.md` on
//! measured data, with the calibrated model, and the ISO 14253-1 decision against an MPE file.

use anyhow::Context;
use armcal::acceptance::{self, mpe::Mpe};
use std::path::PathBuf;

/// Arguments of `armcal check`.
#[derive(clap::Args)]
pub struct Args {
    /// Measured data (`sphere`, `length` and `spat` groups; spec/measured-data.md).
    data: PathBuf,
    /// The calibration the ball centres are evaluated with.
    #[arg(long)]
    calib: PathBuf,
    /// Maximum permissible errors (TOML, spec/acceptance-tests.md): adds the decision.
    #[arg(long)]
    mpe: Option<PathBuf>,
    /// Print the result as JSON instead of the text report.
    #[arg(long)]
    json: bool,
}

/// Runs the subcommand: everything is read and checked before anything is printed.
pub fn run(a: Args) -> anyhow::Result<()> {
    let arm = armcal::load::arm(&a.calib)?;
    let mpe = a.mpe.as_deref().map(Mpe::read).transpose()?;
    let data = armcal::data::read(&a.data, arm.dof())?;
    for w in &data.warnings {
        eprintln!("armcal: warning: {w}");
    }
    let c = acceptance::check(&arm, &data, mpe.as_ref())
        .with_context(|| format!("{}", a.data.display()))?;
    if c.tests.is_empty() {
        anyhow::bail!(
            "{}: no sphere, length or spat group: no acceptance test to run",
            a.data.display()
        );
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&c)?);
    } else {
        print!("{}", c.text());
    }
    Ok(())
}
