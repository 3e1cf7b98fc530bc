//! A QEMU hub whose UART is a pseudo-terminal (`-serial pty`): a path under `/dev/pts/` that
//! programs open as they open a USB serial port, so that the `armcal` binary drives it as a
//! metrologist drives a hub (`armcal table send --port`, `armcal decode --port`).
//!
//! What a pty asks of the runner:
//! - QEMU prints `char device redirected to /dev/pts/N (label serial0)` with `qemu_printf`,
//!   on stdout (7.2 and 10.0), where the guest's semihosting output, the defmt log, follows
//!   it; older releases wrote it on stderr. Both are read; stdout goes to a log file from the
//!   line after the message on.
//! - QEMU drops what the guest sends while no process holds the pty open, and a pty keeps
//!   what was sent while one did but did not read, across a close and the next open. So the
//!   machine starts paused (`-S`) until the test has the pty open ([`PtyHub::run`]), and a
//!   [`Port`] discards what the pty held when it opens.
//! - The other way, QEMU stops reading the pty when its last holder closes it and looks again
//!   once a second: bytes written just before a close are never read, and the first bytes
//!   after an open wait up to a second (each `armcal` run's first answer does). A port stays
//!   open until what it sent is answered. Before QEMU 8.2 (commit 4f7689f0, "Avoid losing
//!   bytes when the other side just (re-)connected") QEMU also dropped what the guest sent
//!   until that poll saw the pty held: [`PtyHub::open_held`] waits it out where a `Hello`
//!   must not be lost.
//! - The terminal settings need nothing: QEMU makes the pty raw (no echo, no line editing,
//!   no CR/LF translation) when it creates it, and `serialport` sets raw mode again on open.

use std::fs::File;
use std::io::{BufRead, BufReader, Read, Write};
use std::os::fd::AsRawFd;
use std::os::unix::fs::OpenOptionsExt;
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, ExitStatus};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use quatarm::stream::ToDevice;
use quatarm_wire::stream_decode::Item;

use crate::boards::Board;
use crate::qemu::{command, connect, image_file, wait_exit, Uart};
use crate::recording::frame;
use crate::session::{Items, ANSWER_TIMEOUT};

/// The path in QEMU's message announcing a pty, if `line` is that message.
pub fn pty_path(line: &str) -> Option<PathBuf> {
    let rest = line.split("char device redirected to ").nth(1)?;
    let path = rest.split_whitespace().next()?;
    path.starts_with('/').then(|| PathBuf::from(path))
}

/// A running QEMU hub on a pty, paused until [`PtyHub::run`].
pub struct PtyHub {
    child: Child,
    path: PathBuf,
    monitor: UnixStream,
    log: Option<JoinHandle<Result<()>>>,
    log_path: PathBuf,
    /// What QEMU printed itself (stderr, and stdout before the guest's log).
    said: Arc<Mutex<String>>,
    _dir: tempfile::TempDir,
}

impl PtyHub {
    /// Starts `board`'s `elf` with `image` (bytes as given) in its calibration region, its
    /// UART on a pty, paused; QEMU's stdout after its own message (the defmt log) goes to
    /// `log`.
    pub fn start(board: &Board, elf: &Path, image: Option<&[u8]>, log: &Path) -> Result<PtyHub> {
        let dir = tempfile::tempdir()?;
        let table_path = image_file(board, elf, image, dir.path())?;
        let mon = dir.path().join("monitor.sock");
        let mut cmd = command(board, &table_path, false, Uart::Pty, Some(&mon))?;
        cmd.arg("-S").arg("-kernel").arg(elf);
        let mut child = cmd.spawn().context("starting qemu-system-arm")?;
        let said = Arc::new(Mutex::new(String::new()));
        let found = Arc::new(AtomicBool::new(false));
        let (tx, paths) = mpsc::channel();
        let stderr = child.stderr.take().context("qemu stderr")?;
        {
            let (said, found, tx) = (said.clone(), found.clone(), tx.clone());
            std::thread::spawn(move || {
                for line in BufReader::new(stderr).lines().map_while(|l| l.ok()) {
                    if let Some(p) = pty_path(&line) {
                        found.store(true, Ordering::SeqCst);
                        let _ = tx.send(p);
                    }
                    let mut s = said.lock().unwrap_or_else(|e| e.into_inner());
                    s.push_str(&line);
                    s.push('\n');
                }
            });
        }
        let stdout = child.stdout.take().context("qemu stdout")?;
        let file = File::create(log).with_context(|| format!("creating {}", log.display()))?;
        let log_thread = {
            let said = said.clone();
            std::thread::spawn(move || split_stdout(stdout, file, &found, &tx, &said))
        };
        let path = match paths.recv_timeout(Duration::from_secs(20)) {
            Ok(p) => p,
            Err(_) => {
                let _ = child.kill();
                let _ = child.wait();
                bail!(
                    "QEMU named no pty in 20 s; it said: {}",
                    said.lock().unwrap_or_else(|e| e.into_inner())
                );
            }
        };
        let monitor = connect(&mut child, &mon)?;
        Ok(PtyHub {
            child,
            path,
            monitor,
            log: Some(log_thread),
            log_path: log.to_path_buf(),
            said,
            _dir: dir,
        })
    }

    /// The pty's path, what `--port` takes.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Where the defmt log goes.
    pub fn log_path(&self) -> &Path {
        &self.log_path
    }

    /// What QEMU printed itself, for messages.
    pub fn qemu_said(&self) -> String {
        self.said.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    fn monitor(&mut self, command: &str) -> Result<()> {
        self.monitor
            .write_all(format!("{command}\n").as_bytes())
            .with_context(|| format!("QEMU monitor: {command}"))
    }

    /// Lets the machine run (it starts paused).
    pub fn run(&mut self) -> Result<()> {
        self.monitor("cont")
    }

    /// Pauses the machine: the hub hears and says nothing until [`PtyHub::run`].
    pub fn pause(&mut self) -> Result<()> {
        self.monitor("stop")
    }

    /// Resets the machine (`system_reset`); the hub boots again and sends a `Hello`.
    pub fn reset(&mut self) -> Result<()> {
        self.monitor("system_reset")
    }

    /// Opens the pty as a program opens a serial port (see [`Port`]).
    pub fn open(&self) -> Result<Port> {
        Port::open(&self.path)
    }

    /// [`PtyHub::open`], then waits out QEMU's once-a-second poll, so that what the hub sends
    /// next (a boot's `Hello`) reaches the port also with a QEMU before 8.2, which drops the
    /// guest's bytes until that poll saw the pty held (10.0 checks at each write).
    pub fn open_held(&self) -> Result<Port> {
        let port = self.open()?;
        std::thread::sleep(Duration::from_millis(1100));
        Ok(port)
    }

    /// Sends `End` through the pty and waits for QEMU to exit; its status. The defmt log is
    /// complete in [`PtyHub::log_path`] then.
    pub fn finish(mut self) -> Result<ExitStatus> {
        // Open until QEMU exits: QEMU stops reading a pty nobody holds, and what was written
        // but not read yet when the last holder closes it is never read.
        let mut port = self.open()?;
        port.send(&ToDevice::End)?;
        let status = wait_exit(&mut self.child)?;
        drop(port);
        if let Some(h) = self.log.take() {
            h.join()
                .map_err(|_| anyhow::anyhow!("the log writer panicked"))??;
        }
        Ok(status)
    }
}

impl Drop for PtyHub {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// Copies QEMU's stdout into `file`, leaving out the text before and including its pty
/// message (sent on `tx`), unless stderr had it first (then stdout holds the log alone; the
/// guest runs only after the path is known, so nothing of it can come before).
fn split_stdout(
    mut stdout: impl Read,
    mut file: File,
    found: &AtomicBool,
    tx: &mpsc::Sender<PathBuf>,
    said: &Mutex<String>,
) -> Result<()> {
    let mut head = Vec::new();
    let mut buf = [0u8; 4096];
    let mut logging = false;
    loop {
        let n = match stdout.read(&mut buf) {
            Ok(0) => return Ok(()),
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e).context("reading QEMU's stdout"),
        };
        if logging {
            file.write_all(&buf[..n])?;
            continue;
        }
        if found.load(Ordering::SeqCst) {
            logging = true;
            file.write_all(&buf[..n])?;
            continue;
        }
        head.extend_from_slice(&buf[..n]);
        while let Some(end) = head.iter().position(|&b| b == b'\n') {
            let line: Vec<u8> = head.drain(..=end).collect();
            let text = String::from_utf8_lossy(&line);
            said.lock()
                .unwrap_or_else(|e| e.into_inner())
                .push_str(&text);
            if let Some(p) = pty_path(&text) {
                found.store(true, Ordering::SeqCst);
                let _ = tx.send(p);
                logging = true;
                file.write_all(&head)?;
                head.clear();
                break;
            }
        }
    }
}

/// The pty opened by the test: raw bytes both ways, what it held before discarded, the hub's
/// frames read item by item. It takes no lock, so `armcal` can open the same pty beside it
/// (the test writes readings, `armcal decode` reads the reports); it reads only when asked.
pub struct Port {
    file: File,
    items: Items,
}

impl Port {
    /// Opens `path` without making it the controlling terminal, non-blocking (reads wait in
    /// `poll` with a deadline), and drops what was waiting in it.
    pub fn open(path: &Path) -> Result<Port> {
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags(libc::O_NOCTTY | libc::O_NONBLOCK)
            .open(path)
            .with_context(|| format!("opening {}", path.display()))?;
        // SAFETY: a valid open descriptor.
        if unsafe { libc::tcflush(file.as_raw_fd(), libc::TCIFLUSH) } != 0 {
            return Err(std::io::Error::last_os_error())
                .with_context(|| format!("tcflush on {}", path.display()));
        }
        Ok(Port {
            file,
            items: Items::default(),
        })
    }

    /// Sends one message as a frame.
    pub fn send(&mut self, msg: &ToDevice) -> Result<()> {
        let bytes = frame(msg);
        let mut sent = 0;
        let deadline = Instant::now() + ANSWER_TIMEOUT;
        while sent < bytes.len() {
            match self.file.write(&bytes[sent..]) {
                Ok(n) => sent += n,
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                    if Instant::now() > deadline {
                        bail!("the pty took no bytes in {ANSWER_TIMEOUT:?}");
                    }
                    std::thread::sleep(Duration::from_millis(1));
                }
                Err(e) => return Err(e).context("writing to the pty"),
            }
        }
        Ok(())
    }

    /// The next decoded item of the hub's stream, waiting up to [`ANSWER_TIMEOUT`].
    pub fn next_item(&mut self) -> Result<Item> {
        let file = &mut self.file;
        self.items.next(|left| {
            let mut fds = libc::pollfd {
                fd: file.as_raw_fd(),
                events: libc::POLLIN,
                revents: 0,
            };
            let ms = libc::c_int::try_from(left.as_millis()).unwrap_or(libc::c_int::MAX);
            // SAFETY: one valid pollfd.
            match unsafe { libc::poll(&mut fds, 1, ms) } {
                0 => return Ok(None),
                n if n < 0 => {
                    let e = std::io::Error::last_os_error();
                    if e.kind() == std::io::ErrorKind::Interrupted {
                        return Ok(Some(Vec::new()));
                    }
                    return Err(e).context("poll on the pty");
                }
                _ => {}
            }
            let mut buf = [0u8; 4096];
            match file.read(&mut buf) {
                Ok(n) => Ok(Some(buf[..n].to_vec())),
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => Ok(Some(Vec::new())),
                Err(e) => Err(e).context("reading the pty (QEMU gone?)"),
            }
        })
    }

    /// Waits until at least `n` bytes wait unread in the pty (`FIONREAD`), reading none.
    pub fn wait_unread(&self, n: usize, within: Duration) -> Result<()> {
        let deadline = Instant::now() + within;
        loop {
            let mut unread: libc::c_int = 0;
            // SAFETY: a valid descriptor, and FIONREAD writes one c_int.
            if unsafe { libc::ioctl(self.file.as_raw_fd(), libc::FIONREAD, &mut unread) } != 0 {
                return Err(std::io::Error::last_os_error()).context("FIONREAD on the pty");
            }
            if usize::try_from(unread).unwrap_or(0) >= n {
                return Ok(());
            }
            if Instant::now() > deadline {
                bail!("{unread} bytes unread in the pty after {within:?}, not {n}");
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// Sends `msg` and returns the next item the hub sends.
    pub fn ask(&mut self, msg: &ToDevice) -> Result<Item> {
        self.send(msg)?;
        self.next_item()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pty_path_from_each_qemu() {
        // On stdout (qemu_printf), and as older releases wrote it on stderr: the same words.
        assert_eq!(
            pty_path("char device redirected to /dev/pts/7 (label serial0)"),
            Some(PathBuf::from("/dev/pts/7"))
        );
        assert_eq!(
            pty_path("qemu-system-arm: -serial pty: char device redirected to /dev/pts/12 (label serial0)"),
            Some(PathBuf::from("/dev/pts/12"))
        );
        assert_eq!(pty_path("QEMU 10.0.2 monitor - type 'help'"), None);
        assert_eq!(pty_path("char device redirected to (label serial0)"), None);
    }
}
