//! `cargo xtask demo`: the main job, end to end on an emulated hub.
//!
//! Builds `qemu-m4f`, builds the binary table of the default full calibration
//! (`data/default-6-full.toml`, as `armcal table build` does) and loads it into the board's
//! own calibration flash region, replays the shipped recording of encoder counts
//! (`data/recordings/default-6-session.csv`) into its UART under QEMU, decodes the stream that
//! comes back and puts each corrected XYZ beside the f64 reference evaluation of the same
//! reading. The last line is the summary outside checks read.

use anyhow::{bail, Result};
use host_tests::boards::board;
use host_tests::e2e::{
    calibration, default_calibration_path, default_recording_path, deviation_um, reference, replay,
};
use host_tests::recording::{self, replay_bytes};

use crate::build::build_board_with;
use crate::setup;
use crate::toolchain;

/// Every how many points a sample line is printed (all with `--all`).
const SAMPLE: usize = 500;

/// `cargo xtask demo [--all]`.
pub fn run(all: bool) -> Result<()> {
    setup::ensure()?;
    let b = board("qemu-m4f")?;
    let survey = toolchain::survey();
    let tc = survey.primary()?;
    // The QEMU run below finds the image by this variable.
    std::env::set_var(toolchain::TOOLCHAIN_ENV, tc.kind.name());
    build_board_with(&b, tc)?;
    let cal_path = default_calibration_path();
    let (arm, table) = calibration(&cal_path)?;
    let readings = recording::read(&default_recording_path())?;
    eprintln!(
        "demo: {} on QEMU {}: {} recorded readings in over UART0, table of {} ({} bytes) in its own flash region",
        b.name,
        b.qemu.map_or("", |m| m.machine),
        readings.len(),
        cal_path.display(),
        table.len()
    );
    let out = replay(&b, Some(&table), &replay_bytes(&readings, None))?;
    if !out.run.status.success() {
        bail!("the firmware ended with {:?}", out.run.status);
    }
    if let Some(h) = out.hellos.first() {
        println!(
            "hub: protocol {}, {:?} chain, {} joints, table {}",
            h.protocol,
            h.precision,
            h.joints,
            h.status.table().name()
        );
    }
    println!(
        "{:>6} {:>10}  {:>34}  {:>34}  {:>9}",
        "seq", "time_us", "streamed x, y, z (mm)", "f64 reference x, y, z (mm)", "diff (um)"
    );
    let mut points = 0usize;
    let mut worst = 0.0f64;
    for (i, (rep, r)) in out.reports.iter().zip(&readings).enumerate() {
        let Some(c) = rep.point else {
            println!(
                "{:>6} {:>10}  no coordinates: status {:#06x}",
                rep.seq, rep.time_us, rep.status.0
            );
            continue;
        };
        points += 1;
        let (p, _) = reference(&arm, r);
        let d = deviation_um(&c, &p);
        worst = worst.max(d);
        if all || i % SAMPLE == 0 || i + 1 == readings.len() {
            let [x, y, z] = c.xyz_nm.map(|v| f64::from(v) / 1e6);
            println!(
                "{:>6} {:>10}  {x:>10.6} {y:>11.6} {z:>11.6}  {:>10.6} {:>11.6} {:>11.6}  {d:>9.4}",
                rep.seq, rep.time_us, p[0], p[1], p[2]
            );
        }
    }
    let lost = (readings.len() - out.reports.len().min(readings.len())) as u64 + out.stats.lost;
    println!(
        "demo: {points} points streamed, {lost} lost, {} crc errors, max deviation from f64 reference {worst:.3} um",
        out.stats.damaged()
    );
    Ok(())
}
