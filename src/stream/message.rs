//! The messages of the stream, one direction each.
//!
//! Both are enums so that a later protocol version can add a message without breaking the
//! ones that exist: postcard writes the variant index as a varint before the fields.

use serde::de::{Error as _, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::Status;
use crate::table::probes::MAX_PROBES;
use crate::table::MAX_JOINTS;
use crate::update::session::{Accepted, Refusal, Step};

/// Firmware to host.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ToHost {
    /// Sent once at boot and after every mode change: who is talking and in what state.
    Hello(Hello),
    /// One per reading: the corrected point, or the status saying why there is none.
    Report(Report),
    /// The answer to one [`ToDevice::Update`] step: carried out, or refused and why.
    Update(UpdateAnswer),
    /// The answer to a [`ToDevice::SelectProbe`] (protocol 4): the id of the probe now
    /// mounted, or why the selection was refused (and the probe mounted before stays).
    Probe(ProbeAnswer),
}

/// What a hub answers to an update step (`docs/update.md`).
pub type UpdateAnswer = Result<Accepted, Refusal>;

/// What a hub answers to a probe selection: the id now mounted, or why not.
pub type ProbeAnswer = Result<u8, ProbeRefusal>;

/// Why a hub refused to mount a probe. Nothing changes: the probe mounted before stays.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ProbeRefusal {
    /// The hub's table holds no probe of this id (or, which a table the hub booted on never
    /// gives, one its chain's numbers cannot hold: the boot checks the arm's reach with the
    /// longest probe).
    Unknown,
    /// The hub has no valid table, so no probe at all.
    NoTable,
}

/// What a hub announces at boot.
///
/// It decodes from protocols 1 to 4 too (without `live` before protocol 2, read as `None`;
/// without the probes before protocol 4, read as probe 0 of none announced; without the
/// calibration's number and date before protocol 5, read as 0, unknown): the version is its
/// first field, so a host tells the layouts apart before it reads the rest. It serialises
/// in the layout of [`super::PROTOCOL_VERSION`] whatever `protocol` says: a hub sends only
/// its own version.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Hello {
    /// [`super::PROTOCOL_VERSION`] of the firmware.
    pub protocol: u16,
    /// The number format of the chain on this hub.
    pub precision: NumberFormat,
    /// Joint count of the loaded table (0 when there is no valid table).
    pub joints: u8,
    /// The boot check's verdict on the table (the same bits every report carries).
    pub status: Status,
    /// Which table is live (protocols 2 to 4): `None` when there is no valid table.
    pub live: Option<LiveTable>,
    /// The id of the probe mounted (protocol 4): the table's first at boot and after an
    /// update, then the last one selected; 0 without a valid table.
    pub probe: u8,
    /// The ids of every probe the table holds, the first first (protocol 4; empty without a
    /// valid table).
    pub probes: heapless::Vec<u8, MAX_PROBES>,
    /// The live table's calibration number (protocol 5; [`crate::table::Release`]): what the
    /// hub's anti-rollback compares, so a host sees which calibration it measures with. 0
    /// without a valid table and for a table of format 3, which has none.
    pub number: u32,
    /// The live table's calibration date as the decimal number YYYYMMDD (protocol 5); 0
    /// unknown (no valid table, a format-3 table, or none given).
    pub date: u32,
}

// By hand: heapless's `defmt` support is for defmt 0.3, the firmware's is 1.
#[cfg(feature = "defmt")]
impl defmt::Format for Hello {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(
            f,
            "Hello protocol {=u16}, precision {}, joints {=u8}, status {}, live {}, probe {=u8}, probes {=[u8]}, number {=u32}, date {=u32}",
            self.protocol,
            self.precision,
            self.joints,
            self.status,
            self.live,
            self.probe,
            self.probes.as_slice(),
            self.number,
            self.date
        )
    }
}

impl<'de> Deserialize<'de> for Hello {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Hello, D::Error> {
        struct HelloVisitor;
        impl<'de> Visitor<'de> for HelloVisitor {
            type Value = Hello;
            fn expecting(&self, f: &mut core::fmt::Formatter) -> core::fmt::Result {
                f.write_str("a Hello of protocol 1 to 5")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Hello, A::Error> {
                let missing = |i| A::Error::invalid_length(i, &self);
                let protocol: u16 = seq.next_element()?.ok_or_else(|| missing(0))?;
                let precision = seq.next_element()?.ok_or_else(|| missing(1))?;
                let joints = seq.next_element()?.ok_or_else(|| missing(2))?;
                let status = seq.next_element()?.ok_or_else(|| missing(3))?;
                // Every version starts with these four; protocols 2 to 5 have `live` after
                // them, protocols 4 and 5 the probes after it, protocol 5 the calibration's
                // number and date last (a Hello of another version decodes as far as these
                // four go, for a host to say which version it met).
                let live = if (2..=5).contains(&protocol) {
                    seq.next_element()?.ok_or_else(|| missing(4))?
                } else {
                    None
                };
                let (mut probe, mut probes) = (0, heapless::Vec::new());
                if (4..=5).contains(&protocol) {
                    probe = seq.next_element()?.ok_or_else(|| missing(5))?;
                    probes = seq.next_element()?.ok_or_else(|| missing(6))?;
                }
                let (mut number, mut date) = (0, 0);
                if protocol == 5 {
                    number = seq.next_element()?.ok_or_else(|| missing(7))?;
                    date = seq.next_element()?.ok_or_else(|| missing(8))?;
                }
                Ok(Hello {
                    protocol,
                    precision,
                    joints,
                    status,
                    live,
                    probe,
                    probes,
                    number,
                    date,
                })
            }
        }
        const FIELDS: &[&str] = &[
            "protocol",
            "precision",
            "joints",
            "status",
            "live",
            "probe",
            "probes",
            "number",
            "date",
        ];
        deserializer.deserialize_struct("Hello", FIELDS, HelloVisitor)
    }
}

/// The table a hub runs on, as its `Hello` names it: a host sees from it which calibration
/// is in use after a boot or an update, without reading the flash.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LiveTable {
    /// The flash slot it lies in (0 or 1, `docs/update.md`).
    pub slot: u8,
    /// The sequence number of the state record naming it; 0 when none does (a table flashed
    /// by a debug probe, found by its contents).
    pub seq: u32,
    /// The table's own CRC-32 (its last four bytes), which `armcal table build` prints.
    pub crc: u32,
}

/// The number format a hub evaluates the chain in, as [`Hello`] announces it (the variant
/// index is the wire value: 0 f32, 1 fixed point). On the firmware side the formats are types
/// ([`crate::F32`], [`crate::Fixed`]); this enum only names one on the wire.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NumberFormat {
    /// f32 on an FPU.
    F32,
    /// Fixed point, for cores without an FPU.
    Fixed,
}

/// One reading's outcome.
///
/// Protocol 4 added `probe`, last: a decoder of protocols 1 to 3 finds a byte left over in
/// every report of protocol 4 and refuses the frame rather than misreading it (the probe
/// before the point could, in one case, be read as an older report's option tag). A host
/// reads a report by the protocol of the last `Hello` (`armcal decode`: older reports were
/// all of the only probe an older table had, id 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Report {
    /// Counts every report the hub sends, wrapping at 2^32: a host sees a gap as lost frames.
    pub seq: u32,
    /// Time of the reading on the hub's clock, microseconds since boot.
    pub time_us: u64,
    /// Why `point` is or is not there.
    pub status: Status,
    /// The corrected point; `None` whenever the status has a fault.
    pub point: Option<Coordinates>,
    /// The id of the probe mounted at the reading (the point is its ball's centre); 0
    /// without a valid table.
    pub probe: u8,
}

/// A corrected probe-ball position and probe direction, in the base frame of the arm, and
/// the position's expanded uncertainty.
///
/// It decodes from protocols 1 and 2 too, which end it after `dir_e9`: a report is the last
/// thing in its frame, so a frame that ends there is an older hub's (`u95_nm` `None`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Coordinates {
    /// Ball centre in integer nanometres.
    pub xyz_nm: [i32; 3],
    /// Unit probe direction in units of 1e-9.
    pub dir_e9: [i32; 3],
    /// U95 (protocol 3): the radius, in nanometres rounded up, of the sphere about the
    /// centre that holds the true centre with 95 % probability (`spec/uncertainty.md`).
    /// `None` where the hub's table carries no uncertainty budget or the hub does not
    /// compute it (the fixed-point boards).
    pub u95_nm: Option<u32>,
}

impl<'de> Deserialize<'de> for Coordinates {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Coordinates, D::Error> {
        struct CoordinatesVisitor;
        impl<'de> Visitor<'de> for CoordinatesVisitor {
            type Value = Coordinates;
            fn expecting(&self, f: &mut core::fmt::Formatter) -> core::fmt::Result {
                f.write_str("coordinates of protocol 1, 2 or 3")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Coordinates, A::Error> {
                let missing = |i| A::Error::invalid_length(i, &self);
                let xyz_nm = seq.next_element()?.ok_or_else(|| missing(0))?;
                let dir_e9 = seq.next_element()?.ok_or_else(|| missing(1))?;
                // Protocol 3's field, or the end of an older frame (protocols 1 and 2): see
                // `U95Field`. (A frame whose bytes do not end here fails the decoder's
                // every-byte-consumed check.)
                let u95_nm = seq.next_element::<U95Field>()?.and_then(|f| f.0);
                Ok(Coordinates {
                    xyz_nm,
                    dir_e9,
                    u95_nm,
                })
            }
        }
        const FIELDS: &[&str] = &["xyz_nm", "dir_e9", "u95_nm"];
        deserializer.deserialize_struct("Coordinates", FIELDS, CoordinatesVisitor)
    }
}

/// `Coordinates::u95_nm` as it decodes: `Option<u32>`, or nothing at all where an older hub's
/// frame ends. Only the end of the input reads as "no field": the option's tag is read as the
/// raw byte postcard writes it as, so a tag other than 0 or 1, or a varint that overflows a
/// `u32`, refuses the frame instead of passing for an older hub's "no U95" (F6 of
/// `../shared/repro/round2`).
struct U95Field(Option<u32>);

impl<'de> Deserialize<'de> for U95Field {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<U95Field, D::Error> {
        struct U95Visitor;
        impl<'de> Visitor<'de> for U95Visitor {
            type Value = U95Field;
            fn expecting(&self, f: &mut core::fmt::Formatter) -> core::fmt::Result {
                f.write_str("an option tag of 0 or 1, then a u32 after 1")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<U95Field, A::Error> {
                match seq.next_element::<u8>() {
                    Err(_) | Ok(None) | Ok(Some(0)) => Ok(U95Field(None)),
                    Ok(Some(1)) => Ok(U95Field(Some(
                        seq.next_element::<u32>()?
                            .ok_or_else(|| A::Error::invalid_length(1, &self))?,
                    ))),
                    Ok(Some(tag)) => Err(A::Error::invalid_value(
                        serde::de::Unexpected::Unsigned(u64::from(tag)),
                        &self,
                    )),
                }
            }
        }
        // Postcard writes a tuple as its fields in a row: the tag, then the value.
        deserializer.deserialize_tuple(2, U95Visitor)
    }
}

/// Host to firmware.
pub type ToDevice = ToDeviceOf<Step>;

/// Host to firmware, with the update steps as `S`: [`Step`] ([`ToDevice`]), or, on a hub
/// without an update port, [`Unread`] (`super::Replay::without_update`), so that its image
/// holds no decoder of steps it would only refuse.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ToDeviceOf<S> {
    /// A recorded reading to evaluate in place of the hub's own encoders (replay).
    Reading(Reading),
    /// Switch the output between binary frames and CSV text.
    SetMode(Mode),
    /// The recording is over: a QEMU hub exits, a real one goes back to its encoders.
    End,
    /// One step of a calibration update over the stream (`docs/update.md`); answered by
    /// [`ToHost::Update`].
    Update(S),
    /// Mount the probe of this id (protocol 4); answered by [`ToHost::Probe`]. The selection
    /// holds until another or a reboot (which mounts the table's first probe).
    SelectProbe(u8),
}

/// The variant index of [`ToDeviceOf::Update`] on the wire: what a hub without an update port
/// recognises an update step by, without decoding it.
pub(super) const UPDATE_INDEX: u8 = 3;

/// An update step not decoded: what a hub without an update port makes of one (it answers
/// `NotSupported` from the frame's variant index alone). It never decodes from bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Unread;

impl<'de> Deserialize<'de> for Unread {
    fn deserialize<D: Deserializer<'de>>(_: D) -> Result<Unread, D::Error> {
        Err(D::Error::custom("an update step this hub does not read"))
    }
}

/// The hub's output format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Mode {
    /// COBS frames of [`ToHost`], for programs.
    Binary,
    /// One CSV line per report (see [`super::write_csv_line`]), for a person at a terminal.
    Text,
}

/// A recorded encoder reading: what a hub's encoders would have given at one instant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Reading {
    /// The recording's own sequence number (not checked by the hub; for the host's matching).
    pub seq: u32,
    /// Raw encoder counts, joint 1 first.
    pub counts: Counts,
    /// Arm temperature in milli-degrees Celsius.
    pub temp_mc: i32,
    /// Encoder faults recorded with the reading, bit j for joint j + 1.
    pub faults: u8,
}

/// Up to [`MAX_JOINTS`](crate::table::MAX_JOINTS) encoder counts. On the wire it is a postcard sequence (varint length,
/// then the counts), exactly like a slice; decoding refuses more than that.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Counts {
    len: u8,
    values: [u32; MAX_JOINTS],
}

impl Counts {
    /// The counts of `values`; `None` if there are more than
    /// [`MAX_JOINTS`](crate::table::MAX_JOINTS).
    pub fn new(values: &[u32]) -> Option<Counts> {
        if values.len() > MAX_JOINTS {
            return None;
        }
        let mut c = Counts {
            len: values.len() as u8,
            values: [0; MAX_JOINTS],
        };
        c.values[..values.len()].copy_from_slice(values);
        Some(c)
    }

    /// The counts, joint 1 first.
    pub fn as_slice(&self) -> &[u32] {
        // `len` is at most MAX_JOINTS by construction (new and deserialize both check it).
        &self.values[..usize::from(self.len).min(MAX_JOINTS)]
    }
}

impl Serialize for Counts {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        // A length-prefixed sequence without needing `collect_seq` (which wants an iterator
        // of references and an allocator-free `serialize_seq`).
        use serde::ser::SerializeSeq;
        let values = self.as_slice();
        let mut seq = serializer.serialize_seq(Some(values.len()))?;
        for v in values {
            seq.serialize_element(v)?;
        }
        seq.end()
    }
}

impl<'de> Deserialize<'de> for Counts {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Counts, D::Error> {
        struct CountsVisitor;
        impl<'de> Visitor<'de> for CountsVisitor {
            type Value = Counts;
            fn expecting(&self, f: &mut core::fmt::Formatter) -> core::fmt::Result {
                f.write_str("at most 7 encoder counts")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Counts, A::Error> {
                let mut c = Counts::default();
                while let Some(v) = seq.next_element::<u32>()? {
                    if usize::from(c.len) == MAX_JOINTS {
                        return Err(A::Error::invalid_length(MAX_JOINTS + 1, &self));
                    }
                    c.values[usize::from(c.len)] = v;
                    c.len += 1;
                }
                Ok(c)
            }
        }
        deserializer.deserialize_seq(CountsVisitor)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `docs/protocol.md`'s `Hello`: the number format is one byte after the protocol varint,
    /// 0 for f32 and 1 for fixed point. The enum's name is not on the wire; its order is.
    /// Protocol 4's probes follow `live`: the mounted id, then the ids as a sequence;
    /// protocol 5's calibration number and date follow them, two `u32` varints.
    #[test]
    fn hello_carries_the_number_format_and_the_probes_as_documented() {
        let hello = |precision| Hello {
            protocol: 5,
            precision,
            joints: 6,
            status: Status::default(),
            live: None,
            probe: 9,
            probes: heapless::Vec::from_slice(&[4, 9, 0]).unwrap(),
            number: 300,
            date: 20261204,
        };
        // 300 = 0xac 0x02; 20261204 = 0x0135_2954 = 0xd4 0xd2 0xd4 0x09.
        let tail = [0xac, 0x02, 0xd4, 0xd2, 0xd4, 0x09];
        let mut buf = [0u8; 24];
        let f32 = postcard::to_slice(&hello(NumberFormat::F32), &mut buf)
            .unwrap()
            .to_vec();
        let fixed = postcard::to_slice(&hello(NumberFormat::Fixed), &mut buf)
            .unwrap()
            .to_vec();
        assert_eq!(f32[..10], [5, 0, 6, 0, 0, 9, 3, 4, 9, 0]);
        assert_eq!(fixed[..10], [5, 1, 6, 0, 0, 9, 3, 4, 9, 0]);
        assert_eq!((&f32[10..], &fixed[10..]), (&tail[..], &tail[..]));
        assert_eq!(
            postcard::from_bytes::<Hello>(&f32).unwrap(),
            hello(NumberFormat::F32)
        );
        // More than eight ids: refused.
        let nine = [5, 0, 6, 0, 0, 9, 9, 1, 2, 3, 4, 5, 6, 7, 8, 9, 0, 0];
        assert!(postcard::from_bytes::<Hello>(&nine).is_err());
    }

    /// Hellos of protocols 1 to 3 (no `live` before 2, no probes before 4) still decode, each
    /// as far as its version goes; protocol 4's round-trips.
    #[test]
    fn hello_decodes_from_every_protocol() {
        let v1: Hello = postcard::from_bytes(&[1, 0, 6, 1]).unwrap();
        assert_eq!((v1.protocol, v1.joints, v1.live), (1, 6, None));
        assert_eq!(
            (v1.probe, v1.probes.len(), v1.number, v1.date),
            (0, 0, 0, 0)
        );
        let live = Some(LiveTable {
            slot: 1,
            seq: 7,
            crc: 0xdead_beef,
        });
        let v5 = Hello {
            protocol: 5,
            precision: NumberFormat::Fixed,
            joints: 6,
            status: Status(Status::TABLE_VALID),
            live,
            probe: 3,
            probes: heapless::Vec::from_slice(&[3]).unwrap(),
            number: 7,
            date: 20261204,
        };
        let mut buf = [0u8; 40];
        let bytes = postcard::to_slice(&v5, &mut buf).unwrap().to_vec();
        assert_eq!(postcard::from_bytes::<Hello>(&bytes).unwrap(), v5);
        // The number (1 byte) and the date (4) are the last 5 bytes.
        let v4_len = bytes.len() - 5;
        let mut v4 = bytes[..v4_len].to_vec();
        v4[0] = 4;
        let h = postcard::from_bytes::<Hello>(&v4).unwrap();
        assert_eq!((h.protocol, h.live, h.probe), (4, live, 3));
        assert_eq!((h.number, h.date), (0, 0));
        // Protocols 2 and 3: the same bytes without the probes (3 more).
        for v in [2, 3] {
            let mut old = bytes[..v4_len - 3].to_vec();
            old[0] = v;
            let h = postcard::from_bytes::<Hello>(&old).unwrap();
            assert_eq!(
                (h.protocol, h.live, h.probe, h.probes.len()),
                (u16::from(v), live, 0, 0)
            );
            // With them, a byte is left over: not a Hello of that protocol.
            let mut more = v4.clone();
            more[0] = v;
            assert!(!matches!(
                postcard::take_from_bytes::<Hello>(&more),
                Ok((_, []))
            ));
        }
        // Protocol 5's bytes under protocol 4: five left over, no Hello of 4.
        let mut more = bytes.clone();
        more[0] = 4;
        assert!(!matches!(
            postcard::take_from_bytes::<Hello>(&more),
            Ok((_, []))
        ));
        // A protocol-2 Hello cut before `live` is refused, not read as protocol 1; so is a
        // protocol-4 one cut before its probes and a protocol-5 one cut before its date or
        // its number.
        assert!(postcard::from_bytes::<Hello>(&[2, 0, 6, 1]).is_err());
        assert!(postcard::from_bytes::<Hello>(&v4[..v4.len() - 3]).is_err());
        assert!(postcard::from_bytes::<Hello>(&bytes[..bytes.len() - 4]).is_err());
        assert!(postcard::from_bytes::<Hello>(&bytes[..v4_len]).is_err());
    }

    /// A probe answer as `docs/protocol.md` spells it: `ToHost::Probe` 3, `Ok` 0 and the id,
    /// or `Err` 1 and the refusal (0 unknown, 1 no table); `ToDevice::SelectProbe` 4 and the
    /// id; an update step starts with [`UPDATE_INDEX`].
    #[test]
    fn the_probe_messages_are_encoded_as_documented() {
        let mut buf = [0u8; 16];
        let to = |m: &ToHost, buf: &mut [u8]| postcard::to_slice(m, buf).unwrap().to_vec();
        assert_eq!(to(&ToHost::Probe(Ok(7)), &mut buf), [3, 0, 7]);
        assert_eq!(
            to(&ToHost::Probe(Err(ProbeRefusal::Unknown)), &mut buf),
            [3, 1, 0]
        );
        assert_eq!(
            to(&ToHost::Probe(Err(ProbeRefusal::NoTable)), &mut buf),
            [3, 1, 1]
        );
        let select = postcard::to_slice(&ToDevice::SelectProbe(200), &mut buf).unwrap();
        assert_eq!(select, [4, 200]);
        let abort = postcard::to_slice(&ToDevice::Update(Step::Abort), &mut buf).unwrap();
        assert_eq!(abort, [UPDATE_INDEX, 3]);
    }

    /// An update answer as `docs/protocol.md` spells it: `ToHost::Update` 2, `Err` 1,
    /// `Refusal::Table` 5, the table state's code (2, corrupt).
    #[test]
    fn an_update_answer_is_encoded_as_documented() {
        use crate::stream::TableState;
        let mut buf = [0u8; 16];
        let msg = ToHost::Update(Err(Refusal::Table(TableState::Corrupt)));
        assert_eq!(postcard::to_slice(&msg, &mut buf).unwrap(), [2, 1, 5, 2]);
        let ok = ToHost::Update(Ok(Accepted::Committed { slot: 1, seq: 3 }));
        assert_eq!(postcard::to_slice(&ok, &mut buf).unwrap(), [2, 0, 2, 1, 3]);
    }

    /// The longest update message (a full chunk at an offset past any slot) fits a frame.
    #[test]
    fn a_full_update_chunk_fits_a_frame() {
        let step = Step::Chunk {
            offset: (1 << 21) - 1,
            bytes: heapless::Vec::from_slice(&[0xa5; crate::update::session::CHUNK_LEN]).unwrap(),
        };
        let mut out = [0u8; crate::stream::MAX_FRAME];
        let n = crate::stream::encode(&ToDevice::Update(step.clone()), &mut out).unwrap();
        let got: ToDevice = crate::stream::decode(&mut out[..n - 1]).unwrap();
        assert_eq!(got, ToDevice::Update(step));
    }
}
