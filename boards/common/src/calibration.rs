//! The table in its flash region, checked once at boot, and the chain built from it.
//!
//! A hub drives a fixed number of encoders, so the table must be for exactly that many joints
//! (`Table::parse_for`); any refusal of the parser or of the chain's constructor becomes the
//! [`TableState`] every report then carries, and no chain exists to produce coordinates.
//! Where the table carries an uncertainty budget and the board's number format computes it,
//! every point gets its U95 ([`PointUncertainty`]). The chain ends at the table's first probe
//! from boot; [`Calibration::mount`] converts another of the table's when the host selects
//! it.

use core::mem::MaybeUninit;
use quatarm::stream::{self, Coordinates, Hub, Measure, TableState};
use quatarm::uncertainty::Uncertainty;
use quatarm::{Chain, ChainError, Evaluator, Point, Table};

/// Joints of the arms these hubs drive.
pub const JOINTS: usize = 6;

/// A chain evaluator a hub can run, with the name its hello message gives its number format:
/// the type picks the arithmetic, so the announced format cannot disagree with the one
/// evaluated.
pub trait HubEvaluator: Evaluator {
    /// What the hub announces.
    const STREAM: stream::NumberFormat;
    /// What it computes of a point's uncertainty (borrowing the table's parameter block).
    type Uncertainty<'a>: PointUncertainty<'a, Self>;
}

/// The f32 hubs stream U95 where they have the flash for it (feature `u95`).
impl HubEvaluator for quatarm::F32 {
    const STREAM: stream::NumberFormat = stream::NumberFormat::F32;
    #[cfg(feature = "u95")]
    type Uncertainty<'a> = Uncertainty<'a, quatarm::F32>;
    #[cfg(not(feature = "u95"))]
    type Uncertainty<'a> = NoUncertainty;
}

/// The fixed-point hubs stream U95 where the board has the flash for it (feature `u95`: the
/// Raspberry Pi Pico's 2 MB). Their U95 is the f32 one in software floating point on a core
/// without an FPU, the Jacobians from the fixed-point matrix chain's frames, and on the Pico
/// the parameter part's product in integers (`quatarm/fixed-u95`; `docs/results/boards.md`,
/// "The Pico's U95": both measured, and why). qemu-m0, the
/// 32 KiB minimal profile, leaves it out: its image holds the chain, the stream and the
/// table's checks, not the uncertainty as well.
impl HubEvaluator for quatarm::Fixed {
    const STREAM: stream::NumberFormat = stream::NumberFormat::Fixed;
    #[cfg(feature = "u95")]
    type Uncertainty<'a> = Uncertainty<'a, quatarm::Fixed>;
    #[cfg(not(feature = "u95"))]
    type Uncertainty<'a> = NoUncertainty;
}

/// A point's U95 as a hub computes it, built at boot from the table.
pub trait PointUncertainty<'a, P: Evaluator>: Sized {
    /// The table's, built in `out` (in place, as the chain: [`Calibration::load_in`]); `None`
    /// where it has no budget (or the hub computes none).
    fn build_in(out: &mut Option<Self>, table: &Table<'a>);
    /// U95 of a point `chain` evaluated (nm); `None` where it cannot be computed.
    fn u95_nm(&self, chain: &Chain<P>, counts: &[u32], temp_mc: i32, p: &Point<P>) -> Option<u32>;
    /// Follows the chain to the table's probe `k`; `false` where it cannot.
    fn mount(&mut self, table: &Table<'a>, k: usize) -> bool;
}

impl<'a, P: Evaluator> PointUncertainty<'a, P> for Uncertainty<'a, P> {
    // Out of line: the temporaries of its construction stay out of the hub's own frame.
    #[inline(never)]
    fn build_in(out: &mut Option<Self>, table: &Table<'a>) {
        // A budget the chain cannot use (it built the same matrix chain's model) gives no U95
        // rather than no coordinates: `out` is `None` on an error.
        let _ = Uncertainty::build_in(out, table);
    }
    // Its own matrix chain's pass gives the Jacobians: neither the hub's chain nor its point.
    fn u95_nm(&self, _: &Chain<P>, counts: &[u32], temp_mc: i32, _: &Point<P>) -> Option<u32> {
        Uncertainty::u95_nm(self, counts, temp_mc).ok()
    }
    fn mount(&mut self, table: &Table<'a>, k: usize) -> bool {
        Uncertainty::mount(self, table, k).is_ok()
    }
}

/// No uncertainty: what a hub without the flash for it computes.
pub enum NoUncertainty {}

impl<P: Evaluator> PointUncertainty<'_, P> for NoUncertainty {
    #[inline(always)]
    fn build_in(out: &mut Option<Self>, _: &Table<'_>) {
        *out = None;
    }
    fn u95_nm(&self, _: &Chain<P>, _: &[u32], _: i32, _: &Point<P>) -> Option<u32> {
        match *self {}
    }
    fn mount(&mut self, _: &Table<'_>, _: usize) -> bool {
        match *self {}
    }
}

/// The boot check's outcome: a chain, or why there is none, and its points' uncertainty
/// where the hub computes one. (Two fields, not a struct of both in the `Result`: built in
/// one, the chain was copied once more on the stack, 728 bytes the M0's 8 KiB did not have.)
///
/// A hub builds it in place, [`Calibration::load_in`], into the one it runs from: 7,856 bytes
/// on the f32 hubs with U95 and the wobble, which built by value and moved (chain, uncertainty,
/// calibration, boot) were on the qemu-m4f hub's stack several times over at boot: its peak
/// was 63,740 bytes, 46,100 since (issue 32, `docs/results/speed.md`).
pub struct Calibration<'a, P: HubEvaluator> {
    /// The chain, written in place by `Chain::build_in` ([`build`]); initialised where
    /// `state` is `Ok` (and only then read), else why there is none.
    chain: MaybeUninit<Chain<P>>,
    state: Result<(), TableState>,
    uncertainty: Option<P::Uncertainty<'a>>,
    /// The table the chain was built from (with the chain only), whose probes it mounts.
    table: Option<Table<'a>>,
}

impl<'a, P: HubEvaluator> Calibration<'a, P> {
    /// No chain: the boot refused every table, for the reason `state` (a signature, a layout
    /// that does not fit the flash).
    pub fn refused(state: TableState) -> Calibration<'a, P> {
        Calibration {
            chain: MaybeUninit::uninit(),
            state: Err(state),
            uncertainty: None,
            table: None,
        }
    }

    /// No chain, for the reason `state`, in place of whatever `self` held.
    pub fn refuse(&mut self, state: TableState) {
        self.state = Err(state);
        self.uncertainty = None;
        self.table = None;
    }

    /// Validates the region's bytes and builds the chain and its points' uncertainty in
    /// `self`, in place of whatever it held (as [`load`]).
    pub fn load_in(&mut self, region: &'a [u8]) {
        self.refuse(TableState::Missing);
        let table = validate(region);
        self.state = build::<P>(&table, &mut self.chain);
        if self.state.is_ok() {
            self.table = table.ok();
            if let Some(t) = &self.table {
                P::Uncertainty::build_in(&mut self.uncertainty, t);
            }
        }
    }

    /// Mounts the table's probe `k` (its index in the table, [`Hub::select`]'s): the chain
    /// and its points' uncertainty end at that probe from the next reading on. `false`, and
    /// the probe before stays, where there is no chain or the probe cannot be converted
    /// (which the boot's check of the reach with the longest probe rules out).
    pub fn mount(&mut self, k: usize) -> bool {
        let (Ok(()), Some(table)) = (self.state, &self.table) else {
            return false;
        };
        // SAFETY: `state` is `Ok`: `build` initialised the chain.
        let chain = unsafe { self.chain.assume_init_mut() };
        if chain.mount(table, k).is_err() {
            return false;
        }
        // It builds on the same model as the chain, which just took the probe; were it to
        // fail anyway, the points go without U95 rather than with one of another probe.
        if let Some(u) = &mut self.uncertainty {
            if !u.mount(table, k) {
                self.uncertainty = None;
            }
        }
        true
    }
}

/// Validates the region's bytes and builds the chain.
pub fn load<P: HubEvaluator>(region: &[u8]) -> Calibration<'_, P> {
    let mut cal = Calibration::refused(TableState::Missing);
    cal.load_in(region);
    cal
}

// Validation and construction are kept out of line, one after the other, so that their stack
// frames are not stacked on top of each other: on the M0 (soft f64) each needs several KiB,
// and the hub's whole budget is 8 KiB.
#[inline(never)]
fn validate(region: &[u8]) -> Result<Table<'_>, TableState> {
    Table::parse_for(region, JOINTS).map_err(|e| TableState::from(&e))
}

// The chain is built where it stays (`Chain::build_in`): returned by value, it was copied.
// `Ok` where `chain` is initialised.
#[inline(never)]
fn build<P: Evaluator>(
    table: &Result<Table<'_>, TableState>,
    chain: &mut MaybeUninit<Chain<P>>,
) -> Result<(), TableState> {
    let table = table.as_ref().map_err(|s| *s)?;
    match Chain::build_in(chain, table) {
        Ok(_) => Ok(()),
        Err(_) => Err(TableState::Malformed),
    }
}

impl<P: HubEvaluator> Calibration<'_, P> {
    /// A hub that reports this calibration's state, joints and precision, the table's
    /// probes, the first mounted, and its calibration number and date (protocol 5).
    #[inline(always)] // called once per image: out of line it only adds a call (24 B on the M0)
    pub fn hub(&self) -> Hub {
        let hub = Hub::new(self.state(), self.joints(), P::STREAM);
        match &self.table {
            Some(t) => hub
                .with_probes((0..t.probe_count()).filter_map(|k| t.probe_id(k)))
                .with_release(t.release()),
            None => hub,
        }
    }
}

impl<P: HubEvaluator> Calibration<'_, P> {
    /// The chain, or why there is none.
    fn chain(&self) -> Result<&Chain<P>, TableState> {
        self.state?;
        // SAFETY: `state` is `Ok`: `build` initialised the chain.
        Ok(unsafe { self.chain.assume_init_ref() })
    }

    /// What the stream reports about the table.
    pub fn state(&self) -> TableState {
        match self.state {
            Ok(()) => TableState::Valid,
            Err(s) => s,
        }
    }

    /// Joints of the valid table (0 without one).
    pub fn joints(&self) -> u8 {
        match self.chain() {
            Ok(c) => c.joint_count() as u8,
            Err(_) => 0,
        }
    }

    /// Runs the chain on one reading, with the point's U95 where the hub computes it.
    pub fn eval(&self, counts: &[u32], temp_mc: i32) -> Result<Coordinates, ChainError> {
        match self.chain() {
            Ok(chain) => chain.eval(counts, temp_mc).map(|p| Coordinates {
                xyz_nm: p.xyz_nm(),
                dir_e9: p.dir_e9(),
                u95_nm: self
                    .uncertainty
                    .as_ref()
                    .and_then(|u| u.u95_nm(chain, counts, temp_mc, &p)),
            }),
            // The hub never calls eval without a valid table; answer like a refusal anyway.
            Err(_) => Err(ChainError::JointCount {
                expected: 0,
                found: counts.len() as u8,
            }),
        }
    }
}

/// What the hub's loop runs: [`Calibration::eval`] and [`Calibration::mount`].
impl<P: HubEvaluator> Measure for Calibration<'_, P> {
    type Error = ChainError;
    #[inline(always)] // a name for the loop: the call is the inherent method's
    fn eval(&self, counts: &[u32], temp_mc: i32) -> Result<Coordinates, ChainError> {
        Calibration::eval(self, counts, temp_mc)
    }
    #[inline(always)]
    fn mount(&mut self, k: usize) -> bool {
        Calibration::mount(self, k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use quatarm::update::fixtures;
    use quatarm::{Fixed, F32};

    /// The fixture arm: six joints turning about z, each link 200 mm along x, the probe
    /// 50 mm along z. At zero counts its tip is at (1200, 0, 50) mm. (Links of 300 mm reach
    /// too far for the i32 nanometres of the stream: the chain refuses them.)
    const LINK_MM: f64 = 200.0;
    const TIP_NM: [i32; 3] = [1_200_000_000, 0, 50_000_000];

    /// The table in a region of erased flash after it, as the boot reads it.
    fn region(table: &[u8]) -> [u8; 4096] {
        let mut r = [0xff; 4096];
        r[..table.len()].copy_from_slice(table);
        r
    }

    fn assert_near(got: [i32; 3], want: [i32; 3], tol_nm: i32) {
        for c in 0..3 {
            assert!(
                (got[c] - want[c]).abs() <= tol_nm,
                "component {c}: {got:?} against {want:?}"
            );
        }
    }

    #[test]
    fn a_valid_table_gives_the_arms_coordinates_in_both_formats() {
        let r = region(&fixtures::table(LINK_MM));
        let f32_cal = load::<F32>(&r);
        let fixed_cal = load::<Fixed>(&r);
        for (state, joints) in [
            (f32_cal.state(), f32_cal.joints()),
            (fixed_cal.state(), fixed_cal.joints()),
        ] {
            assert_eq!(state, TableState::Valid);
            assert_eq!(joints, JOINTS as u8);
        }
        let a = f32_cal.eval(&[0; JOINTS], 0).unwrap();
        let b = fixed_cal.eval(&[0; JOINTS], 0).unwrap();
        // f32 resolves ~1e-7 of 1.2 m; the fixed-point chain to a few nm.
        assert_near(a.xyz_nm, TIP_NM, 1_000);
        assert_near(b.xyz_nm, TIP_NM, 100);
        // A quarter turn of joint 1 (2^14 counts per turn) swings the whole arm about z:
        // the tip stays 1200 mm from the axis and 50 mm up, and leaves the x axis.
        let q = f32_cal.eval(&[1 << 12, 0, 0, 0, 0, 0], 0).unwrap().xyz_nm;
        assert!(q[0].abs() < 1_000, "{q:?}");
        assert!((q[1].abs() - TIP_NM[0]).abs() < 1_000, "{q:?}");
        assert!((q[2] - TIP_NM[2]).abs() < 1_000, "{q:?}");
        // No budget in the table: no U95, whatever the hub computes.
        assert_eq!(a.u95_nm, None);
    }

    #[test]
    fn erased_flash_is_missing_and_gives_no_coordinates() {
        let cal = load::<F32>(&[0xff; 4096]);
        assert_eq!(cal.state(), TableState::Missing);
        assert_eq!(cal.joints(), 0);
        assert!(cal.eval(&[0; JOINTS], 0).is_err());
        let mut cal = cal;
        assert!(!cal.mount(0));
    }

    #[test]
    fn a_table_out_of_the_streams_reach_gives_no_chain() {
        // Six links of 300 mm and the probe: the chain's reach check refuses it.
        let r = region(&fixtures::table(300.0));
        let cal = load::<F32>(&r);
        assert_eq!(cal.state(), TableState::Malformed);
        assert_eq!(cal.joints(), 0);
    }

    #[test]
    fn a_damaged_table_is_corrupt() {
        let mut t = fixtures::table(LINK_MM);
        let mid = t.len() / 2;
        t[mid] ^= 0x01;
        let r = region(&t);
        let cal = load::<Fixed>(&r);
        assert_eq!(cal.state(), TableState::Corrupt);
        assert!(cal.eval(&[0; JOINTS], 0).is_err());
    }

    #[test]
    fn a_refused_calibration_reports_its_reason() {
        let cal = Calibration::<F32>::refused(TableState::BadSignature);
        assert_eq!(cal.state(), TableState::BadSignature);
        assert_eq!(cal.joints(), 0);
        assert!(cal.eval(&[0; JOINTS], 0).is_err());
    }

    #[test]
    fn a_probe_the_table_lacks_is_not_mounted_and_the_chain_stays() {
        let r = region(&fixtures::table(LINK_MM));
        let mut cal = load::<F32>(&r);
        let before = cal.eval(&[0; JOINTS], 0).unwrap();
        // The fixture has one probe: index 0 mounts (again), index 1 does not exist.
        assert!(cal.mount(0));
        assert!(!cal.mount(1));
        assert_eq!(cal.eval(&[0; JOINTS], 0).unwrap(), before);
    }

    /// Loading in place over a calibration replaces all of it: a refusal leaves no chain, a
    /// table after it the same chain and U95 as a fresh load.
    #[test]
    fn a_load_in_place_replaces_what_was_there() {
        let r = region(&fixtures::table_with_budget(LINK_MM));
        let reading = [100, 200, 300, 400, 500, 600];
        let fresh = load::<F32>(&r).eval(&reading, 0).unwrap();
        let erased = [0xff; 4096];
        let mut cal = load::<F32>(&r);
        cal.load_in(&erased);
        assert_eq!((cal.state(), cal.joints()), (TableState::Missing, 0));
        assert!(cal.eval(&reading, 0).is_err());
        assert!(!cal.mount(0));
        cal.load_in(&r);
        assert_eq!(cal.state(), TableState::Valid);
        assert_eq!(cal.eval(&reading, 0).unwrap(), fresh);
        cal.refuse(TableState::BadSignature);
        assert_eq!(cal.state(), TableState::BadSignature);
        assert!(cal.eval(&reading, 0).is_err());
    }

    #[test]
    fn the_stream_format_is_the_evaluators() {
        assert_eq!(F32::STREAM, stream::NumberFormat::F32);
        assert_eq!(Fixed::STREAM, stream::NumberFormat::Fixed);
    }

    /// A table with an axis wobble and a parameter block: the Pico's profile (features `u95`
    /// and `wobble`, what `cargo xtask test` runs these tests with besides none) takes it in
    /// either number format and streams every point's U95 from its parameter block; qemu-m0's
    /// minimal profile (no feature) refuses it as it does today, `Malformed` (the parser's
    /// `Invalid { Flags }`: a block this firmware does not read), and gives no coordinates.
    #[test]
    fn the_profile_decides_on_the_wobble_and_the_parameter_block() {
        let t = fixtures::table_with_blocks(LINK_MM);
        let r = region(&t);
        let reading = [100, 200, 300, 400, 500, 600];
        let fixed = load::<Fixed>(&r);
        let f32_cal = load::<F32>(&r);
        if cfg!(all(feature = "u95", feature = "wobble")) {
            for cal in [fixed.state(), f32_cal.state()] {
                assert_eq!(cal, TableState::Valid);
            }
            let (p, q) = (
                f32_cal.eval(&reading, 0).unwrap(),
                fixed.eval(&reading, 0).unwrap(),
            );
            // The wobble's 20 µrad at joint 2 moves the tip by up to ~20 µm (a metre away),
            // the same in both formats; the two agree to the f32 chain's rounding.
            assert_near(p.xyz_nm, q.xyz_nm, 1_000);
            let (u, v) = (p.u95_nm.unwrap(), q.u95_nm.unwrap());
            assert!(u.abs_diff(v) <= u / 10_000 + 1, "f32 {u} nm, fixed {v} nm");
            // The parameter block adds to the reading's own terms: 10 µrad of joint 1 at up
            // to 1.2 m is ~12 µm, far above the budget's own (one count, 380 µrad, is ~0.5 mm
            // at 1.2 m: so compare with the same table's budget alone).
            let own = load::<Fixed>(&region(&fixtures::table_with_budget(LINK_MM)))
                .eval(&reading, 0)
                .unwrap()
                .u95_nm
                .unwrap();
            assert!(v > own, "with the block {v} nm, the budget alone {own} nm");
        } else {
            assert_eq!(
                Table::parse_for(&r, JOINTS).unwrap_err(),
                quatarm::table::TableError::Invalid {
                    joint: 0,
                    field: quatarm::table::Field::Flags
                }
            );
            for cal in [fixed.state(), f32_cal.state()] {
                assert_eq!(cal, TableState::Malformed);
            }
            assert!(fixed.eval(&reading, 0).is_err());
        }
    }

    /// With a budget in the table, a hub built with `u95` (the f32 boards and the Pico) gives
    /// every point a U95, the same in either number format to the rounding of the f32 sums;
    /// without the feature (qemu-m0's minimal profile) it gives none.
    #[test]
    fn a_budget_gives_u95_only_where_the_hub_computes_it() {
        let r = region(&fixtures::table_with_budget(LINK_MM));
        let reading = [100, 200, 300, 400, 500, 600];
        let p = load::<F32>(&r).eval(&reading, 0).unwrap();
        let q = load::<Fixed>(&r).eval(&reading, 0).unwrap();
        if cfg!(feature = "u95") {
            let u = p.u95_nm.expect("a U95 with the budget");
            // More than the probing (2 µm) and model (1 µm) terms at k = 2; of the order of a
            // millimetre in all, from the budget's one count on each joint (3.8e-4 rad at up to
            // 1.2 m from the tip).
            assert!((4_000..5_000_000).contains(&u), "{u} nm");
            let v = q.u95_nm.expect("a U95 with the budget, fixed point");
            assert!(u.abs_diff(v) <= u / 10_000 + 1, "f32 {u} nm, fixed {v} nm");
        } else {
            assert_eq!(p.u95_nm, None);
            assert_eq!(q.u95_nm, None);
        }
    }
}
