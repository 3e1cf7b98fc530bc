//! Issue 29's customer mistakes, each tried as a new user would, on copies of the inputs: the
//! message names the file and the line, column or key, says what looks wrong and which
//! `--accept-…` flag takes it as it is; nothing is written to stdout when refused.

#[allow(dead_code)]
mod common;

use common::{armcal, armcal_ok, refused, refused_with, simulate, stderr, workdir};
use std::path::Path;

/// `data/NAME` of the project copied into `d` as `as_name`.
fn copy_data(d: &Path, name: &str, as_name: &str) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../data")
        .join(name);
    std::fs::copy(src, d.join(as_name)).unwrap();
}

/// A copy of CSV `src` with each data row's joint cells `j1..jN` put in the order `order`
/// (the new file's column k holds the old column `order[k]`), comments and header kept.
fn reorder(src: &Path, dst: &Path, order: &[usize]) {
    let text = std::fs::read_to_string(src).unwrap();
    let mut joints: Vec<usize> = Vec::new();
    let mut out = String::new();
    for line in text.lines() {
        if line.starts_with('#') {
            out += line;
        } else if joints.is_empty() {
            let names: Vec<&str> = line.split(',').collect();
            joints = (1..=order.len())
                .map(|k| names.iter().position(|n| *n == format!("j{k}")).unwrap())
                .collect();
            out += line;
        } else {
            let cells: Vec<&str> = line.split(',').collect();
            let mut new: Vec<&str> = cells.clone();
            for (k, &from) in order.iter().enumerate() {
                new[joints[k]] = cells[joints[from]];
            }
            out += &new.join(",");
        }
        out += "\n";
    }
    std::fs::write(dst, out).unwrap();
}

/// A copy of text file `src` with `from` replaced by `to` once, after the `nth` (1-based)
/// occurrence of `after` (0: from the start).
fn edit(src: &Path, dst: &Path, after: &str, nth: usize, from: &str, to: &str) {
    let text = std::fs::read_to_string(src).unwrap();
    let mut at = 0;
    for _ in 0..nth {
        at += text[at..].find(after).unwrap() + after.len();
    }
    let k = at + text[at..].find(from).unwrap();
    let out = format!("{}{to}{}", &text[..k], &text[k + from.len()..]);
    std::fs::write(dst, out).unwrap();
}

/// The ISO 10360-12 test set (sphere, length and spat groups) simulated in `d` from the
/// calibration `cal` (seed 1) into `out`.
fn iso_set(d: &Path, cal: &str, out: &str) {
    armcal_ok(
        &[
            "simulate",
            "--truth",
            cal,
            "--seed",
            "1",
            "--test",
            "iso10360-12",
            "-o",
            out,
        ],
        d,
    );
}

/// A fresh folder `name` holding the project's `default-6-full.toml` as `cal.toml` and its
/// ISO 10360-12 test set as `t.csv`; returns the folder and the set's text.
fn with_iso_set(name: &str) -> (std::path::PathBuf, String) {
    let d = workdir(name);
    copy_data(&d, "default-6-full.toml", "cal.toml");
    iso_set(&d, "cal.toml", "t.csv");
    let text = std::fs::read_to_string(d.join("t.csv")).unwrap();
    (d, text)
}

/// `r.csv` in `d`: one joint reading of a 6-joint arm, the input of `armcal eval`.
fn write_reading(d: &Path) {
    std::fs::write(
        d.join("r.csv"),
        "j1,j2,j3,j4,j5,j6\n0.1,0.2,0.3,0.4,0.5,0.6\n",
    )
    .unwrap();
}

/// `armcal check FILE --calib cal.toml` in `d`.
fn check(d: &Path, file: &str) -> std::process::Output {
    armcal(&["check", file, "--calib", "cal.toml"], d)
}

/// Joint columns out of order (two swapped, or all reversed) in `point`, `spat` and
/// `sphere`/`length` data: refused before any fit with the reordering named; the data as
/// recorded pass, and `--accept-order` takes them as they are.
#[test]
fn joint_columns_out_of_order_are_named_before_any_fit() {
    let d = workdir("order");
    // The truth is a calibrated arm (errors of a few mm), the start arm its nominal model:
    // the misfit a real first calibration starts from.
    copy_data(&d, "default-6-full.toml", "truth.toml");
    for (kind, count, out) in [("point", "60", "p.csv"), ("spat", "8", "s.csv")] {
        simulate(&d, kind, count, "4", &[], out);
    }
    let cal = |data: &str, extra: &[&str]| {
        let mut args = vec!["calibrate", data, "--folds", "0", "-o", "out.toml"];
        args.extend_from_slice(extra);
        armcal(&args, &d)
    };
    assert!(cal("p.csv", &[]).status.success(), "as recorded");
    std::fs::remove_file(d.join("out.toml")).unwrap();

    reorder(&d.join("p.csv"), &d.join("p21.csv"), &[1, 0, 2, 3, 4, 5]);
    let e = refused(
        &cal("p21.csv", &[]),
        &[
            "p21.csv: the joint columns look out of order",
            "with j1 and j2 swapped",
            "exchange the columns j1 and j2",
            "--accept-order",
        ],
    );
    assert!(!e.contains("did not converge"), "{e}");
    assert!(!d.join("out.toml").exists(), "no output when refused");
    reorder(&d.join("p.csv"), &d.join("prev.csv"), &[5, 4, 3, 2, 1, 0]);
    refused(
        &cal("prev.csv", &[]),
        &[
            "prev.csv",
            "with j1..j6 reversed",
            "reverse the joint columns",
        ],
    );
    reorder(&d.join("s.csv"), &d.join("s35.csv"), &[0, 1, 4, 3, 2, 5]);
    refused(
        &armcal(&["diagnose", "s35.csv"], &d),
        &["s35.csv", "with j3 and j5 swapped"],
    );
    // Taken as it is deliberately: the order check is not what stops it.
    let o = cal("p21.csv", &["--accept-order"]);
    assert!(!stderr(&o).contains("out of order"), "{}", stderr(&o));

    // `check` on an ISO 10360-12 test set (sphere, length and spat groups).
    iso_set(&d, "truth.toml", "t.csv");
    armcal_ok(&["check", "t.csv", "--calib", "truth.toml"], &d);
    reorder(&d.join("t.csv"), &d.join("t12.csv"), &[1, 0, 2, 3, 4, 5]);
    refused_with(
        &armcal(&["check", "t12.csv", "--calib", "truth.toml"], &d),
        3,
        &["t12.csv", "with j1 and j2 swapped", "--accept-order"],
    );
}

/// A fresh folder `name` holding the project's calibration as `full.toml`, `r.csv`, and four
/// copies of the calibration with one angle in degrees (or beyond every turn): `tilt.toml`
/// (the second joint's tilt of (2.2, 2.4) mrad written in degrees), `zero.toml`,
/// `harm.toml` and `twist.toml` (a quarter turn of 90).
fn with_degrees(name: &str) -> std::path::PathBuf {
    let d = workdir(name);
    copy_data(&d, "default-6-full.toml", "full.toml");
    let full = d.join("full.toml");
    let tilt = "tilt = [0.0022196, 0.0023613]";
    for (file, nth, from, to) in [
        ("tilt.toml", 2, tilt, "tilt = [0.127, 0.135]"),
        (
            "zero.toml",
            3,
            "zero_offset = -0.0020333",
            "zero_offset = -0.1165",
        ),
        ("harm.toml", 1, "sin = -8.8e-5", "sin = -0.005"),
        ("twist.toml", 2, tilt, "tilt = [90.0, 0.0]"),
    ] {
        edit(&full, &d.join(file), "[[joint]]", nth, from, to);
    }
    write_reading(&d);
    d
}

/// `armcal eval --calib CALIB r.csv EXTRA…` in `d`.
fn eval(d: &Path, calib: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["eval", "--calib", calib, "r.csv"];
    args.extend_from_slice(extra);
    armcal(&args, d)
}

/// Degrees inside a calibration file: refused where it is read, with the file, the line and
/// the key; `--accept-units` takes an angle within the loader's limits as it is.
#[test]
fn degrees_in_a_calibration_file_are_refused_with_key_and_line() {
    let d = with_degrees("caldeg");
    armcal_ok(&["eval", "--calib", "full.toml", "r.csv"], &d);
    for (file, line, key, value) in [
        ("tilt.toml", 28, "joint[2].tilt[0]", "0.127 rad"),
        ("zero.toml", 37, "joint[3].zero_offset", "-0.1165 rad"),
        ("harm.toml", 20, "joint[1].harmonics[1].sin", "-0.005 rad"),
        ("twist.toml", 28, "joint[2].tilt[0]", "90 rad"),
    ] {
        let text = std::fs::read_to_string(d.join(file)).unwrap();
        let at = text.lines().nth(line - 1).unwrap();
        assert!(
            at.contains(key.rsplit('.').next().unwrap().split('[').next().unwrap()),
            "{file}: line {line} is `{at}`"
        );
        refused(
            &eval(&d, file, &[]),
            &[
                &format!("{file}: line {line}, {key} = {value}"),
                "in degrees? multiply by π/180",
                "--accept-units",
            ],
        );
    }
    // Deliberately: a tilt of 0.127 rad is within the loader's limits and is read.
    armcal_ok(
        &["eval", "--calib", "tilt.toml", "r.csv", "--accept-units"],
        &d,
    );
    // 90 rad is beyond every turn: the loader's own limit still refuses it, with its key.
    refused(
        &eval(&d, "twist.toml", &["--accept-units"]),
        &["joint[2].tilt[0]", "angle limit"],
    );
}

/// Every command that reads a calibration refuses degrees in it the way `eval` does, and
/// writes nothing.
#[test]
fn every_command_refuses_degrees_in_a_calibration_file() {
    let d = with_degrees("caldeg-all");
    refused(
        &armcal(&["table", "build", "tilt.toml", "-o", "t.bin"], &d),
        &["tilt.toml: line 28, joint[2].tilt[0]"],
    );
    assert!(!d.join("t.bin").exists());
    refused_with(
        &armcal(&["check", "r.csv", "--calib", "zero.toml"], &d),
        3,
        &["zero.toml: line 37"],
    );
    refused(
        &armcal(
            &["calibrate", "r.csv", "--arm", "harm.toml", "-o", "o.toml"],
            &d,
        ),
        &["harm.toml: line 20"],
    );
}

/// The stylus ball's diameter in µm in a calibration file: refused with its line, the unit
/// named rather than the loader's limit.
#[test]
fn a_ball_diameter_in_um_is_refused_with_its_line() {
    let d = workdir("ballum");
    copy_data(&d, "default-6-full.toml", "full.toml");
    write_reading(&d);
    edit(
        &d.join("full.toml"),
        &d.join("ball.toml"),
        "",
        0,
        "[probe]",
        "[probe]\nball_diameter = 6000.0",
    );
    let o = eval(&d, "ball.toml", &[]);
    let e = refused(
        &o,
        &[
            "ball.toml: line",
            "ball_diameter = 6000 mm",
            "in µm? divide by 1000",
        ],
    );
    assert!(
        !e.contains("5000 mm"),
        "the unit, not the loader's limit: {e}"
    );
}

/// A hub running another table than the calibration `decode --calib` is given: another joint
/// count (another arm's table) or another CRC (another calibration's) is refused before any
/// report is written; the table built from the calibration passes.
#[test]
fn decode_refuses_a_hub_running_another_arms_table() {
    use quatarm::stream::{encode, Hello, LiveTable, NumberFormat, Status, ToHost, MAX_FRAME};
    let d = workdir("hubtable");
    copy_data(&d, "default-6-full.toml", "cal.toml");
    armcal_ok(&["table", "build", "cal.toml", "-o", "cal.bin"], &d);
    let bytes = std::fs::read(d.join("cal.bin")).unwrap();
    let crc = quatarm::table::Table::parse(&bytes).unwrap().crc();
    let frame = |msg: &ToHost| {
        let mut out = [0u8; MAX_FRAME];
        let n = encode(msg, &mut out).unwrap();
        out[..n].to_vec()
    };
    let stream = |joints: u8, crc: u32| {
        let mut s = frame(&ToHost::Hello(Hello {
            protocol: quatarm::stream::PROTOCOL_VERSION,
            precision: NumberFormat::F32,
            joints,
            status: Status::default(),
            live: Some(LiveTable {
                slot: 0,
                seq: 1,
                crc,
            }),
            probe: 0,
            probes: Default::default(),
            number: 0,
            date: 0,
        }));
        s.extend(frame(&ToHost::Report(quatarm::stream::Report {
            seq: 0,
            time_us: 1000,
            status: Status(0x0001),
            point: None,
            probe: 0,
        })));
        s
    };
    let decode = |name: &str, bytes: Vec<u8>, extra: &[&str]| {
        std::fs::write(d.join(name), bytes).unwrap();
        let mut args = vec!["decode", name, "--calib", "cal.toml"];
        args.extend_from_slice(extra);
        armcal(&args, &d)
    };
    let o = decode("good.bin", stream(6, crc), &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let seven = refused(
        &decode("seven.bin", stream(7, crc), &[]),
        &[
            "seven.bin",
            "a table of 7 joints",
            "cal.toml is of an arm of 6 joints",
            "another arm's table",
            "--accept-misfit",
        ],
    );
    let other = refused(
        &decode("other.bin", stream(6, crc ^ 1), &[]),
        &[
            "other.bin",
            &format!("CRC {:08x}", crc ^ 1),
            &format!("{crc:08x}"),
            "another calibration",
        ],
    );
    eprintln!("{seven}{other}");
    let o = decode("other2.bin", stream(6, crc ^ 1), &["--accept-misfit"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// Another arm's calibration of another joint count with the data (`check`, `eval`): the
/// message names the calibration's arm and asks whether it is the data's.
#[test]
fn another_arms_calibration_is_named_as_such() {
    let (d, _) = with_iso_set("otherarm");
    copy_data(&d, "mukca/mukca-panda-panda_2.toml", "panda.toml");
    let why = [
        "the arm has 7 joints, the data has 6 joint columns",
        "the calibration's arm is `franka-panda` (serial panda_2, 7 joints)",
        "is it the arm these data were measured with?",
    ];
    let mut needles = vec!["t.csv: line 3, column j7"];
    needles.extend(why);
    refused_with(
        &armcal(&["check", "t.csv", "--calib", "panda.toml"], &d),
        3,
        &needles,
    );
    write_reading(&d);
    let mut needles = vec!["r.csv: line 1, column j7", "panda.toml"];
    needles.extend(why);
    refused(
        &armcal(&["eval", "--calib", "panda.toml", "r.csv"], &d),
        &needles,
    );
}

/// After several files are merged, a group's fault names its own file and line, not
/// `a.csv + b.csv`.
#[test]
fn merged_files_name_the_file_and_line_of_the_row_at_fault() {
    let d = workdir("merged");
    copy_data(&d, "default-6-full.toml", "cal.toml");
    iso_set(&d, "cal.toml", "a.csv");
    // b.csv: a sphere group of ten points of a.csv's (hence `--accept-duplicates`), too few
    // for P_Size and P_Form, after a comment.
    let text = std::fs::read_to_string(d.join("a.csv")).unwrap();
    let header = text.lines().find(|l| l.starts_with("kind")).unwrap();
    let sphere: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("sphere,"))
        .take(10)
        .collect();
    std::fs::write(
        d.join("b.csv"),
        format!("# ten points only\n{header}\n{}\n", sphere.join("\n")),
    )
    .unwrap();
    let e = refused_with(
        &armcal(
            &[
                "check",
                "a.csv",
                "b.csv",
                "--calib",
                "cal.toml",
                "--accept-duplicates",
            ],
            &d,
        ),
        3,
        &["b.csv, line 3: sphere group", "10 points"],
    );
    assert!(!e.contains("a.csv + b.csv"), "{e}");
}

// More mistakes a new user makes, each refused with its place or read right.

/// 1. An empty group cell.
#[test]
fn an_empty_group_cell_is_refused_with_its_line() {
    let (d, text) = with_iso_set("more-group");
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let k = lines.iter().position(|l| l.starts_with("sphere,")).unwrap();
    lines[k] = lines[k].replacen("sphere,1,", "sphere,,", 1);
    std::fs::write(d.join("g.csv"), lines.join("\n") + "\n").unwrap();
    refused_with(
        &check(&d, "g.csv"),
        3,
        &[
            &format!("g.csv: line {}, column group: empty", k + 1),
            "whole number",
        ],
    );
}

/// 2. A header and no rows (an export that kept only the header).
#[test]
fn a_header_without_rows_is_refused() {
    let (d, text) = with_iso_set("more-header");
    let head: String = text
        .lines()
        .filter(|l| l.starts_with('#') || l.starts_with("kind"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(d.join("h.csv"), head).unwrap();
    refused_with(
        &check(&d, "h.csv"),
        3,
        &["h.csv: line 3, column (file): no data rows"],
    );
}

/// 3. Tab-separated (a spreadsheet's "text" export): read the same as the commas.
#[test]
fn tab_separated_data_read_as_the_commas() {
    let (d, text) = with_iso_set("more-tab");
    std::fs::write(d.join("tab.csv"), text.replace(',', "\t")).unwrap();
    let a = armcal_ok(&["check", "t.csv", "--calib", "cal.toml", "--json"], &d);
    let b = armcal_ok(&["check", "tab.csv", "--calib", "cal.toml", "--json"], &d);
    let strip =
        |o: &std::process::Output| String::from_utf8_lossy(&o.stdout).replace("tab.csv", "t.csv");
    let (ja, jb): (serde_json::Value, serde_json::Value) = (
        serde_json::from_str(&strip(&a)).unwrap(),
        serde_json::from_str(&strip(&b)).unwrap(),
    );
    assert_eq!(ja["tests"], jb["tests"]);
}

/// 4. Encoder counts in the radian columns j1..jN.
#[test]
fn counts_in_the_radian_columns_are_named() {
    let (d, text) = with_iso_set("more-counts");
    let counts: String = text
        .lines()
        .map(|l| {
            if l.starts_with('#') || l.starts_with("kind") {
                return format!("{l}\n");
            }
            let mut c: Vec<String> = l.split(',').map(str::to_string).collect();
            for cell in &mut c[2..8] {
                let rad: f64 = cell.parse().unwrap();
                *cell = format!("{}", (rad / std::f64::consts::TAU * 1048576.0).round());
            }
            c.join(",") + "\n"
        })
        .collect();
    std::fs::write(d.join("c.csv"), counts).unwrap();
    refused_with(
        &check(&d, "c.csv"),
        3,
        &[
            "c.csv: line 4, column j1",
            "encoder counts? name the columns c1..cN",
        ],
    );
}

/// 5. A calibration of a later software version (an unknown section and key): read, with
///    each unknown key named on stderr, and the same values.
#[test]
fn a_newer_calibration_is_read_with_its_unknown_keys_named() {
    let d = workdir("more-newer");
    copy_data(&d, "default-6-full.toml", "cal.toml");
    let cal = std::fs::read_to_string(d.join("cal.toml")).unwrap();
    std::fs::write(
        d.join("newer.toml"),
        format!("format_version = 9\n{cal}\n[compensation]\nmode = \"volumetric\"\n"),
    )
    .unwrap();
    write_reading(&d);
    let old = armcal_ok(&["eval", "--calib", "cal.toml", "r.csv"], &d);
    let new = armcal_ok(&["eval", "--calib", "newer.toml", "r.csv"], &d);
    assert_eq!(old.stdout, new.stdout);
    let e = stderr(&new);
    assert!(
        e.contains("newer.toml: unknown key format_version ignored")
            && e.contains("unknown key compensation ignored"),
        "{e}"
    );
}

/// 6. The test sphere's diameter in metres in a sphere group.
#[test]
fn a_sphere_diameter_in_metres_is_refused() {
    let (d, text) = with_iso_set("more-metres");
    let metres: String = text
        .lines()
        .map(|l| {
            if l.starts_with("sphere,") {
                let mut c: Vec<&str> = l.split(',').collect();
                c[10] = "0.025";
                c.join(",") + "\n"
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    std::fs::write(d.join("m.csv"), metres).unwrap();
    refused_with(
        &check(&d, "m.csv"),
        3,
        &[
            "m.csv",
            "sphere group 1",
            "diameter_mm = 0.025",
            "--accept-units",
        ],
    );
}
