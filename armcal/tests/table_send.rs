//! `armcal table send` against a hub in the test process: quatarm's own `Replay`, `Hub` and
//! `Updater` on the mock NOR flash, behind a byte port that answers as a board's serve loop
//! does (a report between answers, as a measuring arm sends them; a `Hello` after a commit).
//! The same command against a QEMU hub through a pseudo-terminal: `host-tests`,
//! `table_send_over_a_pty`.

use std::collections::VecDeque;
use std::io::{self, Read, Write};
use std::time::{Duration, Instant};

use armcal::table_send::{send, Link};
use quatarm::stream::{
    Event, Hub, LiveTable, NumberFormat, Replay, TableState, ToHost, MAX_OUTPUT,
};
use quatarm::table::MAX_TABLE_LEN;
use quatarm::update::fixtures::{boot, factory, layout, table};
use quatarm::update::mock::MockFlash;
use quatarm::update::{live_table, Accept, Accepted, Updater};

/// A hub behind a port: what is written to it is the host's stream, what is read its answers.
struct PortHub {
    flash: MockFlash,
    updater: Updater,
    replay: Replay,
    hub: Hub,
    out: VecDeque<u8>,
    /// Bytes the host wrote.
    received: usize,
    /// Answer no update step (a hub that is off, or one without an update port).
    silent: bool,
    /// Send a report whenever the host reads and nothing else is due (a live arm).
    measuring: bool,
    /// Restart (as a reset does: the update in RAM lost) when this many steps have arrived,
    /// before carrying out the last of them, or with `restart_after_step` after carrying it
    /// out but before its answer left.
    restart_at: Option<usize>,
    restart_after_step: bool,
    /// An answer sent before the real one when this many steps have arrived (one an
    /// earlier session left in the port).
    stray_answer: Option<(usize, quatarm::stream::UpdateAnswer)>,
    /// Update steps received.
    steps: usize,
    /// What a read waits for before it times out.
    timeout: Duration,
}

impl PortHub {
    fn new(factory_table: &[u8]) -> PortHub {
        let mut p = PortHub {
            flash: factory(factory_table),
            updater: Updater::new(layout(), Accept::joints(6)),
            replay: Replay::new(),
            hub: Hub::new(TableState::Valid, 6, NumberFormat::F32),
            out: VecDeque::new(),
            received: 0,
            silent: false,
            measuring: false,
            restart_at: None,
            restart_after_step: false,
            stray_answer: None,
            steps: 0,
            timeout: Duration::ZERO,
        };
        p.boot();
        p
    }

    /// Boots on the live table and sends the `Hello` naming it.
    fn boot(&mut self) {
        let mut scratch = [0u8; MAX_TABLE_LEN];
        let live =
            live_table(&mut self.flash, &layout(), &Accept::joints(6), &mut scratch).unwrap();
        self.hub = Hub::new(TableState::Valid, 6, NumberFormat::F32).with_live(LiveTable {
            slot: live.slot,
            seq: live.seq.unwrap_or(0),
            crc: live.table.crc(),
        });
        self.emit(&self.hub.hello());
    }

    fn emit(&mut self, msg: &ToHost) {
        let mut buf = [0u8; MAX_OUTPUT];
        self.out.extend(self.hub.render(msg, &mut buf));
    }

    /// A reset: the update under way forgotten, the boot's `Hello`.
    fn restart(&mut self) {
        self.updater = Updater::new(layout(), Accept::joints(6));
        self.boot();
    }

    /// One report, as the arm measures.
    fn measure(&mut self) {
        let report = self.hub.report(0, Ok(&reading()), |_, _| {
            Err::<quatarm::stream::Coordinates, ()>(())
        });
        self.emit(&ToHost::Report(report));
    }
}

impl Link for PortHub {
    fn set_timeout(&mut self, wait: Duration) -> io::Result<()> {
        self.timeout = wait;
        Ok(())
    }
    fn discard_input(&mut self) -> io::Result<()> {
        self.out.clear();
        Ok(())
    }
}

impl Write for PortHub {
    fn write(&mut self, bytes: &[u8]) -> io::Result<usize> {
        self.received += bytes.len();
        for &b in bytes {
            let Some(Event::Update(step)) = self.replay.push(b) else {
                continue;
            };
            self.steps += 1;
            if self.silent {
                continue;
            }
            let restart = self.restart_at == Some(self.steps);
            if restart && !self.restart_after_step {
                self.restart();
                continue;
            }
            // The arm keeps measuring: a report before each answer.
            self.measure();
            let mut scratch = [0u8; MAX_TABLE_LEN];
            let answer = self.updater.step(&mut self.flash, &mut scratch, &step);
            if restart {
                self.restart();
                continue;
            }
            if let Some((at, stray)) = self.stray_answer {
                if at == self.steps {
                    self.emit(&ToHost::Update(stray));
                }
            }
            self.emit(&ToHost::Update(answer));
            if let Ok(Accepted::Committed { .. }) = answer {
                self.boot();
            }
        }
        Ok(bytes.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

impl Read for PortHub {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if self.out.is_empty() && self.measuring {
            self.measure();
        }
        if self.out.is_empty() {
            // As a serial port does: waits its timeout for a byte that does not come.
            std::thread::sleep(self.timeout);
            return Err(io::Error::new(io::ErrorKind::TimedOut, "no byte"));
        }
        let n = buf.len().min(self.out.len());
        for (b, x) in buf.iter_mut().zip(self.out.drain(..n)) {
            *b = x;
        }
        Ok(n)
    }
}

/// What the tests wait for each answer: a hub in the process answers at once.
const TIMEOUT: Duration = Duration::from_millis(300);

fn reading() -> quatarm::stream::Reading {
    quatarm::stream::Reading {
        seq: 0,
        counts: quatarm::stream::Counts::new(&[1, 2, 3, 4, 5, 6]).unwrap(),
        temp_mc: 20_000,
        faults: 0,
    }
}

#[test]
fn a_table_sent_goes_live_and_the_hub_says_so() {
    let (old, new) = (table(100.0), table(120.0));
    let mut port = PortHub::new(&old);
    let sent = send(&mut port, &new, TIMEOUT).unwrap();
    let crc = u32::from_le_bytes(new[new.len() - 4..].try_into().unwrap());
    assert_eq!(
        sent.live,
        LiveTable {
            slot: 1,
            seq: 1,
            crc
        }
    );
    assert_eq!(
        sent.steps,
        quatarm::update::session::Step::sequence(&new).count()
    );
    assert_eq!(sent.reports_between, sent.steps as u64);
    assert_eq!(boot(&mut port.flash).as_deref(), Some(&new[..]));
    // And again: the next update goes to the other slot.
    let sent = send(&mut port, &old, TIMEOUT).unwrap();
    assert_eq!((sent.live.slot, sent.live.seq), (0, 2));
    assert_eq!(boot(&mut port.flash).as_deref(), Some(&old[..]));
}

/// A hub driving 7 joints refuses a 6-joint table at commit: the error names the step and
/// the hub's reason, and no table is made live for it.
#[test]
fn a_refused_step_is_named_and_nothing_goes_live() {
    let mut port = PortHub::new(&table(100.0));
    port.updater = Updater::new(layout(), Accept::joints(7));
    let new = table(120.0);
    let err = format!("{:#}", send(&mut port, &new, TIMEOUT).unwrap_err());
    let steps = quatarm::update::session::Step::sequence(&new).count();
    assert!(
        err.contains(&format!("refused step {steps} of {steps} (Commit)"))
            && err.contains("WrongJointCount"),
        "{err}"
    );
    let mut scratch = [0u8; MAX_TABLE_LEN];
    assert!(live_table(&mut port.flash, &layout(), &Accept::joints(7), &mut scratch).is_err());
}

/// An older calibration sent back is refused at commit, and the error says why and what a
/// deliberate return to older values takes.
#[test]
fn an_older_calibration_number_is_refused_with_the_reason() {
    use quatarm::update::fixtures::numbered;
    let mut port = PortHub::new(&numbered(100.0, 3));
    send(&mut port, &numbered(110.0, 4), TIMEOUT).unwrap();
    let old = numbered(100.0, 3);
    let err = format!("{:#}", send(&mut port, &old, TIMEOUT).unwrap_err());
    assert!(
        err.contains("Rollback { live: 4, offered: 3 }")
            && err.contains("anti-rollback")
            && err.contains("re-issues them under a number of at least 4")
            && err.contains("old table stays live"),
        "{err}"
    );
    assert_eq!(boot(&mut port.flash), Some(numbered(110.0, 4)));
}

#[test]
fn an_invalid_file_is_refused_before_a_byte_is_sent() {
    let mut port = PortHub::new(&table(100.0));
    let mut bad = table(120.0);
    bad[40] ^= 1;
    let err = format!("{:#}", send(&mut port, &bad, TIMEOUT).unwrap_err());
    assert!(err.contains("not a valid table"), "{err}");
    assert_eq!(port.received, 0);
}

#[test]
fn a_silent_hub_is_an_error_not_a_hang() {
    let mut port = PortHub::new(&table(100.0));
    port.out.clear();
    port.silent = true;
    let err = format!("{:#}", send(&mut port, &table(120.0), TIMEOUT).unwrap_err());
    assert!(err.contains("step 1") && err.contains("no answer"), "{err}");
}

/// Runs `send` with a deadline of its own: a send that hangs fails the test instead of
/// hanging it.
fn send_within(
    mut port: PortHub,
    table: Vec<u8>,
    limit: Duration,
) -> (anyhow::Result<armcal::table_send::Sent>, PortHub, Duration) {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let start = Instant::now();
        let result = send(&mut port, &table, TIMEOUT);
        let _ = tx.send((result, port, start.elapsed()));
    });
    rx.recv_timeout(limit)
        .unwrap_or_else(|_| panic!("table send still running after {limit:?}: it hangs"))
}

/// A live arm sends reports all the time: a hub that measures but does not take the update
/// (another firmware) must end the send after the timeout, not keep it reading reports.
#[test]
fn a_hub_that_measures_but_never_answers_ends_the_send_at_the_timeout() {
    let mut port = PortHub::new(&table(100.0));
    port.silent = true;
    port.measuring = true;
    let (result, _, took) = send_within(port, table(120.0), 10 * TIMEOUT);
    let err = format!("{:#}", result.unwrap_err());
    assert!(
        err.contains("no answer from the hub to step 1 of") && err.contains("reports meanwhile"),
        "{err}"
    );
    assert!(took >= TIMEOUT && took < 3 * TIMEOUT, "{took:?}");
}

/// A reset between steps: the hub's `Hello` ends the send at once, naming the table it came
/// back on, rather than a refusal of the next chunk or a timeout.
#[test]
fn a_restart_during_the_update_is_named_with_the_table_it_came_back_on() {
    let old = table(100.0);
    let mut port = PortHub::new(&old);
    port.restart_at = Some(5);
    let crc = u32::from_le_bytes(old[old.len() - 4..].try_into().unwrap());
    let (result, mut port, took) = send_within(port, table(120.0), 10 * TIMEOUT);
    let err = format!("{:#}", result.unwrap_err());
    assert!(
        err.contains("the hub restarted while waiting for the answer to step 5 of")
            && err.contains(&format!("slot 0, record 0, CRC {crc:#010x}"))
            && err.contains("old table stays live"),
        "{err}"
    );
    assert!(took < TIMEOUT, "{took:?}: it waited for the timeout");
    assert_eq!(boot(&mut port.flash).as_deref(), Some(&old[..]));
}

/// A restart that lost only the commit's answer: the `Hello` names the new table, so the
/// send succeeds.
#[test]
fn a_commit_whose_answer_a_restart_lost_is_confirmed_by_the_hello() {
    let new = table(120.0);
    let mut port = PortHub::new(&table(100.0));
    port.restart_at = Some(quatarm::update::session::Step::sequence(&new).count());
    port.restart_after_step = true;
    let (result, mut port, _) = send_within(port, new.clone(), 10 * TIMEOUT);
    let sent = result.unwrap();
    assert_eq!((sent.live.slot, sent.live.seq), (1, 1));
    assert_eq!(boot(&mut port.flash).as_deref(), Some(&new[..]));
}

/// Whatever the port held before the send (an earlier session's answers) is dropped, and
/// an accepted answer that is not the step's own ends the send rather than passing for it.
#[test]
fn answers_from_before_the_send_or_out_of_step_are_not_taken() {
    let mut port = PortHub::new(&table(100.0));
    port.emit(&ToHost::Update(Ok(Accepted::Begun { slot: 1 })));
    port.emit(&ToHost::Update(Ok(Accepted::Chunk { next: 48 })));
    send(&mut port, &table(120.0), TIMEOUT).unwrap();

    let mut port = PortHub::new(&table(100.0));
    port.stray_answer = Some((3, Ok(Accepted::Chunk { next: 48 })));
    let err = format!("{:#}", send(&mut port, &table(120.0), TIMEOUT).unwrap_err());
    assert!(
        err.contains("answered Chunk { next: 48 } to step 3 of")
            && err.contains("not that step's answer"),
        "{err}"
    );
}
