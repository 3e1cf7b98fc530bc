//! `armcal accuracy` (placeholder: its issue fills it in).

/// Arguments of `armcal accuracy`.
#[derive(clap::Args)]
pub struct Args {}

/// Runs the subcommand.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("armcal accuracy: not built yet")
}
