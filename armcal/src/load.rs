//! Loading a calibration file for a command: the physical limits applied, unknown keys warned
//! about on stderr. Every command reads its arms through here, so they all refuse the same
//! values.

use crate::limits::CALFILE;
use quatarm_ref::arm::Arm;
use quatarm_ref::calfile;
use std::path::Path;

/// Reads the calibration file at `path`, refusing values beyond [`CALFILE`] with their key.
pub fn arm(path: &Path) -> Result<Arm, calfile::CalFileError> {
    calibration(path).map(|(arm, _)| arm)
}

/// Reads a calibration file with its `[uncertainty]` budget (if it has one).
pub fn calibration(
    path: &Path,
) -> Result<(Arm, Option<calfile::Uncertainty>), calfile::CalFileError> {
    let parsed = calfile::read_with(path, &CALFILE)?;
    for k in &parsed.unknown_keys {
        eprintln!(
            "armcal: warning: {}: unknown key {} ignored",
            path.display(),
            crate::limits::shown(k)
        );
    }
    Ok((parsed.arm, parsed.uncertainty))
}

/// Reads back the text of a calibration file just written, with the same limits: a fit that
/// wandered beyond them is refused here rather than written as a file no command reads.
pub fn written(text: &str) -> Result<Arm, calfile::CalFileError> {
    written_with(text).map(|(arm, _)| arm)
}

/// As [`written`], with the budget read back too.
pub fn written_with(
    text: &str,
) -> Result<(Arm, Option<calfile::Uncertainty>), calfile::CalFileError> {
    calfile::parse_with(text, &CALFILE).map(|p| (p.arm, p.uncertainty))
}

/// A calibration file without the budget an option needs.
#[derive(Debug, thiserror::Error)]
pub enum BudgetLoadError {
    /// The file itself.
    #[error(transparent)]
    CalFile(#[from] calfile::CalFileError),
    /// No `[uncertainty]` section.
    #[error("{path}: no [uncertainty] section: {needed_by} needs the calibration's budget (armcal calibrate writes one)")]
    NoBudget {
        /// The file.
        path: String,
        /// The option that needs it.
        needed_by: &'static str,
    },
}

/// A calibration and, where `needed_by` names an option that needs it, its uncertainty
/// budget: a file without one is refused rather than taken as a zero uncertainty.
pub fn calibration_and_budget(
    path: &Path,
    needed_by: Option<&'static str>,
) -> Result<(Arm, Option<crate::uncertainty::Budget>), BudgetLoadError> {
    let (arm, budget) = calibration_with_budget(path, needed_by)?;
    Ok((arm, budget.filter(|_| needed_by.is_some())))
}

/// A calibration and its budget whenever the file has one (`check` takes U from it); a file
/// without one is refused only where `needed_by` names an option that needs it.
pub fn calibration_with_budget(
    path: &Path,
    needed_by: Option<&'static str>,
) -> Result<(Arm, Option<crate::uncertainty::Budget>), BudgetLoadError> {
    let (arm, file) = calibration(path)?;
    let budget = match (needed_by, file) {
        (_, Some(u)) => Some(crate::uncertainty::Budget::from_file(&u)),
        (None, None) => None,
        (Some(needed_by), None) => {
            return Err(BudgetLoadError::NoBudget {
                path: path.display().to_string(),
                needed_by,
            })
        }
    };
    Ok((arm, budget))
}
