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
