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
use crate::calibration::{Calibration, HubEvaluator};

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
    /// No table yet: the place [`boot`] fills.
    pub fn empty() -> Self {
        Boot {
            calibration: Calibration::refused(TableState::Missing),
            live: None,
        }
    }

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
///
/// The boot is written into `out` (whatever it held, [`Boot::empty`] at first), its chain
/// and uncertainty built in place ([`Calibration::load_in`]): returned by value, the
/// calibration was on the stack once more in each function it passed through.
pub fn boot<'a, P: HubEvaluator, F: NorFlash>(
    flash: &mut F,
    layout: &Layout,
    accept: &Accept,
    live: &'a mut [u8; MAX_TABLE_LEN],
    out: &mut Boot<'a, P>,
) {
    match live_table(flash, layout, accept, live) {
        Ok(live) => {
            out.live = Some(LiveTable {
                slot: live.slot,
                seq: live.seq.unwrap_or(0),
                crc: live.table.crc(),
            });
            out.calibration.load_in(live.table.bytes());
        }
        // No slot boots: slot 0's reason (the factory slot) is what the hub reports.
        Err(BootError::NoTable(why)) => {
            out.live = None;
            out.calibration.refuse(why[0].state());
        }
        Err(BootError::Layout(_)) => {
            out.live = None;
            out.calibration.refuse(TableState::Malformed);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibration;
    use quatarm::stream::TableState;
    use quatarm::update::fixtures;
    use quatarm::update::mock::MockFlash;
    use quatarm::F32;

    const LINK_MM: f64 = 200.0;

    #[test]
    fn the_map_counts_offsets_from_the_lowest_region() {
        // The state copies below the slots, as on the Pico (any order works).
        let slots = [(0x1010_4000, 0x1010_8000), (0x1010_8000, 0x1010_c000)];
        let state = [(0x1010_0000, 0x1010_1000), (0x1010_1000, 0x1010_2000)];
        let m = map_of(slots, Some(state));
        assert_eq!(m.base, 0x1010_0000);
        assert_eq!(m.span, 0xc000);
        assert_eq!(
            m.layout,
            Layout::Regions {
                slots: [0x4000..0x8000, 0x8000..0xc000],
                state: [0..0x1000, 0x1000..0x2000],
            }
        );
    }

    #[test]
    fn without_state_regions_the_record_is_in_the_slots_trailers() {
        // Slot 1 below slot 0: the base is the lower, offsets follow the addresses.
        let slots = [(0x0806_0000, 0x0808_0000), (0x0804_0000, 0x0806_0000)];
        let m = map_of(slots, None);
        assert_eq!(m.base, 0x0804_0000);
        assert_eq!(m.span, 0x4_0000);
        assert_eq!(
            m.layout,
            Layout::Trailers {
                slots: [0x2_0000..0x4_0000, 0..0x2_0000],
            }
        );
    }

    fn boot_of(
        flash: &mut MockFlash,
        layout: &Layout,
        accept: &Accept,
    ) -> (TableState, Option<LiveTable>) {
        let mut live = [0u8; MAX_TABLE_LEN];
        let mut b = Boot::empty();
        boot::<F32, _>(flash, layout, accept, &mut live, &mut b);
        (b.calibration.state(), b.live)
    }

    #[test]
    fn a_factory_table_in_slot_0_boots() {
        let t = fixtures::table(LINK_MM);
        for layout in fixtures::layouts() {
            let mut flash = fixtures::factory(&t);
            let (state, live) = boot_of(&mut flash, &layout, &Accept::joints(calibration::JOINTS));
            assert_eq!(state, TableState::Valid);
            let crc = fixtures::crc_of(&t);
            assert_eq!(
                live,
                Some(LiveTable {
                    slot: 0,
                    seq: 0,
                    crc
                }),
                "{layout:?}"
            );
        }
    }

    #[test]
    fn after_an_update_the_new_table_boots_with_its_chain() {
        let mut flash = fixtures::factory(&fixtures::table(LINK_MM));
        let new = fixtures::numbered(210.0, 2);
        fixtures::update(&mut flash, &new).unwrap();
        let mut live = [0u8; MAX_TABLE_LEN];
        let accept = Accept::joints(calibration::JOINTS);
        let mut b = Boot::empty();
        boot::<F32, _>(&mut flash, &fixtures::layout(), &accept, &mut live, &mut b);
        let id = b.live.expect("a live table");
        assert_eq!((id.slot, id.crc), (1, fixtures::crc_of(&new)));
        assert!(id.seq >= 1, "{id:?}");
        // The chain is the new table's: six links of 210 mm.
        let x = b.calibration.eval(&[0; 6], 0).unwrap().xyz_nm[0];
        assert!((x - 1_260_000_000).abs() < 1_000, "{x} nm");
    }

    #[test]
    fn blank_flash_reports_slot_0s_reason() {
        let mut flash = MockFlash::new(fixtures::FLASH_LEN);
        let (state, live) = boot_of(&mut flash, &fixtures::layout(), &Accept::joints(6));
        assert_eq!((state, live), (TableState::Missing, None));
    }

    #[test]
    fn an_unsigned_table_on_a_hub_with_a_key_is_refused() {
        let mut flash = fixtures::factory(&fixtures::table(LINK_MM));
        let accept = Accept::joints(6).signed_by(fixtures::public_key(7));
        let (state, live) = boot_of(&mut flash, &fixtures::layout(), &accept);
        assert_eq!((state, live), (TableState::Unsigned, None));
    }

    #[test]
    fn a_layout_beyond_the_flash_is_malformed() {
        let mut flash = fixtures::factory(&fixtures::table(LINK_MM));
        let too_far = Layout::Trailers {
            slots: [0..3072, 3072..(fixtures::FLASH_LEN as u32 + 1024)],
        };
        let (state, live) = boot_of(&mut flash, &too_far, &Accept::joints(6));
        assert_eq!((state, live), (TableState::Malformed, None));
    }
}
