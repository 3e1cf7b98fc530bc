//! The pieces of an end-to-end check, shared by `tests/qemu_*.rs` and `cargo xtask demo`:
//! a calibration and its binary table, the host build of a firmware path on the same table,
//! the f64 reference, and a replay through a board under QEMU, decoded.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use quatarm::stream::{Coordinates, Hello, Reading, Report};
use quatarm::{Chain, ChainError, Evaluator, Fixed, Table, F32};
use quatarm_ref::arm::Arm;
use quatarm_wire::stream_decode::{Decoder, Item, Stats};

use crate::boards::{root, Board};
use crate::qemu::{self, Options, Run};

/// The default full calibration: every term of the model set (`data/default-6-full.toml`);
/// the environment variable `QUATARM_CALIBRATION` names another file instead.
pub fn default_calibration_path() -> PathBuf {
    match std::env::var_os("QUATARM_CALIBRATION") {
        Some(p) => PathBuf::from(p),
        None => root().join("data/default-6-full.toml"),
    }
}

/// The shipped recording (`data/recordings/default-6-session.csv`).
pub fn default_recording_path() -> PathBuf {
    root().join("data/recordings/default-6-session.csv")
}

/// A calibration file read, and its binary table built as `armcal table build` builds it.
pub fn calibration(path: &Path) -> Result<(Arm, Vec<u8>)> {
    let arm = quatarm_ref::calfile::read(path)
        .with_context(|| format!("reading {}", path.display()))?
        .arm;
    let table = quatarm_wire::tablebuild::build(&arm)
        .map_err(|e| anyhow::anyhow!("building the table of {}: {e}", path.display()))?;
    Ok((arm, table))
}

fn host_chain<P: Evaluator>(
    table: &[u8],
    probe: usize,
    readings: &[Reading],
) -> Result<Vec<Result<Coordinates, ChainError>>> {
    let t = Table::parse(table).map_err(|e| anyhow::anyhow!("table: {e}"))?;
    let mut chain = Chain::<P>::new(&t).map_err(|e| anyhow::anyhow!("chain: {e}"))?;
    chain
        .mount(&t, probe)
        .map_err(|e| anyhow::anyhow!("probe {probe}: {e}"))?;
    Ok(readings
        .iter()
        .map(|r| {
            chain
                .eval(r.counts.as_slice(), r.temp_mc)
                .map(|p| Coordinates {
                    xyz_nm: p.xyz_nm(),
                    dir_e9: p.dir_e9(),
                    u95_nm: None,
                })
        })
        .collect())
}

/// The host build of a firmware path (`f32` or `fixed`) on the same table and readings: what
/// `armcal eval --precision f32|fixed` computes, as integers.
pub fn host_points(
    precision: &str,
    table: &[u8],
    readings: &[Reading],
) -> Result<Vec<Result<Coordinates, ChainError>>> {
    host_points_with_probe(precision, table, 0, readings)
}

/// [`host_points`] with the table's probe `probe` mounted (its index in the table: 0 the
/// first, as the hub boots).
pub fn host_points_with_probe(
    precision: &str,
    table: &[u8],
    probe: usize,
    readings: &[Reading],
) -> Result<Vec<Result<Coordinates, ChainError>>> {
    match precision {
        "f32" => host_chain::<F32>(table, probe, readings),
        "fixed" => host_chain::<Fixed>(table, probe, readings),
        other => anyhow::bail!("no precision {other}"),
    }
}

/// The f64 reference (tip in mm, direction) of one reading.
pub fn reference(arm: &Arm, r: &Reading) -> ([f64; 3], [f64; 3]) {
    let theta: Vec<f64> = arm
        .joints
        .iter()
        .zip(r.counts.as_slice())
        .map(|(j, &c)| j.count_to_rad(i64::from(c)))
        .collect();
    let pose = quatarm_ref::forward::forward(arm, &theta, f64::from(r.temp_mc) / 1000.0);
    (
        [pose.p.x, pose.p.y, pose.p.z],
        [pose.n.x, pose.n.y, pose.n.z],
    )
}

/// Distance (µm) between streamed coordinates and a reference tip.
pub fn deviation_um(c: &Coordinates, reference_mm: &[f64; 3]) -> f64 {
    let d: f64 = c
        .xyz_nm
        .iter()
        .zip(reference_mm)
        .map(|(&nm, &mm)| (f64::from(nm) * 1e-6 - mm).powi(2))
        .sum();
    d.sqrt() * 1e3
}

/// Largest component difference between a streamed direction and a reference one.
pub fn direction_deviation(c: &Coordinates, reference: &[f64; 3]) -> f64 {
    c.dir_e9
        .iter()
        .zip(reference)
        .map(|(&e9, &n)| (f64::from(e9) * 1e-9 - n).abs())
        .fold(0.0, f64::max)
}

/// A replay's decoded output.
#[derive(Debug)]
pub struct Outcome {
    /// Announcements, in order.
    pub hellos: Vec<Hello>,
    /// Reports, in order of arrival.
    pub reports: Vec<Report>,
    /// The decoder's counts (gaps, damaged frames).
    pub stats: Stats,
    /// The QEMU run itself (exit status, defmt log, timing).
    pub run: Run,
}

/// `table` signed with the repository's test key (`keys/test-maker.pem`, `keys/README.md`),
/// whose public half the qemu-m4f image embeds as its maker's key: the image a maker flashes.
pub fn signed(table: &[u8]) -> Result<Vec<u8>> {
    signed_with(table, "keys/test-maker.pem")
}

/// `table` signed with the test key's successor (`keys/test-maker-next.pem`), the qemu-m4f
/// image's next maker key: the image that rotates a hub to it.
pub fn signed_next(table: &[u8]) -> Result<Vec<u8>> {
    signed_with(table, "keys/test-maker-next.pem")
}

/// `table` signed with the private key at `key` (a path from the repository's root).
fn signed_with(table: &[u8], key: &str) -> Result<Vec<u8>> {
    let key = quatarm_wire::tablesign::read_private(&crate::boards::root().join(key))?;
    Ok(quatarm_wire::tablesign::sign(&key, table)?)
}

/// Writes `table` to a file, as a maker flashes it, that lives as long as the returned guard:
/// a valid table [`signed`] (a signed one as it is), bytes that are no valid
/// table as they are (the boot's table checks come before the signature's).
pub fn table_file(table: &[u8]) -> Result<tempfile::NamedTempFile> {
    let bytes = match quatarm::table::Table::parse(table) {
        Ok(t) if t.bytes().len() == table.len() => signed(table)?,
        _ => table.to_vec(),
    };
    let mut f = tempfile::NamedTempFile::new()?;
    std::io::Write::write_all(&mut f, &bytes)?;
    Ok(f)
}

/// Runs `board`'s main binary under QEMU with `table` in its calibration region (none: the
/// region stays blank), sends `input`, decodes what comes back.
pub fn replay(board: &Board, table: Option<&[u8]>, input: &[u8]) -> Result<Outcome> {
    let file = table.map(table_file).transpose()?;
    let opts = Options {
        table: file.as_ref().map(|f| f.path().to_path_buf()),
        ..Options::default()
    };
    let run = qemu::run(board, &board.elf(board.name), input, &opts)?;
    let mut decoder = Decoder::from_start();
    let mut hellos = Vec::new();
    let mut reports = Vec::new();
    for item in decoder.push_all(&run.stream) {
        reports.extend(item.report());
        if let Item::Hello(h) = item {
            hellos.push(h);
        }
    }
    Ok(Outcome {
        hellos,
        reports,
        stats: decoder.finish(),
        run,
    })
}
