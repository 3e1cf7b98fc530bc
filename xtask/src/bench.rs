//! `cargo xtask bench-target` (filled in with the chain).
use anyhow::Result;

pub fn run() -> Result<()> {
    anyhow::bail!("bench-target: waits for the chain")
}
