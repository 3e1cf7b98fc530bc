//! The end-to-end cases every QEMU board must pass; `qemu_m4f.rs` and `qemu_m0.rs` declare
//! them for their board, bounds and update behaviour with [`board_tests!`]. They need the board built
//! (`cargo xtask build`) and `qemu-system-arm`: a missing one fails the test, it is never
//! skipped.

use host_tests::boards::{board, Board};
use host_tests::e2e::signed;
use host_tests::e2e::{
    calibration, default_calibration_path, default_recording_path, deviation_um,
    direction_deviation, host_points, host_points_with_probe, reference, replay,
};
use host_tests::recording::{self, frame, replay_bytes};
use host_tests::session::Session;
use quatarm::stream::{
    Coordinates, LiveTable, Mode, ProbeRefusal, Reading, Status, TableState, ToDevice, CSV_HEADER,
};
use quatarm::update::session::Step;
use quatarm::update::{Accepted, Refusal};
use quatarm_wire::stream_decode::Item;
use quatarm_wire::tablesign;

pub(crate) mod pty;

/// Declares every case of this module as a test of one board: `board` (a name of
/// `host_tests::boards`), `bounds` for its full recording, `full_recording`, the name of
/// that test (it says the bound), and `update`, the case of its hub's update port
/// ([`update_with_resets`] or [`update_not_supported`]), and `u95`, the case of its points'
/// uncertainty ([`u95_matches_the_host`] or [`no_u95`]), and `wobble`, a table with an axis
/// wobble ([`wobble_applied`] or [`wobble_refused`]), and `probes`, a table with three probes
/// ([`probes_selected_and_updated`] or [`probes_selected`], for a hub without an update
/// port), and `table_send`, the `armcal` binary's `table send` through a pseudo-terminal
/// ([`pty::table_send_over_a_pty`] or [`pty::table_send_refused_over_a_pty`]). They are
/// `#[ignore]`d for plain `cargo test`, which has
/// neither QEMU nor the cross-built board; `cargo xtask test` builds the boards and runs them
/// with `--include-ignored`.
macro_rules! board_tests {
    (board: $board:literal, bounds: $bounds:expr, full_recording: $full:ident,
     update: $update:ident, u95: $u95:ident, wobble: $wobble:ident,
     probes: $probes:ident, table_send: $send:ident $(,)?) => {
        #[test]
        #[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
        fn armcal_table_send_through_a_pty() {
            $crate::common::pty::$send($board);
        }

        #[test]
        #[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
        fn a_table_with_three_probes() {
            $crate::common::$probes($board, $bounds);
        }

        #[test]
        #[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
        fn a_table_with_an_axis_wobble() {
            $crate::common::$wobble($board, $bounds);
        }

        #[test]
        #[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
        fn the_uncertainty_of_every_point() {
            $crate::common::$u95($board);
        }

        #[test]
        #[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
        fn a_calibration_update_over_the_uart() {
            $crate::common::$update($board);
        }

        #[test]
        #[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
        fn $full() {
            $crate::common::full_recording($board, $bounds);
        }

        #[test]
        #[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
        fn a_flipped_bit_in_an_incoming_frame_gives_input_error_and_no_coordinates() {
            $crate::common::flipped_bit_in_an_incoming_frame($board);
        }

        #[test]
        #[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
        fn an_encoder_fault_gives_its_joint_bit_and_no_coordinates() {
            $crate::common::encoder_fault($board);
        }

        #[test]
        #[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
        fn bad_tables_are_reported_and_give_no_coordinates() {
            $crate::common::bad_tables($board);
        }

        #[test]
        #[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
        fn text_mode_prints_the_same_numbers() {
            $crate::common::text_mode($board);
        }

        #[test]
        #[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
        fn the_defmt_log_decodes_on_the_host() {
            $crate::common::defmt_log($board);
        }

        #[test]
        #[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
        fn a_soak_of_25_000_corrupted_frames_accounts_for_every_one() {
            $crate::common::soak($board);
        }
    };
}
pub(crate) use board_tests;

/// What a board's path must achieve against the f64 reference.
pub struct Bounds {
    /// Tip, µm.
    pub tip_um: f64,
    /// Direction, per component.
    pub dir: f64,
}

fn the_board(name: &str) -> Board {
    board(name).unwrap_or_else(|e| panic!("{e:#}"))
}

/// ≥ 10,000 recorded readings in over the UART; every report back, in order, CRC-clean; XYZ
/// bit-identical to the host build of the same path; within `bounds` of the f64 reference.
pub fn full_recording(name: &str, bounds: Bounds) {
    let b = the_board(name);
    let (arm, table) = calibration(&default_calibration_path()).unwrap();
    let readings = recording::read(&default_recording_path()).unwrap();
    assert!(
        readings.len() >= 10_000,
        "the recording has {} readings",
        readings.len()
    );
    let out = replay(&b, Some(&table), &replay_bytes(&readings, None)).unwrap();
    assert!(
        out.run.status.success(),
        "firmware exit: {:?}",
        out.run.status
    );
    assert_eq!(out.stats.damaged(), 0, "damaged frames: {:?}", out.stats);
    assert_eq!(out.stats.lost, 0);
    assert_eq!(out.hellos.len(), 1);
    assert_eq!(out.hellos[0].status.table(), TableState::Valid);
    assert_eq!(out.reports.len(), readings.len(), "one report per reading");
    let host = host_points(b.precision, &table, &readings).unwrap();
    let (mut worst_tip, mut worst_dir) = (0.0f64, 0.0f64);
    for (i, ((rep, r), h)) in out.reports.iter().zip(&readings).zip(&host).enumerate() {
        assert_eq!(rep.seq, i as u32, "in order");
        assert_eq!(rep.status, Status(Status::TABLE_VALID), "reading {i}");
        let c = rep
            .point
            .unwrap_or_else(|| panic!("reading {i}: no coordinates"));
        assert_eq!(Ok(c), *h, "reading {i}: target and host builds differ");
        let (p, n) = reference(&arm, r);
        worst_tip = worst_tip.max(deviation_um(&c, &p));
        worst_dir = worst_dir.max(direction_deviation(&c, &n));
    }
    // And literally what `armcal eval --precision <path>` prints for the same counts and
    // calibration: its CSV is the same integers rendered with 6 and 9 decimals.
    let eval = armcal_eval(b.precision, &readings);
    assert_eq!(eval.len(), readings.len());
    for (i, (rep, line)) in out.reports.iter().zip(&eval).enumerate() {
        let mut csv = [0u8; quatarm::stream::MAX_CSV_LINE];
        let n = quatarm::stream::write_csv_line(rep, &mut csv);
        let streamed = std::str::from_utf8(&csv[..n]).unwrap().trim_end();
        // seq, time, status, the six coordinates, U95 (empty: this table has no budget), the
        // probe (its only one, id 0).
        let fields: Vec<&str> = streamed.splitn(4, ',').collect();
        assert_eq!(
            fields[3],
            format!("{line},,0"),
            "reading {i}: stream and `armcal eval` differ"
        );
    }
    eprintln!(
        "{name}: {} readings, bit-identical to the host and to `armcal eval --precision {}`; max deviation from f64: tip {worst_tip:.4} um, direction {worst_dir:.2e}",
        readings.len(),
        b.precision
    );
    assert!(
        worst_tip <= bounds.tip_um,
        "tip {worst_tip} um > {} um",
        bounds.tip_um
    );
    assert!(
        worst_dir <= bounds.dir,
        "direction {worst_dir} > {}",
        bounds.dir
    );
}

/// Runs the `armcal` binary of this build (`cargo xtask test` builds it before these tests)
/// as a user would: `armcal eval --calib <default calibration> --precision <p> <csv>`.
fn armcal_eval(precision: &str, readings: &[Reading]) -> Vec<String> {
    armcal_eval_with(precision, readings, false)
}

/// The `armcal` binary of this build (`cargo xtask test` builds it before these tests).
fn armcal_exe() -> std::path::PathBuf {
    let exe = std::env::current_exe().unwrap();
    let armcal = exe
        .parent()
        .and_then(|deps| deps.parent())
        .map(|dir| dir.join("armcal"))
        .unwrap();
    assert!(
        armcal.exists(),
        "{} missing: build it with `cargo build -p armcal` (cargo xtask test does)",
        armcal.display()
    );
    armcal
}

/// [`armcal_eval`], with `--uncertainty` where `uncertainty` is set.
fn armcal_eval_with(precision: &str, readings: &[Reading], uncertainty: bool) -> Vec<String> {
    let armcal = armcal_exe();
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("counts.csv");
    std::fs::write(&csv, recording::eval_csv(readings)).unwrap();
    let out = std::process::Command::new(&armcal)
        .arg("eval")
        .arg("--calib")
        .arg(default_calibration_path())
        .args(["--precision", precision])
        .args(uncertainty.then_some("--uncertainty"))
        .arg(&csv)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    let header = if uncertainty {
        "x,y,z,nx,ny,nz,cxx,cyy,czz,cxy,cxz,cyz,U95"
    } else {
        "x,y,z,nx,ny,nz"
    };
    assert_eq!(lines.next(), Some(header));
    lines.map(str::to_owned).collect()
}

/// The firmware exited with success; else its status and its defmt log.
fn assert_ran(b: &Board, out: &host_tests::e2e::Outcome) {
    assert!(
        out.run.status.success(),
        "{:?}: {}",
        out.run.status,
        host_tests::defmt_log::decode(&b.elf(b.name), &out.run.log)
            .unwrap_or_default()
            .join("\n")
    );
}

/// The default calibration's table with its uncertainty budget, as `armcal table build`
/// writes it: the reading's own terms and the first `parameters` of its 52 parameters with
/// their covariance (all 52: the shipped budget; 0: the table a fixed-point hub takes).
fn budget_table(parameters: usize) -> Vec<u8> {
    let parsed = quatarm_ref::calfile::read(&default_calibration_path()).unwrap();
    let mut u = parsed
        .uncertainty
        .expect("the default calibration has a budget");
    let n = u.parameters.len();
    let keep = parameters.min(n);
    u.covariance = (0..keep * keep)
        .map(|k| u.covariance[(k / keep) * n + k % keep])
        .collect();
    u.parameters.truncate(keep);
    quatarm_wire::tablebuild::build_with(&parsed.arm, Some(&u)).unwrap()
}

/// Every point of a table with the default calibration's budget carries its U95, within 1 %
/// of what `armcal eval --uncertainty` prints for the same counts (the host's first order in
/// f64), and the text mode's last column is the same number.
#[allow(dead_code)] // each board's test binary uses one of the two U95 cases
pub fn u95_matches_the_host(name: &str) {
    let b = the_board(name);
    let table = budget_table(usize::MAX);
    let readings = some_readings(40);
    let out = replay(&b, Some(&table), &replay_bytes(&readings, None)).unwrap();
    assert_ran(&b, &out);
    assert_eq!(out.hellos[0].status.table(), TableState::Valid);
    assert_eq!(out.reports.len(), readings.len());
    let eval = armcal_eval_with(b.precision, &readings, true);
    let mut worst: f64 = 0.0;
    for (i, (rep, line)) in out.reports.iter().zip(&eval).enumerate() {
        let hub_nm = rep
            .point
            .and_then(|p| p.u95_nm)
            .unwrap_or_else(|| panic!("reading {i}: no U95 in {rep:?}"));
        let host_mm: f64 = line.rsplit(',').next().unwrap().parse().unwrap();
        let err = f64::from(hub_nm) / (host_mm * 1e6) - 1.0;
        worst = worst.max(err.abs());
        let mut csv = [0u8; quatarm::stream::MAX_CSV_LINE];
        let n = quatarm::stream::write_csv_line(rep, &mut csv);
        let streamed = std::str::from_utf8(&csv[..n]).unwrap().trim_end();
        // U95, then the probe's id.
        let u95: f64 = streamed.rsplit(',').nth(1).unwrap().parse().unwrap();
        assert_eq!(
            (u95 * 1e6).round() as u32,
            hub_nm,
            "reading {i}: {streamed}"
        );
    }
    let mut csv = [0u8; quatarm::stream::MAX_CSV_LINE];
    let n = quatarm::stream::write_csv_line(&out.reports[0], &mut csv);
    eprintln!(
        "{name}: U95 on {} readings within {:.3} % of `armcal eval --uncertainty`; the first \
         reading (counts {:?}, {} m°C): hub `{}`, host `{}`",
        readings.len(),
        100.0 * worst,
        readings[0].counts.as_slice(),
        readings[0].temp_mc,
        std::str::from_utf8(&csv[..n]).unwrap().trim_end(),
        eval[0]
    );
    assert!(worst < 0.01, "hub U95 {worst} off the host's");
}

/// The budget's pose part through the hub's assembly (qemu-m4f: E = J D in blocks of 8
/// columns, `quatarm::uncertainty::pose`): for r = 8 (one block), 9 (a block and one column
/// in Rust) and 16 (two blocks), every streamed U95 is the host build's of the same table and
/// counts (`Uncertainty::<F32>::u95_nm`, the portable code), nanometre for nanometre, and the
/// part widens some of them (D_ij = ±σ_i/4, b = 0.2, m = 1 nm², as `cargo xtask bench-target
/// --pose-factors R` builds it).
#[allow(dead_code)] // qemu-m4f's test binary only
pub fn pose_part_u95_is_the_host_builds(name: &str) {
    let b = the_board(name);
    let readings = some_readings(40);
    let parsed = quatarm_ref::calfile::read(&default_calibration_path()).unwrap();
    let plain = parsed
        .uncertainty
        .expect("the default calibration has a budget");
    let p = plain.parameters.len();
    let plain_table = quatarm_wire::tablebuild::build_with(&parsed.arm, Some(&plain)).unwrap();
    for r in [8, 9, 16] {
        let mut u = plain.clone();
        let sigma = |i: usize| u.covariance[i * p + i].max(0.0).sqrt();
        let factor = (0..r)
            .map(|j| {
                (0..p)
                    .map(|i| if (i + j) % 3 == 0 { 1.0 } else { -0.5 } * sigma(i) / 4.0)
                    .collect()
            })
            .collect();
        u.pose = Some(quatarm_ref::uncertainty::PoseLeverage {
            factor,
            shrink: 0.2,
            leverage_mean: 1e-12,
            joints: None,
        });
        let table = quatarm_wire::tablebuild::build_with(&parsed.arm, Some(&u)).unwrap();
        let out = replay(&b, Some(&table), &replay_bytes(&readings, None)).unwrap();
        assert_ran(&b, &out);
        assert_eq!(out.hellos[0].status.table(), TableState::Valid, "r = {r}");
        assert_eq!(out.reports.len(), readings.len());
        let parsed_table = quatarm::Table::parse(&table).unwrap();
        let host = quatarm::uncertainty::Uncertainty::<quatarm::F32>::new(&parsed_table)
            .unwrap()
            .unwrap();
        assert!(
            host.has_parameters(),
            "the host build reads the parameter block"
        );
        let plain_parsed = quatarm::Table::parse(&plain_table).unwrap();
        let without = quatarm::uncertainty::Uncertainty::<quatarm::F32>::new(&plain_parsed)
            .unwrap()
            .unwrap();
        let mut widest: f64 = 0.0;
        let mut widened = 0;
        for (i, (rep, reading)) in out.reports.iter().zip(&readings).enumerate() {
            let hub_nm = rep
                .point
                .and_then(|p| p.u95_nm)
                .unwrap_or_else(|| panic!("r = {r}, reading {i}: no U95 in {rep:?}"));
            let want = host
                .u95_nm(reading.counts.as_slice(), reading.temp_mc)
                .unwrap();
            assert_eq!(hub_nm, want, "r = {r}, reading {i}");
            let before = without
                .u95_nm(reading.counts.as_slice(), reading.temp_mc)
                .unwrap();
            if hub_nm > before {
                widened += 1;
            }
            widest = widest.max(f64::from(hub_nm) / f64::from(before));
        }
        eprintln!(
            "{name}: r = {r}: {} streamed U95 equal to the host build's, {widened} of them \
             widened by the pose part, up to {widest:.2}×",
            readings.len()
        );
        // The part is in: readings whose leverage is above 1 are widened (not all with this D:
        // 6 to 8 of these 13, and 70 % of the bench's 2,000, counted from a QEMU trace).
        assert!(widened > 0, "r = {r}: none widened");
    }
}

/// A hub that computes no U95 (the fixed-point boards): with the reading's own budget its
/// points carry none; a table with the parameter block, which its flash cannot hold the
/// checks of, is refused by its flags and gives no coordinates.
#[allow(dead_code)] // each board's test binary uses one of the two U95 cases
pub fn no_u95(name: &str) {
    let b = the_board(name);
    let readings = some_readings(4);
    let out = replay(&b, Some(&budget_table(0)), &replay_bytes(&readings, None)).unwrap();
    assert_ran(&b, &out);
    assert_eq!(out.hellos[0].status.table(), TableState::Valid);
    assert_eq!(out.reports.len(), readings.len());
    for r in &out.reports {
        let p = r.point.expect("coordinates");
        assert_eq!(p.u95_nm, None, "{r:?}");
    }
    // Five parameters: a block that fits the board's 4 KiB slot.
    let with_block = budget_table(5);
    assert!(with_block.len() < 4096);
    let out = replay(&b, Some(&with_block), &replay_bytes(&readings, None)).unwrap();
    assert_eq!(out.hellos[0].status.table(), TableState::Malformed);
    assert!(out.reports.iter().all(|r| r.point.is_none()));
}

fn some_readings(n: usize) -> Vec<Reading> {
    recording::read(&default_recording_path())
        .unwrap()
        .into_iter()
        .step_by(997)
        .take(n)
        .collect()
}

/// A bit flipped in one incoming frame: that slot reports INPUT_ERROR without coordinates,
/// every other reading is evaluated as usual.
pub fn flipped_bit_in_an_incoming_frame(name: &str) {
    let b = the_board(name);
    let (_, table) = calibration(&default_calibration_path()).unwrap();
    let readings = some_readings(8);
    let mut input = vec![0u8];
    for (i, r) in readings.iter().enumerate() {
        let mut f = frame(&ToDevice::Reading(*r));
        if i == 3 {
            // A bit that does not turn a byte into the delimiter.
            let at = f.iter().position(|&x| x & 0x10 != 0 && x != 0x10).unwrap();
            f[at] ^= 0x10;
        }
        input.extend(f);
    }
    input.extend(frame(&ToDevice::End));
    let out = replay(&b, Some(&table), &input).unwrap();
    assert!(out.run.status.success());
    assert_eq!(out.reports.len(), readings.len());
    let host = host_points(b.precision, &table, &readings).unwrap();
    for (i, rep) in out.reports.iter().enumerate() {
        if i == 3 {
            assert!(rep.status.has(Status::INPUT_ERROR), "{:?}", rep.status);
            assert_eq!(rep.point, None);
        } else {
            assert_eq!(rep.status, Status(Status::TABLE_VALID));
            assert_eq!(Ok(rep.point.unwrap()), host[i]);
        }
    }
}

/// Encoder faults recorded with a reading: that joint's bit, no coordinates.
pub fn encoder_fault(name: &str) {
    let b = the_board(name);
    let (_, table) = calibration(&default_calibration_path()).unwrap();
    let mut readings = some_readings(6);
    readings[2].faults = 0b00_0100; // joint 3
    readings[4].faults = 0b10_0001; // joints 1 and 6
    let out = replay(&b, Some(&table), &replay_bytes(&readings, None)).unwrap();
    assert!(out.run.status.success());
    assert_eq!(out.reports.len(), readings.len());
    for (rep, r) in out.reports.iter().zip(&readings) {
        assert_eq!(rep.status.encoder_faults(), r.faults);
        assert_eq!(rep.point.is_some(), r.faults == 0, "{:?}", rep);
    }
}

/// A table that is missing, corrupt, of another version or for another joint count: the boot
/// announcement and every report say which, and no report has coordinates.
pub fn bad_tables(name: &str) {
    let b = the_board(name);
    let (mut arm, table) = calibration(&default_calibration_path()).unwrap();
    let mut corrupt = table.clone();
    corrupt[200] ^= 0x01;
    // A version this firmware does not read: the one after its own (u16 LE at byte 4).
    let mut version = table.clone();
    let next = quatarm::table::VERSION + 1;
    version[4..6].copy_from_slice(&next.to_le_bytes());
    let n = version.len();
    let crc = quatarm::table::CRC.checksum(&version[..n - 4]);
    version[n - 4..].copy_from_slice(&crc.to_le_bytes());
    arm.joints.push(arm.joints[5].clone());
    let seven = armcal::tablebuild::build(&arm).unwrap();
    let readings = some_readings(3);
    let input = replay_bytes(&readings, None);
    for (what, t, state) in [
        ("missing", None, TableState::Missing),
        ("corrupt", Some(corrupt), TableState::Corrupt),
        ("wrong version", Some(version), TableState::WrongVersion),
        ("7-joint", Some(seven), TableState::WrongJointCount),
    ] {
        let out = replay(&b, t.as_deref(), &input).unwrap();
        assert!(out.run.status.success(), "{what}");
        assert_eq!(out.hellos.len(), 1, "{what}");
        assert_eq!(out.hellos[0].status.table(), state, "{what}");
        assert_eq!(out.hellos[0].joints, 0, "{what}");
        assert_eq!(out.reports.len(), readings.len(), "{what}");
        for rep in &out.reports {
            assert_eq!(rep.status.table(), state, "{what}");
            assert!(!rep.status.table_valid(), "{what}");
            assert_eq!(rep.point, None, "{what}: coordinates from a bad table");
        }
    }
}

/// The shipped calibration with an axis wobble on every joint (`data/default-6-wobble.toml`).
fn wobble_calibration() -> (quatarm_ref::Arm, Vec<u8>) {
    calibration(&host_tests::boards::root().join("data/default-6-wobble.toml")).unwrap()
}

/// An f32 hub applies the wobble: 2,000 recorded readings, bit-identical to the host build
/// and within `bounds` of the f64 reference with the wobble; the same readings are far from
/// the reference without it (so a hub that ignored the block would fail).
#[allow(dead_code)] // each board's test binary uses one of the two wobble cases
pub fn wobble_applied(name: &str, bounds: Bounds) {
    let b = the_board(name);
    let (arm, table) = wobble_calibration();
    let (still, _) = calibration(&default_calibration_path()).unwrap();
    let readings: Vec<Reading> = recording::read(&default_recording_path())
        .unwrap()
        .into_iter()
        .take(2_000)
        .collect();
    let out = replay(&b, Some(&table), &replay_bytes(&readings, None)).unwrap();
    assert_ran(&b, &out);
    assert_eq!(out.hellos[0].status.table(), TableState::Valid);
    assert_eq!(out.reports.len(), readings.len());
    let host = host_points(b.precision, &table, &readings).unwrap();
    let (mut worst, mut worst_dir, mut moved) = (0.0f64, 0.0f64, 0.0f64);
    for (i, ((rep, r), h)) in out.reports.iter().zip(&readings).zip(&host).enumerate() {
        let c = rep
            .point
            .unwrap_or_else(|| panic!("reading {i}: no coordinates"));
        assert_eq!(Ok(c), *h, "reading {i}: target and host builds differ");
        let (p, n) = reference(&arm, r);
        worst = worst.max(deviation_um(&c, &p));
        worst_dir = worst_dir.max(direction_deviation(&c, &n));
        moved = moved.max(deviation_um(&c, &reference(&still, r).0));
    }
    eprintln!(
        "{name}: axis wobble, {} readings bit-identical to the host; from f64: tip {worst:.4} um, direction {worst_dir:.2e}; the wobble moves the tip by up to {moved:.1} um",
        readings.len()
    );
    assert!(worst <= bounds.tip_um, "tip {worst} um");
    assert!(worst_dir <= bounds.dir, "direction {worst_dir}");
    assert!(
        moved > 20.0 * bounds.tip_um,
        "the wobble moved the tip by {moved} um only"
    );
}

/// A hub built without the wobble (the Cortex-M0's) refuses a table with one as `Malformed`
/// (a flag it does not read), streams no coordinates, and says so in every report.
#[allow(dead_code)] // each board's test binary uses one of the two wobble cases
pub fn wobble_refused(name: &str, _bounds: Bounds) {
    let b = the_board(name);
    let (_, table) = wobble_calibration();
    let readings = some_readings(3);
    let out = replay(&b, Some(&table), &replay_bytes(&readings, None)).unwrap();
    assert_ran(&b, &out);
    assert_eq!(out.hellos[0].status.table(), TableState::Malformed);
    assert_eq!(out.reports.len(), readings.len());
    for rep in &out.reports {
        assert_eq!(rep.status.table(), TableState::Malformed);
        assert_eq!(rep.point, None, "coordinates from a table it cannot apply");
    }
}

/// The calibration with three probes (`data/default-6-probes.toml`: ids 1, 2, 5).
fn probes_calibration() -> (quatarm_ref::Arm, Vec<u8>) {
    calibration(&host_tests::boards::root().join("data/default-6-probes.toml")).unwrap()
}

/// [`probes_selected`], then an update on a hub with an update port: with another probe
/// selected, a committed table boots on its first probe, and the `Hello` says so.
#[allow(dead_code)] // each board's test binary uses one of the two probe cases
pub fn probes_selected_and_updated(name: &str, bounds: Bounds) {
    probes_selected(name, bounds);
    let b = the_board(name);
    let UpdateTables { old, new, .. } = update_tables_of(probes_calibration());
    let reading = some_readings(1)[0];
    let host_new = host_points(b.precision, &new, &[reading]).unwrap()[0].unwrap();
    let host_old_5 = host_points_with_probe(b.precision, &old, 2, &[reading]).unwrap()[0].unwrap();
    let mut s = Session::start(&b, &b.elf(b.name), Some(&old)).unwrap();
    assert!(matches!(s.next_item().unwrap(), Item::Hello(_)));
    assert_eq!(
        s.ask(&ToDevice::SelectProbe(5)).unwrap(),
        Item::Probe(Ok(5))
    );
    assert_eq!(point_now(&mut s, &reading), host_old_5);
    let steps = update_steps(&new);
    for (i, step) in steps.iter().enumerate() {
        let answer = s.ask(&ToDevice::Update(step.clone())).unwrap();
        assert!(
            matches!(answer, Item::Update(Ok(_))),
            "step {i}: {answer:?}"
        );
    }
    match s.next_item().unwrap() {
        Item::Hello(h) => {
            assert_eq!(h.live.map(|l| l.slot), Some(1), "{h:?}");
            assert_eq!((h.probe, h.probes.as_slice()), (1, &[1, 2, 5][..]), "{h:?}");
        }
        other => panic!("expected a Hello after the commit, got {other:?}"),
    }
    match s.ask(&ToDevice::Reading(reading)).unwrap() {
        Item::Report(r) => assert_eq!((r.probe, r.point), (1, Some(host_new))),
        other => panic!("expected a report, got {other:?}"),
    }
    let (status, _) = s.finish().unwrap();
    assert!(status.success(), "{status}");
}

/// A table with three probes (ids 1, 2, 5): the hub boots on the first and names all three
/// in its `Hello`; the host selects each in turn (and an unknown id, refused without a
/// change), each selection answered in a frame; every report carries the mounted probe's id,
/// its points bit for bit the host build of the same chain with that probe mounted, within
/// `bounds` of the f64 reference of the arm measuring with that probe (`Arm::for_probe`).
pub fn probes_selected(name: &str, bounds: Bounds) {
    let b = the_board(name);
    let (arm, table) = probes_calibration();
    let ids: Vec<u8> = arm.probes().map(|p| p.id).collect();
    assert_eq!(ids, [1, 2, 5]);
    let readings: Vec<Reading> = recording::read(&default_recording_path())
        .unwrap()
        .into_iter()
        .step_by(41)
        .take(250)
        .collect();
    // (selection, the probe index mounted after it); the first block before any selection.
    let plan: [(Option<u8>, usize); 5] = [
        (None, 0),
        (Some(2), 1),
        (Some(9), 1),
        (Some(5), 2),
        (Some(1), 0),
    ];
    let mut input = vec![0u8];
    for (select, _) in plan {
        if let Some(id) = select {
            input.extend(frame(&ToDevice::SelectProbe(id)));
        }
        input.extend(readings.iter().flat_map(|r| frame(&ToDevice::Reading(*r))));
    }
    input.extend(frame(&ToDevice::End));
    let file = host_tests::e2e::table_file(&table).unwrap();
    let run = host_tests::qemu::run(
        &b,
        &b.elf(b.name),
        &input,
        &host_tests::qemu::Options {
            table: Some(file.path().to_path_buf()),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(run.status.success(), "{:?}", run.status);
    let mut decoder = quatarm_wire::stream_decode::Decoder::from_start();
    let mut items = decoder.push_all(&run.stream).into_iter();
    assert_eq!(decoder.finish().damaged(), 0);
    match items.next() {
        Some(Item::Hello(h)) => {
            assert_eq!(h.status.table(), TableState::Valid, "{h:?}");
            assert_eq!((h.probe, h.probes.as_slice()), (1, &ids[..]), "{h:?}");
        }
        other => panic!("expected a Hello, got {other:?}"),
    }
    let host: Vec<_> = (0..3)
        .map(|k| host_points_with_probe(b.precision, &table, k, &readings).unwrap())
        .collect();
    assert_ne!(host[0][0], host[1][0], "the probes' points differ");
    assert_ne!(host[1][0], host[2][0], "the probes' points differ");
    let (mut worst_tip, mut worst_dir) = (0.0f64, 0.0f64);
    for (select, k) in plan {
        if let Some(id) = select {
            let want = if ids.contains(&id) {
                Ok(id)
            } else {
                Err(ProbeRefusal::Unknown)
            };
            assert_eq!(items.next(), Some(Item::Probe(want)), "selecting {id}");
        }
        let with_probe = arm.for_probe(k).unwrap();
        for (i, (r, h)) in readings.iter().zip(&host[k]).enumerate() {
            let rep = match items.next() {
                Some(Item::Report(rep)) => rep,
                other => panic!(
                    "probe {}, reading {i}: expected a report, got {other:?}",
                    ids[k]
                ),
            };
            assert_eq!(rep.probe, ids[k], "reading {i}");
            let c = rep
                .point
                .unwrap_or_else(|| panic!("probe {}, reading {i}: no coordinates", ids[k]));
            assert_eq!(
                Ok(c),
                *h,
                "probe {}, reading {i}: target and host differ",
                ids[k]
            );
            let (p, n) = reference(&with_probe, r);
            worst_tip = worst_tip.max(deviation_um(&c, &p));
            worst_dir = worst_dir.max(direction_deviation(&c, &n));
        }
    }
    assert_eq!(items.next(), None);
    eprintln!(
        "{name}: three probes selected in turn, {} readings each, bit-identical to the host \
         with that probe; from f64 (Arm::for_probe): tip {worst_tip:.4} um, direction {worst_dir:.2e}",
        readings.len()
    );
    assert!(worst_tip <= bounds.tip_um, "tip {worst_tip} um");
    assert!(worst_dir <= bounds.dir, "direction {worst_dir}");
}

/// Text mode: CSV lines with the same numbers as the binary stream.
pub fn text_mode(name: &str) {
    let b = the_board(name);
    let (_, table) = calibration(&default_calibration_path()).unwrap();
    let mut readings = some_readings(4);
    readings[1].faults = 1;
    let table_file = host_tests::e2e::table_file(&table).unwrap();
    let out = host_tests::qemu::run(
        &b,
        &b.elf(b.name),
        &replay_bytes(&readings, Some(Mode::Text)),
        &host_tests::qemu::Options {
            table: Some(table_file.path().to_path_buf()),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(out.status.success());
    // Binary: delimiters + Hello; then text, starting after the Hello frame's delimiter, with
    // the text mode's Hello: the header line.
    let first = out.stream.iter().position(|&x| x != 0).unwrap();
    let text_start = first + out.stream[first..].iter().position(|&x| x == 0).unwrap() + 1;
    let text = std::str::from_utf8(&out.stream[text_start..]).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.first(), Some(&CSV_HEADER.trim_end()), "{text}");
    lines.remove(0);
    assert_eq!(lines.len(), readings.len(), "{text}");
    let host = host_points(b.precision, &table, &readings).unwrap();
    assert_eq!(CSV_HEADER.trim_end().split(',').count(), 11);
    for (i, line) in lines.iter().enumerate() {
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(f.len(), 11, "{line}");
        // This table has no budget: no U95; its one probe has id 0.
        assert_eq!((f[9], f[10]), ("", "0"), "{line}");
        assert_eq!(f[0], i.to_string());
        if i == 1 {
            assert!(f[3..10].iter().all(|x| x.is_empty()), "{line}");
        } else {
            let c = host[i].unwrap();
            assert_eq!(
                f[3],
                format!("{:.6}", f64::from(c.xyz_nm[0]) / 1e6),
                "{line}"
            );
            assert_eq!(
                f[8],
                format!("{:.9}", f64::from(c.dir_e9[2]) / 1e9),
                "{line}"
            );
        }
    }
}

/// The defmt log, a channel apart from the data stream, decodes on the host and tells the
/// boot verdict, the replay's counts and the stack peak.
pub fn defmt_log(name: &str) {
    let b = the_board(name);
    let (_, table) = calibration(&default_calibration_path()).unwrap();
    let mut readings = some_readings(5);
    readings[0].faults = 0;
    let mut input = replay_bytes(&readings, None);
    // Damage the second reading's frame (first byte after the first frame's delimiter + 2).
    let second = 1 + frame(&ToDevice::Reading(readings[0])).len() + 2;
    input[second] ^= 0x40;
    if input[second] == 0 {
        input[second] = 0x7F;
    }
    let out = replay(&b, Some(&table), &input).unwrap();
    assert!(out.run.status.success());
    let lines = host_tests::defmt_log::decode(&b.elf(b.name), &out.run.log).unwrap();
    eprintln!("{name} defmt log: {lines:#?}");
    let precision = if b.precision == "f32" { "F32" } else { "Fixed" };
    assert_eq!(
        lines[0],
        format!("hub up: table Valid, 6 joints, {precision}, probe 0")
    );
    assert!(lines[1].starts_with("damaged input frame: "), "{lines:?}");
    assert_eq!(lines[2], "replay done: 5 reports, 1 damaged input frames");
    let stack = host_tests::defmt_log::number_after(&lines, "stack peak").unwrap();
    let ceiling = stack_ceiling(name);
    assert!(
        stack > 0 && stack <= ceiling,
        "{name}: stack peak {stack} B over its ceiling {ceiling} B"
    );
}

/// The most stack a QEMU hub may reach on the default table: its RAM for statics and stack
/// (qemu-m4f 64 KiB; qemu-m0's budget, `boards/qemu-m0/budget.x`, 8 KiB) less a reserve for
/// the tables this replay does not load (a wobble, a pose part: deeper boot paths) and for
/// interrupt frames. Measured: 46,284 B and 5,492 B (rustup 1.95; 46,276 and 5,500 with
/// Debian's 1.96; qemu-m4f 46,100 before the wobble's fixed room of four terms a joint),
/// against 63,740 and 7,836 before the hub built its calibration in place; a change that
/// gives the room back fails here rather than on a customer's hub.
fn stack_ceiling(name: &str) -> u64 {
    match name {
        "qemu-m4f" => 64 * 1024 - 8 * 1024,
        "qemu-m0" => 8 * 1024 - 1536,
        other => panic!("no stack ceiling for {other}"),
    }
}

/// The soak's short version (`cargo xtask soak` runs 10^6): 25,000 readings in (about 40 s
/// under QEMU, whose UART model moves ~60 kB/s), one frame in 50 damaged each way (flips, drops, bursts, garbage), every frame accounted for on both sides
/// (`host_tests::soak`).
pub fn soak(name: &str) {
    let b = the_board(name);
    let c = host_tests::soak::run(&b, 25_000, 50, 7).unwrap();
    eprintln!("{name} soak: {c:#?}");
    assert_eq!(c.hub_reports, c.hub_points + c.hub_rejected);
    assert!(
        c.damage_in.total() > 300 && c.damage_out.total() > 300,
        "{c:?}"
    );
}

/// The steps `armcal table send` sends for `table`.
fn update_steps(table: &[u8]) -> Vec<Step> {
    Step::sequence(table).collect()
}

/// `item` (the next of the hub's stream) must be a `Hello` naming `live` as the table in use.
#[allow(dead_code)] // each board's test binary uses one of the two update cases
fn expect_hello(item: Item, live: Option<LiveTable>, when: &str) {
    match item {
        Item::Hello(h) => assert_eq!(h.live, live, "{when}: {h:?}"),
        other => panic!("{when}: expected a Hello, got {other:?}"),
    }
}

/// The tables of an update test and what a `Hello` says of each once live.
#[allow(dead_code)] // each board's test binary uses one of the two update cases
struct UpdateTables {
    /// The calibration's table (the default calibration's in [`update_tables`]): the
    /// factory's.
    old_table: Vec<u8>,
    /// The same with the probe 0.05 mm longer: the update's.
    new_table: Vec<u8>,
    /// `old_table` signed with the test key, as the hub takes it.
    old: Vec<u8>,
    /// `new_table` signed with the test key.
    new: Vec<u8>,
    /// The factory table live: slot 0, found by its contents (no record).
    factory: Option<LiveTable>,
    /// The update live: slot 1, record 1.
    updated: Option<LiveTable>,
}

#[allow(dead_code)] // each board's test binary uses one of the two update cases
fn update_tables() -> UpdateTables {
    update_tables_of(calibration(&default_calibration_path()).unwrap())
}

/// The tables of an update from the calibration `(arm, old_table)` (its arm, its table).
#[allow(dead_code)] // each board's test binary uses one of the two update cases
fn update_tables_of((mut arm, old_table): (quatarm_ref::Arm, Vec<u8>)) -> UpdateTables {
    arm.probe.error[2] += 0.05;
    let new_table = quatarm_wire::tablebuild::build(&arm).unwrap();
    let (old, new) = (signed(&old_table).unwrap(), signed(&new_table).unwrap());
    let live = |slot, seq, t: &[u8]| {
        Some(LiveTable {
            slot,
            seq,
            crc: table_crc(t),
        })
    };
    UpdateTables {
        factory: live(0, 0, &old),
        updated: live(1, 1, &new),
        old_table,
        new_table,
        old,
        new,
    }
}

/// A valid table's CRC, as `Hello` names it.
#[allow(dead_code)] // each board's test binary uses one of the two update cases
fn table_crc(table: &[u8]) -> u32 {
    quatarm::table::Table::parse(table).unwrap().crc()
}

/// One reading's coordinates as the hub gives them now.
fn point_now(s: &mut Session, r: &Reading) -> Coordinates {
    match s.ask(&ToDevice::Reading(*r)).unwrap() {
        Item::Report(rep) => rep.point.expect("a point"),
        other => panic!("expected a report, got {other:?}"),
    }
}

/// A calibration update over the UART, with the machine reset before the commit at several
/// points (no step, after `Begin`, half the chunks, every chunk) and after it: every boot
/// comes up on the old table until the commit and on the new one after it, as its `Hello`
/// says (slot, record sequence number, CRC) and its points show; readings sent during the
/// update are answered on the old table; a damaged table is refused at commit and changes
/// nothing; a second update cut by a reset leaves the first one live.
#[allow(dead_code)] // each board's test binary uses one of the two update cases
pub fn update_with_resets(name: &str) {
    let b = the_board(name);
    let UpdateTables {
        old_table,
        old,
        new,
        factory,
        updated,
        ..
    } = update_tables();
    let reading = some_readings(1)[0];
    let host_old = host_points(b.precision, &old, &[reading]).unwrap()[0].unwrap();
    let host_new = host_points(b.precision, &new, &[reading]).unwrap()[0].unwrap();
    assert_ne!(host_old, host_new);

    let mut s = Session::start(&b, &b.elf(b.name), Some(&old)).unwrap();
    expect_hello(s.next_item().unwrap(), factory, "boot");
    assert_eq!(point_now(&mut s, &reading), host_old);
    let steps = update_steps(&new);
    let commit = steps.len() - 1;
    for cut in [0, 1, commit / 2, commit] {
        for step in &steps[..cut] {
            let answer = s.ask(&ToDevice::Update(step.clone())).unwrap();
            assert!(matches!(answer, Item::Update(Ok(_))), "{answer:?}");
        }
        s.reset().unwrap();
        expect_hello(
            s.next_item().unwrap(),
            factory,
            &format!("reset after {cut} of {commit} steps"),
        );
    }
    for (i, step) in steps.iter().enumerate() {
        if i == commit / 2 {
            assert_eq!(
                point_now(&mut s, &reading),
                host_old,
                "old table during an update"
            );
        }
        let answer = s.ask(&ToDevice::Update(step.clone())).unwrap();
        if i == commit {
            assert_eq!(
                answer,
                Item::Update(Ok(Accepted::Committed { slot: 1, seq: 1 }))
            );
        } else {
            assert!(matches!(answer, Item::Update(Ok(_))), "{answer:?}");
        }
    }
    expect_hello(s.next_item().unwrap(), updated, "after the commit");
    assert_eq!(point_now(&mut s, &reading), host_new);
    s.reset().unwrap();
    expect_hello(s.next_item().unwrap(), updated, "reset after the commit");
    assert_eq!(point_now(&mut s, &reading), host_new);

    // One byte of the table changed: refused at commit as the boot would call it.
    let mut damaged = update_steps(&old);
    match &mut damaged[3] {
        Step::Chunk { bytes, .. } => bytes[5] ^= 0x01,
        other => panic!("step 3 is a chunk, not {other:?}"),
    }
    let mut last = None;
    for step in &damaged {
        last = Some(s.ask(&ToDevice::Update(step.clone())).unwrap());
    }
    assert_eq!(
        last,
        Some(Item::Update(Err(Refusal::Table(TableState::Corrupt))))
    );
    assert_eq!(
        point_now(&mut s, &reading),
        host_new,
        "a refused update changes nothing"
    );

    // Unsigned, and signed under another key: refused at commit with the boot's states.
    let other_key = {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("other.pem");
        std::fs::write(&path, tablesign::keygen().unwrap().0).unwrap();
        tablesign::read_private(&path).unwrap()
    };
    for (image, state) in [
        (old_table.clone(), TableState::Unsigned),
        (
            tablesign::sign(&other_key, &old_table).unwrap(),
            TableState::BadSignature,
        ),
    ] {
        let mut last = None;
        for step in &update_steps(&image) {
            last = Some(s.ask(&ToDevice::Update(step.clone())).unwrap());
        }
        assert_eq!(last, Some(Item::Update(Err(Refusal::Table(state)))));
    }
    assert_eq!(point_now(&mut s, &reading), host_new);

    // A second update (into slot 0) cut by a reset: the first one stays live.
    for step in &update_steps(&old)[..commit / 2] {
        s.ask(&ToDevice::Update(step.clone())).unwrap();
    }
    s.reset().unwrap();
    expect_hello(
        s.next_item().unwrap(),
        updated,
        "reset during a second update",
    );
    let (status, _) = s.finish().unwrap();
    assert!(status.success(), "{status}");

    // An unsigned factory table does not boot: its state says why, and no point is given.
    let mut s = Session::start(&b, &b.elf(b.name), Some(&old_table)).unwrap();
    match s.next_item().unwrap() {
        Item::Hello(h) => {
            assert_eq!((h.status.table(), h.live), (TableState::Unsigned, None));
        }
        other => panic!("expected a Hello, got {other:?}"),
    }
    match s.ask(&ToDevice::Reading(reading)).unwrap() {
        Item::Report(r) => assert_eq!((r.status.table(), r.point), (TableState::Unsigned, None)),
        other => panic!("expected a report, got {other:?}"),
    }
    let (status, _) = s.finish().unwrap();
    assert!(status.success(), "{status}");
}

/// A hub without an update port (the qemu-m0 image, for its flash budget) answers every update
/// step `NotSupported` and keeps its table.
#[allow(dead_code)] // each board's test binary uses one of the two update cases
pub fn update_not_supported(name: &str) {
    let b = the_board(name);
    let (_, table) = calibration(&default_calibration_path()).unwrap();
    let reading = some_readings(1)[0];
    let host = host_points(b.precision, &table, &[reading]).unwrap()[0].unwrap();
    let mut s = Session::start(&b, &b.elf(b.name), Some(&table)).unwrap();
    assert!(matches!(s.next_item().unwrap(), Item::Hello(_)));
    for step in &update_steps(&table)[..3] {
        assert_eq!(
            s.ask(&ToDevice::Update(step.clone())).unwrap(),
            Item::Update(Err(Refusal::NotSupported))
        );
    }
    assert_eq!(point_now(&mut s, &reading), host);
    let (status, _) = s.finish().unwrap();
    assert!(status.success(), "{status}");
}

/// The default calibration's arm with its probe `dz` mm longer, as a table of calibration
/// `number` dated 2026-12-04 (unsigned).
#[allow(dead_code)] // qemu-m4f only (qemu-m0 has no update port)
fn numbered_table(dz: f64, number: u32) -> Vec<u8> {
    use quatarm_ref::release::{Date, Release};
    let mut arm = calibration(&default_calibration_path()).unwrap().0;
    arm.probe.error[2] += dz;
    let release = Release {
        number,
        date: Date::new(2026, 12, 4),
        due: None,
    };
    quatarm_wire::tablebuild::build_release(&arm, None, &release).unwrap()
}

/// Sends a signed table image step by step; the answer to the last step.
#[allow(dead_code)] // qemu-m4f only
fn send_table(s: &mut Session, image: &[u8]) -> Option<Item> {
    let mut last = None;
    for step in &update_steps(image) {
        last = Some(s.ask(&ToDevice::Update(step.clone())).unwrap());
    }
    last
}

/// The next item, a `Hello` of this protocol: the calibration number and date it announces.
#[allow(dead_code)] // qemu-m4f only
fn announced_calibration(s: &mut Session, when: &str) -> (u32, u32) {
    match s.next_item().unwrap() {
        Item::Hello(h) => {
            assert_eq!(h.protocol, quatarm::stream::PROTOCOL_VERSION, "{when}");
            (h.number, h.date)
        }
        other => panic!("{when}: expected a Hello, got {other:?}"),
    }
}

/// Anti-rollback on a hub under QEMU (`docs/update.md`): on a factory table of calibration
/// number 5, a table of number 6 is committed and its points follow; the number-5 table sent
/// back (validly signed) is refused at commit as `Rollback { live: 6, offered: 5 }`, the points
/// stay the new table's, and after a reset the hub still boots on number 6 and refuses the
/// number-5 table again. Every `Hello` names the live number and date (protocol 5).
#[allow(dead_code)] // qemu-m4f only (qemu-m0 has no update port)
pub fn rollback_refused(name: &str) {
    let b = the_board(name);
    let (five, six) = (
        signed(&numbered_table(0.0, 5)).unwrap(),
        signed(&numbered_table(0.05, 6)).unwrap(),
    );
    let reading = some_readings(1)[0];
    let host_five = host_points(b.precision, &five, &[reading]).unwrap()[0].unwrap();
    let host_six = host_points(b.precision, &six, &[reading]).unwrap()[0].unwrap();
    assert_ne!(host_five, host_six);

    let mut s = Session::start(&b, &b.elf(b.name), Some(&five)).unwrap();
    assert_eq!(announced_calibration(&mut s, "boot"), (5, 20261204));
    assert_eq!(point_now(&mut s, &reading), host_five);
    assert_eq!(
        send_table(&mut s, &six),
        Some(Item::Update(Ok(Accepted::Committed { slot: 1, seq: 1 })))
    );
    assert_eq!(announced_calibration(&mut s, "commit"), (6, 20261204));
    assert_eq!(point_now(&mut s, &reading), host_six);
    let refused = Some(Item::Update(Err(Refusal::Rollback {
        live: 6,
        offered: 5,
    })));
    assert_eq!(send_table(&mut s, &five), refused);
    assert_eq!(
        point_now(&mut s, &reading),
        host_six,
        "a refused rollback changes nothing"
    );
    s.reset().unwrap();
    assert_eq!(announced_calibration(&mut s, "reset"), (6, 20261204));
    assert_eq!(point_now(&mut s, &reading), host_six, "after a reset");
    assert_eq!(send_table(&mut s, &five), refused, "after a reset");
    let (status, _) = s.finish().unwrap();
    assert!(status.success(), "{status}");
}

/// Key rotation on a hub under QEMU (`docs/update.md`, "Key rotation and revocation"): the
/// image holds the test key and its successor. On a factory table of number 5 signed by the
/// test key, a table of number 6 signed by the successor is committed (the rotation) and its
/// points follow; a table of number 7 signed by the now retired test key is refused
/// `RetiredKey` and changes nothing, before and after a reset; the same table signed by the
/// successor is committed.
#[allow(dead_code)] // qemu-m4f only (the one image with a next key)
pub fn key_rotation(name: &str) {
    use host_tests::e2e::signed_next;
    let b = the_board(name);
    let (t5, t6, t7) = (
        numbered_table(0.0, 5),
        numbered_table(0.05, 6),
        numbered_table(-0.05, 7),
    );
    let factory = signed(&t5).unwrap();
    let rotation = signed_next(&t6).unwrap();
    let (retired, renewed) = (signed(&t7).unwrap(), signed_next(&t7).unwrap());
    let reading = some_readings(1)[0];
    let host = |t: &[u8]| host_points(b.precision, t, &[reading]).unwrap()[0].unwrap();
    let (host5, host6, host7) = (host(&t5), host(&t6), host(&t7));
    assert!(host5 != host6 && host6 != host7);

    let mut s = Session::start(&b, &b.elf(b.name), Some(&factory)).unwrap();
    assert_eq!(announced_calibration(&mut s, "boot").0, 5);
    assert_eq!(point_now(&mut s, &reading), host5);
    assert_eq!(
        send_table(&mut s, &rotation),
        Some(Item::Update(Ok(Accepted::Committed { slot: 1, seq: 1 }))),
        "a table signed by the next key rotates the hub"
    );
    assert_eq!(announced_calibration(&mut s, "rotation").0, 6);
    assert_eq!(point_now(&mut s, &reading), host6);
    let refused = Some(Item::Update(Err(Refusal::RetiredKey)));
    assert_eq!(send_table(&mut s, &retired), refused);
    assert_eq!(
        point_now(&mut s, &reading),
        host6,
        "a refusal changes nothing"
    );
    s.reset().unwrap();
    assert_eq!(announced_calibration(&mut s, "reset").0, 6);
    assert_eq!(point_now(&mut s, &reading), host6, "after a reset");
    assert_eq!(send_table(&mut s, &retired), refused, "after a reset");
    assert_eq!(
        send_table(&mut s, &renewed),
        Some(Item::Update(Ok(Accepted::Committed { slot: 0, seq: 2 }))),
        "the new key signs the next update"
    );
    assert_eq!(announced_calibration(&mut s, "renewed").0, 7);
    assert_eq!(point_now(&mut s, &reading), host7);
    let (status, _) = s.finish().unwrap();
    assert!(status.success(), "{status}");
}
