//! The table in its flash region, checked once at boot, and the chain built from it.
//!
//! A hub drives a fixed number of encoders, so the table must be for exactly that many joints
//! (`Table::parse_for`); any refusal of the parser or of the chain's constructor becomes the
//! [`TableState`] every report then carries, and no chain exists to produce coordinates.
//! Where the table carries an uncertainty budget and the board's number format computes it,
//! every point gets its U95 ([`PointUncertainty`]). The chain ends at the table's first probe
//! from boot; [`Calibration::mount`] converts another of the table's when the host selects
//! it.

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

/// The fixed-point hubs stream no U95: the Cortex-M0's 32 KiB hold the chain, the stream and
/// the table's checks, not the uncertainty as well (README, "On the targets": its flash and
/// instructions measured on the M0's benchmark image).
impl HubEvaluator for quatarm::Fixed {
    const STREAM: stream::NumberFormat = stream::NumberFormat::Fixed;
    type Uncertainty<'a> = NoUncertainty;
}

/// A point's U95 as a hub computes it, built at boot from the table.
pub trait PointUncertainty<'a, P: Evaluator>: Sized {
    /// The table's; `None` where it has no budget (or the hub computes none).
    fn of(table: &Table<'a>) -> Option<Self>;
    /// U95 of a point `chain` evaluated (nm); `None` where it cannot be computed.
    fn u95_nm(&self, chain: &Chain<P>, counts: &[u32], temp_mc: i32, p: &Point<P>) -> Option<u32>;
    /// Follows the chain to the table's probe `k`; `false` where it cannot.
    fn mount(&mut self, table: &Table<'a>, k: usize) -> bool;
}

impl<'a, P: Evaluator> PointUncertainty<'a, P> for Uncertainty<'a, P> {
    fn of(table: &Table<'a>) -> Option<Self> {
        // A budget the chain cannot use (it built the same matrix chain's model) gives no U95
        // rather than no coordinates.
        Uncertainty::new(table).ok().flatten()
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
    fn of(_: &Table<'_>) -> Option<Self> {
        None
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
pub struct Calibration<'a, P: HubEvaluator> {
    chain: Result<Chain<P>, TableState>,
    uncertainty: Option<P::Uncertainty<'a>>,
    /// The table the chain was built from (with the chain only), whose probes it mounts.
    table: Option<Table<'a>>,
}

impl<'a, P: HubEvaluator> Calibration<'a, P> {
    /// No chain: the boot refused every table, for the reason `state` (a signature, a layout
    /// that does not fit the flash).
    pub fn refused(state: TableState) -> Calibration<'a, P> {
        Calibration {
            chain: Err(state),
            uncertainty: None,
            table: None,
        }
    }

    fn of(table: Result<Table<'a>, TableState>) -> Calibration<'a, P> {
        let chain = table.and_then(build::<P>);
        let table = table.ok().filter(|_| chain.is_ok());
        let uncertainty = table.as_ref().and_then(P::Uncertainty::of);
        Calibration {
            chain,
            uncertainty,
            table,
        }
    }

    /// Mounts the table's probe `k` (its index in the table, [`Hub::select`]'s): the chain
    /// and its points' uncertainty end at that probe from the next reading on. `false`, and
    /// the probe before stays, where there is no chain or the probe cannot be converted
    /// (which the boot's check of the reach with the longest probe rules out).
    pub fn mount(&mut self, k: usize) -> bool {
        let (Ok(chain), Some(table)) = (&mut self.chain, &self.table) else {
            return false;
        };
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
    Calibration::of(validate(region))
}

// Validation and construction are kept out of line, one after the other, so that their stack
// frames are not stacked on top of each other: on the M0 (soft f64) each needs several KiB,
// and the hub's whole budget is 8 KiB.
#[inline(never)]
fn validate(region: &[u8]) -> Result<Table<'_>, TableState> {
    Table::parse_for(region, JOINTS).map_err(|e| TableState::from(&e))
}

#[inline(never)]
fn build<P: Evaluator>(table: Table<'_>) -> Result<Chain<P>, TableState> {
    Chain::<P>::new(&table).map_err(|_| TableState::Malformed)
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
    /// What the stream reports about the table.
    pub fn state(&self) -> TableState {
        match &self.chain {
            Ok(_) => TableState::Valid,
            Err(s) => *s,
        }
    }

    /// Joints of the valid table (0 without one).
    pub fn joints(&self) -> u8 {
        match &self.chain {
            Ok(c) => c.joint_count() as u8,
            Err(_) => 0,
        }
    }

    /// Runs the chain on one reading, with the point's U95 where the hub computes it.
    pub fn eval(&self, counts: &[u32], temp_mc: i32) -> Result<Coordinates, ChainError> {
        match &self.chain {
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
