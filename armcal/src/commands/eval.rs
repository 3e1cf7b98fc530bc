//! `armcal eval` (placeholder: its issue fills it in).

/// Arguments of `armcal eval`.
#[derive(clap::Args)]
pub struct Args {}

/// Runs the subcommand.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("armcal eval: not built yet")
}
