//! A calibration file read with its uncertainty budget, for the commands that need the budget
//! (`eval --u95`, `check`): the arm through [`crate::load`], the budget made from its
//! `[uncertainty]` section. Here rather than in `load`, which the fit uses too and which must
//! not import the uncertainty (a higher layer).

use super::Budget;
use crate::load::calibration;
use quatarm_ref::arm::Arm;
use quatarm_ref::calfile;
use std::path::Path;

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
) -> Result<(Arm, Option<Budget>), BudgetLoadError> {
    let (arm, budget) = calibration_with_budget(path, needed_by)?;
    Ok((arm, budget.filter(|_| needed_by.is_some())))
}

/// A calibration and its budget whenever the file has one (`check` takes U from it); a file
/// without one is refused only where `needed_by` names an option that needs it.
pub fn calibration_with_budget(
    path: &Path,
    needed_by: Option<&'static str>,
) -> Result<(Arm, Option<Budget>), BudgetLoadError> {
    let (arm, file) = calibration(path)?;
    let budget = match (needed_by, file) {
        (_, Some(u)) => Some(Budget::from_file(&u)),
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
