//! What `docs/protocol.md` forbids, refused by the host's decoder: copies of the reproducers
//! F5 and F6 of `../shared/repro/round2` (`frames.py` built them; kept in `tests/streams/` so
//! the tests do not need `../shared`).

use quatarm_wire::stream_decode::{Decoder, Inconsistency, Item};

fn decode(bytes: &[u8]) -> (Vec<Item>, quatarm_wire::stream_decode::Stats) {
    let mut d = Decoder::from_start();
    let items = d.push_all(bytes);
    (items, d.finish())
}

/// F5: a status of table state 8 (bad signature) or 1 (missing) with bit 0 set, and
/// coordinates: no point handed out, both counted inconsistent for their status word.
#[test]
fn f5_a_status_that_contradicts_itself_gives_no_coordinates() {
    let (items, s) = decode(include_bytes!("streams/f5-status-contradicts.bin"));
    let bad: Vec<(u16, Inconsistency)> = items
        .iter()
        .filter_map(|i| match i {
            Item::Inconsistent(r, why) => {
                assert_eq!(r.point, None);
                Some((r.status.0, *why))
            }
            _ => None,
        })
        .collect();
    assert_eq!(
        bad,
        [
            (0x0081, Inconsistency::Status),
            (0x0011, Inconsistency::Status)
        ]
    );
    assert_eq!((s.reports, s.points, s.inconsistent), (2, 0, 2));
    assert_eq!(s.damaged(), 0);
}

/// F6: a U95 option tag of 2 and a U95 varint that overflows a `u32` are no message: the
/// frames are refused (good CRC, undecodable), not read as "no U95".
#[test]
fn f6_a_u95_no_encoder_writes_refuses_the_frame() {
    let (items, s) = decode(include_bytes!("streams/f6-bad-u95.bin"));
    assert!(matches!(items[0], Item::Hello(_)), "{items:?}");
    assert_eq!((s.hellos, s.reports, s.points), (1, 0, 0), "{items:?}");
    assert_eq!((s.crc_errors, s.undecodable, s.other_errors), (0, 2, 2));
}

/// F6: a report of a probe the `Hello` does not list, and one with a zero direction: each
/// counted inconsistent and handed out without coordinates.
#[test]
fn f6_an_unlisted_probe_and_a_zero_direction_are_inconsistent() {
    let (items, s) = decode(include_bytes!("streams/f6-probe-dir.bin"));
    let why: Vec<Inconsistency> = items
        .iter()
        .filter_map(|i| match i {
            Item::Inconsistent(r, why) => {
                assert_eq!(r.point, None);
                Some(*why)
            }
            _ => None,
        })
        .collect();
    assert_eq!(
        why,
        [Inconsistency::UnknownProbe, Inconsistency::Direction],
        "{items:?}"
    );
    assert_eq!((s.reports, s.points, s.inconsistent), (2, 0, 2));
    assert_eq!(s.damaged(), 0);
}
