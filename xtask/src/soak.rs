//! `cargo xtask soak`: the long soak of `host_tests::soak` (10^6 frames by default) on each
//! QEMU board, with the counts on both sides. `cargo xtask test` runs a shorter one in
//! the QEMU end-to-end tests (25,000).

use anyhow::Result;
use host_tests::boards::{board, boards, Board};
use host_tests::soak;

use crate::{build::build_board, setup};

/// One damaged frame in this many, each way.
pub const ONE_IN: usize = 50;

/// `cargo xtask soak [--board NAME] [--frames N] [--seed S]`.
pub fn run(only: Option<&str>, frames: usize, seed: u64) -> Result<()> {
    setup::ensure()?;
    let boards: Vec<Board> = match only {
        Some(name) => vec![board(name)?],
        None => boards()?
            .iter()
            .filter(|b| b.qemu.is_some())
            .copied()
            .collect(),
    };
    for b in &boards {
        build_board(b)?;
        let c = soak::run(b, frames, ONE_IN, seed)?;
        println!("soak {}: {frames} frames in, seed {seed}, one in {ONE_IN} damaged each way, {:.0} s under QEMU", b.name, c.qemu_seconds);
        println!(
            "  host->hub damage: {:?} ({} frames touched)",
            c.damage_in,
            c.damage_in.total()
        );
        println!(
            "  hub: {} reports, {} with coordinates (= {} intact frames, each equal to the host build), {} rejected as INPUT_ERROR (= its log's count and its receiver's on the host)",
            c.hub_reports, c.hub_points, c.intact_in, c.hub_rejected
        );
        println!(
            "  hub->host damage: {:?} ({} frames touched)",
            c.damage_out,
            c.damage_out.total()
        );
        println!(
            "  host decoder: {} reports (each identical to the hub's), {} lost, {} damaged; {} + {} = {} sent",
            c.host_reports, c.host_lost, c.host_damaged, c.host_reports, c.host_lost, c.hub_reports
        );
    }
    Ok(())
}
