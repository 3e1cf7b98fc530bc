//! The update's flash layout as `memory.x` reserves it, and the boot through it.
//!
//! `memory.x` exports the start and end of `CALTABLE` (slot 0, where a debug probe flashes
//! the factory table), `CALTABLE_B` (slot 1) and `CALSTATE0` / `CALSTATE1` (the state
//! record's copies). A flash driver here covers the span from the lowest of them to the end
//! of the highest, so [`layout`] gives the four regions as offsets from [`base`].

use quatarm::stream::{Hub, LiveTable, TableState};
use quatarm::table::MAX_TABLE_LEN;
use quatarm::update::{live_table, Accept, BootError, Layout};

use embedded_storage::nor_flash::NorFlash;

use crate::calibration::{self, Calibration, HubEvaluator};

extern "C" {
    static _cal_table_start: u8;
    static _cal_table_end: u8;
    static _cal_slot1_start: u8;
    static _cal_slot1_end: u8;
    static _cal_state0_start: u8;
    static _cal_state0_end: u8;
    static _cal_state1_start: u8;
    static _cal_state1_end: u8;
}

/// The four regions as absolute addresses: slot 0, slot 1, state copy 0, state copy 1.
fn regions() -> [(usize, usize); 4] {
    // Only the symbols' addresses are taken (no read): the linker script defines every one.
    [
        (
            core::ptr::addr_of!(_cal_table_start) as usize,
            core::ptr::addr_of!(_cal_table_end) as usize,
        ),
        (
            core::ptr::addr_of!(_cal_slot1_start) as usize,
            core::ptr::addr_of!(_cal_slot1_end) as usize,
        ),
        (
            core::ptr::addr_of!(_cal_state0_start) as usize,
            core::ptr::addr_of!(_cal_state0_end) as usize,
        ),
        (
            core::ptr::addr_of!(_cal_state1_start) as usize,
            core::ptr::addr_of!(_cal_state1_end) as usize,
        ),
    ]
}

/// Address of the lowest region: offset 0 of the calibration flash.
pub fn base() -> usize {
    regions().iter().map(|r| r.0).min().unwrap_or(0)
}

/// Bytes from [`base`] to the end of the highest region.
pub fn span() -> usize {
    regions().iter().map(|r| r.1).max().unwrap_or(0) - base()
}

/// The update's layout, in offsets from [`base`] (checked against the driver by
/// `Layout::check` before any use).
pub fn layout() -> Layout {
    let b = base();
    let off = |(s, e): (usize, usize)| (s - b) as u32..(e - b) as u32;
    let r = regions();
    Layout {
        slots: [off(r[0]), off(r[1])],
        state: [off(r[2]), off(r[3])],
    }
}

/// What a boot found: the chain of the live table (or the state saying why there is none)
/// and which table that is.
pub struct Boot<'a, P: HubEvaluator> {
    /// The calibration the hub runs on (borrowing the table's bytes).
    pub calibration: Calibration<'a, P>,
    /// The live table, for the `Hello` (`None` without a valid one).
    pub live: Option<LiveTable>,
}

impl<P: HubEvaluator> Boot<'_, P> {
    /// A hub announcing this boot's table.
    pub fn hub(&self) -> Hub {
        let hub = self.calibration.hub();
        match self.live {
            Some(l) => hub.with_live(l),
            None => hub,
        }
    }
}

/// Boots on the table `quatarm::update::live_table` picks (the slot the newest valid state
/// record names, else any valid slot, slot 0 first). Without one, slot 0's bytes give the
/// table state the hub reports (blank, corrupt, ...), as before there were two slots.
/// `accept` is what the hub requires of a table (its joints, its maker's signature);
/// `live` receives the table, which the boot's calibration borrows for as long as it runs
/// (its uncertainty reads the parameter block at every point): not the update's scratch.
pub fn boot<'a, P: HubEvaluator, F: NorFlash>(
    flash: &mut F,
    accept: &Accept,
    live: &'a mut [u8; MAX_TABLE_LEN],
) -> Boot<'a, P> {
    let layout = layout();
    match live_table(flash, &layout, accept, live) {
        Ok(live) => {
            let id = LiveTable {
                slot: live.slot,
                seq: live.seq.unwrap_or(0),
                crc: live.table.crc(),
            };
            let calibration = calibration::load::<P>(live.table.bytes());
            Boot {
                calibration,
                live: Some(id),
            }
        }
        // No slot boots: slot 0's reason (the factory slot) is what the hub reports.
        Err(BootError::NoTable(why)) => Boot {
            calibration: Calibration::refused(why[0].state()),
            live: None,
        },
        Err(BootError::Layout(_)) => Boot {
            calibration: Calibration::refused(TableState::Malformed),
            live: None,
        },
    }
}
