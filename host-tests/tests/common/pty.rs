//! `armcal table send` as a metrologist runs it: the `armcal` binary on the hub's UART, which
//! QEMU offers as a pseudo-terminal (`-serial pty`) as a USB serial adapter offers a
//! `/dev/ttyUSB0` (`host_tests::pty`).

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

use host_tests::e2e::{calibration, default_calibration_path, host_points, signed};
use host_tests::pty::PtyHub;
use host_tests::qemu::wait_until;
use quatarm::stream::{Coordinates, Reading, Status, ToDevice, ToHost};
use quatarm::update::session::Step;
use quatarm::update::Accepted;
use quatarm_wire::stream_decode::Item;

use super::{
    armcal_exe, budget_table, expect_hello, some_readings, table_crc, the_board, update_tables,
    UpdateTables,
};

/// What an `armcal` run gave.
struct Run {
    status: ExitStatus,
    stdout: String,
    stderr: String,
    took: Duration,
}

/// Starts `armcal ARGS` with its output captured.
fn spawn_armcal(args: &[&str]) -> std::process::Child {
    Command::new(armcal_exe())
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Waits for `child` to end within `limit` (a hang fails the test, after killing it).
fn wait_armcal(mut child: std::process::Child, limit: Duration, start: Instant) -> Run {
    let mut out = child.stdout.take().unwrap();
    let mut err = child.stderr.take().unwrap();
    let out = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = out.read_to_string(&mut s);
        s
    });
    let err = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        s
    });
    // `limit` counts from `start`, which may be before the spawn.
    let Some(status) = wait_until(&mut child, limit.saturating_sub(start.elapsed())).unwrap()
    else {
        panic!(
            "armcal still running after {limit:?}: it hangs (stderr so far: {})",
            err.join().unwrap_or_default()
        );
    };
    Run {
        status,
        stdout: out.join().unwrap(),
        stderr: err.join().unwrap(),
        took: start.elapsed(),
    }
}

/// `armcal table send FILE --port PTY --timeout SECONDS`, which must end within `limit`.
fn table_send(file: &Path, pty: &Path, timeout_s: f64, limit: Duration) -> Run {
    let timeout = timeout_s.to_string();
    let args = [
        "table",
        "send",
        file.to_str().unwrap(),
        "--port",
        pty.to_str().unwrap(),
        "--timeout",
        &timeout,
    ];
    wait_armcal(spawn_armcal(&args), limit, Instant::now())
}

/// The run failed, and its message says each of `words`.
fn assert_refused(run: &Run, words: &[&str]) {
    assert!(!run.status.success(), "armcal succeeded: {}", run.stdout);
    for w in words {
        assert!(run.stderr.contains(w), "no {w:?} in: {}", run.stderr);
    }
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// One reading's coordinates as the hub gives them now, through a port of the test's own.
/// What the hub answers to input an earlier session left before it is passed over: after a
/// reset in the middle of a step the hub refuses the rest of that step's frame (a report of
/// damaged input); a step sent to a paused hub is answered once it runs (an update answer).
/// The hub takes its input in order, so once the reading's report is in, nothing of those
/// is still to come.
fn point_now(hub: &PtyHub, r: &Reading) -> Coordinates {
    let mut port = hub.open().unwrap();
    port.send(&ToDevice::Reading(*r)).unwrap();
    loop {
        match port.next_item().unwrap() {
            Item::Report(rep) if rep.status.has(Status::INPUT_ERROR) => continue,
            Item::Update(_) => continue,
            Item::Report(rep) => return rep.point.unwrap_or_else(|| panic!("no point: {rep:?}")),
            other => panic!("expected a report, got {other:?}"),
        }
    }
}

/// `c` as `armcal decode` writes it: x, y, z (mm) and the direction.
fn csv_point(c: &Coordinates) -> Vec<String> {
    let xyz = c
        .xyz_nm
        .iter()
        .map(|&v| format!("{:.6}", f64::from(v) / 1e6));
    let dir = c
        .dir_e9
        .iter()
        .map(|&v| format!("{:.9}", f64::from(v) / 1e9));
    xyz.chain(dir).collect()
}

/// Bytes `pid` has written so far (`/proc/PID/io`, `wchar`).
fn written(pid: u32) -> Option<u64> {
    let io = std::fs::read_to_string(format!("/proc/{pid}/io")).ok()?;
    io.lines()
        .find_map(|l| l.strip_prefix("wchar: "))
        .and_then(|v| v.trim().parse().ok())
}

/// On qemu-m4f through a pty, the `armcal` binary as a user runs it:
/// - an unsigned table and one whose signature has a changed byte are refused at commit
///   (`Table(Unsigned)`, `Table(BadSignature)`): armcal exits 1 naming the step and the
///   reason; a table with a changed byte is refused by armcal before a byte goes out; the
///   factory table stays live (its points);
/// - a signed table goes live although an earlier session left an answer unread in the pty:
///   armcal exits 0 printing the slot and record, having checked the hub's `Hello`; then
///   `armcal decode --port` prints the new table's points;
/// - a reset in the middle of an update (after armcal wrote a tenth of the chunks): armcal
///   exits 1 at once, saying the hub restarted and which table it came back on;
/// - a paused hub: armcal exits 1 after its `--timeout`, saying no answer came;
/// - after a reset the hub boots on the table sent.
#[allow(dead_code)] // each board's test binary uses one of the two cases
pub fn table_send_over_a_pty(name: &str) {
    let start = Instant::now();
    let b = the_board(name);
    let UpdateTables {
        new_table,
        old,
        new,
        factory,
        updated,
        ..
    } = update_tables();
    // The largest table (180 steps): time to reset the hub in the middle of its update.
    let big = signed(&budget_table(usize::MAX)).unwrap();
    let crc = table_crc;
    let readings = some_readings(3);
    let host_old = host_points(b.precision, &old, &readings[..1]).unwrap()[0].unwrap();
    let host_new = host_points(b.precision, &new, &readings).unwrap();
    assert_ne!(host_old, host_new[0].unwrap());

    let dir = tempfile::tempdir().unwrap();
    let new_file = write(dir.path(), "new.bin", &new);
    let unsigned_file = write(dir.path(), "unsigned.bin", &new_table);
    let mut bad_signature = new.clone();
    *bad_signature.last_mut().unwrap() ^= 0x01;
    let bad_signature_file = write(dir.path(), "bad-signature.bin", &bad_signature);
    let mut changed = new.clone();
    changed[40] ^= 0x01;
    let changed_file = write(dir.path(), "changed.bin", &changed);
    let big_file = write(dir.path(), "big.bin", &big);

    let log = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}-pty-defmt.bin"));
    let mut hub = PtyHub::start(&b, &b.elf(b.name), Some(&old), &log).unwrap();
    let pty = hub.path().to_path_buf();
    eprintln!(
        "{name}: UART on {}, defmt log in {}",
        pty.display(),
        log.display()
    );
    {
        // Open before the machine runs: the boot's Hello is not lost.
        let mut port = hub.open_held().unwrap();
        hub.run().unwrap();
        expect_hello(port.next_item().unwrap(), factory, "boot");
    }
    assert_eq!(point_now(&hub, &readings[0]), host_old);

    // Refused by the hub at commit, or by armcal before sending; the factory table stays.
    for (file, image, reason) in [
        (&unsigned_file, &new_table, "Table(Unsigned)"),
        (&bad_signature_file, &bad_signature, "Table(BadSignature)"),
    ] {
        let steps = Step::sequence(image).count();
        let at_commit = format!("refused step {steps} of {steps} (Commit)");
        let run = table_send(file, &pty, 5.0, Duration::from_secs(60));
        assert_refused(&run, &[&at_commit, reason, "old table stays live"]);
        eprintln!("{name}: {} -> {}", file.display(), run.stderr.trim());
    }
    let run = table_send(&changed_file, &pty, 5.0, Duration::from_secs(60));
    assert_refused(&run, &["not a valid table"]);
    assert_eq!(point_now(&hub, &readings[0]), host_old, "after refusals");

    // An earlier session's answer left unread in the pty (a Begin it sent, then gave up):
    // the whole of it, its delimiter before it included, before that session closes.
    {
        let mut port = hub.open().unwrap();
        port.send(&ToDevice::Update(Step::sequence(&old).next().unwrap()))
            .unwrap();
        let mut frame = [0u8; quatarm::stream::MAX_FRAME];
        let answer = ToHost::Update(Ok(Accepted::Begun { slot: 1 }));
        let len = 1 + quatarm::stream::encode(&answer, &mut frame).unwrap();
        port.wait_unread(len, Duration::from_secs(30)).unwrap();
    }
    let run = table_send(&new_file, &pty, 5.0, Duration::from_secs(60));
    assert!(run.status.success(), "{}", run.stderr);
    let steps = Step::sequence(&new).count();
    let said = format!(
        "live on the hub in slot 1, record 1, CRC {:08x} ({steps} steps",
        crc(&new)
    );
    assert!(run.stdout.contains(&said), "{}", run.stdout);
    eprintln!("{name}: {} ({:?})", run.stdout.trim(), run.took);

    // The new table's points, as `armcal decode --port` prints them while the test sends
    // readings beside it (the hub under QEMU reports only what it is sent).
    {
        let mut port = hub.open().unwrap();
        let decode_start = Instant::now();
        let decode = spawn_armcal(&[
            "decode",
            "--port",
            pty.to_str().unwrap(),
            "--max-reports",
            "3",
        ]);
        // Until decode has its three reports: answers sent before it opened the pty wait
        // there for it (the test's port reads nothing).
        let mut decode = decode;
        let mut sent = 0;
        while decode.try_wait().unwrap().is_none() && sent < 200 {
            port.send(&ToDevice::Reading(readings[sent % readings.len()]))
                .unwrap();
            sent += 1;
            std::thread::sleep(Duration::from_millis(50));
        }
        let run = wait_armcal(decode, Duration::from_secs(60), decode_start);
        assert!(run.status.success(), "{}", run.stderr);
        let lines: Vec<&str> = run.stdout.lines().collect();
        assert_eq!(lines.len(), 4, "{}", run.stdout);
        for line in &lines[1..] {
            let f: Vec<&str> = line.split(',').collect();
            let seq: usize = f[0].parse().unwrap();
            let expected = csv_point(&host_new[seq % readings.len()].unwrap());
            assert_eq!(f[3..9], expected[..], "{line}");
        }
        eprintln!("{name}: armcal decode --port: {}", lines[1..].join(" | "));
    }

    // A reset in the middle of an update: armcal says so at once, the table before stays.
    let send_start = Instant::now();
    let mut sending = spawn_armcal(&[
        "table",
        "send",
        big_file.to_str().unwrap(),
        "--port",
        pty.to_str().unwrap(),
    ]);
    let tenth = 48 * Step::sequence(&big).count() as u64 / 10;
    let mut wrote = 0;
    while sending.try_wait().unwrap().is_none() && wrote < tenth {
        wrote = written(sending.id()).unwrap_or(0);
        std::thread::sleep(Duration::from_micros(200));
    }
    let reset_after = sending.try_wait().unwrap().is_none().then_some(wrote);
    hub.reset().unwrap();
    let run = wait_armcal(sending, Duration::from_secs(60), send_start);
    assert!(
        reset_after.is_some(),
        "the update ended before the reset ({:?}): {}{}",
        run.took,
        run.stdout,
        run.stderr
    );
    let updated_crc = format!("slot 1, record 1, CRC {:#010x}", crc(&new));
    assert_refused(
        &run,
        &[
            "the hub restarted while waiting",
            &updated_crc,
            "send the table again",
        ],
    );
    assert!(
        run.took < Duration::from_secs(5),
        "{:?}: waited for the timeout",
        run.took
    );
    eprintln!(
        "{name}: reset after armcal wrote {reset_after:?} bytes: {}",
        run.stderr.trim()
    );
    assert_eq!(point_now(&hub, &readings[0]), host_new[0].unwrap());

    // A hub that does not answer at all (paused): an error after the timeout.
    hub.pause().unwrap();
    let run = table_send(&new_file, &pty, 1.0, Duration::from_secs(30));
    hub.run().unwrap();
    assert_refused(&run, &["no answer from the hub to step 1 of", "within 1s"]);
    assert!(run.took >= Duration::from_secs(1), "{:?}", run.took);
    eprintln!("{name}: paused hub: {} ({:?})", run.stderr.trim(), run.took);
    // Its Begin is answered now that the hub runs; the table is the same.
    assert_eq!(point_now(&hub, &readings[0]), host_new[0].unwrap());

    // The table sent is what the hub boots on.
    {
        let mut port = hub.open_held().unwrap();
        hub.reset().unwrap();
        expect_hello(port.next_item().unwrap(), updated, "reset after the update");
    }
    assert_eq!(point_now(&hub, &readings[0]), host_new[0].unwrap());
    let log_path = hub.log_path().to_path_buf();
    let status = hub.finish().unwrap();
    let log = std::fs::read(&log_path).unwrap();
    let lines = host_tests::defmt_log::decode(&b.elf(b.name), &log).unwrap();
    assert!(status.success(), "{status}: {}", lines.join("\n"));
    assert!(
        lines
            .iter()
            .any(|l| l.contains("update committed: slot 1, record 1")),
        "{}",
        lines.join("\n")
    );
    eprintln!(
        "{name}: table send over a pty: {:?} in all",
        start.elapsed()
    );
}

/// A hub without an update port (qemu-m0): `armcal table send` exits 1 on its first step,
/// naming `NotSupported`; the table stays.
#[allow(dead_code)] // each board's test binary uses one of the two cases
pub fn table_send_refused_over_a_pty(name: &str) {
    let b = the_board(name);
    let (_, table) = calibration(&default_calibration_path()).unwrap();
    let reading = some_readings(1)[0];
    let host = host_points(b.precision, &table, &[reading]).unwrap()[0].unwrap();
    let dir = tempfile::tempdir().unwrap();
    let file = write(dir.path(), "table.bin", &table);
    let log = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}-pty-defmt.bin"));
    let mut hub = PtyHub::start(&b, &b.elf(b.name), Some(&table), &log).unwrap();
    {
        let mut port = hub.open_held().unwrap();
        hub.run().unwrap();
        assert!(matches!(port.next_item().unwrap(), Item::Hello(_)));
    }
    let run = table_send(&file, hub.path(), 5.0, Duration::from_secs(60));
    let n = Step::sequence(&table).count();
    assert_refused(
        &run,
        &[&format!("refused step 1 of {n} (Begin"), "NotSupported"],
    );
    assert_eq!(point_now(&hub, &reading), host);
    let status = hub.finish().unwrap();
    assert!(status.success(), "{status}");
}
