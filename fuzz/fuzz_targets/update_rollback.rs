//! Anti-rollback and key rotation of the update (`docs/update.md`) on the mock NOR flash,
//! driven by any program of steps: `Begin` of a signed table of calibration number 1 to 6 (the
//! factory table is number 3) signed by the hub's current key, its next key or a key it does
//! not hold, its chunks (in order, or with one bit flipped), `Commit`, `Abort`, a power cut
//! after any number of flash operations (leaving the operation under way untouched, done or
//! torn), and reboots. After every step a boot of a copy of the flash must come up on a table
//! a `Commit` was sent for (or the factory one), never below the floor (the highest number a
//! boot came up on or an accepted `Commit` made live; a commit cut while under way raises it
//! only once a boot shows it), never under a key the hub retired (once a table signed by the
//! next key went live) or one it never held. An accepted `Commit` never takes a table below
//! the floor, under a retired or an unknown key. Never a panic. The program's first byte picks
//! the layout: state copies of their own (even) or in the slots' trailers (odd).
#![no_main]

use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use quatarm::signature::SIGNATURE_LEN;
use quatarm::table::MAX_TABLE_LEN;
use quatarm::update::fixtures::{boot_with, factory, layouts, numbered, public_key, signed};
use quatarm::update::mock::{Cut, MockFlash};
use quatarm::update::session::{Accepted, Step, CHUNK_LEN};
use quatarm::update::{Accept, Keys, Layout, Updater};

/// Calibration numbers offered: 1 to `NUMBERS`.
const NUMBERS: u32 = 6;
/// The factory table's number.
const FACTORY_NUMBER: u32 = 3;
/// Test key seeds: the hub's current key (generation 0), its next key, a key it never held.
const KEYS: [u8; 3] = [1, 2, 3];
const CURRENT: usize = 0;
const NEXT: usize = 1;
const UNKNOWN: usize = 2;

/// A hub holding test key 1 (generation 0) and test key 2 as its next.
fn accept() -> Accept {
    Accept::joints(6).signed_by_keys(Keys {
        generation: 0,
        current: public_key(KEYS[CURRENT]),
        next: Some(public_key(KEYS[NEXT])),
    })
}

/// One signed table the program can send.
struct Image {
    number: u32,
    /// Index into [`KEYS`].
    key: usize,
    /// The table followed by its signature.
    signed: Vec<u8>,
}

impl Image {
    /// The table bytes (what a boot hands out).
    fn body(&self) -> &[u8] {
        &self.signed[..self.signed.len() - SIGNATURE_LEN]
    }
}

/// Every (number, key) pair, signed once per process (signing is slow next to a step). The
/// link length differs per pair, so a table's bytes tell which pair it is.
fn images() -> &'static [Image] {
    static IMAGES: OnceLock<Vec<Image>> = OnceLock::new();
    IMAGES.get_or_init(|| {
        let mut all = Vec::new();
        for number in 1..=NUMBERS {
            for (key, &seed) in KEYS.iter().enumerate() {
                let link = 100.0 + 10.0 * f64::from(number) + key as f64;
                all.push(Image {
                    number,
                    key,
                    signed: signed(&numbered(link, number), seed),
                });
            }
        }
        all
    })
}

fn image_of(number: u32, key: usize) -> &'static Image {
    &images()[(number as usize - 1) * KEYS.len() + key]
}

/// What the program has established about the hub.
struct Model {
    /// No table below this number may boot or be committed.
    floor: u32,
    /// The hub moved to the next key: a table under the current one is retired.
    rotated: bool,
    /// Tables (bodies) that may be live: the factory one and each one a `Commit` was sent for.
    may_be_live: Vec<Vec<u8>>,
}

fuzz_target!(|program: &[u8]| {
    let [regions, trailers] = layouts();
    let layout = match program.first() {
        Some(b) if b & 1 == 1 => trailers,
        _ => regions,
    };
    let program = program.get(1..).unwrap_or_default();
    let first = image_of(FACTORY_NUMBER, CURRENT);
    let mut flash = factory(&first.signed);
    let mut up = Updater::new(layout.clone(), accept());
    let mut scratch = [0u8; MAX_TABLE_LEN];
    let mut model = Model {
        floor: FACTORY_NUMBER,
        rotated: false,
        may_be_live: vec![first.body().to_vec()],
    };
    // The image the last `Begin` announced, and the bytes accepted since.
    let mut offered: &Image = first;
    let mut sent: Vec<u8> = Vec::new();
    let mut bytes = program.iter().copied();
    while let Some(op) = bytes.next() {
        let arg = bytes.next().unwrap_or(0);
        let step = match op % 7 {
            0 => {
                let number = u32::from(arg) % NUMBERS + 1;
                let key = usize::from(arg / NUMBERS as u8) % KEYS.len();
                offered = image_of(number, key);
                Step::sequence(&offered.signed).next().expect("a Begin")
            }
            1 | 2 => {
                let image = &offered.signed;
                let at = sent.len().min(image.len());
                let end = (at + usize::from(arg) % CHUNK_LEN + 1).min(image.len());
                let mut chunk = image[at..end].to_vec();
                if op % 7 == 2 {
                    // One bit flipped: the table or its signature damaged in transit.
                    let bit = usize::from(bytes.next().unwrap_or(0));
                    if let Some(b) = chunk.get_mut(bit / 8 % (end - at).max(1)) {
                        *b ^= 1 << (bit % 8);
                    }
                }
                Step::Chunk {
                    offset: at as u32,
                    bytes: heapless::Vec::from_slice(&chunk).expect("fits"),
                }
            }
            3 => Step::Commit,
            4 => Step::Abort,
            5 => {
                let cut = match bytes.next().unwrap_or(0) % 3 {
                    0 => Cut::Untouched,
                    1 => Cut::Done,
                    k => Cut::Random(u64::from(arg) << 8 | u64::from(k)),
                };
                flash.cut = Some((flash.ops + usize::from(arg % 64), cut));
                continue;
            }
            _ => {
                // Reboot: the flash as the cut left it, powered again; a new updater.
                flash = MockFlash::from_image(flash.mem.clone());
                up = Updater::new(layout.clone(), accept());
                sent.clear();
                check_boot(&layout, &flash, &mut model);
                continue;
            }
        };
        if step == Step::Commit {
            let body = &sent[..sent.len().saturating_sub(SIGNATURE_LEN)];
            model.may_be_live.push(body.to_vec());
        }
        let result = up.step(&mut flash, &mut scratch, &step);
        match (&step, result) {
            (Step::Begin { .. }, Ok(_)) => sent.clear(),
            (Step::Chunk { bytes: b, .. }, Ok(Accepted::Chunk { next })) => {
                sent.extend_from_slice(b);
                assert_eq!(next as usize, sent.len(), "next offset is the count so far");
            }
            (_, Ok(Accepted::Committed { .. })) => {
                let image = identify(&sent[..sent.len().saturating_sub(SIGNATURE_LEN)])
                    .expect("a committed table is one of the signed images, undamaged");
                assert_eq!(image.signed, sent, "committed with its own signature");
                assert!(
                    image.number >= model.floor,
                    "committed number {} below the floor {}",
                    image.number,
                    model.floor
                );
                assert!(
                    image.key != CURRENT || !model.rotated,
                    "committed a table signed by the retired key"
                );
                assert!(
                    image.key != UNKNOWN,
                    "committed a table signed by a key the hub never held"
                );
                let live = check_boot(&layout, &flash, &mut model);
                assert_eq!(
                    live,
                    image.body(),
                    "an accepted commit makes its table live"
                );
                continue;
            }
            _ => {}
        }
        check_boot(&layout, &flash, &mut model);
    }
});

/// The signed image whose table is `body`.
fn identify(body: &[u8]) -> Option<&'static Image> {
    images().iter().find(|i| i.body() == body)
}

/// A boot of a copy of `flash` comes up on a table a commit was sent for, at or above the
/// floor, under a key the hub holds and has not retired; what it shows raises the floor and
/// records a rotation. Returns the live table.
fn check_boot(layout: &Layout, flash: &MockFlash, model: &mut Model) -> Vec<u8> {
    let mut copy = MockFlash::from_image(flash.mem.clone());
    let live = boot_with(layout, &accept(), &mut copy).expect("a boot always finds a table");
    assert!(
        model.may_be_live.iter().any(|t| *t == live),
        "the boot came up on a table no commit sent ({} bytes)",
        live.len()
    );
    let image = identify(&live).expect("a live table is one of the signed images");
    assert!(
        image.number >= model.floor,
        "booted number {} below the floor {}",
        image.number,
        model.floor
    );
    assert!(
        image.key != CURRENT || !model.rotated,
        "booted a table signed by the retired key"
    );
    assert!(
        image.key != UNKNOWN,
        "booted a table signed by a key the hub never held"
    );
    model.floor = model.floor.max(image.number);
    model.rotated |= image.key == NEXT;
    live
}
