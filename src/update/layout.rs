//! Where the update's regions lie in a flash device: two table slots, and the two copies of the
//! state record either in erase units of their own ([`Layout::Regions`]) or in the last bytes
//! of each slot ([`Layout::Trailers`], MCUboot's image trailer), for chips whose erase units
//! are too large to spend two of them on a 24-byte record.

use core::ops::Range;
use embedded_storage::nor_flash::NorFlash;

use super::record::padded_len;
use crate::table::MAX_PLAIN_TABLE_LEN;

/// Offsets (from the start of the flash device, as `NorFlash` counts them) of the regions.
/// Slot 0 is the region a probe or `picotool` writes a factory table into (`CALTABLE` in
/// `memory.x`), so a board without any state record boots from it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Layout {
    /// Two slots and two state copies, each a whole number of erase units of its own, so that
    /// erasing one never touches another: a new record erases its copy first. For flash of
    /// small, equal erase units (4 KiB on the RP2040, 1 KiB pages on the nRF51).
    Regions {
        /// The two table slots.
        slots: [Range<u32>; 2],
        /// The two copies of the state record.
        state: [Range<u32>; 2],
    },
    /// Two slots only; state copy `i` is slot `i`'s trailer, its last [`RECORD_LEN`](super::record::RECORD_LEN) bytes
    /// rounded up to the write unit ([`Layout::trailer_len`]). Slot `i`'s erase (an update's
    /// `Begin`) erases copy `i` with it, the commit writes the record into that erased trailer
    /// without a second erase, and a table must end before the trailer. Copy `i` only ever
    /// holds a record naming slot `i`. For the STM32F4, whose update would otherwise take
    /// four sectors of 64–128 KiB (`docs/update.md`, why a power cut is still harmless).
    Trailers {
        /// The two table slots, each ending with its state copy.
        slots: [Range<u32>; 2],
    },
}

/// Why a [`Layout`] cannot be used with a flash device.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LayoutError {
    /// A region does not start and end on an erase unit (slot 0–1, then state 2–3).
    Unaligned(u8),
    /// A region lies past the end of the device.
    OutOfFlash(u8),
    /// A slot is smaller than the largest table without a parameter block
    /// ([`crate::table::MAX_PLAIN_TABLE_LEN`]), its trailer not counted.
    SlotTooSmall(u8),
    /// Two regions share bytes.
    Overlap(u8, u8),
    /// The flash's write unit is larger than this crate's write buffer.
    WriteSizeTooLarge,
}

/// Largest flash write unit supported (the RP2040 programs 256-byte pages).
pub const MAX_WRITE_SIZE: usize = 256;

impl Layout {
    /// The two table slots, whole (a trailer included).
    pub fn slots(&self) -> &[Range<u32>; 2] {
        match self {
            Layout::Regions { slots, .. } | Layout::Trailers { slots } => slots,
        }
    }

    /// Bytes of a slot's trailer on a flash of write unit `F::WRITE_SIZE`: the record padded
    /// to whole write units, so that its one write touches nothing of the table.
    pub const fn trailer_len<F: NorFlash>() -> u32 {
        padded_len::<F>() as u32
    }

    /// Where state copy `copy` (0 or 1) lies.
    pub(crate) fn state<F: NorFlash>(&self, copy: usize) -> Range<u32> {
        match self {
            Layout::Regions { state, .. } => state[copy & 1].clone(),
            Layout::Trailers { slots } => {
                let end = slots[copy & 1].end;
                end.saturating_sub(Self::trailer_len::<F>())..end
            }
        }
    }

    /// The bytes of slot `slot` a table (and its signature) may take: the whole slot, or all
    /// before its trailer.
    pub fn table_area<F: NorFlash>(&self, slot: u8) -> Range<u32> {
        let whole = self.slots()[usize::from(slot & 1)].clone();
        match self {
            Layout::Regions { .. } => whole,
            Layout::Trailers { .. } => {
                whole.start..whole.end.saturating_sub(Self::trailer_len::<F>())
            }
        }
    }

    /// Whether a state copy has erase units of its own (erased before each record) rather
    /// than being erased with its slot.
    pub(crate) fn state_has_own_erase(&self) -> bool {
        matches!(self, Layout::Regions { .. })
    }

    /// Checks the layout against a device: every region erase-aligned, inside the device,
    /// apart from the others, and each slot able to hold the largest table without a parameter
    /// block (before its trailer, where it has one).
    pub fn check<F: NorFlash>(&self, flash: &F) -> Result<(), LayoutError> {
        if F::WRITE_SIZE > MAX_WRITE_SIZE || F::WRITE_SIZE == 0 {
            return Err(LayoutError::WriteSizeTooLarge);
        }
        let erase = F::ERASE_SIZE as u32;
        let (regions, count): ([&Range<u32>; 4], usize) = match self {
            Layout::Regions { slots, state } => ([&slots[0], &slots[1], &state[0], &state[1]], 4),
            // No regions of their own: each trailer is inside its slot, checked with it.
            Layout::Trailers { slots } => ([&slots[0], &slots[1], &slots[0], &slots[1]], 2),
        };
        for (i, r) in regions.iter().enumerate().take(count) {
            let i = i as u8;
            if erase == 0 || r.start % erase != 0 || r.end % erase != 0 || r.end <= r.start {
                return Err(LayoutError::Unaligned(i));
            }
            if r.end as usize > flash.capacity() {
                return Err(LayoutError::OutOfFlash(i));
            }
            if i < 2 {
                let area = self.table_area::<F>(i);
                if ((area.end - area.start) as usize) < MAX_PLAIN_TABLE_LEN {
                    return Err(LayoutError::SlotTooSmall(i));
                }
            }
            for (j, o) in regions
                .iter()
                .enumerate()
                .take(count)
                .skip(usize::from(i) + 1)
            {
                if r.start < o.end && o.start < r.end {
                    return Err(LayoutError::Overlap(i, j as u8));
                }
            }
        }
        Ok(())
    }
}
