//! The calibration file a command writes (`calibrate`, `diagnose -o`), checked before it is
//! written: a file that does not read back, or reads back as another model, is a bug caught
//! here rather than a file no command can use.

use anyhow::bail;
use armcal::fit::probes::Mounted;
use quatarm_ref::calfile;

/// The calibration file's text, checked by reading it back (the budget too) and evaluating
/// it on the first rows of the data against the fit itself.
pub fn checked_text(
    arm: &quatarm_ref::arm::Arm,
    budget: Option<&quatarm_ref::calfile::Uncertainty>,
    header: &[&str],
    data: &armcal::data::Dataset,
) -> anyhow::Result<String> {
    let text = calfile::write_with(arm, budget, header);
    let (back, back_budget) = armcal::load::written_with(&text)
        .map_err(|e| anyhow::anyhow!("the calibration file written does not read back: {e}"))?;
    if back_budget.as_ref() != budget {
        bail!("the [uncertainty] section written does not read back the same (a bug)");
    }
    let (back_m, arm_m) = (Mounted::new(&back), Mounted::new(arm));
    for r in data.rows.iter().take(50) {
        let d = (back_m.tip(r) - arm_m.tip(r)).norm();
        if d > 1e-9 {
            bail!("the calibration file written evaluates {d} mm away from the fit (a bug)");
        }
    }
    Ok(text)
}

/// Stages the calibration `text` at `out` and its binary table beside it (`.bin`), for
/// `calibrate` and `diagnose -o` alike. Where the firmware cannot hold the model the table
/// is not written, a stale one there is removed at commit (it would describe another
/// model), and the build's error is returned for the command's report to word.
pub fn stage_with_table(
    files: &mut armcal::output::Staged,
    out: &std::path::Path,
    text: &str,
    arm: &quatarm_ref::arm::Arm,
    budget: Option<&quatarm_ref::calfile::Uncertainty>,
) -> anyhow::Result<Result<std::path::PathBuf, armcal::tablebuild::BuildError>> {
    files.write(out, text.as_bytes())?;
    let table = out.with_extension("bin");
    match armcal::tablebuild::build_with(arm, budget) {
        Ok(bytes) => {
            files.write(&table, &bytes)?;
            Ok(Ok(table))
        }
        Err(e) => {
            files.remove_at_commit(&table);
            Ok(Err(e))
        }
    }
}
