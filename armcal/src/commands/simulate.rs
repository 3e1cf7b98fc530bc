//! `armcal simulate` (placeholder: its issue fills it in).

/// Arguments of `armcal simulate`.
#[derive(clap::Args)]
pub struct Args {}

/// Runs the subcommand.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("armcal simulate: not built yet")
}
