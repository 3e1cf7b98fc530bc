//! The UART stream between an encoder hub and a host: framed binary messages both ways.
//!
//! Every message is one frame: the postcard encoding of a [`ToHost`] or [`ToDevice`] value,
//! then a CRC-32/ISCSI of those bytes (little-endian), the whole COBS-encoded and closed by a
//! single `0x00`. COBS guarantees that `0x00` occurs nowhere else, so a host that opens the port
//! mid-stream, or loses a byte, throws away at most the frame it is in and resynchronises on
//! the next delimiter; the CRC catches the corruption COBS alone cannot see.
//!
//! ```text
//!  one frame on the wire
//!  +----------------------------------------------------------+------+
//!  | COBS( postcard(message) ‖ CRC-32/ISCSI(postcard bytes) ) | 0x00 |
//!  +----------------------------------------------------------+------+
//!     no 0x00 inside                      4 bytes, LE            delimiter
//!
//!  ToHost::Report, the per-reading message (postcard: varints, zigzag for signed)
//!  +-----+---------+-----------+---------+-------+------------------------------+---------+
//!  | tag | seq u32 | time_us   | status  | point | xyz_nm [i32; 3],             | probe   |
//!  |  1  | varint  | u64 varint| u16 var | 0 / 1 | dir_e9 [i32; 3], u95_nm      | u8      |
//!  |     |         |           |         |       | 0 / 1 + u32 varint;          | (proto- |
//!  |     |         |           |         |       | present only when point is 1 | col 4)  |
//!  +-----+---------+-----------+---------+-------+------------------------------+---------+
//! ```
//!
//! Why integers, not f32 millimetres: the fixed-point chain resolves a few nanometres, while
//! an f32 near 1.5 m has a unit in the last place of 0.12 µm, which would throw away the
//! accuracy the chain worked for. Integer nanometres span ±2.1 m in an i32, more than any arm
//! of this class reaches, and the probe direction in units of 1e-9 keeps what the f32 and
//! fixed paths deliver (1e-6 and 1e-7). `docs/protocol.md` is the full specification.
//!
//! Decoding never panics on bytes from outside: a frame is checked (COBS, length, CRC, a
//! postcard decode that must consume every byte) before any field is used, and every failure
//! is a [`FrameError`] variant.

mod csv;
mod framing;
mod hub;
mod live;
mod message;
mod replay;
mod serve;
mod status;

pub use csv::{write_csv_header, write_csv_line, CSV_HEADER, MAX_CSV_LINE};
pub use framing::{
    decode, decode_message, encode, FrameError, FrameReader, CRC, MAX_FRAME, MAX_PAYLOAD,
};
pub use hub::{Hub, MAX_OUTPUT, RATED_TEMP_MC};
pub use live::{Live, TEMP_PERIOD_US, TEMP_STALE_POLLS};
pub use message::{
    Coordinates, Counts, Hello, LiveTable, Mode, NumberFormat, ProbeAnswer, ProbeRefusal, Reading,
    Report, ToDevice, ToDeviceOf, ToHost, Unread, UpdateAnswer,
};
pub use replay::{Event, Replay, StepReading};
pub use serve::{HubLoop, Measure, Reply, Then};
pub use status::{Status, TableState};

/// Protocol version carried in [`Hello`]; bumped on any incompatible change of a message.
/// Version 2 added the live table to `Hello`; version 3 the point's U95 to its coordinates;
/// version 4 the probes: the mounted probe's id in every report, the mounted probe and the
/// table's in `Hello`, `ToDevice::SelectProbe` answered by `ToHost::Probe`; version 5 the
/// live table's calibration number and date at the end of `Hello` (the other messages are
/// protocol 4's).
pub const PROTOCOL_VERSION: u16 = 5;
