//! Held-out validation: how a calibration predicts data it did not fit.
//!
//! A model is fitted on every fold but one and judged on the one left out, in turn. What is
//! left out is a whole unit of evidence: a `point` row alone, but a `spat` or `length` group
//! whole, since a group's fixed point is estimated from its own rows (a held-out group is then
//! judged, as the MUKCa authors judge a session, by how tightly the model's ball centres
//! gather, how well the bar keeps its length and how round the sphere stays). Held-out `point` rows go through the
//! instrument frame fitted on the other folds. Sessions are held out whole by [`by_group`].

use crate::data::{Dataset, Kind};
use crate::fit::calib::calibrate;
use crate::fit::error::CalibError;
use crate::fit::options::Options;
use crate::fit::residuals::{residuals, summarise, Residuals, Summary};
use nalgebra::Vector3;
use quatarm_ref::arm::Arm;
use rand::seq::SliceRandom;
use std::collections::BTreeMap;

/// Folds: each a set of row indices to leave out.
pub type Folds = Vec<Vec<usize>>;

/// `k` folds of the data's units (point rows one by one, groups whole), shuffled by `seed`.
/// Fewer units than `k` give one fold per unit.
pub fn kfold(data: &Dataset, k: usize, seed: u64) -> Folds {
    let layout = data.layout();
    let mut units: Vec<Vec<usize>> = layout.units().into_iter().map(|u| u.rows).collect();
    let mut rng = crate::rng::rng(seed);
    units.shuffle(&mut rng);
    let k = k.min(units.len()).max(1);
    let mut folds = vec![Vec::new(); k];
    for (i, u) in units.into_iter().enumerate() {
        folds[i % k].extend(u);
    }
    for f in &mut folds {
        f.sort_unstable();
    }
    folds
}

/// One fold per group number (a session, an artefact position); `point` rows by their group
/// too.
pub fn by_group(data: &Dataset) -> Folds {
    let mut m: BTreeMap<i64, Vec<usize>> = BTreeMap::new();
    for (i, r) in data.rows.iter().enumerate() {
        m.entry(r.group).or_default().push(i);
    }
    m.into_values().collect()
}

/// The outcome of held-out validation.
#[derive(Clone, Debug)]
pub struct Holdout {
    /// Folds fitted.
    pub folds: usize,
    /// Residuals of every held-out row (rows never held out stay zero and are not counted).
    pub residuals: Residuals,
    /// Which rows were held out and judged.
    pub judged: Vec<bool>,
    /// Statistics over the judged rows.
    pub summary: Summary,
    /// Folds whose training part could not be calibrated, with the reason.
    pub failed: Vec<String>,
    /// Every fold that fitted: what it left out and what its training part gave (the
    /// between-group spread of the parameters, [`crate::uncertainty::pose`]).
    pub fits: Vec<FoldFit>,
}

/// One fold's fit on the other folds.
#[derive(Clone, Debug)]
pub struct FoldFit {
    /// The rows left out (ascending).
    pub rows: Vec<usize>,
    /// The arm the other folds calibrated.
    pub arm: Arm,
    /// The unknowns that fit estimated (the others held at their start value).
    pub fitted: Vec<crate::params::Param>,
    /// That fit's covariance of its unknowns (the frame's among them), by unknown; `None`
    /// where JᵀJ was singular. What a held-out row's tip leverage against the fold's own
    /// design is taken with ([`crate::uncertainty::pose`]).
    pub covariance: Option<(Vec<crate::params::Param>, nalgebra::DMatrix<f64>)>,
}

/// Fits `start` on all folds but one and judges the one left out, for every fold.
pub fn validate(start: &Arm, data: &Dataset, opts: &Options, folds: &Folds) -> Holdout {
    validate_observed(start, data, opts, folds, &mut crate::progress::Silent)
}

/// [`validate`], telling `observer` which fold it fits.
pub fn validate_observed(
    start: &Arm,
    data: &Dataset,
    opts: &Options,
    folds: &Folds,
    observer: &mut dyn crate::progress::Observer,
) -> Holdout {
    let n = data.rows.len();
    let mut rows = vec![Vector3::zeros(); n];
    let mut judged = vec![false; n];
    let mut lengths = Vec::new();
    let mut failed = Vec::new();
    let mut fits = Vec::new();
    let mut opts = opts.clone();
    opts.design_check = false;
    opts.allow_degenerate = true;
    for (f, out) in folds.iter().enumerate() {
        let mut left = vec![false; n];
        out.iter().for_each(|&i| left[i] = true);
        let train: Vec<usize> = (0..n).filter(|&i| !left[i]).collect();
        observer.step("held-out validation, fold", f, folds.len());
        let fit = match calibrate(start, &data.subset(&train), &opts) {
            Ok(fit) => fit,
            Err(e) => {
                failed.push(format!("fold {}: {}", f + 1, describe(&e)));
                continue;
            }
        };
        let test = data.subset(out);
        if test.rows.iter().any(|r| r.kind == Kind::Point) && fit.frame.is_none() {
            failed.push(format!(
                "fold {}: point rows held out, but the other folds have none to fix the frame",
                f + 1
            ));
            continue;
        }
        let res = residuals(&fit.arm, &test, fit.frame);
        for (k, &i) in out.iter().enumerate() {
            rows[i] = res.rows[k];
            judged[i] = true;
        }
        lengths.extend(res.lengths);
        fits.push(FoldFit {
            rows: out.clone(),
            fitted: fit.ident.kept.iter().map(|&k| fit.params[k]).collect(),
            covariance: fit
                .covariance
                .map(|(order, c)| (order.iter().map(|&k| fit.params[k]).collect(), c)),
            arm: fit.arm,
        });
    }
    let residuals = Residuals {
        rows,
        lengths,
        frame: None,
    };
    let judged_data = data.subset(&(0..n).filter(|&i| judged[i]).collect::<Vec<_>>());
    let judged_res = Residuals {
        rows: (0..n)
            .filter(|&i| judged[i])
            .map(|i| residuals.rows[i])
            .collect(),
        lengths: residuals.lengths.clone(),
        frame: None,
    };
    let summary = summarise(&judged_res, &judged_data);
    Holdout {
        folds: folds.len(),
        residuals,
        judged,
        summary,
        failed,
        fits,
    }
}

fn describe(e: &CalibError) -> String {
    e.to_string()
}
