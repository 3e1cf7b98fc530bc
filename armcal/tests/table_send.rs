//! `armcal table send` against a hub in the test process: quatarm's own `Replay`, `Hub` and
//! `Updater` on the mock NOR flash, behind a byte port that answers as a board's serve loop
//! does (a report between answers, as a measuring arm sends them; a `Hello` after a commit).

use std::collections::VecDeque;
use std::io::{self, Read, Write};

use armcal::table_send::send;
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
    /// Answer nothing (a hub that is off).
    silent: bool,
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
}

impl Write for PortHub {
    fn write(&mut self, bytes: &[u8]) -> io::Result<usize> {
        self.received += bytes.len();
        for &b in bytes {
            let Some(Event::Update(step)) = self.replay.push(b) else {
                continue;
            };
            if self.silent {
                continue;
            }
            // The arm keeps measuring: a report before each answer.
            let report = self.hub.report(0, Ok(&reading()), |_, _| {
                Err::<quatarm::stream::Coordinates, ()>(())
            });
            self.emit(&ToHost::Report(report));
            let mut scratch = [0u8; MAX_TABLE_LEN];
            let answer = self.updater.step(&mut self.flash, &mut scratch, &step);
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
        if self.out.is_empty() {
            return Err(io::Error::new(io::ErrorKind::TimedOut, "no byte"));
        }
        let n = buf.len().min(self.out.len());
        for (b, x) in buf.iter_mut().zip(self.out.drain(..n)) {
            *b = x;
        }
        Ok(n)
    }
}

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
    let sent = send(&mut port, &new).unwrap();
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
    let sent = send(&mut port, &old).unwrap();
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
    let err = format!("{:#}", send(&mut port, &new).unwrap_err());
    let steps = quatarm::update::session::Step::sequence(&new).count();
    assert!(
        err.contains(&format!("refused step {steps} of {steps} (Commit)"))
            && err.contains("WrongJointCount"),
        "{err}"
    );
    let mut scratch = [0u8; MAX_TABLE_LEN];
    assert!(live_table(&mut port.flash, &layout(), &Accept::joints(7), &mut scratch).is_err());
}

#[test]
fn an_invalid_file_is_refused_before_a_byte_is_sent() {
    let mut port = PortHub::new(&table(100.0));
    let mut bad = table(120.0);
    bad[40] ^= 1;
    let err = format!("{:#}", send(&mut port, &bad).unwrap_err());
    assert!(err.contains("not a valid table"), "{err}");
    assert_eq!(port.received, 0);
}

#[test]
fn a_silent_hub_is_an_error_not_a_hang() {
    let mut port = PortHub::new(&table(100.0));
    port.out.clear();
    port.silent = true;
    let err = format!("{:#}", send(&mut port, &table(120.0)).unwrap_err());
    assert!(err.contains("step 1") && err.contains("no answer"), "{err}");
}
