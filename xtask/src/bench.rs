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
use host_tests::e2e::{default_calibration_path, default_recording_path, table_file};
use host_tests::qemu::{self, Options};
use host_tests::recording::{self, replay_bytes};
use object::{Object, ObjectSegment};
use std::path::{Path, PathBuf};

use crate::build::build_board_with;
use crate::cbase;
use crate::floor;
use crate::setup;
use crate::toolchain::{self, Toolchain};

/// The Raspberry Pi Pico's profile measured on qemu-m0's core (the RP2040 is a Cortex-M0+:
/// the same Armv6-M instructions; QEMU models no RP2040): qemu-m0's crate built with its
/// feature `pico-profile` (the wobble, the parameter block, U95 in software f32) into a folder
/// of its own, timed on the full table with its parameter block, and on the wobble
/// calibration.
pub const PICO_PROFILE: &str = "pico-profile";

/// RAM of the profile's benchmark runs: the stack top of `boards/qemu-m0/pico-profile.x`.
const PICO_PROFILE_RAM: u32 = 64 * 1024;

/// The calibration whose every joint wobbles (no budget): the Pico profile's wobble chain and
/// the product's wobble row beside the C baselines.
const WOBBLE_CALIBRATION: &str = "data/default-6-wobble.toml";

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
    /// What the row's first column says: the board's name, or the profile measured on its
    /// core ([`PICO_PROFILE`]).
    pub label: String,
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

fn instructions(b: &Board, elf: &Path, table: &[u8], extra_args: &[String]) -> Result<Measured> {
    let readings = recording::read(&default_recording_path())?;
    let input = replay_bytes(&readings[..POINTS.min(readings.len())], None);
    let file = table_file(table)?;
    let run = qemu::run(
        b,
        elf,
        &input,
        &Options {
            table: Some(file.path().to_path_buf()),
            icount: true,
            extra_args: extra_args.to_vec(),
            ..Options::default()
        },
    )?;
    if !run.status.success() {
        bail!("{} bench image failed: {:?}", b.name, run.status);
    }
    let lines = defmt_log::decode(elf, &run.log)?;
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

/// The row of board `b`'s own images, built by `tc`.
fn measure(b: &Board, tc: &Toolchain, table: &[u8]) -> Result<Row> {
    measure_images(b, b.name.to_owned(), tc, &release_dir(b, tc), table, None)
}

/// Where board `b`'s crate leaves its release images (hub and bench) when built by `tc`.
fn release_dir(b: &Board, tc: &Toolchain) -> std::path::PathBuf {
    tc.kind.target_dir(&b.dir()).join(b.target).join("release")
}

/// The row of the hub and benchmark images in `dir` (release binaries of board `b`'s crate),
/// labelled `label`; the hub's stack peak from a replay, unless the row is a profile's run
/// with more QEMU arguments (`profile_args`: its benchmark image only).
fn measure_images(
    b: &Board,
    label: String,
    tc: &Toolchain,
    dir: &Path,
    table: &[u8],
    profile_args: Option<&[String]>,
) -> Result<Row> {
    let hub = dir.join(b.name);
    let (flash, statics) = sizes(&hub)?;
    let (mut stack, mut instr, mut signature, mut u95) = (None, None, None, [None; 2]);
    let mut lean = false;
    if b.qemu.is_some() && profile_args.is_none() {
        let readings: Vec<_> = recording::read(&default_recording_path())?
            .into_iter()
            .take(50)
            .collect();
        let file = table_file(table)?;
        let opts = Options {
            table: Some(file.path().to_path_buf()),
            ..Options::default()
        };
        let run = qemu::run(b, &hub, &replay_bytes(&readings, None), &opts)?;
        if !run.status.success() {
            bail!("{label} hub image failed: {:?}", run.status);
        }
        let lines = defmt_log::decode(&hub, &run.log)?;
        stack = number_after(&lines, "stack peak");
    }
    if b.qemu.is_some() {
        let m = instructions(b, &dir.join("bench"), table, profile_args.unwrap_or(&[]))?;
        instr = Some(m.chains);
        lean = m.lean;
        signature = Some(m.signature);
        u95 = m.u95;
    }
    Ok(Row {
        board: *b,
        label,
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
            r.label, r.compiler, r.board.precision, r.flash, ram, h, q, m, own, streamed, sig
        ));
    }
    s
}

/// The rows of the Pico's profile on qemu-m0's core ([`PICO_PROFILE`]): the calibration at
/// `calib` whole (the parameter block's U95) with U95 in software f32 and with its parameter
/// product in integers (feature `pico-profile-fixed-u95`), and [`WOBBLE_CALIBRATION`] (the
/// wobble chain).
fn pico_profile(tc: &Toolchain, calib: &Path) -> Result<Vec<Row>> {
    let m0 = host_tests::boards::board("qemu-m0")?;
    let whole = |file: &Path| -> Result<Vec<u8>> {
        let parsed = quatarm_ref::calfile::read(file)?;
        quatarm_wire::tablebuild::build_with(&parsed.arm, parsed.uncertainty.as_ref())
            .map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))
    };
    let wobble = host_tests::boards::root().join(WOBBLE_CALIBRATION);
    // The benchmark image holds both chains, the U95 and the table's boot check at once: with
    // the profile's wobble and parameter block 21 KB of stack in all, more than the nRF51's
    // 16 KiB (instructions do not depend on it). QEMU's nRF51 takes a larger SRAM (its
    // `sram-size`), which `pico-profile.x` puts the stack top in: the Pico has 264 KB.
    let ram = vec![
        "-global".to_owned(),
        format!("nrf51-soc.sram-size={PICO_PROFILE_RAM}"),
    ];
    let mut rows = Vec::new();
    for (feature, label, files) in [
        (
            PICO_PROFILE,
            "rp-pico profile (U95 soft f32)",
            vec![("", calib), (", wobble", wobble.as_path())],
        ),
        (
            "pico-profile-fixed-u95",
            "rp-pico profile (U95 product in integers)",
            vec![("", calib)],
        ),
    ] {
        let target_dir = PathBuf::from(format!(
            "{}-{feature}",
            tc.kind.target_dir(&m0.dir()).display()
        ));
        eprintln!(
            "xtask: building qemu-m0 with the Pico's profile (feature {feature}) with {}",
            tc.version
        );
        let mut cmd = tc.cargo(&m0.dir(), m0.target, "build");
        cmd.env("CARGO_TARGET_DIR", &target_dir).args([
            "--release",
            "--locked",
            "--bins",
            "--features",
            feature,
        ]);
        crate::build::check(&mut cmd, &format!("building qemu-m0 --features {feature}"))?;
        let dir = target_dir.join(m0.target).join("release");
        for (suffix, file) in files {
            let label = format!("qemu-m0, {label}{suffix}");
            // Its hub image is no hub (the Pico's is `boards/rp-pico`, with its update port, on
            // 264 KB of RAM): not replayed, only its benchmark image is run.
            rows.push(measure_images(
                &m0,
                label,
                tc,
                &dir,
                &whole(file)?,
                Some(&ram),
            )?);
        }
    }
    Ok(rows)
}

/// `cargo xtask bench-target`: every board with every firmware tool chain this machine has
/// (or only the one `QUATARM_FIRMWARE` names).
pub fn run(
    only: Option<&str>,
    calib: Option<&std::path::Path>,
    pose_factors: Option<(usize, bool)>,
) -> Result<()> {
    setup::ensure()?;
    let path = calib.map_or_else(default_calibration_path, std::path::Path::to_path_buf);
    // With the calibration's uncertainty budget where it has one: whole for the f32 boards,
    // without the parameters' covariance for the fixed-point ones: qemu-m0 (the minimal
    // profile) refuses the block, and rp-pico, which takes it, runs no QEMU (its profile's
    // rows, `pico_profile`, take the table whole).
    let mut parsed = quatarm_ref::calfile::read(&path)?;
    if let Some((r, joints)) = pose_factors {
        let dof = parsed.arm.joints.len();
        let u = parsed
            .uncertainty
            .as_mut()
            .context("--pose-factors needs a calibration with a budget")?;
        let mut pose = synthetic_pose(u, r);
        if joints {
            pose.joints = Some(synthetic_joints(dof));
        }
        u.pose = Some(pose);
        println!(
            "(the budget with a synthetic pose part of r = {r} columns of D over its {} parameters{}; \
             every reading's leverage above 1)",
            u.parameters.len(),
            if joints {
                format!(" and the joint leverage of its {dof} joints")
            } else {
                String::new()
            }
        );
    }
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
    // The product's chains on the board the C baselines run on, for the side-by-side table.
    let mut products = Vec::new();
    for tc in chains {
        // The QEMU runs below find each board's image by this variable.
        std::env::set_var(toolchain::TOOLCHAIN_ENV, tc.kind.name());
        for b in boards()?
            .iter()
            .filter(|b| only.is_none_or(|o| o == b.name))
        {
            build_board_with(b, tc)?;
            let row = measure(b, tc, &table_for(b)?)?;
            if b.name == C_BOARD {
                if let Some(chains) = row.instructions {
                    products.push(product(b, tc, &row, chains)?);
                }
            }
            rows.push(row);
        }
        if only.is_none_or(|o| o == "rp-pico" || o == PICO_PROFILE) {
            rows.extend(pico_profile(tc, &path)?);
        }
    }
    println!("\n{}", table(&rows));
    println!(
        "(instructions under qemu-system-arm -icount shift=0, mean over {POINTS} recorded readings, calibration {}; \
         the real boards share the cores of qemu-m4f (Cortex-M4F) and qemu-m0 (Cortex-M0; the RP2040 is an M0+))",
        path.display()
    );
    let f = floor::product_lean(&parsed.arm);
    println!(
        "(the product's lean form's counted floor for this arm, from src/lean.rs (xtask/src/floor.rs), \
         one instruction an operation, no fused multiply-add: {} floating-point, {} loads and \
         stores, {} integer: {} in all, before the quarter-turn selections (2 a joint: the first \
         pass's quadrant, the second pass's Rz), register moves or flag tests)",
        f.fp,
        f.memory,
        f.integer,
        f.fp + f.memory + f.integer
    );
    for (k, why) in &survey.missing {
        println!("(not measured with {}: {why})", k.name());
    }
    if only.is_none_or(|o| o == C_BOARD) {
        side_by_side(&parsed.arm, &path, products)?;
    }
    Ok(())
}

/// A pose part of `r` columns for the budget `u` (`--pose-factors`): what U95's cost on the
/// hub depends on is r, P and whether a reading's leverage is above 1 (its outer products),
/// not D's values. D_ij = ±σ_i/4 (σ_i = √C_ii, the sign varying with i + j), b = 0.2, and
/// m = 1e-12 mm² (1 nm²), which puts every reading's leverage far above 1.
fn synthetic_pose(
    u: &quatarm_ref::uncertainty::Uncertainty,
    r: usize,
) -> quatarm_ref::uncertainty::PoseLeverage {
    let p = u.parameters.len();
    let sigma = |i: usize| u.covariance[i * p + i].max(0.0).sqrt();
    quatarm_ref::uncertainty::PoseLeverage {
        factor: (0..r)
            .map(|j| {
                (0..p)
                    .map(|i| {
                        let sign = if (i + j) % 3 == 0 { 1.0 } else { -0.5 };
                        sign * sigma(i) / 4.0
                    })
                    .collect()
            })
            .collect(),
        shrink: 0.2,
        leverage_mean: 1e-12,
        joints: None,
    }
}

/// A joint leverage for `k` joints (`--pose-joints`): what ℓJ's cost depends on is k, not
/// μ's or W's values. μ = π for every joint, W = 0.1 · (I + 0.1 · (1 1ᵀ − I)) (1/rad²):
/// dense, positive definite, every entry read.
fn synthetic_joints(k: usize) -> quatarm_ref::uncertainty::JointLeverage {
    quatarm_ref::uncertainty::JointLeverage {
        mean: vec![std::f64::consts::PI; k],
        weight: (0..k * k)
            .map(|x| if x % (k + 1) == 0 { 0.1 } else { 0.01 })
            .collect(),
    }
}

/// The board whose core the C baselines are measured on (QEMU mps2-an386, Cortex-M4F).
const C_BOARD: &str = "qemu-m4f";

/// The product's row of the side-by-side table from a measured qemu-m4f board, with the hub's
/// chain timed again on the wobble calibration.
fn product(
    b: &Board,
    tc: &Toolchain,
    row: &Row,
    chains: (f64, f64, f64),
) -> Result<cbase::table::Product> {
    let path = host_tests::boards::root().join(WOBBLE_CALIBRATION);
    let w = quatarm_ref::calfile::read(&path)?;
    let table = quatarm_wire::tablebuild::build_with(&w.arm, w.uncertainty.as_ref())
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let wobble = instructions(b, &release_dir(b, tc).join("bench"), &table, &[])?;
    Ok(cbase::table::Product {
        compiler: row.compiler.clone(),
        flash: row.flash,
        chains,
        lean: row.lean,
        wobble: Some((WOBBLE_CALIBRATION.into(), wobble.chains.0, wobble.lean)),
        u95: row.u95[1],
    })
}

/// The product's chains, the C baselines (`bench/c/`, built with arm-none-eabi-gcc where the
/// machine has it) and the counted floor in one table: instructions a point over the same
/// recorded readings, flash, accuracy against the f64 reference on those readings.
fn side_by_side(
    arm: &quatarm_ref::arm::Arm,
    path: &std::path::Path,
    products: Vec<cbase::table::Product>,
) -> Result<()> {
    let readings = recording::read(&default_recording_path())?;
    let readings = &readings[..POINTS.min(readings.len())];
    let wobble_arm =
        quatarm_ref::calfile::read(&host_tests::boards::root().join(WOBBLE_CALIBRATION))?.arm;
    let mut measured = Vec::new();
    for p in products {
        let a = cbase::table::product_accuracy(arm, readings)?;
        let wa = cbase::table::product_accuracy(&wobble_arm, readings)?[0];
        measured.push((p, a, Some(wa)));
    }
    let stem = path
        .file_stem()
        .map_or("calibration".into(), |s| s.to_string_lossy().into_owned());
    let gen = host_tests::boards::root().join("target/cbase").join(stem);
    let c = cbase::measure(
        arm,
        &path.display().to_string(),
        readings,
        &cbase::CChain::ALL,
        &gen,
    )?;
    let gcc = cbase::image::gcc_version().unwrap_or_else(|| "arm-none-eabi-gcc".into());
    println!(
        "\n{}",
        cbase::table::render(&measured, &c, &gcc, floor::c_lean(arm), readings.len())
    );
    println!(
        "(C: bench/c/, {} {}; flash of a C image is its whole image without the readings it carries, \
         of a quatarm row the whole hub image; the floor is counted from the C lean form's structure, \
         xtask/src/floor.rs)",
        gcc,
        cbase::image::CFLAGS.join(" ")
    );
    if let cbase::Outcome::Skipped(why) = &c {
        println!("({why})");
    }
    Ok(())
}
