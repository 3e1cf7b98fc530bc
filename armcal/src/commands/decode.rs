//! `armcal decode` (placeholder: its issue fills it in).

/// Arguments of `armcal decode`.
#[derive(clap::Args)]
pub struct Args {}

/// Runs the subcommand.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("armcal decode: not built yet")
}
