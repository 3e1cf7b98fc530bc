//! `cargo xtask fuzz-seeds`: writes the seed files of the fuzz corpora (`fuzz/corpus/<target>/
//! seed-*`) from the shipped data and the tests' streams, so that each target starts from
//! inputs of the right shape. The rest of each committed corpus is what long runs found,
//! minimised with `cargo fuzz cmin`.

use anyhow::{Context, Result};
use host_tests::boards::root;
use host_tests::e2e::{calibration, default_recording_path};
use host_tests::recording::{self, frame, replay_bytes};
use quatarm::stream::{
    encode, Coordinates, Hello, LiveTable, Mode, NumberFormat, ProbeRefusal, Report, Status,
    ToDevice, ToHost, MAX_FRAME,
};

fn write(target: &str, name: &str, bytes: &[u8]) -> Result<()> {
    let dir = root().join("fuzz/corpus").join(target);
    std::fs::create_dir_all(&dir)?;
    let path = dir.join(format!("seed-{name}"));
    std::fs::write(&path, bytes).with_context(|| format!("writing {}", path.display()))?;
    eprintln!("fuzz-seeds: {} ({} bytes)", path.display(), bytes.len());
    Ok(())
}

fn host_frame(msg: &ToHost) -> Vec<u8> {
    let mut out = [0u8; MAX_FRAME];
    let n = encode(msg, &mut out).expect("every ToHost fits a frame");
    out[..n].to_vec()
}

/// `pick` (the targets' first byte, choosing table or joint count) before `rest`.
fn picked(pick: u8, rest: &[u8]) -> Vec<u8> {
    [&[pick][..], rest].concat()
}

/// A short 6-joint data file with every row kind and a temperature column.
const DATA_6: &str = "\
# seed: one row of each kind
kind,group,j1,j2,j3,j4,j5,j6,x,y,z,end,length_mm,temp_c
point,1,0.1,-0.5,1.2,0.3,-0.2,0.05,812.5,-10.25,300.125,,,20.5
point,1,0.2,-0.4,1.1,0.2,-0.1,0.15,802.5,-20.25,310.125,,,20.5
spat,2,0.3,-0.3,1.0,0.1,0.0,0.25,,,,,,21
spat,2,-0.3,0.3,-1.0,-0.1,0.1,-0.25,,,,,,21
length,3,0.5,-0.2,0.9,0.0,0.2,0.35,,,,a,300,22
length,3,0.6,-0.1,0.8,-0.1,0.3,0.45,,,,b,300,22
";

/// `cargo xtask fuzz-seeds`: the seeds of each target in turn.
pub fn run() -> Result<()> {
    let data = root().join("data");
    table_and_calfile_seeds(&data)?;
    hub_frames_seeds(&data)?;
    host_frames_seeds()?;
    data_csv_seeds(&data)
}

/// `table_parse` and `calfile_toml`: the shipped calibrations as tables and as text, and the
/// shipped budget's table (the reading's own terms and the 52 parameters' block).
fn table_and_calfile_seeds(data: &std::path::Path) -> Result<()> {
    let panda = data.join("mukca/mukca-panda-panda_3-repo-calibrated.toml");
    for (name, path) in [
        ("default-6-full", data.join("default-6-full.toml")),
        ("default-6", data.join("default-6.toml")),
        ("default-6-probes", data.join("default-6-probes.toml")),
        ("panda_3", panda.clone()),
    ] {
        let (_, table) = calibration(&path)?;
        write("table_parse", &format!("{name}.bin"), &table)?;
        let text = std::fs::read(&path)?;
        write("calfile_toml", &format!("{name}.toml"), &text)?;
    }
    let full = quatarm_ref::calfile::read(&data.join("default-6-full.toml"))?;
    let with_budget = quatarm_wire::tablebuild::build_with(&full.arm, full.uncertainty.as_ref())
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    write("table_parse", "default-6-full-budget.bin", &with_budget)
}

/// `hub_frames`: recorded readings replayed in binary and text mode, a damaged frame, a whole
/// calibration update with a reading and a mode switch in its middle, probe selections.
fn hub_frames_seeds(data: &std::path::Path) -> Result<()> {
    let readings: Vec<_> = recording::read(&default_recording_path())?
        .into_iter()
        .step_by(1999)
        .take(4)
        .collect();
    write(
        "hub_frames",
        "replay.bin",
        &picked(0, &replay_bytes(&readings, None)),
    )?;
    write(
        "hub_frames",
        "text-fixed.bin",
        &picked(4, &replay_bytes(&readings, Some(Mode::Text))),
    )?;
    let mut damaged = vec![0u8];
    for (i, r) in readings.iter().enumerate() {
        let mut f = frame(&ToDevice::Reading(*r));
        if i == 1 {
            f[3] = f[3].wrapping_add(1).max(1);
        }
        damaged.extend(f);
    }
    damaged.extend(frame(&ToDevice::SetMode(Mode::Binary)));
    write("hub_frames", "damaged.bin", &picked(1, &damaged))?;
    // A whole calibration update, a reading and a switch to text mode in its middle.
    let (_, new_table) = calibration(&data.join("default-6.toml"))?;
    let steps: Vec<_> = quatarm::update::session::Step::sequence(&new_table).collect();
    let mut update = vec![0u8];
    for (i, step) in steps.into_iter().enumerate() {
        if i == 10 {
            update.extend(frame(&ToDevice::Reading(readings[0])));
            update.extend(frame(&ToDevice::SetMode(Mode::Text)));
        }
        update.extend(frame(&ToDevice::Update(step)));
    }
    write("hub_frames", "update.bin", &picked(0, &update))?;
    // Probe selections: known and unknown ids between readings, in both modes.
    let mut probes = vec![0u8];
    for (i, id) in [2u8, 9, 0, 5, 255].into_iter().enumerate() {
        probes.extend(frame(&ToDevice::SelectProbe(id)));
        probes.extend(frame(&ToDevice::Reading(readings[i % readings.len()])));
        if i == 2 {
            probes.extend(frame(&ToDevice::SetMode(Mode::Text)));
        }
    }
    // Pick 0x10: the hub on the three-probe table (`fuzz/fuzz_targets/hub_frames.rs`).
    write("hub_frames", "probes.bin", &picked(0x10, &probes))
}

/// `host_frames`: the tests' streams, and a session (a hello, reports with a fault and
/// without a U95, probe answers) written frame by frame.
fn host_frames_seeds() -> Result<()> {
    let streams = root().join("armcal/tests/streams");
    for name in ["s-dup.bin", "s-fault-with-point.bin"] {
        write("host_frames", name, &std::fs::read(streams.join(name))?)?;
    }
    let mut session = vec![0u8];
    session.extend(host_frame(&ToHost::Hello(Hello {
        protocol: quatarm::stream::PROTOCOL_VERSION,
        precision: NumberFormat::F32,
        joints: 6,
        status: Status(Status::TABLE_VALID),
        live: Some(LiveTable {
            slot: 1,
            seq: 3,
            crc: 0x1234_5678,
        }),
        probe: 1,
        probes: [1u8, 2, 5].into_iter().collect(),
        number: 7,
        date: 20261204,
    })));
    for seq in 0..4u32 {
        let fault = seq == 2;
        session.extend(host_frame(&ToHost::Report(Report {
            seq,
            time_us: 5000 * u64::from(seq),
            status: Status(Status::TABLE_VALID | if fault { 0x0100 } else { 0 }),
            point: (!fault).then_some(Coordinates {
                xyz_nm: [812_500_000, -10_250_000, 300_125_000 + seq as i32],
                dir_e9: [0, -600_000_000, 800_000_000],
                u95_nm: (seq != 1).then_some(9_800 + seq),
            }),
            probe: if seq < 2 { 1 } else { 5 },
        })));
        if seq == 1 {
            session.extend(host_frame(&ToHost::Probe(Ok(5))));
            session.extend(host_frame(&ToHost::Probe(Err(ProbeRefusal::Unknown))));
        }
    }
    write("host_frames", "session.bin", &session)
}

/// `data_csv`: a short file of every row kind, and the head of a MUKCa file (7 joints,
/// `length` rows).
fn data_csv_seeds(data: &std::path::Path) -> Result<()> {
    write(
        "data_csv",
        "point-spat-length-6.csv",
        &picked(0, DATA_6.as_bytes()),
    )?;
    let mukca = std::fs::read_to_string(data.join("mukca/mukca-panda-panda_3.csv"))?;
    let head: String = mukca.lines().take(9).map(|l| format!("{l}\n")).collect();
    write(
        "data_csv",
        "mukca-length-7.csv",
        &picked(1, head.as_bytes()),
    )?;
    Ok(())
}
