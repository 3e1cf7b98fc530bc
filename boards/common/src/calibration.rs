//! The table in its flash region, checked once at boot, and the chain built from it.
//!
//! A hub drives a fixed number of encoders, so the table must be for exactly that many joints
//! (`Table::parse_for`); any refusal of the parser or of the chain's constructor becomes the
//! [`TableState`] every report then carries, and no chain exists to produce coordinates.

use quatarm::stream::{self, Coordinates, Hub, TableState};
use quatarm::{Chain, ChainError, Evaluator, Table};

/// Joints of the arms these hubs drive.
pub const JOINTS: usize = 6;

/// A chain evaluator a hub can run, with the name its hello message gives its number format:
/// the type picks the arithmetic, so the announced format cannot disagree with the one
/// evaluated.
pub trait HubEvaluator: Evaluator {
    /// What the hub announces.
    const STREAM: stream::NumberFormat;
}

impl HubEvaluator for quatarm::F32 {
    const STREAM: stream::NumberFormat = stream::NumberFormat::F32;
}

impl HubEvaluator for quatarm::Fixed {
    const STREAM: stream::NumberFormat = stream::NumberFormat::Fixed;
}

/// The boot check's outcome: a chain, or why there is none.
pub struct Calibration<P: Evaluator> {
    chain: Result<Chain<P>, TableState>,
}

impl<P: Evaluator> Calibration<P> {
    /// No chain: the boot refused every table, for the reason `state` (a signature, a layout
    /// that does not fit the flash).
    pub fn refused(state: TableState) -> Calibration<P> {
        Calibration { chain: Err(state) }
    }
}

/// Validates the region's bytes and builds the chain.
pub fn load<P: Evaluator>(region: &[u8]) -> Calibration<P> {
    let chain = validate(region).and_then(build::<P>);
    Calibration { chain }
}

/// Like [`load`], for a hub whose encoders have the given counts per revolution (joint 1
/// first): a table made for other encoders would turn every count into a wrong angle.
pub fn load_for_encoders<P: Evaluator>(region: &[u8], counts_per_rev: &[u32]) -> Calibration<P> {
    let chain = validate(region)
        .and_then(|t| {
            let fits =
                (0..JOINTS).all(|i| t.joint(i).map(|j| j.counts) == counts_per_rev.get(i).copied());
            if fits {
                Ok(t)
            } else {
                Err(TableState::WrongResolution)
            }
        })
        .and_then(build::<P>);
    Calibration { chain }
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

impl<P: HubEvaluator> Calibration<P> {
    /// A hub that reports this calibration's state, joints and precision.
    #[inline(always)] // called once per image: out of line it only adds a call (24 B on the M0)
    pub fn hub(&self) -> Hub {
        Hub::new(self.state(), self.joints(), P::STREAM)
    }
}

impl<P: Evaluator> Calibration<P> {
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

    /// Runs the chain on one reading.
    pub fn eval(&self, counts: &[u32], temp_mc: i32) -> Result<Coordinates, ChainError> {
        match &self.chain {
            Ok(chain) => chain.eval(counts, temp_mc).map(|p| Coordinates {
                xyz_nm: p.xyz_nm(),
                dir_e9: p.dir_e9(),
            }),
            // The hub never calls eval without a valid table; answer like a refusal anyway.
            Err(_) => Err(ChainError::JointCount {
                expected: 0,
                found: counts.len() as u8,
            }),
        }
    }
}
