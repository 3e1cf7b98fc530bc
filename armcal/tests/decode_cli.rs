//! `armcal decode` as a user runs it: a captured stream on stdin, CSV on stdout, the counts
//! that tell whether the capture can be trusted on stderr.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use quatarm::stream::{encode, Coordinates, Report, Status, ToHost, MAX_FRAME};

fn frame(msg: &ToHost) -> Vec<u8> {
    let mut out = [0u8; MAX_FRAME];
    let n = encode(msg, &mut out).unwrap();
    out[..n].to_vec()
}

fn report(seq: u32, point: bool) -> ToHost {
    ToHost::Report(Report {
        seq,
        time_us: 1000 * u64::from(seq),
        status: Status(if point { 0x0001 } else { 0x0401 }),
        point: point.then_some(Coordinates {
            xyz_nm: [1_500_000_000, -2, 3],
            dir_e9: [0, 0, 1_000_000_000],
            u95_nm: Some(12_345 + seq),
        }),
        probe: 3,
    })
}

/// `armcal decode` with `args`, `stdin` piped in.
fn decode(args: &[&std::ffi::OsStr], stdin: &[u8]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_armcal"))
        .arg("decode")
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut pipe = child.stdin.take().unwrap();
    let input = stdin.to_vec();
    // A thread, so that a large input cannot dead-lock against a full stderr pipe.
    let writer = std::thread::spawn(move || {
        let _ = pipe.write_all(&input);
    });
    let out = child.wait_with_output().unwrap();
    writer.join().unwrap();
    out
}

fn stream_file(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/streams")
        .join(name)
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The run failed with `what` in its message and wrote nothing to stdout.
fn assert_refused(out: &Output, what: &str) {
    let err = text(&out.stderr);
    assert!(!out.status.success(), "exit 0: {err}");
    assert!(
        out.stdout.is_empty(),
        "partial output: {}",
        text(&out.stdout)
    );
    assert!(err.contains(what), "{err}");
}

#[test]
fn a_repeated_frame_is_written_once_and_loses_nothing() {
    // ../shared/repro/s-dup.bin: reports 0, 1, 1, 2. It was "4294967295 lost".
    let out = decode(&[stream_file("s-dup.bin").as_os_str()], &[]);
    assert!(out.status.success());
    let csv = text(&out.stdout);
    let seqs: Vec<&str> = csv.lines().skip(1).map(|l| &l[..2]).collect();
    assert_eq!(seqs, ["0,", "1,", "2,"], "{csv}");
    let err = text(&out.stderr);
    assert!(
        err.contains("decode: 3 reports (3 with coordinates), 0 lost,")
            && err.contains(" 1 repeated, 0 backward,"),
        "{err}"
    );
}

#[test]
fn a_backward_step_is_not_counted_as_lost() {
    let bytes = [0, 5, 6, 2, 3]
        .iter()
        .flat_map(|&s| frame(&report(s, true)))
        .collect::<Vec<u8>>();
    let out = decode(&[], &bytes);
    assert!(out.status.success());
    let err = text(&out.stderr);
    assert!(
        err.contains("5 reports (5 with coordinates), 4 lost,"),
        "{err}"
    );
    assert!(err.contains(" 1 backward,"), "{err}");
    assert!(err.contains("report 2 where 7 was due"), "{err}");
}

#[test]
fn coordinates_beside_a_fault_are_not_written_as_points() {
    // ../shared/repro/s-fault-with-point.bin: statuses 0x0009 (chain error), 0x0020 (table
    // corrupt) and 0x0101 (joint 1 encoder fault), each with coordinates. A capture of
    // protocol 3 without its Hello: read in that layout, the probe its hub's only one, id 0.
    let out = decode(&[stream_file("s-fault-with-point.bin").as_os_str()], &[]);
    assert!(out.status.success());
    let csv = text(&out.stdout);
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(
        rows,
        [
            "0,0,0x0009,,,,,,,,0",
            "1,0,0x0020,,,,,,,,0",
            "2,0,0x0101,,,,,,,,0"
        ]
    );
    let err = text(&out.stderr);
    assert!(err.contains("3 reports (0 with coordinates)"), "{err}");
    assert!(err.contains(" 3 inconsistent,"), "{err}");
}

#[test]
fn bytes_without_a_delimiter_are_refused_not_dropped() {
    // 50 MB of line noise that never reaches a 0x00 (it was "0 reports, 0 damaged", exit 0).
    let out = decode(&[], &vec![b'U'; 50_000_000]);
    assert_refused(
        &out,
        "no valid frame in the 50000000 bytes of stdin (1 damaged)",
    );
    assert!(text(&out.stderr).contains("50000000 unterminated bytes"));
}

#[test]
fn a_text_mode_capture_is_named_as_such() {
    let capture = "seq,time_us,status,x_mm,y_mm,z_mm,nx,ny,nz\n\
                   0,1000,0x0001,1.000000,2.000000,3.000000,0.000000000,0.000000000,1.000000000\n";
    let out = decode(&[], capture.as_bytes());
    assert_refused(&out, "looks like the hub's text mode");
    // Rows without the header too.
    let out = decode(&[], b"42,1000001,0x0401,,,,,,\n43,1001001,0x0401,,,,,,\n");
    assert_refused(&out, "looks like the hub's text mode");
}

#[test]
fn a_capture_of_damaged_frames_only_fails() {
    let mut bytes = vec![0u8];
    for seq in 0..5 {
        let mut f = frame(&report(seq, true));
        f[4] = f[4].wrapping_add(1).max(1); // changed, and still not a delimiter
        bytes.extend(f);
    }
    let out = decode(&[], &bytes);
    assert_refused(&out, "no valid frame in the");
    let err = text(&out.stderr);
    assert!(err.contains("(5 damaged)"), "{err}");
}

#[test]
fn bad_inputs_leave_no_partial_output() {
    let dir = stream_file("");
    let out = decode(&[dir.as_os_str()], &[]);
    assert_refused(&out, "is a directory, not a captured stream");
    let out = decode(&[], &[]);
    assert_refused(&out, "stdin is empty");
    let missing = stream_file("nothing.bin");
    let out = decode(&[missing.as_os_str()], &[]);
    assert_refused(&out, "nothing.bin");
}

#[test]
fn decodes_a_capture_counting_gaps_and_damage() {
    let mut bytes = vec![0u8];
    for (seq, point) in [(0, true), (1, false), (4, true)] {
        bytes.extend(frame(&report(seq, point)));
    }
    let mut damaged = frame(&report(5, true));
    damaged[6] ^= 0x08;
    bytes.extend(damaged);
    bytes.extend(frame(&report(6, true)));

    let out = decode(&[], &bytes);
    assert!(out.status.success());
    let csv = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "seq,time_us,status,x_mm,y_mm,z_mm,nx,ny,nz,u95_mm,probe"
    );
    assert_eq!(
        lines[1],
        "0,0,0x0001,1500.000000,-0.000002,0.000003,0.000000000,0.000000000,1.000000000,0.012345,3"
    );
    assert_eq!(lines[2], "1,1000,0x0401,,,,,,,,3");
    assert!(lines[3].starts_with("4,4000,"));
    assert!(lines[4].starts_with("6,6000,"));
    assert_eq!(lines.len(), 5);
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.contains("decode: 4 reports (3 with coordinates), 3 lost, 1 crc errors, 0 other damaged frames, 0 bytes skipped"),
        "{err}"
    );
}

/// A protocol-5 `Hello` names the live calibration's number and date: `decode` says them on
/// stderr; a protocol-4 one (which has none) and a hub without a valid table say nothing of
/// a calibration.
#[test]
fn the_hello_s_calibration_number_and_date_are_shown() {
    use quatarm::stream::{Hello, LiveTable, NumberFormat, PROTOCOL_VERSION};
    let hello = |status: u16, number, date| {
        frame(&ToHost::Hello(Hello {
            protocol: PROTOCOL_VERSION,
            precision: NumberFormat::F32,
            joints: 6,
            status: Status(status),
            live: (status == 1).then_some(LiveTable {
                slot: 1,
                seq: 2,
                crc: 0x1234,
            }),
            probe: 3,
            probes: [3u8].into_iter().collect(),
            number,
            date,
        }))
    };
    let mut bytes = vec![0u8];
    bytes.extend(hello(1, 12, 20261204));
    bytes.extend(frame(&report(0, true)));
    bytes.extend(hello(1, 0, 0));
    bytes.extend(frame(&report(0, true)));
    let out = decode(&[], &bytes);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let err = text(&out.stderr);
    let hubs: Vec<&str> = err.lines().filter(|l| l.starts_with("# hub:")).collect();
    assert_eq!(hubs.len(), 2, "{err}");
    assert!(
        hubs[0].ends_with(", calibration number 12, dated 2026-12-04"),
        "{err}"
    );
    assert!(
        hubs[1].ends_with(", calibration number 0, no date"),
        "{err}"
    );
    // A protocol-4 Hello: the same fields without the number and date (a tuple: `Hello`
    // serialises protocol 5's layout).
    let v4 = frame_of_tuple(&(
        0u8,
        4u16,
        NumberFormat::F32,
        6u8,
        Status(1),
        None::<u8>,
        3u8,
        &[3u8][..],
    ));
    let mut bytes = vec![0u8];
    bytes.extend(v4);
    bytes.extend(frame(&report(0, true)));
    let out = decode(&[], &bytes);
    let err = text(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("# hub: protocol 4") && !err.contains("calibration number"),
        "{err}"
    );
}

fn frame_of_tuple(msg: &impl serde::Serialize) -> Vec<u8> {
    let mut out = [0u8; MAX_FRAME];
    let n = encode(msg, &mut out).unwrap();
    out[..n].to_vec()
}
