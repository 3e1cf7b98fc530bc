//! A fleet prior: what other units of the same design say about one unit's geometric errors
//! before it is measured.
//!
//! Units built to one design share systematic errors (a machining offset in every casting, an
//! assembly habit) and scatter about them. From N calibration files of that design, each
//! geometric unknown's error relative to the nominal arm is averaged over the units, and its
//! sample standard deviation is the spread: a Gaussian prior N(mean, sd²) per unknown for
//! [`Options::prior`](crate::fit::options::Options). A calibration from few rows then pulls its
//! weakly determined directions towards the fleet's typical errors instead of towards the
//! nominal arm.
//!
//! An unknown gets its own Gaussian only where at least [`MIN_UNITS`] units determined it and
//! they do not all agree exactly; the others are left to the calibration's class prior or
//! ridge, or to plain least squares ([`Fallback`] says which rule is left and why).
//!
//! A unit's error equal to the nominal arm's bit for bit is taken as *not determined* by that
//! unit: a calibration holds what its data cannot determine at its start value, and a fitted
//! floating-point value never lands exactly on it. Counting such a zero as a measurement would
//! pull the mean towards nominal and shrink the spread.

use crate::fit::priors::Gaussian;
use crate::params::{geometric_params, Param, ParamExt};
use quatarm_ref::arm::Arm;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Fewest units that determined an unknown for the fleet to give it a prior: a spread from
/// two values is too unreliable a width.
pub const MIN_UNITS: usize = 3;

/// A spread at or below this fraction of the largest |error| among the units is no spread:
/// units that share one value differ only by the rounding of `unit − nominal` (1e-16
/// relative), and a prior that narrow would pin the unknown (issue 27, F7: a spread of
/// 7.7e-20 rad). 1e-9 is far above rounding and far below any real scatter between units.
pub const SPREAD_REL_TOL: f64 = 1e-9;

/// One unknown's fleet statistics.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Entry {
    /// The calibration-file key (`joint[2].tilt[0]`).
    pub key: String,
    /// The unknown.
    #[serde(skip)]
    pub param: Param,
    /// Units that determined it (an error not exactly nominal).
    pub units: usize,
    /// Mean error relative to the nominal arm (the unknown's unit).
    pub mean: f64,
    /// Sample standard deviation of the errors (n − 1), 0 with fewer than two units.
    pub spread: f64,
    /// The prior's standard deviation: the spread of a new unit about a mean itself estimated
    /// from n units, spread · √(1 + 1/n).
    pub sd: f64,
    /// Unit of `mean` and `sd`.
    pub unit: &'static str,
    /// `None`: the fleet's Gaussian is used; else why the calibration's own rule applies.
    pub fallback: Option<Fallback>,
}

/// Why an unknown gets no fleet Gaussian.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Fallback {
    /// Fewer than [`MIN_UNITS`] units determined it (0: every unit held it at nominal).
    TooFewUnits,
    /// Every unit found the same value (to [`SPREAD_REL_TOL`]): no spread to weigh it by.
    NoSpread,
}

impl Fallback {
    /// In words.
    pub fn words(self) -> &'static str {
        match self {
            Fallback::TooFewUnits => "too few units determined it",
            Fallback::NoSpread => "no spread between the units",
        }
    }
}

/// The fleet's statistics of every geometric unknown.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FleetPrior {
    /// The calibration files (or names) the statistics come from.
    pub units: Vec<String>,
    /// Every geometric unknown of the design, in the calibration's order.
    pub entries: Vec<Entry>,
}

/// Why a fleet prior could not be built.
#[derive(Debug, thiserror::Error)]
pub enum FleetError {
    /// A file could not be read.
    #[error("fleet prior: {0}")]
    File(#[from] quatarm_ref::calfile::CalFileError),
    /// A unit is not of the nominal arm's design.
    #[error("fleet prior: {unit}: not the design of the nominal arm: {why}")]
    OtherDesign {
        /// The unit's file (or name).
        unit: String,
        /// What differs.
        why: String,
    },
    /// No units given.
    #[error("fleet prior: no calibration files given")]
    Empty,
    /// One file given twice: it would count as two units that agree exactly.
    #[error("fleet prior: {0} is given more than once: each unit counts once")]
    Duplicate(String),
}

/// The error of `p` in `unit` relative to `nominal`: the whole of a link or probe component
/// (nominal and error keys together), so that a file that moved a link into its `link` key
/// and one that put it into `link_error` say the same.
pub fn error_of(p: Param, unit: &Arm, nominal: &Arm) -> f64 {
    match p {
        Param::ZeroOffset(j) => unit.joints[j].zero_offset - nominal.joints[j].zero_offset,
        Param::Tilt(j, c) => unit.joints[j].tilt[c] - nominal.joints[j].tilt[c],
        Param::LinkError(j, c) => {
            let (u, n) = (&unit.joints[j], &nominal.joints[j]);
            (u.link[c] - n.link[c]) + (u.link_error[c] - n.link_error[c])
        }
        Param::ProbeError(k, c) => match (unit.probe_at(k), nominal.probe_at(k)) {
            (Some(u), Some(n)) => (u.vector[c] - n.vector[c]) + (u.error[c] - n.error[c]),
            _ => 0.0,
        },
        _ => 0.0,
    }
}

/// Refuses a unit that is not of the nominal arm's design: another joint count, another axis,
/// or an error beyond the plausible size of its unknown ([`Param::plausible`]: a link tens of
/// millimetres off is another arm, or the same arm described in other link conventions).
fn check_design(name: &str, unit: &Arm, nominal: &Arm) -> Result<(), FleetError> {
    let other = |why: String| FleetError::OtherDesign {
        unit: name.to_string(),
        why,
    };
    if unit.dof() != nominal.dof() {
        return Err(other(format!(
            "it has {} joints, the nominal arm {}",
            unit.dof(),
            nominal.dof()
        )));
    }
    for (j, (u, n)) in unit.joints.iter().zip(&nominal.joints).enumerate() {
        if u.axis != n.axis {
            return Err(other(format!(
                "joint {} turns about {:?}, the nominal arm's about {:?}",
                j + 1,
                u.axis,
                n.axis
            )));
        }
    }
    for p in geometric_params(nominal.dof()) {
        let e = error_of(p, unit, nominal);
        if !e.is_finite() || e.abs() > p.plausible() {
            return Err(other(format!(
                "{} differs from the nominal arm's by {e:.6} {}, beyond the plausible {} {}",
                p,
                p.unit(),
                p.plausible(),
                p.unit()
            )));
        }
    }
    Ok(())
}

/// The fleet prior of named arms (`(name, arm)`: a file name, or a unit's name) of the design
/// `nominal`.
pub fn from_arms(nominal: &Arm, units: &[(String, Arm)]) -> Result<FleetPrior, FleetError> {
    if units.is_empty() {
        return Err(FleetError::Empty);
    }
    for (name, arm) in units {
        check_design(name, arm, nominal)?;
    }
    let entries = geometric_params(nominal.dof())
        .into_iter()
        .map(|p| {
            let v: Vec<f64> = units
                .iter()
                .map(|(_, a)| error_of(p, a, nominal))
                .filter(|e| *e != 0.0)
                .collect();
            let n = v.len();
            let mean = if n > 0 {
                v.iter().sum::<f64>() / n as f64
            } else {
                0.0
            };
            let spread = if n > 1 {
                (v.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
            } else {
                0.0
            };
            let fallback = if n < MIN_UNITS {
                Some(Fallback::TooFewUnits)
            } else if !spread.is_finite()
                || spread <= SPREAD_REL_TOL * v.iter().fold(0.0f64, |m, e| m.max(e.abs()))
            {
                Some(Fallback::NoSpread)
            } else {
                None
            };
            Entry {
                key: p.to_string(),
                param: p,
                units: n,
                mean,
                spread,
                sd: spread * (1.0 + 1.0 / n.max(1) as f64).sqrt(),
                unit: p.unit(),
                fallback,
            }
        })
        .collect();
    Ok(FleetPrior {
        units: units.iter().map(|(n, _)| n.clone()).collect(),
        entries,
    })
}

/// The fleet prior of calibration files of the design `nominal`; an error names the file.
pub fn from_files(nominal: &Arm, paths: &[PathBuf]) -> Result<FleetPrior, FleetError> {
    let mut units = Vec::with_capacity(paths.len());
    let mut seen = Vec::with_capacity(paths.len());
    for p in paths {
        // The same file by another spelling (./a.toml, a link) is the same unit.
        let id = std::fs::canonicalize(p).unwrap_or_else(|_| p.clone());
        if seen.contains(&id) {
            return Err(FleetError::Duplicate(shown(p)));
        }
        seen.push(id);
        units.push((shown(p), crate::load::arm(p)?));
    }
    from_arms(nominal, &units)
}

fn shown(p: &Path) -> String {
    p.display().to_string()
}

impl FleetPrior {
    /// The per-unknown Gaussians for [`Prior::unknowns`](crate::fit::priors::Prior): every
    /// entry without a fallback. They are increments from the nominal arm, so the calibration
    /// must start from it.
    pub fn gaussians(&self) -> Vec<(Param, Gaussian)> {
        self.entries
            .iter()
            .filter(|e| e.fallback.is_none())
            .map(|e| {
                (
                    e.param,
                    Gaussian {
                        mean: e.mean,
                        sd: e.sd,
                    },
                )
            })
            .collect()
    }

    /// The entries left to the calibration's own rule.
    pub fn fallbacks(&self) -> impl Iterator<Item = &Entry> {
        self.entries.iter().filter(|e| e.fallback.is_some())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A copy of issue 27's reproducer F7 (`../shared/repro/round2/`).
    fn repro(name: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/repro27")
            .join(name)
    }

    #[test]
    fn f7_a_value_every_unit_shares_is_no_spread() {
        let nominal = crate::load::arm(&repro("arm.toml")).unwrap();
        let files: Vec<PathBuf> = (1..=3)
            .map(|k| repro(&format!("f7-prior{k}.toml")))
            .collect();
        let f = from_files(&nominal, &files).unwrap();
        let shared = f
            .entries
            .iter()
            .find(|e| e.param == Param::ZeroOffset(0))
            .unwrap();
        // The three units hold one non-nominal value: its spread is rounding (1e-20 rad).
        assert_eq!(shared.units, 3);
        assert!(shared.mean != 0.0 && shared.spread < 1e-15, "{shared:?}");
        assert_eq!(shared.fallback, Some(Fallback::NoSpread), "{shared:?}");
        assert!(f
            .gaussians()
            .iter()
            .all(|(p, _)| *p != Param::ZeroOffset(0)));
        // The link errors the units do not share keep their fleet Gaussian.
        let link = f
            .entries
            .iter()
            .find(|e| e.param == Param::LinkError(0, 0))
            .unwrap();
        assert_eq!(link.fallback, None, "{link:?}");
    }

    #[test]
    fn f7_a_file_given_twice_is_refused() {
        let nominal = crate::load::arm(&repro("arm.toml")).unwrap();
        let one = repro("f7-prior1.toml");
        let other = repro("f7-prior2.toml");
        // The same file spelt another way is the same unit.
        let again = one.parent().unwrap().join(".").join("f7-prior1.toml");
        let e = from_files(&nominal, &[one.clone(), other, again]).unwrap_err();
        assert!(
            matches!(e, FleetError::Duplicate(ref s) if s.contains("f7-prior1.toml")),
            "{e}"
        );
        assert!(from_files(&nominal, &[one.clone(), one.clone(), one]).is_err());
    }
}
