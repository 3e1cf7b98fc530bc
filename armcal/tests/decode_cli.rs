//! `armcal decode` as a user runs it: a captured stream on stdin, CSV on stdout, the counts
//! that tell whether the capture can be trusted on stderr.

use std::io::Write;
use std::process::{Command, Stdio};

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
        }),
    })
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

    let mut child = Command::new(env!("CARGO_BIN_EXE_armcal"))
        .arg("decode")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(&bytes).unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    let csv = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], "seq,time_us,status,x_mm,y_mm,z_mm,nx,ny,nz");
    assert_eq!(
        lines[1],
        "0,0,0x0001,1500.000000,-0.000002,0.000003,0.000000000,0.000000000,1.000000000"
    );
    assert_eq!(lines[2], "1,1000,0x0401,,,,,,");
    assert!(lines[3].starts_with("4,4000,"));
    assert!(lines[4].starts_with("6,6000,"));
    assert_eq!(lines.len(), 5);
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.contains("decode: 4 reports (3 with coordinates), 3 lost, 1 crc errors, 0 other damaged frames, 0 bytes skipped"),
        "{err}"
    );
}
