//! `cargo xtask demo` (filled in with the chain).
use anyhow::Result;

pub fn run(_all: bool) -> Result<()> {
    anyhow::bail!("demo: waits for the chain")
}
