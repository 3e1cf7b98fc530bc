//! The soak: a long replay into a hub under QEMU with random corruption of the host→hub
//! frames (bit flips, dropped bytes, dropped frames, bursts, garbage between frames), and of
//! the hub→host stream after it (decoded by the host's decoder), with every frame accounted
//! for on both sides.
//!
//! What it checks, for every run:
//! - the hub is never stuck: it answers every frame and exits on the final `End`;
//! - the hub's count of damaged input frames (its defmt log, and the `INPUT_ERROR` reports)
//!   is the number of frames its receiver refused, and it gives one report per frame;
//! - every intact incoming frame gives exactly the coordinates the host build of the chain
//!   computes for its reading, and no report carries coordinates for a damaged one;
//! - the host decoder's lost and damaged counts match what was damaged on the way back, and
//!   every report it hands out is, bit for bit, one the hub sent.

use anyhow::{bail, ensure, Context, Result};
use quatarm::stream::{Coordinates, Event, Reading, Replay, Report, Status, ToDevice};
use quatarm_wire::stream_decode::{Decoder, Item};

use crate::boards::Board;
use crate::e2e::{calibration, default_calibration_path, default_recording_path, host_points};
use crate::qemu::{self, Options};
use crate::recording::{self, frame};

/// xorshift64*: reproducible corruption without a dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in `0..n` (n > 0).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    fn byte(&mut self) -> u8 {
        self.next() as u8
    }
}

/// What corruption was applied, by kind.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Damage {
    /// Frames with 1–3 bits flipped.
    pub flips: u64,
    /// Frames with one byte dropped (perhaps the delimiter).
    pub dropped_bytes: u64,
    /// Frames dropped whole, delimiter included.
    pub dropped_frames: u64,
    /// Frames with a run of 2–16 bytes overwritten by random ones.
    pub bursts: u64,
    /// Runs of 1–64 random bytes (zeros possible) inserted before a frame.
    pub garbage: u64,
}

impl Damage {
    /// Frames touched in any way (garbage runs included).
    pub fn total(&self) -> u64 {
        self.flips + self.dropped_bytes + self.dropped_frames + self.bursts + self.garbage
    }
}

/// Corrupts a sequence of frames: about one frame in `one_in` gets one kind of damage.
/// Returns the bytes and, per frame, whether it reached the stream untouched with a
/// delimiter right before it (so that a receiver must decode it as sent).
fn corrupt(
    frames: &[Vec<u8>],
    one_in: usize,
    rng: &mut Rng,
    damage: &mut Damage,
) -> (Vec<u8>, Vec<bool>) {
    let mut out = vec![0u8];
    let mut intact = Vec::with_capacity(frames.len());
    for f in frames {
        let mut f = f.clone();
        let mut touched = true;
        match (rng.below(one_in), rng.below(5)) {
            (0, 0) => {
                // 1–3 distinct bits, so that the frame surely changed.
                let mut bits = Vec::new();
                while bits.len() < 1 + rng.below(3) {
                    let bit = rng.below(8 * f.len());
                    if !bits.contains(&bit) {
                        bits.push(bit);
                    }
                }
                for bit in bits {
                    f[bit / 8] ^= 1 << (bit % 8);
                }
                damage.flips += 1;
            }
            (0, 1) => {
                f.remove(rng.below(f.len()));
                damage.dropped_bytes += 1;
            }
            (0, 2) => {
                f.clear();
                damage.dropped_frames += 1;
            }
            (0, 3) => {
                let len = (2 + rng.below(15)).min(f.len());
                let at = rng.below(f.len() - len + 1);
                let before = f.clone();
                for b in &mut f[at..at + len] {
                    *b = rng.byte();
                }
                if f == before {
                    f[at] ^= 1; // surely changed
                }
                damage.bursts += 1;
            }
            (0, _) => {
                for _ in 0..1 + rng.below(64) {
                    out.push(rng.byte());
                }
                damage.garbage += 1;
                // The frame itself is untouched, but whether it starts clean depends on the
                // garbage's last byte: decided below.
                touched = false;
            }
            _ => touched = false,
        }
        let clean_start = out.last() == Some(&0);
        intact.push(!touched && clean_start && !f.is_empty());
        out.extend(f);
    }
    (out, intact)
}

/// The counts of one soak run.
#[derive(Debug, Default, Clone, Copy)]
pub struct Counts {
    /// Readings sent to the hub.
    pub frames_in: u64,
    /// Corruption applied to the host→hub frames.
    pub damage_in: Damage,
    /// Incoming frames that reached the hub intact.
    pub intact_in: u64,
    /// Reports the hub sent.
    pub hub_reports: u64,
    /// Reports with coordinates (each checked against the host build of the chain).
    pub hub_points: u64,
    /// Frames the hub refused (`INPUT_ERROR` reports; also its defmt log's count).
    pub hub_rejected: u64,
    /// Corruption applied to the hub→host report frames.
    pub damage_out: Damage,
    /// Reports the host decoder handed out, each identical to the hub's of the same `seq`.
    pub host_reports: u64,
    /// The host decoder's lost count.
    pub host_lost: u64,
    /// The host decoder's damaged count.
    pub host_damaged: u64,
    /// Wall-clock seconds under QEMU.
    pub qemu_seconds: f64,
}

/// Runs the soak on `board` with `frames` readings (the shipped recording, cycled), about one
/// frame in `one_in` damaged in each direction; `seed` makes it reproducible.
///
/// The steps: the input damaged (`damaged_input`), the hub run on it under QEMU, its
/// reports checked frame by frame against what its receiver must make of the bytes
/// (`check_reports`) and against its log (`check_log`), then its stream damaged on the
/// way back and decoded by the host (`check_way_back`).
pub fn run(board: &Board, frames: usize, one_in: usize, seed: u64) -> Result<Counts> {
    let (_, table) = calibration(&default_calibration_path())?;
    let recorded = recording::read(&default_recording_path())?;
    let points = host_points(board.precision, &table, &recorded)?;
    let readings: Vec<Reading> = (0..frames)
        .map(|i| Reading {
            seq: i as u32,
            ..recorded[i % recorded.len()]
        })
        .collect();
    let expected = |r: &Reading| -> Option<Coordinates> {
        let sent = readings.get(r.seq as usize)?;
        (sent == r)
            .then(|| points[r.seq as usize % recorded.len()].ok())
            .flatten()
    };

    let mut rng = Rng(seed | 1);
    let mut counts = Counts {
        frames_in: frames as u64,
        ..Counts::default()
    };
    let (input, intact) = damaged_input(&readings, one_in, &mut rng, &mut counts);
    // What the hub's receiver must make of these bytes: its own code, run on the host.
    let mut model = Replay::new();
    let events: Vec<Event> = input.iter().filter_map(|&b| model.push(b)).collect();
    ensure!(
        matches!(events.last(), Some(Event::End)),
        "the corrupted input lost its End"
    );

    let opts = Options {
        icount: false,
        timeout: std::time::Duration::from_secs(3600),
        ..Options::default()
    };
    let file = crate::e2e::table_file(&table)?;
    let opts = Options {
        table: Some(file.path().to_path_buf()),
        ..opts
    };
    let run = qemu::run(board, &board.elf(board.name), &input, &opts)?;
    counts.qemu_seconds = run.elapsed.as_secs_f64();
    ensure!(
        run.status.success(),
        "{}: firmware exit {:?}",
        board.name,
        run.status
    );
    let reports = check_reports(&run.stream, &events, &intact, &expected, &mut counts)?;
    check_log(board, &run.log, &counts)?;
    check_way_back(&run.stream, &reports, one_in, &mut rng, &mut counts)?;
    Ok(counts)
}

/// The readings' frames, about one in `one_in` damaged (counted in `counts`), then a
/// delimiter and `End` (so that garbage or a lost delimiter cannot swallow it); with, per
/// reading, whether its frame arrives intact.
fn damaged_input(
    readings: &[Reading],
    one_in: usize,
    rng: &mut Rng,
    counts: &mut Counts,
) -> (Vec<u8>, Vec<bool>) {
    let sent: Vec<Vec<u8>> = readings
        .iter()
        .map(|r| frame(&ToDevice::Reading(*r)))
        .collect();
    let (mut input, intact) = corrupt(&sent, one_in, rng, &mut counts.damage_in);
    counts.intact_in = intact.iter().filter(|&&x| x).count() as u64;
    input.push(0);
    input.extend(frame(&ToDevice::End));
    (input, intact)
}

/// The hub's own (clean) stream: one report per frame the receiver made an event of, in
/// order; a damaged frame's report flags `INPUT_ERROR` and carries no point; an intact
/// reading's carries exactly what `expected` (the host build of the chain) gives, in the
/// intact frames' order. Counts the hub's reports, points and refusals; returns the reports.
fn check_reports(
    stream: &[u8],
    events: &[Event],
    intact: &[bool],
    expected: &dyn Fn(&Reading) -> Option<Coordinates>,
    counts: &mut Counts,
) -> Result<Vec<Report>> {
    let mut clean = Decoder::from_start();
    let items = clean.push_all(stream);
    let s = clean.finish();
    ensure!(
        s.damaged() == 0 && s.lost == 0 && s.hellos == 1,
        "the hub's own stream: {s:?}"
    );
    let reports: Vec<Report> = items.iter().filter_map(Item::report).copied().collect();
    let mut want = events
        .iter()
        .filter(|e| !matches!(e, Event::SetMode(_) | Event::End));
    let mut intact_seqs = intact
        .iter()
        .enumerate()
        .filter(|(_, &x)| x)
        .map(|(i, _)| i as u32);
    for (i, rep) in reports.iter().enumerate() {
        ensure!(rep.seq == i as u32, "report {i} has seq {}", rep.seq);
        let Some(event) = want.next() else {
            bail!("report {i} beyond the frames the hub received");
        };
        match event {
            Event::InputError(_) => {
                ensure!(
                    rep.status.has(Status::INPUT_ERROR) && rep.point.is_none(),
                    "report {i}: a damaged frame gave {rep:?}"
                );
                counts.hub_rejected += 1;
            }
            Event::Reading(r) => {
                let Some(c) = expected(r) else {
                    bail!("report {i}: a reading that was never sent decoded: {r:?}");
                };
                ensure!(
                    rep.point == Some(c) && rep.status == Status(Status::TABLE_VALID),
                    "report {i}: {rep:?}, the host build gives {c:?}"
                );
                ensure!(
                    intact_seqs.next() == Some(r.seq),
                    "report {i}: reading {} decoded out of the intact ones' order",
                    r.seq
                );
                counts.hub_points += 1;
            }
            _ => unreachable!("filtered"),
        }
    }
    ensure!(want.next().is_none(), "fewer reports than frames received");
    ensure!(
        intact_seqs.next().is_none(),
        "an intact frame gave no coordinates"
    );
    counts.hub_reports = reports.len() as u64;
    ensure!(counts.hub_points == counts.intact_in);
    Ok(reports)
}

/// The hub's defmt log (`log`, raw) says it replayed as many reports and refused as many
/// damaged frames as its stream shows.
fn check_log(board: &Board, log: &[u8], counts: &Counts) -> Result<()> {
    let log = crate::defmt_log::decode(&board.elf(board.name), log)?;
    let done = format!(
        "replay done: {} reports, {} damaged input frames",
        counts.hub_reports, counts.hub_rejected
    );
    ensure!(
        log.contains(&done),
        "the hub's log does not say `{done}`: {:?}",
        log.iter()
            .filter(|l| l.starts_with("replay"))
            .collect::<Vec<_>>()
    );
    Ok(())
}

/// The way back: the hub's report frames (`stream`) damaged the same ways, the Hello and the
/// last report kept (a decoder cannot see a loss after the last frame it gets), decoded by
/// the host. Every report it hands out is one the hub sent (`reports`), and its lost and
/// damaged counts account for the damage.
fn check_way_back(
    stream: &[u8],
    reports: &[Report],
    one_in: usize,
    rng: &mut Rng,
    counts: &mut Counts,
) -> Result<()> {
    let mut frames_out: Vec<Vec<u8>> = Vec::new();
    let mut start = 0;
    for (i, &b) in stream.iter().enumerate() {
        if b == 0 {
            if i > start {
                frames_out.push(stream[start..=i].to_vec());
            }
            start = i + 1;
        }
    }
    let hello = frames_out.remove(0);
    let last = frames_out.pop().context("no reports")?;
    let (damaged_out, _) = corrupt(&frames_out, one_in, rng, &mut counts.damage_out);
    let back = [&hello[..], &damaged_out, &[0], &last].concat();
    let mut host = Decoder::from_start();
    let got = host.push_all(&back);
    let hs = host.finish();
    for r in got.iter().filter_map(Item::report) {
        let sent = reports.get(r.seq as usize);
        ensure!(
            sent == Some(r),
            "the host decoder gave {r:?}, the hub sent {sent:?}"
        );
    }
    ensure!(
        hs.backward == 0 && hs.repeated == 0 && hs.inconsistent == 0,
        "{hs:?}"
    );
    ensure!(
        hs.reports + hs.lost == counts.hub_reports,
        "decoded {} + lost {} != sent {}",
        hs.reports,
        hs.lost,
        counts.hub_reports
    );
    // Every damaged or dropped report frame is lost; a damaged frame (not a dropped one) is
    // also seen as damage, unless its damage merged it into a neighbour's.
    ensure!(hs.lost >= counts.damage_out.total() - counts.damage_out.garbage);
    ensure!(hs.damaged() > 0 || counts.damage_out.total() == 0);
    counts.host_reports = hs.reports;
    counts.host_lost = hs.lost;
    counts.host_damaged = hs.damaged();
    Ok(())
}
