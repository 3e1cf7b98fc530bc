//! `cargo xtask`: the project's build, test and demo commands, run the same way by a person
//! and by CI (`.ci/run` calls `cargo xtask test`).
//!
//! - `setup`: installs the firmware tool chain and QEMU where missing (the others call it).
//! - `build`: cross-builds every board (or one).
//! - `test`: fmt, clippy, workspace tests (doctests included), rustdoc with `-D warnings`,
//!   board builds, QEMU end-to-end runs.
//! - `demo`: the main job: qemu-m4f replays a recording; XYZ beside the f64 reference.
//! - `bench-target`: flash, RAM and instructions per point of every board and chain.
//! - `fuzz`: long runs of the libFuzzer targets of `fuzz/`.
//! - `soak`: 10^6 corrupted frames into each QEMU hub, every one accounted for.

mod bench;
mod build;
mod cbase;
mod demo;
mod floor;
mod fuzz;
mod fuzz_seeds;
mod make_recording;
mod setup;
mod soak;
mod test;
mod toolchain;

use anyhow::Result;
use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "cargo xtask")]
struct Cli {
    #[command(subcommand)]
    command: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Install the thumb tool chain (rustup targets, else Debian's rustc-web with build-std)
    /// and qemu-system-arm, where missing. Never removes a package.
    Setup {
        /// Also install Debian's tool chain where rustup has the targets, so that the firmware
        /// is built and tested with both compilers (what CI does).
        #[arg(long)]
        every_compiler: bool,
    },
    /// Cross-build the boards (release).
    Build {
        /// Only this board.
        #[arg(long)]
        board: Option<String>,
    },
    /// Everything CI checks: fmt, clippy, tests, rustdoc, board builds, QEMU end-to-end runs.
    Test,
    /// Replay the shipped recording on qemu-m4f and compare with the f64 reference.
    Demo {
        /// Print every point, not a sample.
        #[arg(long)]
        all: bool,
    },
    /// Flash, RAM and instructions per corrected point, per board and chain.
    BenchTarget {
        /// Only this board.
        #[arg(long)]
        board: Option<String>,
        /// Calibration file to measure with (default: data/default-6-full.toml).
        #[arg(long)]
        calib: Option<std::path::PathBuf>,
        /// Give the calibration's budget a pose part of this many columns of D (issue 27;
        /// synthetic values, every reading's leverage above 1: U95's widest path).
        #[arg(long)]
        pose_factors: Option<usize>,
        /// With `--pose-factors`: give the pose part the joint leverage too (issue 27,
        /// synthetic μ and a dense W: ℓJ's cost on every reading).
        #[arg(long, requires = "pose_factors")]
        pose_joints: bool,
    },
    /// Run the fuzz targets of fuzz/ (libFuzzer, cargo-fuzz), each for a while.
    Fuzz {
        /// Only this target.
        #[arg(long)]
        target: Option<String>,
        /// Seconds per target.
        #[arg(long, default_value_t = 300)]
        seconds: u32,
    },
    /// Soak each QEMU hub: frames with random corruption both ways, every one accounted for.
    Soak {
        /// Only this board.
        #[arg(long)]
        board: Option<String>,
        /// Readings sent.
        #[arg(long, default_value_t = 1_000_000)]
        frames: usize,
        /// Seed of the corruption.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// Regenerate the shipped recording data/recordings/default-6-session.csv.
    #[command(hide = true)]
    MakeRecording,
    /// Regenerate the seed files of the fuzz corpora (fuzz/corpus/*/seed-*) from data/ and
    /// the tests' streams.
    #[command(hide = true)]
    FuzzSeeds,
}

fn main() -> Result<()> {
    match Cli::parse().command {
        Cmd::Setup { every_compiler } => setup::run(every_compiler),
        Cmd::Build { board } => build::run(board.as_deref()),
        Cmd::Test => test::run(),
        Cmd::Demo { all } => demo::run(all),
        Cmd::BenchTarget {
            board,
            calib,
            pose_factors,
            pose_joints,
        } => bench::run(
            board.as_deref(),
            calib.as_deref(),
            pose_factors.map(|r| (r, pose_joints)),
        ),
        Cmd::Fuzz { target, seconds } => fuzz::run(target.as_deref(), seconds),
        Cmd::Soak {
            board,
            frames,
            seed,
        } => soak::run(board.as_deref(), frames, seed),
        Cmd::MakeRecording => make_recording::run(),
        Cmd::FuzzSeeds => fuzz_seeds::run(),
    }
}
