//! The host's decoder of hub→host `ToHost` frames (`armcal::stream_decode`, what `armcal
//! decode` runs): any bytes, read from the start and joined mid-stream. Never a panic; no
//! report handed out with coordinates its status forbids; every frame accounted for in the
//! counts, probe answers (protocol 4) and reports of every protocol included. The document's
//! rules on what a report may carry (`docs/protocol.md`, "What a decoder refuses"): every
//! point handed out has a coherent status with no fault, a unit direction, and a probe the
//! last `Hello` of protocol 4 or 5 lists; nothing handed out breaks them.
#![no_main]

use armcal::stream_decode::{is_unit_direction, Decoder, Item};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    for mut decoder in [Decoder::from_start(), Decoder::joining()] {
        let items = decoder.push_all(bytes);
        let s = decoder.finish();
        let (mut reports, mut points, mut damaged, mut hellos) = (0u64, 0u64, 0u64, 0u64);
        let mut probe_answers = 0u64;
        // The probes the last `Hello` of protocol 4 or 5 listed ([0] for none), as the document says.
        let mut listed: Option<Vec<u8>> = None;
        for item in &items {
            match item {
                Item::Damaged(_) => damaged += 1,
                Item::Hello(h) => {
                    hellos += 1;
                    listed = (4..=5).contains(&h.protocol).then(|| {
                        if h.probes.is_empty() {
                            vec![0]
                        } else {
                            h.probes.to_vec()
                        }
                    });
                }
                Item::Probe(_) => probe_answers += 1,
                _ => {}
            }
            if let Some(r) = item.report() {
                reports += 1;
                if r.point.is_some() {
                    points += 1;
                    assert!(
                        r.status.is_measurement() && r.status.is_coherent(),
                        "coordinates beside {:?}",
                        r.status
                    );
                    let p = r.point.expect("a point");
                    assert!(is_unit_direction(p.dir_e9), "direction {:?}", p.dir_e9);
                    if let Some(ids) = &listed {
                        assert!(ids.contains(&r.probe), "probe {} of {ids:?}", r.probe);
                    }
                }
            }
        }
        assert_eq!((s.reports, s.points, s.hellos), (reports, points, hellos));
        assert_eq!(s.probe_answers, probe_answers);
        assert_eq!(s.crc_errors + s.other_errors, damaged);
        assert_eq!(s.valid_frames() + damaged, items.len() as u64);
        assert!(s.skipped_bytes + s.unterminated_bytes <= bytes.len() as u64);
    }
});
