//! `cargo xtask bench-target`: per board, flash and RAM used and instructions per corrected
//! point of the quaternion chain and of the 3×4 matrix chain, measured on the target code.
//!
//! Instructions: the board's benchmark image runs under `qemu-system-arm -icount shift=0`
//! (one instruction per nanosecond of virtual time; SysTick counts that clock), timing each
//! evaluation of both chains on the first readings of the shipped recording with the default
//! full calibration (`docs/benchmark-method.md` has the method). Flash and RAM: the hub
//! image's loadable segments (flash: every byte stored; RAM: statics), plus the stack's peak
//! measured by painting during a replay. Boards QEMU does not model are only measured for size.

use anyhow::{bail, Context, Result};
use host_tests::boards::{boards, Board};
use host_tests::defmt_log::{self, number_after};
use host_tests::e2e::{default_calibration_path, default_recording_path, replay, table_file};
use host_tests::qemu::{self, Options};
use host_tests::recording::{self, replay_bytes};
use object::{Object, ObjectSegment};

use crate::build::build_board_with;
use crate::setup;
use crate::toolchain::{self, Toolchain};

/// Readings timed per chain.
const POINTS: usize = 2_000;
const RAM_START: u64 = 0x2000_0000;

/// Bytes of flash and of RAM statics of an ELF.
pub fn sizes(elf: &std::path::Path) -> Result<(u64, u64)> {
    let data = std::fs::read(elf).with_context(|| format!("reading {}", elf.display()))?;
    let file = object::File::parse(&*data)?;
    let (mut flash, mut ram) = (0, 0);
    for seg in file.segments() {
        flash += seg.file_range().1;
        if seg.address() >= RAM_START {
            ram += seg.size();
        }
    }
    Ok((flash, ram))
}

/// One row of the table.
pub struct Row {
    /// The board.
    pub board: Board,
    /// The compiler that built it (`rustc --version`'s number, and its kind).
    pub compiler: String,
    /// Flash bytes of the hub image.
    pub flash: u64,
    /// RAM statics of the hub image.
    pub statics: u64,
    /// Peak stack of the hub during a replay (QEMU boards).
    pub stack: Option<u64>,
    /// Instructions per point: the hub's chain (the lean form where the arm fits it),
    /// the quaternion chain, the matrix chain (QEMU boards).
    pub instructions: Option<(f64, f64, f64)>,
    /// Whether the hub's chain is the lean form.
    pub lean: bool,
    /// Instructions of one Ed25519 check of the table's signature (QEMU boards).
    pub signature: Option<f64>,
    /// Instructions per point of U95: the reading's own terms alone, and the whole U95 as the
    /// hub streams it (QEMU boards with a budget in the table; the second where the hub
    /// computes U95).
    pub u95: [Option<f64>; 2],
}

/// Instructions per point of both chains, of one signature check, and per point of U95
/// (where the table has a budget).
/// What a bench image measured, in instructions.
struct Measured {
    /// Per point: the hub's chain, the quaternion chain, the matrix chain.
    chains: (f64, f64, f64),
    /// Whether the hub's chain is the lean form.
    lean: bool,
    /// One signature check.
    signature: f64,
    /// Per point: U95's own terms, U95 as streamed.
    u95: [Option<f64>; 2],
}

fn instructions(b: &Board, table: &[u8]) -> Result<Measured> {
    let readings = recording::read(&default_recording_path())?;
    let input = replay_bytes(&readings[..POINTS.min(readings.len())], None);
    let file = table_file(table)?;
    let elf = b.elf("bench");
    let run = qemu::run(
        b,
        &elf,
        &input,
        &Options {
            table: Some(file.path().to_path_buf()),
            icount: true,
            ..Options::default()
        },
    )?;
    if !run.status.success() {
        bail!("{} bench image failed: {:?}", b.name, run.status);
    }
    let lines = defmt_log::decode(&elf, &run.log)?;
    let get = |key: &str| {
        number_after(&lines, key).with_context(|| format!("`{key}` missing in {lines:?}"))
    };
    let loop_instr = get("bench calibration loop")? as f64;
    let loop_ticks = lines
        .iter()
        .find(|l| l.starts_with("bench calibration loop"))
        .and_then(|l| l.split_whitespace().rev().nth(1)?.parse::<f64>().ok())
        .context("calibration loop ticks")?;
    let per_tick = loop_instr / loop_ticks;
    let ticks_of = |key: &str| -> Result<(f64, f64)> {
        let line = lines
            .iter()
            .find(|l| l.starts_with(key))
            .with_context(|| format!("`{key}` missing"))?;
        let w: Vec<&str> = line.split_whitespace().collect();
        let points: f64 =
            w[w.iter().position(|&x| x == "points").context("points")? - 1].parse()?;
        let ticks: f64 = w[w.iter().position(|&x| x == "ticks").context("ticks")? - 1].parse()?;
        if line.contains("failures") && !line.ends_with(" 0 failures") {
            bail!("{}: {line}", b.name);
        }
        Ok((points, ticks))
    };
    let sig_line = lines
        .iter()
        .find(|l| l.starts_with("bench signature"))
        .context("`bench signature` missing")?;
    if !sig_line.ends_with("true valid") {
        bail!(
            "{}: the table's signature did not verify: {sig_line}",
            b.name
        );
    }
    let sig_ticks = number_after(&lines, "bench signature").context("signature ticks")? as f64;
    let (n0, t0) = ticks_of("bench clock overhead")?;
    let (nq, tq) = ticks_of("bench quaternion")?;
    let (nh, th) = ticks_of("bench hub chain")?;
    let lean = lines
        .iter()
        .any(|l| l.starts_with("bench hub chain (lean true)"));
    let (nm, tm) = ticks_of("bench matrix")?;
    let (no, to) = ticks_of("bench u95 own terms")?;
    let (nu, tu) = ticks_of("bench u95 streamed")?;
    let overhead = t0 / n0;
    eprintln!(
        "{}: {per_tick:.2} instructions per SysTick tick (nominal {}), clock read {:.0} instructions",
        b.name,
        1e9 / f64::from(b.qemu.map_or(1, |m| m.core_hz)),
        overhead * per_tick
    );
    Ok(Measured {
        chains: (
            (th / nh - overhead) * per_tick,
            (tq / nq - overhead) * per_tick,
            (tm / nm - overhead) * per_tick,
        ),
        lean,
        signature: (sig_ticks - overhead) * per_tick,
        u95: [
            (no > 0.0).then(|| (to / no - overhead) * per_tick),
            (nu > 0.0).then(|| (tu / nu - overhead) * per_tick),
        ],
    })
}

fn measure(b: &Board, tc: &Toolchain, table: &[u8]) -> Result<Row> {
    let (flash, statics) = sizes(&b.elf(b.name))?;
    let (mut stack, mut instr, mut signature, mut u95) = (None, None, None, [None; 2]);
    let mut lean = false;
    if b.qemu.is_some() {
        let readings: Vec<_> = recording::read(&default_recording_path())?
            .into_iter()
            .take(50)
            .collect();
        let out = replay(b, Some(table), &replay_bytes(&readings, None))?;
        let lines = defmt_log::decode(&b.elf(b.name), &out.run.log)?;
        stack = number_after(&lines, "stack peak");
        let m = instructions(b, table)?;
        instr = Some(m.chains);
        lean = m.lean;
        signature = Some(m.signature);
        u95 = m.u95;
    }
    Ok(Row {
        board: *b,
        compiler: format!(
            "{} {}",
            tc.kind.name(),
            tc.version.split_whitespace().nth(1).unwrap_or("?")
        ),
        flash,
        statics,
        stack,
        instructions: instr,
        lean,
        signature,
        u95,
    })
}

/// The table, as markdown.
pub fn table(rows: &[Row]) -> String {
    let mut s = String::from(
        "| board | compiler | chain | flash (bytes) | RAM: statics + stack peak (bytes) | hub's chain (instr/point) | quaternion chain (instr/point) | 3×4 matrix chain (instr/point) | U95, reading's own terms (instr/point) | U95 as streamed (instr/point) | Ed25519 check of the table (instr) |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let ram = match r.stack {
            Some(st) => format!("{} + {} = {}", r.statics, st, r.statics + st),
            None => format!("{} + (not run)", r.statics),
        };
        let (h, q, m) = match r.instructions {
            Some((h, q, m)) => (
                format!("{h:.0} ({})", if r.lean { "lean" } else { "quaternion" }),
                format!("{q:.0}"),
                format!("{m:.0}"),
            ),
            None => (
                "(no QEMU model)".into(),
                "(no QEMU model)".into(),
                "(no QEMU model)".into(),
            ),
        };
        let sig = r
            .signature
            .map_or_else(|| "(no QEMU model)".into(), |n| format!("{n:.0}"));
        let cell = |u: Option<f64>, none: &str| match (u, r.instructions) {
            (Some(n), _) => format!("{n:.0}"),
            (None, Some(_)) => none.into(),
            (None, None) => "(no QEMU model)".into(),
        };
        let own = cell(r.u95[0], "(no budget)");
        let streamed = cell(r.u95[1], "(not computed)");
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.board.name, r.compiler, r.board.precision, r.flash, ram, h, q, m, own, streamed, sig
        ));
    }
    s
}

/// `cargo xtask bench-target`: every board with every firmware tool chain this machine has
/// (or only the one `QUATARM_FIRMWARE` names).
pub fn run(only: Option<&str>, calib: Option<&std::path::Path>) -> Result<()> {
    setup::ensure()?;
    let path = calib.map_or_else(default_calibration_path, std::path::Path::to_path_buf);
    // With the calibration's uncertainty budget where it has one: whole for the f32 boards,
    // without the parameters' covariance for the fixed-point ones (which refuse the block).
    let parsed = quatarm_ref::calfile::read(&path)?;
    let table_for = |b: &Board| -> Result<Vec<u8>> {
        let budget = match &parsed.uncertainty {
            Some(u) if b.precision != "f32" => Some(u.without_covariance()),
            other => other.clone(),
        };
        quatarm_wire::tablebuild::build_with(&parsed.arm, budget.as_ref())
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
    };
    let survey = toolchain::survey();
    let chains: Vec<&Toolchain> = match std::env::var(toolchain::TOOLCHAIN_ENV) {
        Ok(_) => vec![survey.primary()?],
        Err(_) => survey.available.iter().collect(),
    };
    let mut rows = Vec::new();
    for tc in chains {
        // The QEMU runs below find each board's image by this variable.
        std::env::set_var(toolchain::TOOLCHAIN_ENV, tc.kind.name());
        for b in boards()?
            .iter()
            .filter(|b| only.is_none_or(|o| o == b.name))
        {
            build_board_with(b, tc)?;
            rows.push(measure(b, tc, &table_for(b)?)?);
        }
    }
    println!("\n{}", table(&rows));
    println!(
        "(instructions under qemu-system-arm -icount shift=0, mean over {POINTS} recorded readings, calibration {}; \
         the real boards share the cores of qemu-m4f (Cortex-M4F) and qemu-m0 (Cortex-M0; the RP2040 is an M0+))",
        path.display()
    );
    let joints = parsed.arm.joints.len() as u32;
    let compliant = parsed
        .arm
        .joints
        .iter()
        .filter(|j| j.gravity != 0.0)
        .count() as u32;
    let f = lean_floor(joints, compliant);
    println!(
        "(the lean form's counted floor for this arm ({joints} joints, {compliant} compliant), \
         from src/lean.rs, one instruction an operation: {} floating-point (a multiply-add as \
         one), {} loads and stores, {} integer: {} in all, before any quarter-turn selection \
         (4 a joint), register move or flag test; the issue's C lean chain was measured at \
         866, its own floor counted at about 380 floating-point, 500-600 in all)",
        f.fp,
        f.memory,
        f.integer,
        f.fp + f.memory + f.integer
    );
    for (k, why) in &survey.missing {
        println!("(not measured with {}: {why})", k.name());
    }
    Ok(())
}

/// The lean chain's operations a point, counted from its source (`src/lean.rs`): what the
/// hub's chain would take with no register moves, selections or tests.
#[derive(Debug, PartialEq, Eq)]
pub struct Floor {
    /// Floating-point instructions, a multiply-add (`vmla`) as one.
    pub fp: u32,
    /// Loads and stores: the joints' constants, the count, the first pass's records.
    pub memory: u32,
    /// Integer instructions: the count's range check, binary angle, quadrant and remainder.
    pub integer: u32,
}

/// [`Floor`] for an arm of `joints` joints, `compliant` of them with gravity (the power-of-two
/// scales of the hub's encoders). Per joint, first pass: the remainder to f32 and its sine
/// and 1 − cos (2 + 1 + 4 + 3), doubled (4), cos r (1), the harmonic error (5), the vertical
/// turned by Rx, Rz and e (4 + 4 + 4; 3 for the first joint, whose vertical is ẑ); second
/// pass: the link at temperature added (6; 3 for the tip's), the turn by e (10), Rz on the
/// tip and the direction (6 + 4), Rx on both (6 + 4), gravity's deflection (3 where
/// compliant). Per point: the temperature (1), the base's Rz (6 + 4).
pub fn lean_floor(joints: u32, compliant: u32) -> Floor {
    let first = 2 + 1 + 4 + 3 + 4 + 1 + 5 + 12;
    let second = 6 + 10 + 6 + 4 + 6 + 4;
    let fp = joints * (first + second) + 3 * compliant + 1 + 10 - (12 - 3) - 3;
    // Count, its limit, the unit, the offset, 4 harmonic coefficients and cos α, sin α (10);
    // the record (4) and the vertical (2) stored and read back (12); the link and its rate
    // (6), Rx's sin and 1 − cos (2), cos α and sin α again (2); gravity and the vertical (3
    // where compliant). The base turn's 3 and the probe direction's 3, the point's 6 stores.
    let memory = joints * (10 + 12 + 10) + 3 * compliant + 12;
    // Range check (2), multiply, offset, quadrant (add, and, subtract, shift), to f32 (1).
    let integer = joints * 9;
    Floor {
        fp,
        memory,
        integer,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hub's arm (6 joints, 3 compliant): the counts the docs quote.
    #[test]
    fn the_lean_floor_of_the_hub_arm() {
        let f = lean_floor(6, 3);
        assert_eq!((f.fp, f.memory, f.integer), (416, 213, 54));
        // Each joint and each compliant joint adds its share.
        assert_eq!(lean_floor(7, 3).fp - f.fp, 68);
        assert_eq!(lean_floor(6, 4).fp - f.fp, 3);
    }
}
