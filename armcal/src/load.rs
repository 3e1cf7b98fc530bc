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
    calibration_release(path).map(|(arm, u, _)| (arm, u))
}

/// The arm, budget and `[calibration]` section (number, date, due date) of a file.
pub type WithRelease = (
    Arm,
    Option<calfile::Uncertainty>,
    quatarm_ref::release::Release,
);

/// [`calibration`] with its `[calibration]` section.
pub fn calibration_release(path: &Path) -> Result<WithRelease, calfile::CalFileError> {
    let parsed = calfile::read_with(path, &CALFILE)?;
    for k in &parsed.unknown_keys {
        eprintln!(
            "armcal: warning: {}: unknown key {} ignored",
            path.display(),
            crate::limits::shown(k)
        );
    }
    Ok((parsed.arm, parsed.uncertainty, parsed.release))
}

/// The warning for a calibration past its due date on `today` (`None` within it, or
/// without a due date): what `armcal eval` and `armcal decode --calib` print on stderr.
pub fn due_warning(
    path: &Path,
    release: &quatarm_ref::release::Release,
    today: quatarm_ref::release::Date,
) -> Option<String> {
    let due = release.due.filter(|_| release.overdue(today))?;
    let date = release
        .date
        .map_or_else(String::new, |d| format!(", dated {d}"));
    Some(format!(
        "armcal: warning: {}: calibration number {}{date} was due on {due} (today is {today}): recalibrate the arm",
        path.display(),
        release.number
    ))
}

/// Reads `path`'s `[calibration]` and prints [`due_warning`] for today, if any.
/// (Read without [`calibration`]'s unknown-key warnings: the command reads the file again
/// for its arm and prints them then.)
pub fn warn_if_due(path: &Path) -> Result<(), calfile::CalFileError> {
    let release = calfile::read_with(path, &CALFILE)?.release;
    if let Some(w) = due_warning(path, &release, quatarm_ref::release::Date::today()) {
        eprintln!("{w}");
    }
    Ok(())
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

#[cfg(test)]
mod tests {
    use super::*;
    use quatarm_ref::release::{Date, Release};

    #[test]
    fn the_due_warning_comes_only_past_the_due_date() {
        let r = Release {
            number: 7,
            date: Date::new(2025, 12, 1),
            due: Date::new(2026, 12, 1),
        };
        let p = Path::new("arm.toml");
        assert_eq!(due_warning(p, &r, Date::new(2026, 12, 1).unwrap()), None);
        let w = due_warning(p, &r, Date::new(2026, 12, 4).unwrap()).unwrap();
        assert!(
            w.contains("arm.toml")
                && w.contains("number 7, dated 2025-12-01")
                && w.contains("due on 2026-12-01")
                && w.contains("today is 2026-12-04"),
            "{w}"
        );
        let undated = Release { due: None, ..r };
        assert_eq!(
            due_warning(p, &undated, Date::new(2030, 1, 1).unwrap()),
            None
        );
    }
}
