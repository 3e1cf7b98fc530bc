//! Where the update's regions lie in a flash device: two table slots and two copies of the
//! state record, each a whole number of erase units of its own, so that erasing one never
//! touches another.

use core::ops::Range;
use embedded_storage::nor_flash::NorFlash;

use crate::table::MAX_PLAIN_TABLE_LEN;

/// Offsets (from the start of the flash device, as `NorFlash` counts them) of the regions.
/// Slot 0 is the region a probe or `picotool` writes a factory table into (`CALTABLE` in
/// `memory.x`), so a board without any state record boots from it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Layout {
    /// The two table slots.
    pub slots: [Range<u32>; 2],
    /// The two copies of the state record.
    pub state: [Range<u32>; 2],
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
    /// ([`crate::table::MAX_PLAIN_TABLE_LEN`]).
    SlotTooSmall(u8),
    /// Two regions share bytes.
    Overlap(u8, u8),
    /// The flash's write unit is larger than this crate's write buffer.
    WriteSizeTooLarge,
}

/// Largest flash write unit supported (the RP2040 programs 256-byte pages).
pub const MAX_WRITE_SIZE: usize = 256;

impl Layout {
    /// The four regions, slots first.
    pub(crate) fn regions(&self) -> [&Range<u32>; 4] {
        [
            &self.slots[0],
            &self.slots[1],
            &self.state[0],
            &self.state[1],
        ]
    }

    /// Checks the layout against a device: every region erase-aligned, inside the device,
    /// apart from the others, and each slot able to hold the largest table.
    pub fn check<F: NorFlash>(&self, flash: &F) -> Result<(), LayoutError> {
        if F::WRITE_SIZE > MAX_WRITE_SIZE || F::WRITE_SIZE == 0 {
            return Err(LayoutError::WriteSizeTooLarge);
        }
        let erase = F::ERASE_SIZE as u32;
        let regions = self.regions();
        for (i, r) in regions.iter().enumerate() {
            let i = i as u8;
            if erase == 0 || r.start % erase != 0 || r.end % erase != 0 || r.end <= r.start {
                return Err(LayoutError::Unaligned(i));
            }
            if r.end as usize > flash.capacity() {
                return Err(LayoutError::OutOfFlash(i));
            }
            if i < 2 && ((r.end - r.start) as usize) < MAX_PLAIN_TABLE_LEN {
                return Err(LayoutError::SlotTooSmall(i));
            }
            for (j, o) in regions.iter().enumerate().skip(usize::from(i) + 1) {
                if r.start < o.end && o.start < r.end {
                    return Err(LayoutError::Overlap(i, j as u8));
                }
            }
        }
        Ok(())
    }
}
