//! `armcal table send`: a calibration table to a hub over its stream's UART, as the update
//! steps of `docs/update.md` (`Begin`, the chunks in order, `Commit`), each step sent only
//! after the hub accepted the one before it.
//!
//! The hub keeps measuring during an update, so its answers arrive between reports; this
//! reads the stream through the one decoder of the host ([`quatarm_wire::stream_decode`]) and
//! waits for each step's answer, skipping reports. After the commit the hub boots on the new
//! table and says so in its `Hello`; the send is done when that `Hello` names the table's CRC.
//!
//! What a real port adds to that (found driving a QEMU hub through a pseudo-terminal,
//! `host-tests` `table_send_over_a_pty`):
//! - a port keeps what arrived while nobody read it, across a close and the next open (a pty
//!   does; whether a USB adapter does depends on its driver): the input is discarded before
//!   the first step, or an earlier session's unread answer is taken for this one's (the
//!   `Begun` of a `Begin` it sent, then the rest of the steps out of step);
//! - an answer can also arrive late, after the discard (a hub that was slow for the session
//!   before): an accepted answer must be the step's own (`Begun` for `Begin`, for a chunk the
//!   offset after it, `Committed` for `Commit`), else the send ends, saying so;
//! - the timeout is a deadline for each answer, not a limit on each read: a measuring hub
//!   sends reports all the time, so a read never times out while it ignores the update;
//! - an update does not survive a restart of the hub (`Begin` is held in RAM): a `Hello`
//!   between steps ends the send at once, naming the table the hub came back on, instead of
//!   waiting for an answer that will not come or sending chunks it will refuse. A `Hello`
//!   naming the table sent while the commit's answer is awaited means the commit was written
//!   and only its answer lost: the send succeeded.

use std::collections::VecDeque;
use std::io::{self, ErrorKind, Read, Write};
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context, Result};
use quatarm::stream::{encode, Hello, LiveTable, ToDevice, UpdateAnswer, MAX_FRAME};
use quatarm::table::Table;
use quatarm::update::session::Step;
use quatarm::update::Accepted;
use quatarm_wire::stream_decode::{Decoder, Item};

/// What a send achieved.
#[derive(Debug, PartialEq, Eq)]
pub struct Sent {
    /// Steps sent (`Begin`, chunks, `Commit`).
    pub steps: usize,
    /// Reports that arrived while the update ran (the arm kept measuring).
    pub reports_between: u64,
    /// The table the hub announced after the commit.
    pub live: LiveTable,
}

/// A byte link to a hub whose reads give up after a set time: a serial port (a hub in the
/// test process in `tests/table_send.rs`).
pub trait Link: Read + Write {
    /// Makes each later read (and write) wait at most `wait` before failing with
    /// `TimedOut`.
    fn set_timeout(&mut self, wait: Duration) -> io::Result<()>;
    /// Drops what arrived before this call and was not read.
    fn discard_input(&mut self) -> io::Result<()>;
}

impl Link for Box<dyn serialport::SerialPort> {
    fn set_timeout(&mut self, wait: Duration) -> io::Result<()> {
        serialport::SerialPort::set_timeout(self.as_mut(), wait).map_err(io::Error::from)
    }
    fn discard_input(&mut self) -> io::Result<()> {
        self.clear(serialport::ClearBuffer::Input)
            .map_err(io::Error::from)
    }
}

/// Sends `table` (checked here as the hub will check it, before a byte goes out) through
/// `port`, waiting at most `timeout` for each answer. A refused step ends the send with the
/// hub's reason; so do an answer that does not come in time and a restart of the hub.
pub fn send(port: &mut impl Link, table: &[u8], timeout: Duration) -> Result<Sent> {
    let crc = Table::parse(table)
        .map_err(|e| anyhow!("not a valid table: {e}"))?
        .crc();
    port.discard_input()
        .context("discarding what the port held from before")?;
    let mut stream = Stream {
        port,
        // From the first byte: the input was just discarded, so a frame cut by that is the
        // only damage possible and its CRC refuses it, where joining would skip the first
        // frame whole (a report has no delimiter before it).
        decoder: Decoder::from_start(),
        pending: VecDeque::new(),
        timeout,
    };
    let mut reports_between = 0u64;
    stream.write(&[0])?;
    let steps: Vec<Step> = Step::sequence(table).collect();
    let n = steps.len();
    for (i, step) in steps.iter().enumerate() {
        let mut out = [0u8; MAX_FRAME];
        let len = encode(&ToDevice::Update(step.clone()), &mut out)?;
        stream.write(&out[..len])?;
        let what = format!("step {} of {n} ({})", i + 1, name(step));
        let (waited, reports) = stream.answer(step, &what, crc)?;
        reports_between += reports;
        match waited {
            Waited::Answer(answer) => check_answer(step, &what, answer)?,
            Waited::Committed(live) => {
                return Ok(Sent {
                    steps: n,
                    reports_between,
                    live,
                })
            }
        }
    }
    let live = stream.announcement(crc)?;
    Ok(Sent {
        steps: n,
        reports_between,
        live,
    })
}

/// How the wait for a step's answer ended.
enum Waited {
    /// The hub answered the step.
    Answer(UpdateAnswer),
    /// The hub restarted on the table sent while the commit's answer was awaited: the
    /// commit was written and only its answer lost.
    Committed(LiveTable),
}

/// Ends the send unless `answer` accepts `step` as that step's own answer.
fn check_answer(step: &Step, what: &str, answer: UpdateAnswer) -> Result<()> {
    match answer {
        Ok(a) if answers(step, &a) => Ok(()),
        Ok(a) => bail!(
            "the hub answered {a:?} to {what}, which is not that step's answer (one left from an earlier session, or a hub out of step); the update is not done"
        ),
        Err(why) => bail!(
            "the hub refused {what}: {why:?}{}; its old table stays live",
            why_refused(&why)
        ),
    }
}

/// Whether an accepted answer is the one `step` gets: `Begun` for `Begin`, for a chunk the
/// offset after it, `Committed` for `Commit`.
fn answers(step: &Step, answer: &Accepted) -> bool {
    match (step, answer) {
        (Step::Begin { .. }, Accepted::Begun { .. })
        | (Step::Commit, Accepted::Committed { .. }) => true,
        (Step::Chunk { offset, bytes }, Accepted::Chunk { next }) => {
            u64::from(*next) == u64::from(*offset) + bytes.len() as u64
        }
        _ => false,
    }
}

/// What a `Hello` says is live, in words.
fn announced(h: &Hello) -> String {
    match h.live {
        Some(l) => format!(
            "it announced the table in slot {}, record {}, CRC {:#010x}",
            l.slot, l.seq, l.crc
        ),
        None => format!("it announced no valid table: {}", h.status.table().name()),
    }
}

/// A step in words, for messages.
fn name(step: &Step) -> String {
    match step {
        Step::Begin { len, crc } => format!("Begin, {len} bytes, CRC {crc:#010x}"),
        Step::Chunk { offset, bytes } => format!("chunk of {} bytes at {offset}", bytes.len()),
        Step::Commit => "Commit".into(),
        Step::Abort => "Abort".into(),
    }
}

/// The port and the decoder of what it reads.
struct Stream<'a, P> {
    port: &'a mut P,
    decoder: Decoder,
    pending: VecDeque<Item>,
    timeout: Duration,
}

impl<P: Link> Stream<'_, P> {
    /// Waits for the answer to `step` (`what` in messages), counting the reports that
    /// arrive meanwhile; a restart of the hub ends the wait (see the module's notes), the
    /// deadline too.
    fn answer(&mut self, step: &Step, what: &str, crc: u32) -> Result<(Waited, u64)> {
        let timeout = self.timeout;
        let mut restarted = None;
        let deadline = Instant::now() + timeout;
        let mut reports = 0u64;
        loop {
            let Some(item) = self.next(deadline)? else {
                bail!(
                    "no answer from the hub to {what} within {timeout:?}{}{}; its old table stays live",
                    match reports {
                        0 => String::new(),
                        r => format!(
                            ", although it sent {r} reports meanwhile (it measures but does not take the update: another firmware?)"
                        ),
                    },
                    match restarted {
                        Some(h) => format!(", after it restarted ({})", announced(&h)),
                        None => String::new(),
                    }
                );
            };
            match item {
                Item::Update(a) => return Ok((Waited::Answer(a), reports)),
                // The state record was written, the answer lost in the restart.
                Item::Hello(Hello {
                    live: Some(live), ..
                }) if matches!(step, Step::Commit) && live.crc == crc => {
                    return Ok((Waited::Committed(live), reports));
                }
                // A restart before `Begin` arrived loses nothing: the hub may still answer
                // it (else the deadline says so, and that it restarted).
                Item::Hello(h) if matches!(step, Step::Begin { .. }) => restarted = Some(h),
                Item::Hello(h) => bail!(
                    "the hub restarted while waiting for the answer to {what} ({}): an update does not survive a restart; its old table stays live, send the table again",
                    announced(&h)
                ),
                Item::Report(_) | Item::Backward { .. } | Item::Inconsistent(..) => reports += 1,
                // A probe answer is not this session's (another program selected a probe).
                Item::Repeated(_) | Item::Damaged(_) | Item::Probe(_) => {}
            }
        }
    }

    /// After the commit: waits for the `Hello` the hub boots with, which must name the
    /// table sent (CRC `crc`).
    fn announcement(&mut self, crc: u32) -> Result<LiveTable> {
        let timeout = self.timeout;
        let deadline = Instant::now() + timeout;
        loop {
            let Some(item) = self.next(deadline)? else {
                bail!(
                    "the hub committed the table but did not announce it within {timeout:?}: it boots on it at its next start; its Hello (armcal decode) says which table is live"
                );
            };
            if let Item::Hello(h) = item {
                return match h.live {
                    Some(live) if live.crc == crc => Ok(live),
                    _ => bail!(
                        "after the commit the hub announced {}, not the table sent (CRC {crc:#010x})",
                        announced(&h)
                    ),
                };
            }
        }
    }

    fn write(&mut self, bytes: &[u8]) -> Result<()> {
        self.port
            .set_timeout(self.timeout)
            .and_then(|()| self.port.write_all(bytes))
            .context("writing to the port")?;
        // Waits for the bytes to leave where the port can tell (tcdrain); none is lost if
        // it cannot.
        self.port.flush().ok();
        Ok(())
    }

    /// The next decoded item, reading the port as needed; `None` once `deadline` passed.
    fn next(&mut self, deadline: Instant) -> Result<Option<Item>> {
        let mut buf = [0u8; 256];
        loop {
            if let Some(item) = self.pending.pop_front() {
                return Ok(Some(item));
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(None);
            }
            self.port
                .set_timeout(left)
                .context("setting the port's timeout")?;
            match self.port.read(&mut buf) {
                Ok(0) => bail!("the port closed"),
                Ok(n) => self.pending.extend(self.decoder.push_all(&buf[..n])),
                Err(e)
                    if matches!(
                        e.kind(),
                        ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted
                    ) => {}
                Err(e) if e.kind() == ErrorKind::BrokenPipe => bail!(
                    "the port hung up: the hub went away (unplugged, switched off, or its emulator ended)"
                ),
                Err(e) => return Err(e).context("reading the port"),
            }
        }
    }
}

/// What a refusal means for the person sending, where its name alone does not say it.
pub fn why_refused(why: &quatarm::update::Refusal) -> String {
    use quatarm::update::Refusal;
    match why {
        Refusal::Rollback { live, offered } => format!(
            " (anti-rollback: this table is calibration number {offered}, below number {live}, the highest this hub has made live; to return to older values the maker re-issues them under a number of at least {live} and signs them anew)"
        ),
        Refusal::RetiredKey => " (the table is signed by a maker's key this hub has retired: sign it with the current key)".into(),
        _ => String::new(),
    }
}
