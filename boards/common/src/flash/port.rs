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

    /// Boots on the live table, copied into `live`, into `out` ([`slots::boot`]: in place).
    pub fn boot<'a, P: HubEvaluator>(
        &mut self,
        live: &'a mut [u8; MAX_TABLE_LEN],
        out: &mut Boot<'a, P>,
    ) {
        let (layout, accept) = (self.updater.layout(), self.updater.accept());
        slots::boot::<P, F>(&mut self.flash, layout, accept, live, out);
    }

    /// Carries out one update step (`Updater::step`).
    pub fn step(&mut self, step: &Step) -> UpdateAnswer {
        self.updater.step(&mut self.flash, self.scratch, step)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use quatarm::stream::TableState;
    use quatarm::update::fixtures;
    use quatarm::F32;

    /// The port's whole cycle: boot on the factory table, take an update step by step (the
    /// old chain answering meanwhile), boot on the new one.
    #[test]
    fn boot_update_and_boot_again() {
        let old = fixtures::table(200.0);
        let new = fixtures::numbered(220.0, 5);
        let mut scratch = [0u8; MAX_TABLE_LEN];
        let mut port = Port::new(
            fixtures::factory(&old),
            fixtures::layout(),
            Accept::joints(6),
            &mut scratch,
        );
        {
            let mut live = [0u8; MAX_TABLE_LEN];
            let mut first = Boot::empty();
            port.boot::<F32>(&mut live, &mut first);
            assert_eq!(first.calibration.state(), TableState::Valid);
            assert_eq!(first.live.map(|l| l.slot), Some(0));
        }
        let steps = fixtures::steps(&new);
        assert!(steps.len() > 2);
        for s in &steps {
            port.step(s).unwrap();
        }
        let mut live = [0u8; MAX_TABLE_LEN];
        let mut second = Boot::empty();
        port.boot::<F32>(&mut live, &mut second);
        let id = second.live.expect("the new table");
        assert_eq!((id.slot, id.crc), (1, fixtures::crc_of(&new)));
        let x = second.calibration.eval(&[0; 6], 0).unwrap().xyz_nm[0];
        assert!((x - 1_320_000_000).abs() < 1_000, "{x} nm");
    }

    /// A table the hub does not accept is refused at its commit, and the old one stays.
    #[test]
    fn a_refused_update_leaves_the_old_table() {
        let old = fixtures::table(200.0);
        let mut scratch = [0u8; MAX_TABLE_LEN];
        let mut port = Port::new(
            fixtures::factory(&old),
            fixtures::layout(),
            Accept::joints(6).for_encoders(&[1 << 14; 6]),
            &mut scratch,
        );
        // Encoders of another resolution: a valid table, not this hub's.
        let other = fixtures::table_for_encoders(220.0, 1 << 16);
        let refused = fixtures::steps(&other)
            .iter()
            .map(|s| port.step(s))
            .any(|a| a.is_err());
        assert!(refused);
        let mut live = [0u8; MAX_TABLE_LEN];
        let mut b = Boot::empty();
        port.boot::<F32>(&mut live, &mut b);
        let id = b.live.expect("the old table");
        assert_eq!((id.slot, id.crc), (0, fixtures::crc_of(&old)));
    }
}
