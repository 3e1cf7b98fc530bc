//! The state record: which slot holds the live table. Two copies, each in an erase unit of
//! its own (as embassy-boot keeps its state partition apart from the images) or each in the
//! trailer of its slot ([`Layout::Trailers`]); a new record always goes into the copy that
//! does not hold the newest valid one, so a torn erase or write spoils only the copy being
//! written and the previous record still stands. In the trailers that copy is the new
//! table's slot's, which the update's `Begin` erased with the slot.
//!
//! ```text
//! offset size field (little-endian)
//!      0    4 magic "QAST"
//!      4    4 sequence number (the highest valid one wins)
//!      8    1 slot (0 or 1)
//!      9    1 key generation: which of the maker's keys the hub trusts (never goes down)
//!     10    2 reserved, 0
//!     12    4 table length in bytes
//!     16    4 table CRC-32 (the table's own last four bytes)
//!     20    4 floor: the highest calibration number ever made live (the anti-rollback
//!             counter; never goes down)
//!     24    4 CRC-32 (ISO-HDLC) of bytes 0..24
//! ```
//!
//! The floor and the key generation are persisted in the same record, in the same write, as
//! the slot they came with: a power cut leaves the previous record (previous table, previous
//! floor, previous key) or the new one, never a new table with an old floor. MCUboot keeps
//! its security counter apart from the image swap and its users report it raised before an
//! interrupted upgrade was confirmed (`docs/update.md`, "Anti-rollback"); here they cannot
//! part. The magic is `QAS2`: a record of the 24-byte format (`QAST`) is no record.
//!
//! Its CRC is written in the same flash write as the rest, after it in address order; a cut
//! that leaves any part unwritten, or bits of an erase, fails the CRC (erased flash, all
//! 0xFF, and zeros fail the magic first).

use embedded_storage::nor_flash::NorFlash;

use super::layout::{Layout, MAX_WRITE_SIZE};
use crate::table::CRC;

/// The record's magic bytes.
pub const MAGIC: [u8; 4] = *b"QAS2";
/// Encoded length of a record.
pub const RECORD_LEN: usize = 28;

/// The record as written on a flash of write unit `F::WRITE_SIZE`: padded with 0xFF to whole
/// write units, so that its one write touches nothing else (in the trailers, the table).
pub const fn padded_len<F: NorFlash>() -> usize {
    RECORD_LEN.div_ceil(F::WRITE_SIZE) * F::WRITE_SIZE
}

/// What a valid state record says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StateRecord {
    /// Sequence number: one more than the newest record before it.
    pub seq: u32,
    /// The live slot (0 or 1).
    pub slot: u8,
    /// The table's length in bytes.
    pub len: u32,
    /// The table's CRC-32 (its last four bytes, over everything before them).
    pub crc: u32,
    /// The highest calibration number made live on this hub: an update offering a lower one
    /// is refused (`Refusal::Rollback`).
    pub floor: u32,
    /// The generation of the maker's key the hub trusts ([`super::boot::Keys`]); it only
    /// grows, when a table signed by the next key is committed.
    pub key_gen: u8,
}

impl StateRecord {
    /// The record's bytes.
    pub fn encode(&self) -> [u8; RECORD_LEN] {
        let mut b = [0u8; RECORD_LEN];
        b[0..4].copy_from_slice(&MAGIC);
        b[4..8].copy_from_slice(&self.seq.to_le_bytes());
        b[8] = self.slot;
        b[9] = self.key_gen;
        b[12..16].copy_from_slice(&self.len.to_le_bytes());
        b[16..20].copy_from_slice(&self.crc.to_le_bytes());
        b[20..24].copy_from_slice(&self.floor.to_le_bytes());
        let crc = CRC.checksum(&b[..24]);
        b[24..28].copy_from_slice(&crc.to_le_bytes());
        b
    }

    /// The record in `b`, or `None` if these bytes are not a whole, valid record (erased,
    /// torn, or corrupt: the caller treats all three alike, as no record).
    pub fn decode(b: &[u8; RECORD_LEN]) -> Option<StateRecord> {
        let u32_at = |at: usize| u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]);
        let valid = b[0..4] == MAGIC
            && CRC.checksum(&b[..24]) == u32_at(24)
            && b[8] <= 1
            && b[10..12] == [0; 2];
        valid.then(|| StateRecord {
            seq: u32_at(4),
            slot: b[8],
            len: u32_at(12),
            crc: u32_at(16),
            floor: u32_at(20),
            key_gen: b[9],
        })
    }
}

/// The valid record of each copy (`None` where a copy is erased, torn or unreadable; in a
/// slot's trailer, also where it names the other slot, which no update writes).
pub fn read_copies<F: NorFlash>(flash: &mut F, layout: &Layout) -> [Option<StateRecord>; 2] {
    [0, 1].map(|copy| {
        let mut b = [0u8; RECORD_LEN];
        flash.read(layout.state::<F>(copy).start, &mut b).ok()?;
        StateRecord::decode(&b)
            .filter(|r| layout.state_has_own_erase() || usize::from(r.slot) == copy)
    })
}

/// The newest valid record and the copy that holds it.
pub fn newest(copies: &[Option<StateRecord>; 2]) -> Option<(usize, StateRecord)> {
    match copies {
        [Some(a), Some(b)] => Some(if b.seq > a.seq { (1, *b) } else { (0, *a) }),
        [Some(a), None] => Some((0, *a)),
        [None, Some(b)] => Some((1, *b)),
        [None, None] => None,
    }
}

/// Writes `rec` into the copy that does not hold the newest valid record, then one write of
/// the record padded with 0xFF to the write unit. With copies of their own: the other copy
/// than the newest record's (copy 0 when there is none), erased first. In the trailers: copy
/// `rec.slot`, the trailer of the slot the update's `Begin` erased (with the slot, so no
/// second erase here, which would take the new table with it); the newest record is in the
/// live slot's trailer, the other one.
/// Crate-only: callers have checked the layout (a write unit within `MAX_WRITE_SIZE`).
pub(crate) fn write<F: NorFlash>(
    flash: &mut F,
    layout: &Layout,
    rec: &StateRecord,
) -> Result<(), F::Error> {
    let region = if layout.state_has_own_erase() {
        let target = match newest(&read_copies(flash, layout)) {
            Some((copy, _)) => 1 - copy,
            None => 0,
        };
        let region = layout.state::<F>(target);
        flash.erase(region.start, region.end)?;
        region
    } else {
        layout.state::<F>(usize::from(rec.slot))
    };
    let mut buf = [0xffu8; MAX_WRITE_SIZE];
    let len = padded_len::<F>();
    buf[..RECORD_LEN].copy_from_slice(&rec.encode());
    flash.write(region.start, &buf[..len])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_rejections() {
        let r = StateRecord {
            seq: 7,
            slot: 1,
            len: 1596,
            crc: 0xdead_beef,
            floor: 12,
            key_gen: 1,
        };
        let b = r.encode();
        assert_eq!(StateRecord::decode(&b), Some(r));
        assert_eq!(StateRecord::decode(&[0xff; RECORD_LEN]), None);
        assert_eq!(StateRecord::decode(&[0; RECORD_LEN]), None);
        for at in 0..RECORD_LEN {
            for bit in 0..8 {
                let mut c = b;
                c[at] ^= 1 << bit;
                assert_eq!(StateRecord::decode(&c), None, "byte {at} bit {bit}");
            }
        }
    }

    #[test]
    fn newest_wins() {
        let r = |seq| {
            Some(StateRecord {
                seq,
                slot: 0,
                len: 0,
                crc: 0,
                floor: 0,
                key_gen: 0,
            })
        };
        assert_eq!(newest(&[r(3), r(4)]).map(|x| x.0), Some(1));
        assert_eq!(newest(&[r(5), r(4)]).map(|x| x.0), Some(0));
        assert_eq!(newest(&[None, r(1)]).map(|x| x.0), Some(1));
        assert_eq!(newest(&[None, None]), None);
    }
}
