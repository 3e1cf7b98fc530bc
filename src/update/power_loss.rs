//! Power loss at every operation of an update, and of the state record's write alone, in
//! both layouts (state copies of their own, and in the slots' trailers): after each cut the
//! flash is rebooted and must come up on the old table or the new one, byte for byte (never a
//! mix, never none), and a retried update must then succeed.

use super::fixtures::{boot_in, crc_of, factory, layouts, table, update_in};
use super::layout::Layout;
use super::mock::{Cut, MockFlash};
use super::record::{self, StateRecord};
use super::session::Accepted;

const CUTS: [Cut; 4] = [
    Cut::Untouched,
    Cut::Done,
    Cut::Random(0x9e37_79b9),
    Cut::Random(7),
];

/// Cuts the power at every operation of `run` on `start` (for each kind of cut), reboots,
/// and checks the boot (on `layout`) and a retried update. Returns (cut points, boots on a
/// valid table, operations of the uncut run).
fn sweep(
    layout: &Layout,
    start: &MockFlash,
    old: &[u8],
    new: &[u8],
    run: &dyn Fn(&mut MockFlash) -> bool,
) -> (usize, usize, usize) {
    let boot = |f: &mut MockFlash| boot_in(layout, f);
    let mut clean = start.clone();
    assert!(run(&mut clean), "the uncut run succeeds");
    let total = clean.ops;
    assert!(boot(&mut clean).as_deref() == Some(new));
    let (mut tried, mut valid) = (0, 0);
    for cut in CUTS {
        let (mut saw_old, mut saw_new) = (false, false);
        for at in 0..total {
            let mut f = start.clone();
            f.cut = Some((at, cut));
            assert!(
                !run(&mut f),
                "{layout:?}: cut at {at} of {total} ({cut:?}) stops the run"
            );
            let mut rebooted = MockFlash::from_image(f.mem);
            tried += 1;
            let got = boot(&mut rebooted);
            let is_old = got.as_deref() == Some(old);
            let is_new = got.as_deref() == Some(new);
            assert!(
                is_old || is_new,
                "{layout:?}: cut at {at} of {total} ({cut:?}): no valid table"
            );
            valid += 1;
            saw_old |= is_old;
            saw_new |= is_new;
            // Only the last operation (the word holding the record's CRC) can make the new
            // table live.
            if at + 1 < total {
                assert!(
                    is_old,
                    "{layout:?}: cut at {at} of {total} ({cut:?}): new table before its record"
                );
            }
            if at + 1 == total {
                match cut {
                    Cut::Untouched => assert!(is_old),
                    Cut::Done => assert!(is_new),
                    Cut::Random(_) => {}
                }
            }
            // A retried update (after the reboot, from the start) succeeds.
            let mut retry = MockFlash::from_image(rebooted.mem.clone());
            assert!(
                matches!(
                    update_in(layout, &mut retry, new),
                    Ok(Accepted::Committed { .. })
                ),
                "{layout:?}: retry after cut at {at} ({cut:?})"
            );
            assert!(boot(&mut retry).as_deref() == Some(new));
        }
        assert!(saw_old, "{cut:?}: some cut leaves the old table");
        if cut == Cut::Done {
            assert!(saw_new, "{cut:?}: the last cut leaves the new table");
        }
    }
    (tried, valid, total)
}

/// A short name of a layout for the printed counts.
fn name(layout: &Layout) -> &'static str {
    match layout {
        Layout::Regions { .. } => "state copies of their own",
        Layout::Trailers { .. } => "state in the slots' trailers",
    }
}

#[test]
fn power_loss_at_every_operation_of_an_update() {
    let (a, b, c) = (table(100.0), table(120.0), table(140.0));
    for layout in layouts() {
        // First update of a factory board (no record yet), then the next one (a record in
        // place, the other slot and the other record copy written).
        let first = factory(&a);
        let (t1, v1, n1) = sweep(&layout, &first, &a, &b, &|f| {
            update_in(&layout, f, &b).is_ok()
        });
        let mut second = first.clone();
        assert_eq!(
            update_in(&layout, &mut second, &b),
            Ok(Accepted::Committed { slot: 1, seq: 1 })
        );
        let second = MockFlash::from_image(second.mem);
        let (t2, v2, n2) = sweep(&layout, &second, &b, &c, &|f| {
            update_in(&layout, f, &c).is_ok()
        });
        let mut third = second.clone();
        assert_eq!(
            update_in(&layout, &mut third, &c),
            Ok(Accepted::Committed { slot: 0, seq: 2 })
        );
        std::println!(
            "update, {}: {} cut points tried, {} boots on a valid table (first update {t1}/{v1} of {n1} operations, next {t2}/{v2} of {n2})",
            name(&layout),
            t1 + t2,
            v1 + v2
        );
        assert_eq!((t1, t2), (v1, v2));
    }
}

#[test]
fn power_loss_at_every_operation_of_the_state_record() {
    let (a, b) = (table(100.0), table(120.0));
    for layout in layouts() {
        // Slot 0 live by record 1; slot 1 holds a complete, checked new table.
        let mut start = factory(&a);
        let rec = |seq, slot, t: &[u8]| StateRecord {
            seq,
            slot,
            len: t.len() as u32,
            crc: crc_of(t),
            floor: 0,
            key_gen: 0,
        };
        record::write(&mut start, &layout, &rec(1, 0, &a)).expect("record 1");
        start.mem[3072..3072 + b.len()].copy_from_slice(&b);
        let start = MockFlash::from_image(start.mem);
        let (tried, valid, n) = sweep(&layout, &start, &a, &b, &|f| {
            record::write(f, &layout, &rec(2, 1, &b)).is_ok()
        });
        std::println!(
            "state record, {}: {tried} cut points tried ({n} operations), {valid} boots on a valid table",
            name(&layout)
        );
        assert_eq!(tried, valid);
    }
}
