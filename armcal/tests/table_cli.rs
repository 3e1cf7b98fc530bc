//! `armcal table build` and `table show` on real calibrations: every MUKCa arm becomes a table
//! the firmware's parser accepts and reads back as built, serial included. (Table format
//! version 1 held a 16-byte serial and refused `panda_1_with_sensor`'s 19 bytes.)

#[allow(dead_code)] // `write_truth` is for the simulating suites
mod common;

use common::{armcal, armcal_ok, workdir};

#[test]
fn panda_1_with_sensor_builds_and_reads_back() {
    let d = workdir("panda1sensor");
    let calib = armcal::mukca::default_dir().join("mukca-panda-panda_1_with_sensor.toml");
    let calib = calib.to_str().unwrap();
    armcal_ok(&["table", "build", calib, "-o", "t.bin"], &d);
    let bytes = std::fs::read(d.join("t.bin")).unwrap();
    let t = quatarm::Table::parse(&bytes).unwrap();
    assert_eq!(t.serial(), b"panda_1_with_sensor");
    assert_eq!(bytes.len(), quatarm::table::table_len(t.joint_count()));
    // What was built is what the calibration says, bit for bit (the builder is the one the
    // accuracy measurements use).
    let arm = quatarm_ref::calfile::read(std::path::Path::new(calib))
        .unwrap()
        .arm;
    assert_eq!(t.joint_count(), arm.dof());
    assert_eq!(bytes, armcal::tablebuild::build(&arm).unwrap());
    let out = armcal_ok(&["table", "show", "t.bin"], &d);
    let shown = String::from_utf8_lossy(&out.stdout);
    assert!(
        shown.contains(&format!(
            "quatarm calibration table v{}",
            quatarm::table::VERSION
        )) && shown.contains("serial: panda_1_with_sensor\n"),
        "{shown}"
    );
}

/// The table's serial limit is named, with the serial's length, when a calibration exceeds it.
#[test]
fn a_serial_beyond_the_table_is_refused_by_length() {
    let d = workdir("longserial");
    let base = quatarm_ref::calfile::write(&quatarm_ref::Arm::default6(), &[]);
    let serial = "s".repeat(quatarm::table::SERIAL_LEN + 1);
    std::fs::write(
        d.join("long.toml"),
        format!("serial = \"{serial}\"\n{base}"),
    )
    .unwrap();
    let o = armcal(&["table", "build", "long.toml", "-o", "t.bin"], &d);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("serial: 33 bytes; the table holds at most 32"),
        "{err}"
    );
    assert!(!d.join("t.bin").exists());
    // 32 bytes fit.
    let serial = "s".repeat(quatarm::table::SERIAL_LEN);
    std::fs::write(
        d.join("fits.toml"),
        format!("serial = \"{serial}\"\n{base}"),
    )
    .unwrap();
    armcal_ok(&["table", "build", "fits.toml", "-o", "t.bin"], &d);
}

/// Every MUKCa calibration in `data/mukca` becomes a valid table.
#[test]
fn every_mukca_calibration_builds_a_table() {
    let dir = armcal::mukca::default_dir();
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            let arm = quatarm_ref::calfile::read(&p).unwrap().arm;
            let bytes =
                armcal::tablebuild::build(&arm).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            let t = quatarm::Table::parse(&bytes).unwrap();
            assert_eq!(
                t.serial(),
                arm.serial.as_deref().unwrap_or("").as_bytes(),
                "{}",
                p.display()
            );
            n += 1;
        }
    }
    assert!(n >= 18, "{n} calibrations");
}

/// `keygen`, `sign`, `verify`: a signed table verifies under its key only, a changed byte is
/// refused, a key is never overwritten, and every refusal names its file.
#[test]
fn a_signed_table_verifies_under_its_own_key_only() {
    let d = workdir("signing");
    let calib = armcal::mukca::default_dir().join("mukca-panda-panda_3-repo-calibrated.toml");
    armcal_ok(
        &["table", "build", calib.to_str().unwrap(), "-o", "t.bin"],
        &d,
    );
    armcal_ok(&["table", "keygen", "--out", "maker"], &d);
    armcal_ok(&["table", "keygen", "--out", "other"], &d);
    let again = armcal(&["table", "keygen", "--out", "maker"], &d);
    assert!(!again.status.success());
    assert!(String::from_utf8_lossy(&again.stderr).contains("maker.pem: exists"));
    armcal_ok(
        &[
            "table",
            "sign",
            "t.bin",
            "--key",
            "maker.pem",
            "-o",
            "s.bin",
        ],
        &d,
    );
    let (table, image) = (
        std::fs::read(d.join("t.bin")).unwrap(),
        std::fs::read(d.join("s.bin")).unwrap(),
    );
    assert_eq!(&image[..table.len()], &table[..]);
    assert_eq!(image.len(), table.len() + quatarm::signature::SIGNATURE_LEN);
    armcal_ok(&["table", "verify", "s.bin", "--key", "maker.pub"], &d);
    for (file, key, why) in [
        ("s.bin", "other.pub", "does not verify"),
        ("t.bin", "maker.pub", "bytes after the table"),
    ] {
        let out = armcal(&["table", "verify", file, "--key", key], &d);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(file) && err.contains(why),
            "{err}"
        );
    }
    let mut changed = image.clone();
    changed[200] ^= 1;
    std::fs::write(d.join("c.bin"), &changed).unwrap();
    let out = armcal(&["table", "verify", "c.bin", "--key", "maker.pub"], &d);
    assert!(!out.status.success());
    // A private key file that is not one is named.
    let out = armcal(
        &[
            "table",
            "sign",
            "t.bin",
            "--key",
            "maker.pub",
            "-o",
            "x.bin",
        ],
        &d,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("maker.pub"), "{err}");
    assert!(!d.join("x.bin").exists(), "no partial output");
}

/// The shipped budget goes into the table whole (its 52 parameters' covariance after the
/// reading's own terms), and `--without-covariance` leaves the parameters out for the
/// fixed-point hubs; `table show` says which.
#[test]
fn the_budget_goes_into_the_table_with_or_without_its_covariance() {
    let d = workdir("budgettable");
    let calib =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/default-6-full.toml");
    let calib = calib.to_str().unwrap();
    armcal_ok(&["table", "build", calib, "-o", "full.bin"], &d);
    armcal_ok(
        &[
            "table",
            "build",
            calib,
            "-o",
            "own.bin",
            "--without-covariance",
        ],
        &d,
    );
    let full = std::fs::read(d.join("full.bin")).unwrap();
    let own = std::fs::read(d.join("own.bin")).unwrap();
    let (tf, to) = (
        quatarm::Table::parse(&full).unwrap(),
        quatarm::Table::parse(&own).unwrap(),
    );
    assert_eq!(tf.parameters().map(|p| p.count()), Some(52));
    assert!(to.parameters().is_none() && to.budget().is_some());
    assert_eq!(
        full.len(),
        own.len() + quatarm::table::parameters::len(52),
        "the block after the budget"
    );
    let shown =
        String::from_utf8_lossy(&armcal_ok(&["table", "show", "full.bin"], &d).stdout).to_string();
    assert!(
        shown.contains("parameter covariance: 52 parameters"),
        "{shown}"
    );
    let shown =
        String::from_utf8_lossy(&armcal_ok(&["table", "show", "own.bin"], &d).stdout).to_string();
    assert!(shown.contains("parameter covariance: none"), "{shown}");
}

/// A calibration with three probes: `table show` lists each, its id, vector, direction,
/// thermal expansion and ball diameter, the first as the one mounted at boot.
#[test]
fn table_show_lists_every_probe() {
    let d = workdir("probes");
    let calib =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/default-6-probes.toml");
    armcal_ok(
        &["table", "build", calib.to_str().unwrap(), "-o", "p.bin"],
        &d,
    );
    let shown =
        String::from_utf8_lossy(&armcal_ok(&["table", "show", "p.bin"], &d).stdout).to_string();
    let lines: Vec<&str> = shown.lines().filter(|l| l.starts_with("probe ")).collect();
    assert_eq!(lines.len(), 3, "{shown}");
    assert!(
        lines[0].starts_with(
            "probe 1 (mounted at boot): vector (mm) = [-0.237145, 0.253024, 120.022125]"
        ),
        "{shown}"
    );
    assert!(
        lines[1].starts_with("probe 2: vector (mm) = [0.051200, -0.118400, 180.312100]"),
        "{shown}"
    );
    assert!(
        lines[2].starts_with(
            "probe 5: vector (mm) = [50.101300, 0.020700, 99.953200], direction = [0.448105617940,"
        ),
        "{shown}"
    );
    assert!(
        lines[2].ends_with("thermal = 2.3e-5 /degC, ball diameter = 2 mm"),
        "{shown}"
    );
}

/// `[calibration]`'s number and date go into the table, and `table build` and `table show`
/// print them; a bad date is refused with its key and no table is written.
#[test]
fn the_calibration_number_and_date_are_built_and_shown() {
    let d = workdir("release");
    let base = quatarm_ref::calfile::write(&quatarm_ref::Arm::default6(), &[]);
    std::fs::write(
        d.join("numbered.toml"),
        format!("{base}\n[calibration]\nnumber = 12\ndate = 2026-12-04\ndue = 2027-12-04\n"),
    )
    .unwrap();
    let out = armcal_ok(&["table", "build", "numbered.toml", "-o", "t.bin"], &d);
    let built = String::from_utf8_lossy(&out.stdout);
    assert!(
        built.contains("calibration number 12, dated 2026-12-04"),
        "{built}"
    );
    let t = std::fs::read(d.join("t.bin")).unwrap();
    let r = quatarm::Table::parse(&t).unwrap().release();
    assert_eq!((r.number, r.date), (12, 20261204));
    let out = armcal_ok(&["table", "show", "t.bin"], &d);
    let shown = String::from_utf8_lossy(&out.stdout);
    assert!(
        shown.contains("quatarm calibration table v4")
            && shown.contains("calibration number 12, dated 2026-12-04\n"),
        "{shown}"
    );
    std::fs::write(
        d.join("bad.toml"),
        format!("{base}\n[calibration]\nnumber = 12\ndate = \"04.12.2026\"\n"),
    )
    .unwrap();
    let o = armcal(&["table", "build", "bad.toml", "-o", "bad.bin"], &d);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("bad.toml: calibration.date"), "{err}");
    assert!(!d.join("bad.bin").exists());
}
