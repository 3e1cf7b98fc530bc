//! Running a board's firmware under QEMU: a recording in on the UART, the stream out, the
//! defmt log out of semihosting into a file of its own, the exit code back.

use std::io::{Read, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
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
    /// More QEMU arguments, after the machine's (the Pico's profile on `microbit` gives the
    /// nRF51 more RAM: `-global nrf51-soc.sram-size=N`).
    pub extra_args: Vec<String>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            table: None,
            icount: true,
            timeout: Duration::from_secs(300),
            extra_args: Vec::new(),
        }
    }
}

/// Where QEMU connects a board's UART.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Uart<'a> {
    /// A Unix socket at this path, QEMU the server, waiting for the connection before the
    /// machine starts.
    Socket(&'a Path),
    /// A pseudo-terminal of its own (`-serial pty`), whose path QEMU prints at start.
    Pty,
}

/// The QEMU command line of `board` (without `-kernel`): its UART on `uart`, semihosting (the
/// defmt log) on QEMU's stdout, `table` loaded into the calibration region, the monitor on a
/// Unix socket at `monitor` if given (for resets), else none.
pub(crate) fn command(
    board: &Board,
    table: &Option<PathBuf>,
    icount: bool,
    uart: Uart<'_>,
    monitor: Option<&Path>,
) -> Result<Command> {
    let Some(m) = board.qemu else {
        bail!("{} does not run under QEMU", board.name);
    };
    // QEMU 7.2 sends a semihosting `:tt` handle to stdout whatever `-semihosting-config
    // chardev=` says, so the log goes there.
    let mut cmd = Command::new("qemu-system-arm");
    cmd.args(["-M", m.machine, "-display", "none"]);
    match monitor {
        Some(p) => cmd
            .arg("-monitor")
            .arg(format!("unix:{},server=on,wait=off", p.display())),
        None => cmd.args(["-monitor", "none"]),
    };
    match uart {
        Uart::Socket(sock) => cmd
            .arg("-chardev")
            .arg(format!(
                "socket,id=uart,path={},server=on,wait=on",
                sock.display()
            ))
            .args(["-serial", "chardev:uart"]),
        Uart::Pty => cmd.args(["-serial", "pty"]),
    };
    cmd.args(["-semihosting-config", "enable=on,target=native"]);
    if icount {
        cmd.args(["-icount", "shift=0"]);
    }
    if let Some(table) = table {
        cmd.arg("-device").arg(format!(
            "loader,file={},addr={:#x},force-raw=on",
            table.display(),
            m.table_addr
        ));
    }
    cmd.stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    Ok(cmd)
}

/// Checks that `elf` is built and writes `image` (bytes as given) into `dir` for QEMU's
/// loader; its path.
pub(crate) fn image_file(
    board: &Board,
    elf: &Path,
    image: Option<&[u8]>,
    dir: &Path,
) -> Result<Option<PathBuf>> {
    if !elf.exists() {
        bail!("{} is not built: run `cargo xtask build`", board.name);
    }
    image
        .map(|t| {
            let p = dir.join("table.bin");
            std::fs::write(&p, t)?;
            Ok(p)
        })
        .transpose()
}

/// Waits up to `limit` for `child` to exit, polling every 5 ms; its status, or `None` when it
/// was still running at the limit, after killing and reaping it.
pub fn wait_until(child: &mut Child, limit: Duration) -> Result<Option<ExitStatus>> {
    let start = Instant::now();
    loop {
        if let Some(s) = child.try_wait()? {
            return Ok(Some(s));
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            return Ok(None);
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Waits for QEMU to exit after the hub was sent `End`; kills it after
/// [`crate::session::ANSWER_TIMEOUT`].
pub(crate) fn wait_exit(child: &mut Child) -> Result<ExitStatus> {
    match wait_until(child, crate::session::ANSWER_TIMEOUT)? {
        Some(s) => Ok(s),
        None => bail!("QEMU did not exit after End"),
    }
}

/// Connects to QEMU's UART socket at `sock` once QEMU has opened it.
pub(crate) fn connect(child: &mut Child, sock: &Path) -> Result<UnixStream> {
    let start = Instant::now();
    loop {
        match UnixStream::connect(sock) {
            Ok(s) => return Ok(s),
            Err(_) if start.elapsed() < Duration::from_secs(20) => {
                if let Some(status) = child.try_wait()? {
                    bail!("qemu exited before opening its socket ({status})");
                }
                std::thread::sleep(Duration::from_millis(10));
            }
            Err(e) => {
                let _ = child.kill();
                return Err(e).context("connecting to QEMU's socket");
            }
        }
    }
}

/// Runs `elf` on `board`'s QEMU machine, sending `input` to its UART.
pub fn run(board: &Board, elf: &Path, input: &[u8], opts: &Options) -> Result<Run> {
    if !elf.exists() {
        bail!(
            "{} is not built: run `cargo xtask build` (looked for {})",
            board.name,
            elf.display()
        );
    }
    let dir = tempfile::tempdir()?;
    let sock = dir.path().join("uart.sock");
    let mut cmd = command(board, &opts.table, opts.icount, Uart::Socket(&sock), None)?;
    cmd.args(&opts.extra_args).arg("-kernel").arg(elf);
    let start = Instant::now();
    let mut child = cmd.spawn().context("starting qemu-system-arm")?;
    let mut stdout = child.stdout.take().context("qemu stdout")?;
    let mut stderr = child.stderr.take().context("qemu stderr")?;
    let log_reader = std::thread::spawn(move || {
        let mut out = Vec::new();
        let _ = stdout.read_to_end(&mut out);
        out
    });
    let err_reader = std::thread::spawn(move || {
        let mut out = String::new();
        let _ = stderr.read_to_string(&mut out);
        out
    });
    let uart = connect(&mut child, &sock)?;
    let mut uart_in = uart.try_clone()?;
    let mut uart_out = uart;
    let input = input.to_vec();
    // QEMU takes input as fast as the UART model drains it; a thread keeps the socket full.
    let writer = std::thread::spawn(move || {
        let _ = uart_in.write_all(&input);
    });
    let reader = std::thread::spawn(move || {
        let mut out = Vec::new();
        let _ = uart_out.read_to_end(&mut out);
        out
    });
    // The limit counts from the start, before QEMU opened its socket.
    let Some(status) = wait_until(&mut child, opts.timeout.saturating_sub(start.elapsed()))? else {
        bail!(
            "{} timed out after {:?} under QEMU",
            board.name,
            opts.timeout
        );
    };
    let elapsed = start.elapsed();
    let stream = reader.join().unwrap_or_default();
    let _ = writer.join();
    let log = log_reader.join().unwrap_or_default();
    let qemu_err = err_reader.join().unwrap_or_default();
    if !qemu_err.trim().is_empty() && !status.success() {
        eprintln!("qemu: {}", qemu_err.trim());
    }
    Ok(Run {
        stream,
        log,
        status,
        elapsed,
    })
}
