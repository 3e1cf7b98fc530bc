//! The hub's receive side: any bytes on the UART into `quatarm::stream::Replay` (the decoder
//! of host→hub `ToDevice` frames) and the `Hub` that turns each event into a report, as a
//! board's replay loop (`board_common::serve`) does. Never a panic; coordinates exactly when
//! the report's status allows them, never for a damaged frame; every report rendered in the
//! hub's mode reads back as itself; update steps go to the updater on a mock flash and its
//! answers read back as themselves; probe selections mount a probe of a table with three
//! (`data/default-6-probes.toml`), are answered as the hub's probe table says, and every
//! report carries the id mounted.
#![no_main]

use libfuzzer_sys::fuzz_target;
use quatarm::stream::{
    Coordinates, Event, FrameReader, Hub, Mode, NumberFormat, ProbeRefusal, Replay, Status,
    TableState, ToHost, MAX_FRAME, MAX_OUTPUT,
};
use quatarm::table::MAX_TABLE_LEN;
use quatarm::update::{fixtures, Accept, Updater};
use quatarm::{Chain, Fixed, Table, F32};
use quatarm_fuzz::{chains, probes_table};

/// The messages a rendered output decodes to, as a host reads them.
fn frames(rendered: &[u8]) -> Vec<Result<ToHost, quatarm::stream::FrameError>> {
    let mut reader = FrameReader::<MAX_FRAME>::new();
    rendered
        .iter()
        .filter_map(|&x| reader.push::<ToHost>(x))
        .collect()
}

/// An answer (to an update step, a probe selection), rendered in the hub's mode, reads back as
/// itself: a frame in either mode.
fn answers_read_back(hub: &Hub, msg: ToHost, out: &mut [u8]) {
    let rendered = hub.render(&msg, out);
    assert_eq!(frames(rendered), [Ok(msg)], "an answer does not read back");
}

fuzz_target!(|bytes: &[u8]| {
    let Some((&pick, stream)) = bytes.split_first() else {
        return;
    };
    // Pick 0..=3: a shipped table's chains; 4 (with 0x3 of 0) also: the three-probe table,
    // whose probes the selections mount.
    let (f32_chain, fixed_chain) = &chains()[usize::from(pick & 0x3) % chains().len()];
    let (mut f32_chain, mut fixed_chain) = (f32_chain.clone(), fixed_chain.clone());
    let probes = Table::parse(probes_table()).expect("the three-probe table parses");
    let with_probes = pick & 0x13 == 0x10;
    if with_probes {
        f32_chain = Chain::<F32>::new(&probes).expect("an f32 chain");
        fixed_chain = Chain::<Fixed>::new(&probes).expect("a fixed chain");
    }
    let fixed = pick & 0x4 != 0;
    let state = if pick & 0x8 != 0 {
        TableState::Corrupt
    } else {
        TableState::Valid
    };
    let precision = if fixed {
        NumberFormat::Fixed
    } else {
        NumberFormat::F32
    };
    let ids: Vec<u8> = if with_probes {
        (0..probes.probe_count())
            .filter_map(|k| probes.probe_id(k))
            .collect()
    } else {
        vec![0]
    };
    let mut hub =
        Hub::new(state, f32_chain.joint_count() as u8, precision).with_probes(ids.clone());
    let mut mounted = if state == TableState::Valid {
        ids[0]
    } else {
        0
    };
    let mut replay = Replay::new();
    let mut out = [0u8; MAX_OUTPUT];
    let mut flash = fixtures::factory(&fixtures::table(100.0));
    let mut updater = Updater::new(fixtures::layout(), Accept::joints(6));
    let mut scratch = [0u8; MAX_TABLE_LEN];
    let mut time = 0u64;
    for &b in stream {
        let Some(event) = replay.push(b) else {
            continue;
        };
        time += 1;
        let eval = |counts: &[u32], temp_mc: i32| {
            let p = if fixed {
                fixed_chain
                    .eval(counts, temp_mc)
                    .map(|p| (p.xyz_nm(), p.dir_e9()))
            } else {
                f32_chain
                    .eval(counts, temp_mc)
                    .map(|p| (p.xyz_nm(), p.dir_e9()))
            };
            p.map(|(xyz_nm, dir_e9)| Coordinates {
                xyz_nm,
                dir_e9,
                u95_nm: None,
            })
        };
        let (report, damaged) = match event {
            Event::Reading(r) => (hub.report(time, Ok(&r), eval), false),
            Event::InputError(e) => (hub.report(time, Err(e), eval), true),
            Event::SelectProbe(id) => {
                // The hub answers from its probe table; a probe it names is one the chains
                // mount (the boot checked the reach with the longest).
                let answer = hub.select(id, |k| {
                    if !with_probes {
                        return true;
                    }
                    f32_chain.mount(&probes, k).is_ok() && fixed_chain.mount(&probes, k).is_ok()
                });
                let want = match (state, ids.contains(&id)) {
                    (TableState::Valid, true) => Ok(id),
                    (TableState::Valid, false) => Err(ProbeRefusal::Unknown),
                    _ => Err(ProbeRefusal::NoTable),
                };
                assert_eq!(answer, want, "selecting {id} of {ids:?}");
                if answer.is_ok() {
                    mounted = id;
                }
                answers_read_back(&hub, ToHost::Probe(answer), &mut out);
                continue;
            }
            Event::SetMode(m) => {
                hub.set_mode(m);
                let _ = hub.render(&hub.hello(), &mut out);
                continue;
            }
            Event::End => break,
            Event::Update(step) => {
                // The update steps go to the update state machine on a mock flash, as a
                // board's serve loop sends them; the answer must read back as itself in
                // either mode (update answers are frames in text mode too).
                let answer = updater.step(&mut flash, &mut scratch, &step);
                answers_read_back(&hub, ToHost::Update(answer), &mut out);
                continue;
            }
        };
        assert_eq!(report.point.is_some(), report.status.is_measurement());
        assert_eq!(
            report.probe, mounted,
            "the report names another probe than mounted"
        );
        if damaged {
            assert!(report.status.has(Status::INPUT_ERROR) && report.point.is_none());
        }
        if state != TableState::Valid {
            assert!(report.point.is_none(), "coordinates from a bad table");
        }
        let msg = ToHost::Report(report);
        let rendered = hub.render(&msg, &mut out);
        match hub.mode() {
            Mode::Binary => {
                assert_eq!(
                    frames(rendered),
                    [Ok(msg)],
                    "a report frame does not read back"
                );
            }
            Mode::Text => {
                assert!(rendered.ends_with(b"\n") && rendered.is_ascii());
                let seq = report.seq.to_string();
                assert!(rendered.starts_with(seq.as_bytes()));
            }
        }
    }
});
