//! An interactive QEMU run: frames sent one at a time, the hub's answers read as they arrive,
//! the machine reset through QEMU's monitor in between (`system_reset`: the core and its
//! peripherals restart from the reset vector, as after a power cycle or a watchdog; the
//! flash keeps what was written). The calibration-update tests drive a hub through it.

use std::io::{Read, Write};
use std::os::unix::net::UnixStream;
use std::process::{Child, ExitStatus};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use quatarm::stream::ToDevice;
use quatarm_wire::stream_decode::{Decoder, Item};

use crate::boards::Board;
use crate::qemu::{command, connect, image_file, wait_exit, Uart};
use crate::recording::frame;

/// How long an answer may take before the session counts it as missing.
pub const ANSWER_TIMEOUT: Duration = Duration::from_secs(30);

/// A running QEMU hub.
pub struct Session {
    child: Child,
    uart: UnixStream,
    monitor: UnixStream,
    bytes: Receiver<Vec<u8>>,
    items: Items,
    log: Option<JoinHandle<Vec<u8>>>,
    _dir: tempfile::TempDir,
}

impl Session {
    /// Starts `board`'s main binary with `image` (bytes, exactly as given: sign a table
    /// first with `e2e::signed` for a board with a key) in its calibration region (slot 0).
    pub fn start(board: &Board, elf: &std::path::Path, image: Option<&[u8]>) -> Result<Session> {
        let dir = tempfile::tempdir()?;
        let table_path = image_file(board, elf, image, dir.path())?;
        let sock = dir.path().join("uart.sock");
        let mon = dir.path().join("monitor.sock");
        let mut cmd = command(board, &table_path, false, Uart::Socket(&sock), Some(&mon))?;
        cmd.arg("-kernel").arg(elf);
        let mut child = cmd.spawn().context("starting qemu-system-arm")?;
        let mut stdout = child.stdout.take().context("qemu stdout")?;
        let log = std::thread::spawn(move || {
            let mut out = Vec::new();
            let _ = stdout.read_to_end(&mut out);
            out
        });
        let uart = connect(&mut child, &sock)?;
        let monitor = connect(&mut child, &mon)?;
        let mut rx = uart.try_clone()?;
        let (tx, bytes) = mpsc::channel();
        std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n) = rx.read(&mut buf) {
                if n == 0 || tx.send(buf[..n].to_vec()).is_err() {
                    break;
                }
            }
        });
        Ok(Session {
            child,
            uart,
            monitor,
            bytes,
            items: Items::default(),
            log: Some(log),
            _dir: dir,
        })
    }

    /// Sends one message as a frame.
    pub fn send(&mut self, msg: &ToDevice) -> Result<()> {
        self.uart.write_all(&frame(msg))?;
        Ok(())
    }

    /// The next decoded item of the hub's stream, waiting up to [`ANSWER_TIMEOUT`].
    pub fn next_item(&mut self) -> Result<Item> {
        let bytes = &self.bytes;
        self.items.next(|left| match bytes.recv_timeout(left) {
            Ok(chunk) => Ok(Some(chunk)),
            Err(RecvTimeoutError::Timeout) => Ok(None),
            Err(RecvTimeoutError::Disconnected) => bail!("the hub's UART closed"),
        })
    }

    /// Sends `msg` and returns the next item the hub sends.
    pub fn ask(&mut self, msg: &ToDevice) -> Result<Item> {
        self.send(msg)?;
        self.next_item()
    }

    /// Resets the machine through QEMU's monitor. The hub boots again and sends a `Hello`.
    pub fn reset(&mut self) -> Result<()> {
        self.monitor.write_all(b"system_reset\n")?;
        Ok(())
    }

    /// Sends `End` and waits for QEMU to exit; returns its status and the defmt log bytes.
    pub fn finish(mut self) -> Result<(ExitStatus, Vec<u8>)> {
        self.send(&ToDevice::End)?;
        let status = wait_exit(&mut self.child)?;
        let log = self
            .log
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default();
        Ok((status, log))
    }
}

/// A hub's stream read item by item, each within [`ANSWER_TIMEOUT`].
pub(crate) struct Items {
    decoder: Decoder,
    pending: std::collections::VecDeque<Item>,
}

impl Default for Items {
    fn default() -> Items {
        Items {
            decoder: Decoder::from_start(),
            pending: Default::default(),
        }
    }
}

impl Items {
    /// The next item; `more(left)` gives the next bytes within `left`, `None` when none came.
    pub(crate) fn next(
        &mut self,
        mut more: impl FnMut(Duration) -> Result<Option<Vec<u8>>>,
    ) -> Result<Item> {
        let deadline = Instant::now() + ANSWER_TIMEOUT;
        loop {
            if let Some(item) = self.pending.pop_front() {
                return Ok(item);
            }
            let left = deadline.saturating_duration_since(Instant::now());
            match more(left)? {
                Some(chunk) => self.pending.extend(self.decoder.push_all(&chunk)),
                None => bail!("no answer from the hub in {ANSWER_TIMEOUT:?}"),
            }
        }
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}
