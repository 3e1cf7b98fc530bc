//! The budget a calibration leaves, and what of it the data estimated and what was assumed.
//!
//! - Parameters: the sub-block of σ̂² (JᵀJ)⁻¹ for the arm's unknowns. The inverse is of the
//!   whole fit (instrument frame included), so its sub-block is the covariance marginal over
//!   the frame; `spat` points are eliminated by variable projection, the same marginalisation.
//!   σ̂ is the residual standard deviation per equation. When held-out residuals exceed what
//!   the in-sample σ̂ predicts for them (mean square ratio (1 + p/n)/(1 − p/n) for p unknowns
//!   and n equations), C is inflated by the excess: what the in-sample estimate misses.
//! - Reading: 1/√12 counts (quantisation) unless set: the data cannot separate encoder noise
//!   from the instrument's.
//! - Probing: the `spat` scatter per axis (and that of each bar end of `length` data, the
//!   same kind of repeated probing), less what the reading's own uncertainty explains of it,
//!   when there are such rows; else assumed (0 unless set): `point` residuals carry the
//!   instrument's noise and cannot tell the probing apart.
//! - Model and temperature: assumed (0 unless set).

use super::{propagate, Budget, QUANTISATION_COUNTS};
use crate::calib::Fit;
use crate::data::{Dataset, Kind};
use crate::holdout::Holdout;
use nalgebra::DMatrix;

/// What the caller sets; `None` lets the data decide where they can.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Reading (counts).
    pub encoder_counts: f64,
    /// Probing per axis (mm); `None`: from `spat` scatter, or 0 without `spat` rows.
    pub probing_mm: Option<f64>,
    /// Model per axis (mm).
    pub model_mm: f64,
    /// Temperature reading (°C).
    pub temperature_c: f64,
}

impl Default for Settings {
    fn default() -> Settings {
        Settings {
            encoder_counts: QUANTISATION_COUNTS,
            probing_mm: None,
            model_mm: 0.0,
            temperature_c: 0.0,
        }
    }
}

/// A budget with, per term, how it was obtained.
#[derive(Clone, Debug)]
pub struct Estimated {
    /// The budget.
    pub budget: Budget,
    /// One line per term: its value and whether estimated or assumed.
    pub notes: Vec<String>,
    /// Factor C was multiplied by after the held-out check (1: none).
    pub inflation: f64,
}

/// The parameters' covariance of a fit, marginal over the frame: (params, C).
fn marginal(fit: &Fit) -> Result<(Vec<crate::params::Param>, DMatrix<f64>), super::BudgetError> {
    let (order, c) = fit
        .covariance
        .as_ref()
        .ok_or(super::BudgetError::NoCovariance)?;
    let keep: Vec<usize> = (0..order.len())
        .filter(|&k| !fit.params[order[k]].is_frame())
        .collect();
    let params = keep.iter().map(|&k| fit.params[order[k]]).collect();
    let m = DMatrix::from_fn(keep.len(), keep.len(), |a, b| c[(keep[a], keep[b])]);
    Ok((params, m))
}

/// Held-out over in-sample mean square, against what it should be for an honest σ̂.
fn held_out_excess(fit: &Fit, holdout: &Holdout, in_sample_rms_um: f64) -> Option<f64> {
    let ho = holdout.summary.all.rms_um;
    if !(ho > 0.0 && in_sample_rms_um > 0.0) {
        return None;
    }
    let p = fit.ident.kept.len() as f64;
    let n = fit.equations as f64;
    let expected = (1.0 + p / n) / (1.0 - p / n).max(1e-3);
    Some(((ho / in_sample_rms_um).powi(2) / expected).max(1.0))
}

/// Per-axis probing from the scatter of the `spat` groups and bar ends (each probing of a
/// fixed point from another pose) and the radial scatter of the `sphere` groups about their
/// sphere of known radius: (sd, rows used), less the reading's own part.
fn spat_probing(fit: &Fit, data: &Dataset, budget: &Budget) -> Option<(f64, usize)> {
    let res = crate::residuals::residuals(&fit.arm, data, fit.frame);
    let layout = data.layout();
    let groups = layout
        .spat
        .iter()
        .map(|g| &g.rows)
        .chain(layout.length.iter().flat_map(|g| [&g.a, &g.b]))
        .map(|g| (g, 3, 3))
        // A sphere row's residual is radial: one equation per row, less the centre's three.
        .chain(layout.sphere.iter().map(|g| (&g.rows, 1, 3)));
    let (mut ss, mut dof, mut own, mut rows) = (0.0, 0usize, 0.0, 0usize);
    let st = budget.sigma_theta(&fit.arm);
    // (rows, equations per row, equations the group's own point or centre takes)
    for (g, per_row, lost) in groups {
        for &i in g {
            ss += res.rows[i].norm_squared();
            let r = &data.rows[i];
            let j = {
                let probe = crate::probes::index(&fit.arm, r);
                propagate::jacobians(&fit.arm, probe, budget, &r.theta, r.temp_c)
            };
            own += propagate::own_terms(budget, &st, &j).trace();
            rows += 1;
        }
        dof += (per_row * g.len()).saturating_sub(lost);
    }
    (dof > 0).then(|| {
        let var = ss / dof as f64 - own / (3 * rows) as f64;
        (var.max(0.0).sqrt(), rows)
    })
}

/// The covariance of a fit's identified arm unknowns, marginal over the frame, inflated by
/// the held-out excess when `holdout` is given (see the module text): (params, C, the
/// factor). The budget's parameter term, and what the fleet's same-arm test
/// ([`crate::diagnose::same_arm`]) compares recordings with.
pub fn parameters(
    fit: &Fit,
    holdout: Option<&Holdout>,
    in_sample_rms_um: f64,
) -> Result<(Vec<crate::params::Param>, DMatrix<f64>, f64), super::BudgetError> {
    let (params, mut cov) = marginal(fit)?;
    let mut inflation = 1.0;
    if let Some(k) = holdout.and_then(|h| held_out_excess(fit, h, in_sample_rms_um)) {
        inflation = k;
        cov *= k;
    }
    Ok((params, cov, inflation))
}

/// The budget of a fit of `data`; `holdout` the held-out validation if one was run.
pub fn from_fit(
    fit: &Fit,
    data: &Dataset,
    holdout: Option<&Holdout>,
    in_sample_rms_um: f64,
    s: &Settings,
) -> Result<Estimated, super::BudgetError> {
    let (params, cov, inflation) = parameters(fit, holdout, in_sample_rms_um)?;
    let mut notes = vec![format!(
        "parameters: covariance of the {} identified unknowns, estimated: σ̂² (JᵀJ)⁻¹ with σ̂ = \
         {:.2} µm per equation, marginal over the instrument frame, the spat points and the sphere centres",
        params.len(),
        fit.sigma_mm * 1e3
    )];
    if let Some(k) = holdout.and_then(|h| held_out_excess(fit, h, in_sample_rms_um)) {
        notes.push(format!(
            "held-out residuals: mean square {k:.3}× what σ̂ predicts for them{}",
            if k > 1.0 {
                "; C inflated by that factor"
            } else {
                ": C kept"
            }
        ));
    }
    let mut budget = Budget {
        params,
        cov,
        encoder_counts: vec![s.encoder_counts; data.dof],
        probing_mm: 0.0,
        temperature_c: s.temperature_c,
        model_mm: s.model_mm,
    };
    notes.push(format!(
        "reading: {:.3} counts, {}",
        s.encoder_counts,
        if s.encoder_counts == QUANTISATION_COUNTS {
            "assumed: quantisation alone (1/√12); set --encoder-counts for a noisier encoder"
        } else {
            "set by the caller"
        }
    ));
    let has_spat = data.rows.iter().any(|r| r.kind != Kind::Point);
    budget.probing_mm = match (s.probing_mm, has_spat) {
        (Some(p), _) => {
            notes.push(format!(
                "probing: {:.2} µm per axis, set by the caller",
                p * 1e3
            ));
            p
        }
        (None, true) => {
            let (p, rows) = spat_probing(fit, data, &budget).unwrap_or((0.0, 0));
            notes.push(format!(
                "probing: {:.2} µm per axis, estimated from the scatter of {rows} spat and \
                 length rows about their points, less the reading's own part (it holds what \
                 the model leaves unexplained there too)",
                p * 1e3
            ));
            p
        }
        (None, false) => {
            notes.push(
                "probing: 0, assumed: no spat or length rows, and point residuals cannot \
                 tell it from the instrument's noise (set --probing-mm)"
                    .into(),
            );
            0.0
        }
    };
    notes.push(format!(
        "model: {:.2} µm per axis, {}; temperature: {:.3} °C, {}",
        s.model_mm * 1e3,
        if s.model_mm == 0.0 {
            "assumed 0 (--model-mm)"
        } else {
            "set by the caller"
        },
        s.temperature_c,
        if s.temperature_c == 0.0 {
            "assumed 0 (--temperature-c)"
        } else {
            "set by the caller"
        }
    ));
    Ok(Estimated {
        budget,
        notes,
        inflation,
    })
}
