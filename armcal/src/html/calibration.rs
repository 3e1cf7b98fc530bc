//! The calibration certificate of `armcal calibrate --report FILE.html`: the header, the
//! result (RMS residuals, held out where validated), the residual plots, and the whole text
//! report (every parameter with its uncertainty).

use super::{header::Provenance, residuals, Document, Tone};
use crate::data::Dataset;
use crate::fit::finish::Fit;
use crate::fit::holdout::Holdout;
use crate::fit::report::{Report, Section};

/// The page.
pub fn page(
    rep: &Report<impl Section>,
    fit: &Fit,
    data: &Dataset,
    validation: Option<&Holdout>,
    prov: &Provenance,
) -> String {
    let r = &rep.residuals;
    let held = r
        .holdout
        .as_ref()
        .map_or("not validated on held-out data".to_string(), |h| {
            format!(
                "{:.2} µm RMS on held-out data ({})",
                h.residuals.all.rms_um, h.method
            )
        });
    let detail = format!(
        "RMS residual on the data fitted: {:.2} µm before, {:.2} µm after the fit; {} of {} \
         unknowns fitted; terms {}",
        r.before.all.rms_um, r.after.all.rms_um, rep.fitted, rep.unknowns, rep.terms
    );
    let mut d = Document::opening(
        "Calibration certificate",
        prov,
        (&format!("Residual {held}"), &detail, Tone::Plain),
        &rep.warnings,
    );
    d.heading("Plots");
    let at = crate::acceptance::centres(&fit.arm, data);
    let before = crate::fit::residuals::residuals(&fit.start, data, None);
    let after = crate::fit::residuals::residuals(&fit.arm, data, fit.frame);
    let all = |_: usize| true;
    let mut plots = vec![
        residuals::vectors("Residual vectors after the fit", &at, &after.rows, &all),
        residuals::before_after(
            "Residuals before and after the fit",
            ("before (start arm)", "after (calibrated)"),
            &at,
            &before.rows,
            &after.rows,
            &all,
        ),
    ];
    if let Some(h) = validation {
        let judged = |i: usize| h.judged.get(i).copied().unwrap_or(false);
        plots.push(residuals::vectors(
            "Held-out residual vectors",
            &at,
            &h.residuals.rows,
            &judged,
        ));
    }
    d.figures(&plots);
    d.closing(&rep.text())
}
