//! The calibration's uncertainty budget as the hub carries it (`quatarm::table::budget`):
//! the reading's own terms. The parameter covariance is not carried yet (the table module
//! says why, with the measurement).

use quatarm::table::budget::BudgetData;
use quatarm::table::MAX_JOINTS;
use quatarm_ref::uncertainty::Uncertainty;

/// The table's budget of a calibration file's `[uncertainty]` section.
pub fn budget_data(u: &Uncertainty) -> BudgetData {
    let mut encoder_counts = [0.0; MAX_JOINTS];
    for (e, c) in encoder_counts.iter_mut().zip(&u.encoder_counts) {
        *e = *c;
    }
    BudgetData {
        encoder_counts,
        probing_mm: u.probing_mm,
        model_mm: u.model_mm,
        temperature_c: u.temperature_c,
    }
}
