//! `armcal calibrate` (placeholder: its issue fills it in).

/// Arguments of `armcal calibrate`.
#[derive(clap::Args)]
pub struct Args {}

/// Runs the subcommand.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("armcal calibrate: not built yet")
}
