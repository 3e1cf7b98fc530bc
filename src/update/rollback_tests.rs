//! Anti-rollback and key rotation (`docs/update.md`): a table whose calibration number is below
//! the hub's floor is refused, at every cut point of its update and after a reboot; a key
//! rotation cut at any point leaves the hub on the old key or the new one, never none; a table
//! signed by a retired key is refused. Both layouts.

use std::vec::Vec;

use super::boot::{Accept, Keys};
use super::fixtures::{
    boot_with, factory, layouts, numbered, public_key, signed, table, update_with,
};
use super::layout::Layout;
use super::mock::{Cut, MockFlash};
use super::record;
use super::session::{Accepted, Refusal};
use crate::stream::TableState;

const CUTS: [Cut; 4] = [
    Cut::Untouched,
    Cut::Done,
    Cut::Random(0x9e37_79b9),
    Cut::Random(7),
];

fn plain() -> Accept {
    Accept::joints(6)
}

/// A hub holding test key 1 (generation 0) and test key 2 as its next.
fn keyed() -> Accept {
    Accept::joints(6).signed_by_keys(Keys {
        generation: 0,
        current: public_key(1),
        next: Some(public_key(2)),
    })
}

/// `layout`'s flash with the table `t` (bytes, signed or not) live by a committed update
/// over a factory table `factory_t`.
fn with_live(layout: &Layout, accept: &Accept, factory_t: &[u8], t: &[u8]) -> MockFlash {
    let mut f = factory(factory_t);
    let got = update_with(layout, accept, &mut f, t);
    assert!(matches!(got, Ok(Accepted::Committed { .. })), "{got:?}");
    MockFlash::from_image(f.mem)
}

fn committed(r: Result<Accepted, Refusal>) -> bool {
    matches!(r, Ok(Accepted::Committed { .. }))
}

#[test]
fn a_lower_number_is_refused_an_equal_or_higher_one_committed() {
    for layout in layouts() {
        let t = |link, n| numbered(link, n);
        let mut f = with_live(&layout, &plain(), &t(100.0, 4), &t(110.0, 5));
        // Below the live number: refused with both numbers, the live table unchanged.
        assert_eq!(
            update_with(&layout, &plain(), &mut f, &t(120.0, 4)),
            Err(Refusal::Rollback {
                live: 5,
                offered: 4
            })
        );
        assert_eq!(boot_with(&layout, &plain(), &mut f), Some(t(110.0, 5)));
        // A version-3 table (no number: 0) is below too.
        let mut v3 = [0u8; crate::table::MAX_TABLE_LEN];
        let n = crate::table::tests::as_version_3(&t(120.0, 9), &mut v3);
        assert_eq!(
            update_with(&layout, &plain(), &mut f, &v3[..n]),
            Err(Refusal::Rollback {
                live: 5,
                offered: 0
            })
        );
        // The same number (a re-issue of the same calibration, another table) and a higher
        // one go live.
        assert!(committed(update_with(
            &layout,
            &plain(),
            &mut f,
            &t(130.0, 5)
        )));
        assert!(committed(update_with(
            &layout,
            &plain(),
            &mut f,
            &t(140.0, 6)
        )));
        assert_eq!(boot_with(&layout, &plain(), &mut f), Some(t(140.0, 6)));
        // The old values re-issued under a higher number: the deliberate downgrade.
        assert!(committed(update_with(
            &layout,
            &plain(),
            &mut f,
            &t(110.0, 7)
        )));
        // After a reboot (a fresh updater over the same bytes) the floor holds.
        let mut f = MockFlash::from_image(f.mem);
        assert_eq!(
            update_with(&layout, &plain(), &mut f, &t(140.0, 6)),
            Err(Refusal::Rollback {
                live: 7,
                offered: 6
            })
        );
        // A factory table's own number is the floor of a board without a record.
        let mut g = factory(&t(100.0, 3));
        assert_eq!(
            update_with(&layout, &plain(), &mut g, &t(120.0, 2)),
            Err(Refusal::Rollback {
                live: 3,
                offered: 2
            })
        );
        // Old tables on an old hub (all number 0) still update each other.
        let mut h = factory(&table(100.0));
        assert!(committed(update_with(
            &layout,
            &plain(),
            &mut h,
            &table(120.0)
        )));
    }
}

/// The floor lives in the state record, not only in the live table: a hub whose newest slot
/// was lost boots no table below the highest number it made live (the older record's slot
/// holds one), and still refuses a number below it; an older slot of the same number boots.
#[test]
fn a_slot_below_the_floor_is_not_made_live_at_boot() {
    for layout in layouts() {
        let mut f = with_live(&layout, &plain(), &numbered(100.0, 1), &numbered(110.0, 8));
        // Slot 1 (number 8) corrupted: slot 0 (number 1) is below the floor, so nothing boots.
        f.mem[3072 + 100] ^= 0xff;
        let mut f = MockFlash::from_image(f.mem);
        assert_eq!(boot_with(&layout, &plain(), &mut f), None, "{layout:?}");
        let mut buf = [0u8; crate::table::MAX_TABLE_LEN];
        match super::boot::live_slot(&mut f, &layout, &plain(), &mut buf) {
            Err(super::BootError::NoTable([why, _])) => {
                assert_eq!(
                    why,
                    super::boot::SlotError::BelowFloor {
                        number: 1,
                        floor: 8
                    }
                );
                assert_eq!(why.state(), TableState::Corrupt);
            }
            other => panic!("{layout:?}: {other:?}"),
        }
        assert_eq!(
            update_with(&layout, &plain(), &mut f, &numbered(120.0, 7)),
            Err(Refusal::Rollback {
                live: 8,
                offered: 7
            })
        );
        assert!(committed(update_with(
            &layout,
            &plain(),
            &mut f,
            &numbered(120.0, 8)
        )));
        assert_eq!(
            boot_with(&layout, &plain(), &mut f),
            Some(numbered(120.0, 8))
        );
        // The same number in the older slot is no rollback: it boots when the newest is lost.
        let mut g = with_live(&layout, &plain(), &numbered(100.0, 8), &numbered(110.0, 8));
        g.mem[3072 + 100] ^= 0xff;
        let mut g = MockFlash::from_image(g.mem);
        assert_eq!(
            boot_with(&layout, &plain(), &mut g),
            Some(numbered(100.0, 8)),
            "{layout:?}"
        );
    }
}

/// A refused rollback cut at every operation, then the live slot lost (corrupted) before the
/// reboot: the offered lower table, which from some cut on lies whole and valid in the other
/// slot, is never made live; the hub boots no table. Returns (cut points, of them those that
/// left the offered table whole in its slot).
fn lost_live_sweep(layout: &Layout, start: &MockFlash, offered: &[u8]) -> (usize, usize) {
    let mut clean = start.clone();
    assert!(update_with(layout, &plain(), &mut clean, offered).is_err());
    let total = clean.ops;
    // Uncut, the refused update leaves the offered table whole in the other slot.
    assert_eq!(clean.mem[..offered.len()], *offered);
    clean.mem[3072 + 100] ^= 0xff;
    let mut lost = MockFlash::from_image(clean.mem);
    assert_eq!(boot_with(layout, &plain(), &mut lost), None, "{layout:?}");
    let (mut tried, mut whole) = (0, 0);
    for cut in CUTS {
        for at in 0..total {
            let mut f = start.clone();
            f.cut = Some((at, cut));
            assert!(update_with(layout, &plain(), &mut f, offered).is_err());
            let mut mem = f.mem;
            whole += usize::from(mem[..offered.len()] == *offered);
            mem[3072 + 100] ^= 0xff;
            let mut rebooted = MockFlash::from_image(mem);
            tried += 1;
            assert_eq!(
                boot_with(layout, &plain(), &mut rebooted),
                None,
                "{layout:?}: cut at {at} of {total} ({cut:?}), live slot lost"
            );
        }
    }
    (tried, whole)
}

#[test]
fn a_lower_table_left_by_a_cut_update_never_boots() {
    let (old, live, offered) = (numbered(100.0, 2), numbered(110.0, 3), numbered(120.0, 2));
    for layout in layouts() {
        let start = with_live(&layout, &plain(), &old, &live);
        let (tried, whole) = lost_live_sweep(&layout, &start, &offered);
        std::println!(
            "boot floor, {}: {tried} cut points of a refused update with the live slot then lost, {whole} of them with the offered table whole in its slot, 0 boots on it",
            layout_name(&layout)
        );
        assert!(tried > 400 && whole > 0, "{tried} {whole}");
    }
}

/// Cuts the power at every operation of sending `offered` (a number below the live one's) to
/// a hub on `live`, reboots, and checks that it boots on `live` and refuses `offered` again.
/// Returns (cut points, boots on the live table).
fn rollback_sweep(
    layout: &Layout,
    start: &MockFlash,
    live: &[u8],
    offered: &[u8],
) -> (usize, usize) {
    let mut clean = start.clone();
    let refused = update_with(layout, &plain(), &mut clean, offered);
    assert!(
        matches!(refused, Err(Refusal::Rollback { .. })),
        "{refused:?}"
    );
    let total = clean.ops;
    let (mut tried, mut held) = (0, 0);
    for cut in CUTS {
        for at in 0..total {
            let mut f = start.clone();
            f.cut = Some((at, cut));
            assert!(update_with(layout, &plain(), &mut f, offered).is_err());
            let mut rebooted = MockFlash::from_image(f.mem);
            tried += 1;
            assert_eq!(
                boot_with(layout, &plain(), &mut rebooted).as_deref(),
                Some(live),
                "{layout:?}: cut at {at} of {total} ({cut:?})"
            );
            held += 1;
            assert_eq!(
                update_with(layout, &plain(), &mut rebooted, offered),
                refused,
                "{layout:?}: resent after the cut at {at} ({cut:?})"
            );
        }
    }
    (tried, held)
}

#[test]
fn a_rollback_is_refused_at_every_cut_point_and_after_a_reboot() {
    let (old, live) = (numbered(100.0, 2), numbered(110.0, 3));
    for layout in layouts() {
        let start = with_live(&layout, &plain(), &old, &live);
        let (tried, held) = rollback_sweep(&layout, &start, &live, &old);
        std::println!(
            "rollback, {:?}: {tried} cut points of a refused update, {held} boots on the live table, each refusing it again",
            layout_name(&layout)
        );
        assert_eq!(tried, held);
        assert!(tried > 400);
    }
}

fn layout_name(layout: &Layout) -> &'static str {
    match layout {
        Layout::Regions { .. } => "state copies of their own",
        Layout::Trailers { .. } => "state in the slots' trailers",
    }
}

/// The table bytes of a signed image (what a boot hands out).
fn body(image: &[u8]) -> Vec<u8> {
    image[..image.len() - crate::signature::SIGNATURE_LEN].to_vec()
}

#[test]
fn a_table_signed_by_the_next_key_rotates_and_the_old_key_is_retired() {
    for layout in layouts() {
        let a = signed(&numbered(100.0, 1), 1);
        let mut f = factory(&a);
        // Another key than the two: refused as a bad signature.
        assert_eq!(
            update_with(&layout, &keyed(), &mut f, &signed(&numbered(105.0, 2), 3)),
            Err(Refusal::Table(TableState::BadSignature))
        );
        // Signed by the next key: committed, and the record moves to generation 1.
        let b = signed(&numbered(110.0, 2), 2);
        assert!(committed(update_with(&layout, &keyed(), &mut f, &b)));
        let copies = record::read_copies(&mut f, &layout);
        assert_eq!(super::boot::key_generation(&keyed(), &copies), 1);
        // The retired key is refused by name, whatever the number; after a reboot too.
        let old_key = signed(&numbered(120.0, 9), 1);
        assert_eq!(
            update_with(&layout, &keyed(), &mut f, &old_key),
            Err(Refusal::RetiredKey)
        );
        let mut f = MockFlash::from_image(f.mem);
        assert_eq!(boot_with(&layout, &keyed(), &mut f), Some(body(&b)));
        assert_eq!(
            update_with(&layout, &keyed(), &mut f, &old_key),
            Err(Refusal::RetiredKey)
        );
        // The new key keeps working, with the floor.
        assert_eq!(
            update_with(&layout, &keyed(), &mut f, &signed(&numbered(120.0, 1), 2)),
            Err(Refusal::Rollback {
                live: 2,
                offered: 1
            })
        );
        assert!(committed(update_with(
            &layout,
            &keyed(),
            &mut f,
            &signed(&numbered(130.0, 3), 2)
        )));
        // An image built later with the next pair (generation 1 = key 2, next key 4) takes
        // the hub over; the one that knows only key 1 boots nothing (its key is retired).
        let later = Accept::joints(6).signed_by_keys(Keys {
            generation: 1,
            current: public_key(2),
            next: Some(public_key(4)),
        });
        assert_eq!(
            boot_with(&layout, &later, &mut f),
            Some(body(&signed(&numbered(130.0, 3), 2)))
        );
        assert_eq!(
            boot_with(&layout, &Accept::joints(6).signed_by(public_key(1)), &mut f),
            None
        );
    }
}

/// A rotation (the update of a table signed by the next key) cut at every operation: the hub
/// boots on the old table under the old key or on the new one under the new key, and the
/// key it is on signs the next update (never no key); once on the new key, the old is refused.
#[test]
fn a_rotation_cut_at_every_point_leaves_the_old_key_or_the_new() {
    let a = signed(&numbered(100.0, 1), 1);
    let b = signed(&numbered(110.0, 2), 2);
    for layout in layouts() {
        for start in [
            factory(&a),
            with_live(&layout, &keyed(), &a, &signed(&numbered(105.0, 1), 1)),
        ] {
            let old = boot_with(&layout, &keyed(), &mut start.clone()).expect("boots");
            let mut clean = start.clone();
            assert!(committed(update_with(&layout, &keyed(), &mut clean, &b)));
            let total = clean.ops;
            let (mut tried, mut on_old, mut on_new) = (0, 0, 0);
            for cut in CUTS {
                for at in 0..total {
                    let mut f = start.clone();
                    f.cut = Some((at, cut));
                    assert!(update_with(&layout, &keyed(), &mut f, &b).is_err());
                    let mut r = MockFlash::from_image(f.mem);
                    tried += 1;
                    let got = boot_with(&layout, &keyed(), &mut r);
                    let gen = super::boot::key_generation(
                        &keyed(),
                        &record::read_copies(&mut r, &layout),
                    );
                    let next_number = 3 + at as u32;
                    if got.as_deref() == Some(&old[..]) {
                        assert_eq!(gen, 0, "{layout:?} cut {at} ({cut:?}): old table, new key");
                        on_old += 1;
                        // Still on key 1: a table it signs goes live.
                        let mut g = MockFlash::from_image(r.mem.clone());
                        assert!(committed(update_with(
                            &layout,
                            &keyed(),
                            &mut g,
                            &signed(&numbered(120.0, next_number), 1)
                        )));
                    } else {
                        assert_eq!(
                            got,
                            Some(body(&b)),
                            "{layout:?} cut {at} ({cut:?}): no table"
                        );
                        assert_eq!(gen, 1, "{layout:?} cut {at} ({cut:?}): new table, old key");
                        on_new += 1;
                        let mut g = MockFlash::from_image(r.mem.clone());
                        assert_eq!(
                            update_with(
                                &layout,
                                &keyed(),
                                &mut g,
                                &signed(&numbered(120.0, next_number), 1)
                            ),
                            Err(Refusal::RetiredKey)
                        );
                        assert!(committed(update_with(
                            &layout,
                            &keyed(),
                            &mut g,
                            &signed(&numbered(120.0, next_number), 2)
                        )));
                    }
                }
            }
            std::println!(
                "rotation, {}: {tried} cut points of {total} operations: {on_old} boots on the old key, {on_new} on the new, 0 on none",
                layout_name(&layout)
            );
            assert_eq!(tried, on_old + on_new);
            assert!(on_old > 0 && on_new > 0);
        }
    }
}
