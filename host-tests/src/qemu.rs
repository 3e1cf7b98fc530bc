//! Running a board's firmware under QEMU: a recording in on the UART, the stream out, the
//! defmt log out of semihosting into a file of its own, the exit code back.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};

use crate::boards::Board;

/// What one run gave.
#[derive(Debug)]
pub struct Run {
    /// Bytes the firmware wrote to its UART.
    pub stream: Vec<u8>,
    /// Bytes written through semihosting (the defmt log of the QEMU boards).
    pub log: Vec<u8>,
    /// QEMU's exit status (semihosting exit code of the firmware).
    pub status: ExitStatus,
    /// Wall-clock time of the run.
    pub elapsed: Duration,
}

/// How to run.
#[derive(Debug, Clone)]
pub struct Options {
    /// Calibration table to load into the board's table region (none: the region stays 0).
    pub table: Option<PathBuf>,
    /// `-icount shift=0`: one instruction per nanosecond of virtual time (for counting).
    pub icount: bool,
    /// Kill QEMU after this long.
    pub timeout: Duration,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            table: None,
            icount: true,
            timeout: Duration::from_secs(300),
        }
    }
}

/// Runs `elf` on `board`'s QEMU machine, sending `input` to its UART.
pub fn run(board: &Board, elf: &Path, input: &[u8], opts: &Options) -> Result<Run> {
    let Some(m) = board.qemu else {
        bail!("{} does not run under QEMU", board.name);
    };
    if !elf.exists() {
        bail!(
            "{} is not built: run `cargo xtask build` (looked for {})",
            board.name,
            elf.display()
        );
    }
    let dir = tempfile::tempdir()?;
    let log_path = dir.path().join("semihosting.bin");
    let mut cmd = Command::new("qemu-system-arm");
    cmd.args(["-M", m.machine, "-display", "none", "-monitor", "none"])
        .args(["-serial", "stdio"])
        .arg("-chardev")
        .arg(format!("file,id=semihosting,path={}", log_path.display()))
        .args([
            "-semihosting-config",
            "enable=on,target=native,chardev=semihosting",
        ]);
    if opts.icount {
        cmd.args(["-icount", "shift=0"]);
    }
    if let Some(table) = &opts.table {
        cmd.arg("-device").arg(format!(
            "loader,file={},addr={:#x},force-raw=on",
            table.display(),
            m.table_addr
        ));
    }
    cmd.arg("-kernel")
        .arg(elf)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let start = Instant::now();
    let mut child = cmd.spawn().context("starting qemu-system-arm")?;
    let mut stdin = child.stdin.take().context("qemu stdin")?;
    let mut stdout = child.stdout.take().context("qemu stdout")?;
    let mut stderr = child.stderr.take().context("qemu stderr")?;
    let input = input.to_vec();
    // QEMU takes input as fast as the UART model drains it; a thread keeps the pipe full.
    let writer = std::thread::spawn(move || {
        let _ = stdin.write_all(&input);
    });
    let reader = std::thread::spawn(move || {
        let mut out = Vec::new();
        let _ = stdout.read_to_end(&mut out);
        out
    });
    let err_reader = std::thread::spawn(move || {
        let mut out = String::new();
        let _ = stderr.read_to_string(&mut out);
        out
    });
    let status = loop {
        if let Some(s) = child.try_wait()? {
            break s;
        }
        if start.elapsed() > opts.timeout {
            let _ = child.kill();
            let _ = child.wait();
            bail!(
                "{} timed out after {:?} under QEMU",
                board.name,
                opts.timeout
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let elapsed = start.elapsed();
    let _ = writer.join();
    let stream = reader.join().unwrap_or_default();
    let qemu_err = err_reader.join().unwrap_or_default();
    if !qemu_err.trim().is_empty() && !status.success() {
        eprintln!("qemu: {}", qemu_err.trim());
    }
    let log = std::fs::read(&log_path).unwrap_or_default();
    Ok(Run {
        stream,
        log,
        status,
        elapsed,
    })
}
