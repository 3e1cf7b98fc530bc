//! `armcal diagnose` (placeholder: its issue fills it in).

/// Arguments of `armcal diagnose`.
#[derive(clap::Args)]
pub struct Args {}

/// Runs the subcommand.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("armcal diagnose: not built yet")
}
