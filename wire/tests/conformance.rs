//! The conformance vectors of `docs/protocol.md` (`docs/protocol/vectors-v4.txt`: frames as hex
//! and what each must decode to, or be refused as), replayed through the host's decoder. The
//! file is the contract another implementation checks itself against; this test holds ours to
//! it, so `cargo test --workspace` (and `cargo xtask test`) fails when decoder and document part.

use quatarm::stream::{FrameError, Hello, Report};
use quatarm_wire::stream_decode::{Decoder, Inconsistency, Item};

const VECTORS: &str = include_str!("../../docs/protocol/vectors-v4.txt");

fn hex(s: &str) -> Vec<u8> {
    assert!(s.len().is_multiple_of(2), "odd hex {s}");
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&s[i..i + 2], 16).expect("hex"))
        .collect()
}

fn hello(h: &Hello) -> String {
    let live = match h.live {
        Some(l) => format!("{}/{}/{:#010x}", l.slot, l.seq, l.crc),
        None => "none".into(),
    };
    let probes: Vec<String> = h.probes.iter().map(u8::to_string).collect();
    format!(
        "hello protocol={} precision={} joints={} status={:#06x} live={live} probe={} probes={}",
        h.protocol,
        h.precision as u8,
        h.joints,
        h.status.0,
        h.probe,
        probes.join(",")
    )
}

fn report(r: &Report) -> String {
    let point = match r.point {
        Some(p) => {
            let join = |v: [i32; 3]| v.map(|c| c.to_string()).join(",");
            let u95 = p.u95_nm.map_or("none".into(), |u| u.to_string());
            format!("{}/{}/{u95}", join(p.xyz_nm), join(p.dir_e9))
        }
        None => "none".into(),
    };
    format!(
        "report seq={} time_us={} status={:#06x} point={point} probe={}",
        r.seq, r.time_us, r.status.0, r.probe
    )
}

/// One item in the file's notation.
fn render(item: &Item) -> String {
    match item {
        Item::Hello(h) if (1..=4).contains(&h.protocol) => hello(h),
        Item::Hello(h) => format!("foreign-hello protocol={}", h.protocol),
        Item::Report(r) => report(r),
        Item::Backward {
            report: r,
            expected,
        } => {
            format!("backward expected={expected} {}", report(r))
        }
        Item::Repeated(r) => format!("repeated seq={}", r.seq),
        Item::Inconsistent(r, why) => {
            let why = match why {
                Inconsistency::Status => "status",
                Inconsistency::Forbidden => "forbidden",
                Inconsistency::Missing => "missing",
                Inconsistency::UnknownProbe => "probe",
                Inconsistency::Direction => "direction",
            };
            format!("inconsistent({why}) {}", report(r))
        }
        Item::Update(a) => format!("update {a:?}"),
        Item::Probe(a) => format!("probe {a:?}"),
        Item::Damaged(e) => format!(
            "refused {}",
            match e {
                FrameError::Crc => "crc",
                FrameError::Decode => "undecodable",
                FrameError::Cobs => "cobs",
                FrameError::TooShort => "short",
                FrameError::Overflow => "overflow",
                _ => "other",
            }
        ),
    }
}

#[test]
fn the_decoder_gives_what_the_conformance_vectors_say() {
    let (mut vectors, mut streams) = (0, 0);
    for block in VECTORS.split("\n\n") {
        let mut d = Decoder::from_start();
        let mut any = false;
        for (n, line) in block.lines().enumerate() {
            if line.starts_with('#') || line.is_empty() {
                continue;
            }
            any = true;
            vectors += 1;
            let (bytes, want) = line.split_once(' ').unwrap_or((line, ""));
            let got: Vec<String> = d.push_all(&hex(bytes)).iter().map(render).collect();
            let got = got.join(" | ");
            if want == "refused unterminated" {
                assert_eq!(got, "", "line {n} of a block: {line}");
                assert!(d.finish().unterminated_bytes > 0, "{line}");
            } else {
                assert_eq!(got, want, "line {n} of the block starting {block:.60}");
            }
        }
        streams += usize::from(any);
    }
    // The file is not empty or cut: every stream of make_vectors.py is there.
    assert_eq!(
        (streams, vectors),
        (8, 47),
        "streams and vectors in the file"
    );
}
