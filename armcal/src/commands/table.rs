//! `armcal table build|show` (placeholder: its issue fills it in).

/// `armcal table` subcommands.
#[derive(clap::Subcommand)]
pub enum Command {
    /// Build a binary table from a calibration file.
    Build {},
    /// Show a binary table.
    Show {},
}

/// Runs the subcommand.
pub fn run(_command: Command) -> anyhow::Result<()> {
    anyhow::bail!("armcal table: not built yet")
}
