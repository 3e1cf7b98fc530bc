//! A hub's update port: its calibration flash, the updater and the scratch the updater checks
//! a table in; the boot on the live table through the same flash and layout. The QEMU hub
//! (`qemu::hub_main`) and the real hubs ([`crate::live::run`]) each boot, serve until
//! an update commits, and boot again through one of these.
//!
//! **The live table is copied into RAM**, on every board, rather than read in place from
//! memory-mapped flash (`quatarm::update::live_slot` would give the slot for that):
//! - the f32 hubs' uncertainty reads the table's parameter block at every point, so the table
//!   must stay readable and unchanged for as long as the chain runs: a copy of its own, apart
//!   from the update's scratch, which the next update overwrites;
//! - on the RP2040 the flash is not readable at all while it is erased or programmed (XIP is
//!   off, `rp-pico`'s driver), and the XIP cache must be flushed after; on the STM32F4 the
//!   ART accelerator's caches must be (`nucleo-f446re`'s driver). A copy taken once at boot,
//!   after the flash checks passed, is out of reach of both;
//! - a `&'static [u8]` over a slot that the update erases once a newer table is live would be
//!   a reference whose bytes change under it; the copy's borrow ends with the boot's
//!   calibration, before the next boot;
//! - one path for every board (`update::live_table`, which reads and checks into a buffer),
//!   tested on qemu-m4f end to end.
//!
//! It costs `MAX_TABLE_LEN` bytes of RAM (13,824 on the f32 hubs with U95 and the wobble,
//! 2,448 on the fixed-point ones, room for eight probes) of the NUCLEO's 128 KiB and the Pico's 264 KiB.

use embedded_storage::nor_flash::NorFlash;
use quatarm::stream::UpdateAnswer;
use quatarm::table::MAX_TABLE_LEN;
use quatarm::update::session::Step;
use quatarm::update::{Accept, Layout, Updater};

use super::slots::{self, Boot};
use crate::calibration::HubEvaluator;

/// The flash, the updater on it, and its scratch.
pub struct Port<'s, F: NorFlash> {
    flash: F,
    updater: Updater,
    scratch: &'s mut [u8; MAX_TABLE_LEN],
}

impl<'s, F: NorFlash> Port<'s, F> {
    /// An update port on `flash` laid out as `layout`; `accept` is what the hub requires of a
    /// table, at boot and at an update's commit alike; `scratch` holds a table while the
    /// updater checks it.
    pub fn new(
        flash: F,
        layout: Layout,
        accept: Accept,
        scratch: &'s mut [u8; MAX_TABLE_LEN],
    ) -> Self {
        Port {
            flash,
            updater: Updater::new(layout, accept),
            scratch,
        }
    }

    /// Boots on the live table, copied into `live` ([`slots::boot`]).
    pub fn boot<'a, P: HubEvaluator>(&mut self, live: &'a mut [u8; MAX_TABLE_LEN]) -> Boot<'a, P> {
        let (layout, accept) = (self.updater.layout(), self.updater.accept());
        slots::boot::<P, F>(&mut self.flash, layout, accept, live)
    }

    /// Carries out one update step (`Updater::step`).
    pub fn step(&mut self, step: &Step) -> UpdateAnswer {
        self.updater.step(&mut self.flash, self.scratch, step)
    }
}
