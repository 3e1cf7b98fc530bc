//! The measured data of `calibrate`, `diagnose` and `check`, read the one way: one file or
//! several (each file's groups kept apart, `armcal::data::read_all`), radians or counts,
//! then the probes and plausibility checked, file by file, before any fit or decision.

use armcal::data::Dataset;
use armcal::plausible::Accept;
use quatarm_ref::arm::Arm;
use std::path::{Path, PathBuf};

/// The files as one dataset for `arm`, checked; its notes (renumbered groups) and the reader's
/// warnings are printed on stderr, each naming its file once.
pub fn read(paths: &[PathBuf], arm: &Arm, accept: Accept) -> anyhow::Result<Dataset> {
    let files = armcal::data::read_all(paths, arm)?;
    // File by file, so that a message names the file and the line of the row at fault.
    for part in &files.parts {
        armcal::fit::probes::check(arm, part)?;
        armcal::plausible::data(arm, part, accept)?;
    }
    if !accept.duplicates {
        armcal::plausible::duplicates(&files.parts)?;
    }
    for n in &files.notes {
        eprintln!("armcal: note: {n}");
    }
    for w in &files.data.warnings {
        eprintln!("armcal: warning: {w}");
    }
    Ok(files.data)
}

/// The files as the output guard lists them (no output may overwrite one).
pub fn inputs(paths: &[PathBuf]) -> Vec<(&Path, &'static str)> {
    paths.iter().map(|p| (p.as_path(), "data")).collect()
}

/// The files as messages and a calibration's header name them: `a.csv + b.csv`.
pub fn names(paths: &[PathBuf]) -> String {
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(" + ")
}
