//! The conformance vectors of `docs/protocol.md` (`docs/protocol/vectors-v5.txt`: frames as hex
//! and what each must decode to, or be refused as), replayed through the host's decoder. The
//! file is the contract another implementation checks itself against; this test holds ours to
//! it, so `cargo test --workspace` (and `cargo xtask test`) fails when decoder and document part.

use quatarm::stream::{FrameError, Hello, ProbeAnswer, ProbeRefusal, Report, UpdateAnswer};
use quatarm::update::boot::FlashFault;
use quatarm::update::{Accepted, LayoutError, Refusal};
use quatarm_wire::stream_decode::{Decoder, Inconsistency, Item};

const VECTORS: &str = include_str!("../../docs/protocol/vectors-v5.txt");

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
        "hello protocol={} precision={} joints={} status={:#06x} live={live} probe={} probes={} number={} date={}",
        h.protocol,
        h.precision as u8,
        h.joints,
        h.status.0,
        h.probe,
        probes.join(","),
        h.number,
        h.date
    )
}

/// An update answer in the file's notation (every `Accepted` and `Refusal`, by name).
fn update(a: &UpdateAnswer) -> String {
    let words = match a {
        Ok(Accepted::Begun { slot }) => format!("begun slot={slot}"),
        Ok(Accepted::Chunk { next }) => format!("chunk next={next}"),
        Ok(Accepted::Committed { slot, seq }) => format!("committed slot={slot} seq={seq}"),
        Ok(Accepted::Aborted) => "aborted".into(),
        Err(r) => format!(
            "refused {}",
            match r {
                Refusal::NotBegun => "not-begun".into(),
                Refusal::BadLength(len) => format!("bad-length len={len}"),
                Refusal::OutOfOrder { expected } => format!("out-of-order expected={expected}"),
                Refusal::PastEnd { len } => format!("past-end len={len}"),
                Refusal::Incomplete { received, len } => {
                    format!("incomplete received={received} len={len}")
                }
                Refusal::Table(state) => format!("table state={}", state.code()),
                Refusal::NotAnnounced => "not-announced".into(),
                Refusal::Layout(e) => format!(
                    "layout {}",
                    match e {
                        LayoutError::Unaligned(r) => format!("unaligned region={r}"),
                        LayoutError::OutOfFlash(r) => format!("out-of-flash region={r}"),
                        LayoutError::SlotTooSmall(s) => format!("slot-too-small slot={s}"),
                        LayoutError::Overlap(a, b) => format!("overlap first={a} second={b}"),
                        LayoutError::WriteSizeTooLarge => "write-size-too-large".into(),
                    }
                ),
                Refusal::Flash(f) => format!(
                    "flash {}",
                    match f {
                        FlashFault::NotAligned => "not-aligned",
                        FlashFault::OutOfBounds => "out-of-bounds",
                        FlashFault::Other => "other",
                    }
                ),
                Refusal::SequenceExhausted => "sequence-exhausted".into(),
                Refusal::NotSupported => "not-supported".into(),
                Refusal::Rollback { live, offered } => {
                    format!("rollback live={live} offered={offered}")
                }
                Refusal::RetiredKey => "retired-key".into(),
            }
        ),
    };
    format!("update {words}")
}

/// A probe selection's answer in the file's notation.
fn probe(a: &ProbeAnswer) -> String {
    match a {
        Ok(id) => format!("probe mounted id={id}"),
        Err(ProbeRefusal::Unknown) => "probe refused unknown".into(),
        Err(ProbeRefusal::NoTable) => "probe refused no-table".into(),
    }
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
        Item::Hello(h) if (1..=quatarm::stream::PROTOCOL_VERSION).contains(&h.protocol) => hello(h),
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
        Item::Update(a) => update(a),
        Item::Probe(a) => probe(a),
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
        (10, 79),
        "streams and vectors in the file"
    );
}
