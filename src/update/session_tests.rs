//! The update's answers: each wrong step refused with its reason, and the old table live
//! after every refusal.

use super::boot::FlashFault;
use super::boot::{Accept, BootError};
use super::fixtures::{boot, crc_of, factory, layout, steps, table, table_with_budget, update};
use super::live_table;
use super::session::{Accepted, Refusal, Step, Updater, CHUNK_LEN};
use crate::stream::TableState;
use crate::table::{TableError, MAX_TABLE_LEN};

fn chunk(offset: u32, bytes: &[u8]) -> Step {
    Step::Chunk {
        offset,
        bytes: heapless::Vec::from_slice(bytes).expect("chunk fits"),
    }
}

#[test]
fn out_of_order_steps_are_refused() {
    let (a, b) = (table(100.0), table(120.0));
    let mut f = factory(&a);
    let mut up = Updater::new(layout(), Accept::joints(6));
    let mut s = [0u8; MAX_TABLE_LEN];
    assert_eq!(
        up.step(&mut f, &mut s, &chunk(0, &b[..8])),
        Err(Refusal::NotBegun)
    );
    assert_eq!(
        up.step(&mut f, &mut s, &Step::Commit),
        Err(Refusal::NotBegun)
    );
    assert_eq!(
        up.step(&mut f, &mut s, &Step::Begin { len: 1000, crc: 0 }),
        Err(Refusal::BadLength(1000))
    );
    let begin = Step::Begin {
        len: b.len() as u32,
        crc: crc_of(&b),
    };
    assert_eq!(
        up.step(&mut f, &mut s, &begin),
        Ok(Accepted::Begun { slot: 1 })
    );
    assert_eq!(
        up.step(&mut f, &mut s, &chunk(4, &b[4..8])),
        Err(Refusal::OutOfOrder { expected: 0 })
    );
    assert_eq!(
        up.step(&mut f, &mut s, &chunk(0, &b[..6])),
        Ok(Accepted::Chunk { next: 6 })
    );
    // The refused chunk did not end the update: the next one at the right offset is taken.
    let n = b.len() as u32;
    assert_eq!(
        up.step(&mut f, &mut s, &chunk(6, &[0; 48])),
        Ok(Accepted::Chunk { next: 54 })
    );
    assert_eq!(
        up.step(&mut f, &mut s, &Step::Commit),
        Err(Refusal::Incomplete {
            received: 54,
            len: n
        })
    );
    // The refused commit ended the update; the old table is live.
    assert_eq!(
        up.step(&mut f, &mut s, &chunk(54, &[0; 4])),
        Err(Refusal::NotBegun)
    );
    assert!(boot(&mut f).as_deref() == Some(&a[..]));
    up.step(&mut f, &mut s, &begin).unwrap();
    for st in &steps(&b)[1..steps(&b).len() - 1] {
        up.step(&mut f, &mut s, st).unwrap();
    }
    assert_eq!(
        up.step(&mut f, &mut s, &chunk(n, &[0])),
        Err(Refusal::PastEnd { len: n })
    );
    assert_eq!(
        up.step(&mut f, &mut s, &Step::Commit),
        Ok(Accepted::Committed { slot: 1, seq: 1 })
    );
    assert!(boot(&mut f).as_deref() == Some(&b[..]));
}

/// A table that is not what was announced, or fails a check of the boot, is never made live.
#[test]
fn bad_tables_are_refused_at_commit() {
    let (a, b) = (table(100.0), table(120.0));
    let send = |t: &[u8], crc: u32| {
        let mut f = factory(&a);
        let mut up = Updater::new(layout(), Accept::joints(6));
        let mut s = [0u8; MAX_TABLE_LEN];
        let mut st = steps(t);
        st[0] = Step::Begin {
            len: t.len() as u32,
            crc,
        };
        let mut last = Ok(Accepted::Aborted);
        for x in &st {
            last = up.step(&mut f, &mut s, x);
        }
        assert!(
            boot(&mut f).as_deref() == Some(&a[..]),
            "old table stays live"
        );
        last
    };
    // One byte changed: the table's own CRC fails.
    let mut t = b.clone();
    t[100] ^= 1;
    assert_eq!(
        send(&t, crc_of(&b)),
        Err(Refusal::Table(TableState::Corrupt))
    );
    // A valid table, but another CRC announced.
    assert_eq!(send(&b, crc_of(&b) ^ 1), Err(Refusal::NotAnnounced));
    // Blank bytes.
    let blank = std::vec![0xffu8; b.len()];
    assert_eq!(send(&blank, 0), Err(Refusal::Table(TableState::Missing)));
}

/// A table for another joint count than the hub drives is refused, as the boot refuses it.
#[test]
fn wrong_joint_count_is_refused() {
    let (a, b) = (table(100.0), table(120.0));
    let mut f = factory(&a);
    let mut up = Updater::new(layout(), Accept::joints(7));
    let mut s = [0u8; MAX_TABLE_LEN];
    let mut last = Ok(Accepted::Aborted);
    for x in &steps(&b) {
        last = up.step(&mut f, &mut s, x);
    }
    assert_eq!(last, Err(Refusal::Table(TableState::WrongJointCount)));
}

/// Updates alternate slots and count up; a flash that lost power is reported as a fault.
#[test]
fn updates_alternate_slots() {
    let mut f = factory(&table(100.0));
    for (k, link) in [110.0, 120.0, 130.0, 140.0].into_iter().enumerate() {
        let t = table(link);
        assert_eq!(
            update(&mut f, &t),
            Ok(Accepted::Committed {
                slot: (1 - k % 2) as u8,
                seq: k as u32 + 1
            })
        );
        assert!(boot(&mut f).as_deref() == Some(&t[..]));
    }
    f.cut = Some((f.ops, super::mock::Cut::Untouched));
    assert_eq!(
        update(&mut f, &table(150.0)),
        Err(Refusal::Flash(FlashFault::Other))
    );
}

/// The boot falls back when the slot the newest record names does not verify: to the slot of
/// the older record, else to any valid slot; with no valid table it says what each slot holds.
#[test]
fn boot_falls_back_past_a_bad_slot() {
    use super::boot::{BootError, SlotError};
    use super::live_table;
    let (a, b, c) = (table(100.0), table(120.0), table(140.0));
    let mut f = factory(&a);
    update(&mut f, &b).unwrap(); // slot 1, seq 1
    update(&mut f, &c).unwrap(); // slot 0, seq 2
    let mut buf = [0u8; MAX_TABLE_LEN];
    let live = live_table(&mut f, &layout(), &Accept::joints(6), &mut buf).unwrap();
    assert_eq!((live.slot, live.seq), (0, Some(2)));
    f.mem[300] ^= 0x04; // slot 0 corrupt: record 1's slot
    let live = live_table(&mut f, &layout(), &Accept::joints(6), &mut buf).unwrap();
    assert_eq!((live.slot, live.seq), (1, Some(1)));
    assert!(live.table.bytes() == &b[..]);
    f.mem[6144] ^= 0x01; // and record 1 (copy 0) torn: slot 1 by its contents
    let live = live_table(&mut f, &layout(), &Accept::joints(6), &mut buf).unwrap();
    assert_eq!((live.slot, live.seq), (1, None));
    f.mem[3072 + 40] ^= 0x01; // slot 1 corrupt too: nothing
    assert!(matches!(
        live_table(&mut f, &layout(), &Accept::joints(6), &mut buf),
        Err(BootError::NoTable([
            SlotError::Table(TableError::Crc { .. }),
            SlotError::Table(_)
        ]))
    ));
}

#[test]
fn layouts_that_do_not_fit_are_refused() {
    use super::layout::{Layout, LayoutError};
    let f = factory(&table(100.0));
    let ok = layout();
    assert_eq!(ok.check(&f), Ok(()));
    let regions = |slots: [core::ops::Range<u32>; 2], state: [core::ops::Range<u32>; 2]| {
        Layout::Regions { slots, state }
    };
    let (s, st) = ([0..3072, 3072..6144], [6144..7168, 7168..8192]);
    let l = regions(s.clone(), [6144..7168, 7168..8000]);
    assert_eq!(l.check(&f), Err(LayoutError::Unaligned(3)));
    let l = regions([0..3072, 1024..4096], st.clone());
    assert_eq!(l.check(&f), Err(LayoutError::Overlap(0, 1)));
    let l = regions([8192..9216, 3072..6144], st.clone());
    assert_eq!(l.check(&f), Err(LayoutError::SlotTooSmall(0)));
    let l = regions(s.clone(), [6144..7168, 9216..10240]);
    assert_eq!(l.check(&f), Err(LayoutError::OutOfFlash(3)));
    let l = regions(s.clone(), [6144..7168, 3072..4096]);
    assert_eq!(l.check(&f), Err(LayoutError::Overlap(1, 3)));

    // The state in the slots' trailers: only the slots are regions, and a slot must hold the
    // largest plain table before its trailer.
    let trailers = |slots| Layout::Trailers { slots };
    assert_eq!(trailers(s.clone()).check(&f), Ok(()));
    assert_eq!(
        trailers([0..3072, 3072..5120]).check(&f),
        Err(LayoutError::SlotTooSmall(1))
    );
    assert_eq!(
        trailers([0..3072, 1024..4096]).check(&f),
        Err(LayoutError::Overlap(0, 1))
    );
    assert_eq!(
        trailers([0..3072, 8192..11264]).check(&f),
        Err(LayoutError::OutOfFlash(1))
    );
    assert_eq!(
        trailers([0..3000, 3072..6144]).check(&f),
        Err(LayoutError::Unaligned(0))
    );
}

/// In the trailers, a table ends 28 bytes (the record, in 4-byte write units) before its
/// slot, and each copy is the end of its slot.
#[test]
fn the_trailer_is_the_slot_end() {
    use super::layout::Layout;
    use super::mock::MockFlash;
    let l = super::fixtures::trailer_layout();
    assert_eq!(Layout::trailer_len::<MockFlash>(), 28);
    assert_eq!(l.table_area::<MockFlash>(0), 0..3044);
    assert_eq!(l.table_area::<MockFlash>(1), 3072..6116);
    assert_eq!(l.state::<MockFlash>(0), 3044..3072);
    assert_eq!(l.state::<MockFlash>(1), 6116..6144);
    let r = super::fixtures::layout();
    assert_eq!(r.table_area::<MockFlash>(1), 3072..6144);
    assert_eq!(r.state::<MockFlash>(1), 7168..8192);
}

/// In the trailers, a record is only believed in the trailer of the slot it names (no update
/// writes another), and an update's `Begin` erases the older record with its slot.
#[test]
fn trailer_records_name_their_own_slot() {
    use super::fixtures::{boot_in, trailer_layout, update_in};
    use super::record::{self, StateRecord};
    let l = trailer_layout();
    let (a, b, c) = (table(100.0), table(120.0), table(140.0));
    let mut f = factory(&a);
    assert_eq!(
        update_in(&l, &mut f, &b),
        Ok(Accepted::Committed { slot: 1, seq: 1 })
    );
    let rec = record::read_copies(&mut f, &l);
    assert_eq!(rec[0], None);
    assert_eq!(rec[1].map(|r| (r.slot, r.seq)), Some((1, 1)));
    assert_eq!(
        update_in(&l, &mut f, &c),
        Ok(Accepted::Committed { slot: 0, seq: 2 })
    );
    let rec = record::read_copies(&mut f, &l);
    assert_eq!(
        rec.map(|r| r.map(|r| (r.slot, r.seq))),
        [Some((0, 2)), Some((1, 1))]
    );
    assert!(boot_in(&l, &mut f).as_deref() == Some(&c[..]));
    // A record naming slot 1 written into slot 0's trailer is not a record.
    let mut g = factory(&a);
    let bytes = StateRecord {
        seq: 9,
        slot: 1,
        len: b.len() as u32,
        crc: crc_of(&b),
        floor: 0,
        key_gen: 0,
    }
    .encode();
    g.mem[3072 - bytes.len()..3072].copy_from_slice(&bytes);
    assert_eq!(record::read_copies(&mut g, &l), [None, None]);
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

    /// Any sequence of steps (right or wrong lengths, CRCs, offsets, bytes) never panics, and
    /// the boot is always on the old table or on one whose commit was accepted.
    #[test]
    fn arbitrary_steps_never_leave_a_bad_table(
        ops in proptest::collection::vec((0u8..40, 0u32..2000, proptest::collection::vec(proptest::num::u8::ANY, 0..48)), 0..200)
    ) {
        let (a, b) = (table(100.0), table(120.0));
        for layout in super::fixtures::layouts() {
        let mut f = factory(&a);
        let mut up = Updater::new(layout.clone(), Accept::joints(6));
        let mut s = [0u8; MAX_TABLE_LEN];
        let mut committed = false;
        let mut next = 0u32;
        for (kind, n, bytes) in ops.clone() {
            let step = match kind {
                // Mostly the right next chunk, so that some updates reach their commit.
                0 => Step::Begin { len: b.len() as u32, crc: if n % 2 == 0 { crc_of(&b) } else { n } },
                // The right next bytes of `b`, or the given ones at a given offset.
                4.. => {
                    let at = next as usize;
                    let end = (at + CHUNK_LEN).min(b.len());
                    chunk(next, &b[at.min(end)..end])
                }
                1 => chunk(n, &bytes),
                2 => Step::Commit,
                _ => Step::Abort,
            };
            match up.step(&mut f, &mut s, &step) {
                Ok(Accepted::Begun { .. }) => next = 0,
                Ok(Accepted::Chunk { next: x }) => next = x,
                Ok(Accepted::Committed { .. }) => committed = true,
                _ => {}
            }
            let got = super::fixtures::boot_in(&layout, &mut f);
            let ok = got.as_deref() == Some(&a[..]) || (committed && got.as_deref() == Some(&b[..]));
            proptest::prop_assert!(ok, "boot on neither the old nor a committed table");
        }
        }
    }
}

/// A hub told its encoders' resolution refuses, at commit, a table made for others (the
/// status word's `WrongResolution`), keeps the old one live, and boots past such a slot.
#[test]
fn a_table_for_other_encoders_is_refused() {
    use super::fixtures::table_for_encoders;
    let (a, b, c) = (
        table(100.0), // 2^14 counts per revolution
        table_for_encoders(120.0, 1 << 12),
        table(140.0),
    );
    let own = Accept::joints(6).for_encoders(&[1 << 14; 6]);
    let mut f = factory(&a);
    let mut buf = [0u8; MAX_TABLE_LEN];
    let mut send = |t: &[u8]| {
        let mut up = Updater::new(layout(), own);
        let mut s = [0u8; MAX_TABLE_LEN];
        let mut last = Ok(Accepted::Aborted);
        for st in &steps(t) {
            last = up.step(&mut f, &mut s, st);
        }
        let live = live_table(&mut f, &layout(), &own, &mut buf).map(|l| l.table.crc());
        (last, live)
    };
    assert_eq!(
        send(&b),
        (
            Err(Refusal::Table(TableState::WrongResolution)),
            Ok(crc_of(&a))
        )
    );
    let (answer, live) = send(&c);
    assert_eq!(answer, Ok(Accepted::Committed { slot: 1, seq: 1 }));
    assert_eq!(live, Ok(crc_of(&c)));
    // A board whose only table is for other encoders boots on none, and says why.
    let mut g = factory(&b);
    match live_table(&mut g, &layout(), &own, &mut buf) {
        Err(BootError::NoTable(why)) => assert_eq!(why[0].state(), TableState::WrongResolution),
        r => panic!("{:?}", r.map(|l| l.slot)),
    }
    // Joint 6 on another encoder is enough to refuse a table.
    let mut counts = [1 << 14; 6];
    counts[5] = 1 << 16;
    let odd = Accept::joints(6).for_encoders(&counts);
    assert!(live_table(&mut factory(&a), &layout(), &odd, &mut buf).is_err());
}

#[test]
fn a_table_with_its_budget_is_an_update_like_any_other() {
    // `armcal calibrate` writes the budget into the table: 80 bytes longer than the plain one,
    // and a length `Begin` must accept (it refused it once, as a length no table has).
    let (a, b) = (table(100.0), table_with_budget(120.0));
    assert_eq!(b.len(), a.len() + crate::table::budget::LEN);
    let mut f = factory(&a);
    let r = update(&mut f, &b);
    assert!(matches!(r, Ok(Accepted::Committed { .. })), "{r:?}");
    let live = boot(&mut f).expect("a live table");
    assert_eq!(live, b);
    let t = crate::table::Table::parse(&live).expect("it parses");
    assert!(t.budget().is_some());
    // And back to a table without one.
    assert!(matches!(update(&mut f, &a), Ok(Accepted::Committed { .. })));
    assert_eq!(boot(&mut f).as_deref(), Some(&a[..]));
}

/// A hub with a key commits only a table signed under it: unsigned, another key's and a
/// changed signature byte are refused with the state a boot would give, and the old table
/// stays live; a boot with the key refuses an unsigned factory table.
#[test]
fn only_a_table_signed_under_the_hub_key_is_committed() {
    use super::fixtures::{public_key, signed};
    let (a, b) = (signed(&table(100.0), 1), table(120.0));
    let accept = Accept::joints(6).signed_by(public_key(1));
    let mut f = factory(&a);
    let mut buf = [0u8; MAX_TABLE_LEN];
    assert_eq!(
        live_table(&mut f, &layout(), &accept, &mut buf)
            .unwrap()
            .slot,
        0
    );
    let mut send = |image: &[u8]| {
        let mut up = Updater::new(layout(), accept);
        let mut s = [0u8; MAX_TABLE_LEN];
        let mut last = Ok(Accepted::Aborted);
        for step in Step::sequence(image) {
            last = up.step(&mut f, &mut s, &step);
        }
        let live = live_table(&mut f, &layout(), &accept, &mut s).map(|l| l.table.crc());
        (last, live)
    };
    let crc_a = crc_of(&table(100.0));
    let crc_b = crc_of(&b);
    assert_eq!(
        send(&b),
        (Err(Refusal::Table(TableState::Unsigned)), Ok(crc_a))
    );
    assert_eq!(
        send(&signed(&b, 2)),
        (Err(Refusal::Table(TableState::BadSignature)), Ok(crc_a))
    );
    let mut bad = signed(&b, 1);
    let last = bad.len() - 1;
    bad[last] ^= 0x40;
    assert_eq!(
        send(&bad),
        (Err(Refusal::Table(TableState::BadSignature)), Ok(crc_a))
    );
    let (answer, live) = send(&signed(&b, 1));
    assert!(
        matches!(answer, Ok(Accepted::Committed { slot: 1, .. })),
        "{answer:?}"
    );
    assert_eq!(live, Ok(crc_b));

    // An unsigned factory table does not boot on a hub with a key; it does without one.
    let mut f = factory(&table(100.0));
    match live_table(&mut f, &layout(), &accept, &mut buf) {
        Err(BootError::NoTable(why)) => assert_eq!(why[0].state(), TableState::Unsigned),
        other => panic!("{:?}", other.map(|l| l.slot)),
    }
    assert!(live_table(&mut f, &layout(), &Accept::joints(6), &mut buf).is_ok());
}
