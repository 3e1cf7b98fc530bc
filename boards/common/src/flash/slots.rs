//! The update's flash layout as `memory.x` reserves it, and the boot through it.
//!
//! `memory.x` exports the start and end of `CALTABLE` (slot 0, where a debug probe flashes
//! the factory table) and `CALTABLE_B` (slot 1), and on boards whose state record has regions
//! of its own, `CALSTATE0` / `CALSTATE1` ([`map`]); a board whose erase units are too large
//! for that keeps the record in the slots' trailers and exports no state regions
//! ([`trailer_map`]: a board that called [`map`] without them would fail to link, not run on
//! a wrong layout). A flash driver covers the span from the lowest region to the end of the
//! highest ([`Map`]), so the layouts give offsets from its start.

use quatarm::stream::{Hub, LiveTable, TableState};
use quatarm::table::MAX_TABLE_LEN;
use quatarm::update::{live_table, Accept, BootError, Layout};

use embedded_storage::nor_flash::NorFlash;

use super::window::{Raw, Window};
use crate::calibration::{self, Calibration, HubEvaluator};

extern "C" {
    static _cal_table_start: u8;
    static _cal_table_end: u8;
    static _cal_slot1_start: u8;
    static _cal_slot1_end: u8;
}

// Apart: referenced only by `map`, so a board without these regions links as long as it
// uses `trailer_map`.
extern "C" {
    static _cal_state0_start: u8;
    static _cal_state0_end: u8;
    static _cal_state1_start: u8;
    static _cal_state1_end: u8;
}

/// The two slots as absolute addresses.
fn slot_regions() -> [(usize, usize); 2] {
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
    ]
}

/// The calibration flash of a board: where a driver's window over it starts and how long it
/// is (from the lowest region to the end of the highest), and the update's layout in offsets
/// from that start (checked against the driver by `Layout::check` before any use).
pub struct Map {
    /// Address of the lowest region: offset 0 of the driver.
    base: usize,
    /// Bytes from `base` to the end of the highest region.
    span: usize,
    /// The slots and state copies, in offsets from `base`.
    layout: Layout,
}

/// The map of `slots` and, where the board has them, `state` regions: offsets from the lowest
/// start, and the state copies in the slots' trailers where there are none.
fn map_of(slots: [(usize, usize); 2], state: Option<[(usize, usize); 2]>) -> Map {
    let all = || slots.iter().chain(state.iter().flatten());
    let base = all().map(|r| r.0).min().unwrap_or(0);
    let end = all().map(|r| r.1).max().unwrap_or(0);
    let off = |(s, e): (usize, usize)| (s - base) as u32..(e - base) as u32;
    let slots = slots.map(off);
    let layout = match state {
        Some(state) => Layout::Regions {
            slots,
            state: state.map(off),
        },
        None => Layout::Trailers { slots },
    };
    Map {
        base,
        span: end - base,
        layout,
    }
}

/// The map of a board whose state record's copies have regions of their own (`CALSTATE0`,
/// `CALSTATE1`).
pub fn map() -> Map {
    let state = [
        (
            core::ptr::addr_of!(_cal_state0_start) as usize,
            core::ptr::addr_of!(_cal_state0_end) as usize,
        ),
        (
            core::ptr::addr_of!(_cal_state1_start) as usize,
            core::ptr::addr_of!(_cal_state1_end) as usize,
        ),
    ];
    map_of(slot_regions(), Some(state))
}

/// The map of a board whose state record's copies are the slots' trailers (the
/// NUCLEO-F446RE's two 128 KiB sectors).
pub fn trailer_map() -> Map {
    map_of(slot_regions(), None)
}

impl Map {
    /// The driver of this calibration flash over the chip routine `raw`, and the layout.
    ///
    /// # Safety
    /// As [`Window::new`]: the regions are flash `raw` erases and programs, memory-mapped,
    /// outside the firmware image, and nothing else writes them while the driver lives.
    pub unsafe fn window<R: Raw>(self, raw: R) -> (Window<R>, Layout) {
        (Window::new(raw, self.base, self.span), self.layout)
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

/// Boots on the table `quatarm::update::live_table` picks in `layout` (the slot the newest
/// valid state record names, else any valid slot, slot 0 first). Without one, slot 0's reason
/// gives the table state the hub reports (blank, corrupt, ...), as before there were two
/// slots. `accept` is what the hub requires of a table (its joints, its encoders, its
/// maker's signature); `live` receives the table, which the boot's calibration borrows for as
/// long as it runs (its uncertainty reads the parameter block at every point): not the
/// update's scratch, and a copy in RAM rather than the slot in place (`flash::port`).
pub fn boot<'a, P: HubEvaluator, F: NorFlash>(
    flash: &mut F,
    layout: &Layout,
    accept: &Accept,
    live: &'a mut [u8; MAX_TABLE_LEN],
) -> Boot<'a, P> {
    match live_table(flash, layout, accept, live) {
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
