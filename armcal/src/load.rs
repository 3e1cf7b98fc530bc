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
