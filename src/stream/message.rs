//! The messages of the stream, one direction each.
//!
//! Both are enums so that a later protocol version can add a message without breaking the
//! ones that exist: postcard writes the variant index as a varint before the fields.

use serde::de::{Error as _, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::Status;
use crate::table::MAX_JOINTS;

/// Firmware to host.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ToHost {
    /// Sent once at boot and after every mode change: who is talking and in what state.
    Hello(Hello),
    /// One per reading: the corrected point, or the status saying why there is none.
    Report(Report),
}

/// What a hub announces at boot.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Hello {
    /// [`super::PROTOCOL_VERSION`] of the firmware.
    pub protocol: u16,
    /// The number format of the chain on this hub.
    pub precision: NumberFormat,
    /// Joint count of the loaded table (0 when there is no valid table).
    pub joints: u8,
    /// The boot check's verdict on the table (the same bits every report carries).
    pub status: Status,
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
}

/// A corrected probe-ball position and probe direction, in the base frame of the arm.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Coordinates {
    /// Ball centre in integer nanometres.
    pub xyz_nm: [i32; 3],
    /// Unit probe direction in units of 1e-9.
    pub dir_e9: [i32; 3],
}

/// Host to firmware.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ToDevice {
    /// A recorded reading to evaluate in place of the hub's own encoders (replay).
    Reading(Reading),
    /// Switch the output between binary frames and CSV text.
    SetMode(Mode),
    /// The recording is over: a QEMU hub exits, a real one goes back to its encoders.
    End,
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
    #[test]
    fn hello_carries_the_number_format_as_documented() {
        let hello = |precision| Hello {
            protocol: 1,
            precision,
            joints: 6,
            status: Status::default(),
        };
        let mut buf = [0u8; 16];
        let f32 = postcard::to_slice(&hello(NumberFormat::F32), &mut buf)
            .unwrap()
            .to_vec();
        let fixed = postcard::to_slice(&hello(NumberFormat::Fixed), &mut buf)
            .unwrap()
            .to_vec();
        assert_eq!(f32, [1, 0, 6, 0]);
        assert_eq!(fixed, [1, 1, 6, 0]);
    }
}
