//! The diagnosis report of `armcal diagnose --report FILE.html`: the header, the verdict (the
//! causes named and the held-out gain), held-out residuals before and after the diagnosis,
//! the residual vectors, and the whole text report (each cause with its evidence).

use super::{header::Provenance, residuals, Document, Tone};
use crate::data::Dataset;
use crate::diagnose::report::Report;
use crate::diagnose::Diagnosis;

/// The page.
pub fn page(rep: &Report, d: &Diagnosis, data: &Dataset, prov: &Provenance) -> String {
    let headline = format!(
        "Held-out RMS {:.2} µm → {:.2} µm ({:+.1} %)",
        rep.baseline.holdout_rms_um,
        rep.extended.holdout_rms_um,
        -d.gain_percent()
    );
    let tone = if d.causes.is_empty() {
        Tone::Plain
    } else {
        Tone::Unsure
    };
    let mut doc = Document::opening(
        "Diagnosis report",
        prov,
        (&headline, &rep.verdict, tone),
        &rep.warnings,
    );
    doc.heading("Sessions and the nested held-out test");
    doc.paragraph(&format!("Sessions: {}.", rep.sessions_from));
    doc.paragraph(&match (&rep.nested, &rep.nested_not_run) {
        (Some(n), _) => format!(
            "The whole selection rerun without each session: {}.",
            n.summary
        ),
        (None, Some(why)) => format!("Nested held-out test {why}."),
        (None, None) => "Nested held-out test not run.".into(),
    });
    doc.heading("Plots");
    let arm = &d.extended.fit.arm;
    let at = crate::acceptance::centres(arm, data);
    let (b, e) = (&d.baseline.holdout, &d.extended.holdout);
    let judged = |i: usize| {
        b.judged.get(i).copied().unwrap_or(false) && e.judged.get(i).copied().unwrap_or(false)
    };
    let plots = vec![
        residuals::before_after(
            "Held-out residuals before and after the diagnosis",
            (
                &format!("before: {}", rep.baseline.model),
                &format!("after: {}", rep.extended.model),
            ),
            &at,
            &b.residuals.rows,
            &e.residuals.rows,
            &judged,
        ),
        residuals::vectors(
            "Held-out residual vectors, geometric model",
            &at,
            &b.residuals.rows,
            &judged,
        ),
        residuals::vectors(
            "Held-out residual vectors, extended model",
            &at,
            &e.residuals.rows,
            &judged,
        ),
    ];
    doc.figures(&plots);
    doc.closing(&rep.text())
}
