//! The update state machine (`quatarm::update::Updater`) on the mock NOR flash, driven by any
//! program of steps: the new table's own `Begin` and chunks, chunks of any bytes at any offset,
//! `Begin`s of any length and CRC, `Commit`, `Abort`, a power cut after any number of flash
//! operations (leaving the operation under way untouched, done or torn), and reboots. After
//! every step a boot of the flash as it stands must come up on a table, and only on the old
//! table or one whose `Commit` was accepted or under way when the power went: never a mix,
//! never none. Never a panic. The program's first byte picks the layout: state copies of
//! their own (even) or in the slots' trailers (odd).
#![no_main]

use libfuzzer_sys::fuzz_target;
use quatarm::table::MAX_TABLE_LEN;
use quatarm::update::fixtures::{boot_in, crc_of, factory, layouts, table};
use quatarm::update::mock::{Cut, MockFlash};
use quatarm::update::session::{Accepted, Step, CHUNK_LEN};
use quatarm::update::{Accept, Layout, Updater};

fuzz_target!(|program: &[u8]| {
    let (old, new) = (table(100.0), table(120.0));
    let [regions, trailers] = layouts();
    let layout = match program.first() {
        Some(b) if b & 1 == 1 => trailers,
        _ => regions,
    };
    let program = program.get(1..).unwrap_or_default();
    let mut flash = factory(&old);
    let mut up = Updater::new(layout.clone(), Accept::joints(6));
    let mut scratch = [0u8; MAX_TABLE_LEN];
    // What may be live: the old table, and each table a `Commit` was sent for.
    let mut may_be_live: Vec<Vec<u8>> = vec![old.clone()];
    // The bytes the updater accepted since its last `Begin`.
    let mut sent: Vec<u8> = Vec::new();
    let mut bytes = program.iter().copied();
    while let Some(op) = bytes.next() {
        let arg = bytes.next().unwrap_or(0);
        let step = match op % 8 {
            0 => Step::Begin {
                len: new.len() as u32,
                crc: crc_of(&new),
            },
            1 => {
                let at = sent.len().min(new.len());
                let end = (at + usize::from(arg) % CHUNK_LEN + 1).min(new.len());
                Step::Chunk {
                    offset: at as u32,
                    bytes: heapless::Vec::from_slice(&new[at..end]).expect("fits"),
                }
            }
            2 => {
                let n = usize::from(arg) % CHUNK_LEN + 1;
                let chunk: Vec<u8> = bytes.by_ref().take(n).collect();
                let offset = if arg & 0x80 != 0 {
                    u32::from(bytes.next().unwrap_or(0)) * 4
                } else {
                    sent.len() as u32
                };
                Step::Chunk {
                    offset,
                    bytes: heapless::Vec::from_slice(&chunk).expect("fits"),
                }
            }
            3 => Step::Commit,
            4 => Step::Abort,
            5 => {
                let len = u32::from(arg) * 16 + u32::from(bytes.next().unwrap_or(0));
                let crc = u32::from_le_bytes([arg, arg ^ 0x5a, 0, 1]);
                Step::Begin { len, crc }
            }
            6 => {
                let cut = match bytes.next().unwrap_or(0) % 3 {
                    0 => Cut::Untouched,
                    1 => Cut::Done,
                    k => Cut::Random(u64::from(arg) << 8 | u64::from(k)),
                };
                flash.cut = Some((flash.ops + usize::from(arg % 32), cut));
                continue;
            }
            _ => {
                // Reboot: the flash as the cut left it, powered again; a new updater.
                flash = MockFlash::from_image(flash.mem.clone());
                up = Updater::new(layout.clone(), Accept::joints(6));
                sent.clear();
                check_boot(&layout, &flash, &may_be_live, None);
                continue;
            }
        };
        if step == Step::Commit {
            may_be_live.push(sent.clone());
        }
        let result = up.step(&mut flash, &mut scratch, &step);
        match (&step, result) {
            (Step::Begin { .. }, Ok(_)) => sent.clear(),
            (Step::Chunk { bytes: b, .. }, Ok(Accepted::Chunk { next })) => {
                sent.extend_from_slice(b);
                assert_eq!(next as usize, sent.len(), "next offset is the count so far");
            }
            (_, Ok(Accepted::Committed { .. })) => {
                check_boot(&layout, &flash, &may_be_live, Some(&sent));
                continue;
            }
            _ => {}
        }
        check_boot(&layout, &flash, &may_be_live, None);
    }
});

/// A boot of a copy of `flash` (powered again, read as `layout`) comes up on one of `may_be_live`, and on
/// `exactly` where given.
fn check_boot(layout: &Layout, flash: &MockFlash, may_be_live: &[Vec<u8>], exactly: Option<&[u8]>) {
    let mut copy = MockFlash::from_image(flash.mem.clone());
    let live = boot_in(layout, &mut copy).expect("a boot always finds a table");
    assert!(
        may_be_live.iter().any(|t| *t == live),
        "the boot came up on a table no commit sent ({} bytes)",
        live.len()
    );
    if let Some(t) = exactly {
        assert_eq!(live, t, "an accepted commit makes its table live");
    }
}
