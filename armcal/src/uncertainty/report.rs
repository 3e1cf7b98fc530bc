//! The budget in a calibration's report: each term, how it was obtained, and a picture of U95
//! across the workspace (median over random poses, by reach from the base axis and height).

use super::estimate::Estimated;
use super::{propagate, u95, Budget};
use crate::fit::design::poses::{limits, random_pose};
use quatarm_ref::arm::Arm;
use quatarm_ref::forward::REFERENCE_TEMP_C;
use serde::Serialize;
use std::fmt::Write as _;

/// Reach bins (columns) and height bins (rows) of the workspace picture.
const REACH_BINS: usize = 4;
const HEIGHT_BINS: usize = 3;
/// Random poses behind the picture.
const POSES: usize = 400;

/// The budget as reported.
#[derive(Clone, Debug, Serialize)]
pub struct BudgetReport {
    /// Parameters in the covariance.
    pub parameters: usize,
    /// Factor applied to the covariance after the held-out check.
    pub inflation: f64,
    /// Reading (counts; the first joint's, all equal unless set per joint).
    pub encoder_counts: f64,
    /// Probing per axis (µm).
    pub probing_um: f64,
    /// Model per axis (µm).
    pub model_um: f64,
    /// Where the model term came from when it was estimated (`None`: set or assumed, as the
    /// notes say).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model_estimated: Option<super::estimate::ModelSource>,
    /// Temperature (°C).
    pub temperature_c: f64,
    /// How each term was obtained.
    pub notes: Vec<String>,
    /// Median U95 (µm) per cell, rows from the highest height bin down; `None` for an
    /// empty cell.
    pub workspace_u95_um: Vec<Vec<Option<f64>>>,
    /// Edges of the reach bins (mm, distance from the base z axis).
    pub reach_edges_mm: Vec<f64>,
    /// Edges of the height bins (mm, base z), highest first.
    pub height_edges_mm: Vec<f64>,
    /// Median and largest U95 over the poses (µm).
    pub u95_median_um: f64,
    /// Where a reading is flagged as extrapolated (`None`: the data are one unit).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub extrapolation: Option<super::extrapolation::ExtrapolationReport>,
    /// Largest U95 over the poses (µm).
    pub u95_max_um: f64,
}

fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

fn edges(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    (0..=n)
        .map(|k| lo + (hi - lo) * k as f64 / n as f64)
        .collect()
}

fn bin(x: f64, e: &[f64]) -> usize {
    let n = e.len() - 1;
    (((x - e[0]) / (e[n] - e[0]) * n as f64) as usize).min(n - 1)
}

impl BudgetReport {
    /// The report of an estimated budget for the calibrated `arm`.
    pub fn build(est: &Estimated, arm: &Arm) -> BudgetReport {
        let b: &Budget = &est.budget;
        let lim = limits(arm);
        let mut rng = crate::rng::rng(0x0095);
        let pts: Vec<(f64, f64, f64)> = (0..POSES)
            .map(|_| {
                let th = random_pose(&lim, &mut rng);
                let (p, s) = propagate::point(arm, 0, b, &th, REFERENCE_TEMP_C);
                (p.x.hypot(p.y), p.z, u95::u95(&s) * 1e3)
            })
            .collect();
        let max_r = pts.iter().map(|p| p.0).fold(0.0, f64::max);
        let (zlo, zhi) = pts
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, c), p| (a.min(p.1), c.max(p.1)));
        let re = edges(0.0, max_r.max(1e-9), REACH_BINS);
        let he = edges(zlo, zhi.max(zlo + 1e-9), HEIGHT_BINS);
        let mut cells = vec![vec![Vec::new(); REACH_BINS]; HEIGHT_BINS];
        for (r, z, u) in &pts {
            cells[HEIGHT_BINS - 1 - bin(*z, &he)][bin(*r, &re)].push(*u);
        }
        let mut all: Vec<f64> = pts.iter().map(|p| p.2).collect();
        BudgetReport {
            parameters: b.params.len(),
            inflation: est.inflation,
            encoder_counts: b.encoder_counts.first().copied().unwrap_or(0.0),
            probing_um: b.probing_mm * 1e3,
            model_um: b.model_mm * 1e3,
            model_estimated: est.model.clone(),
            temperature_c: b.temperature_c,
            notes: est.notes.clone(),
            workspace_u95_um: cells
                .iter_mut()
                .map(|row| row.iter_mut().map(|c| median(c)).collect())
                .collect(),
            reach_edges_mm: re,
            height_edges_mm: he.into_iter().rev().collect(),
            u95_max_um: all.iter().copied().fold(0.0, f64::max),
            extrapolation: None,
            u95_median_um: median(&mut all).unwrap_or(0.0),
        }
    }

    /// What the report's reader must see first: the held-out groups the budget's own
    /// held-out check misses as a whole (each a placement the other groups do not predict).
    pub fn warnings(&self) -> Vec<String> {
        let Some(src) = &self.model_estimated else {
            return Vec::new();
        };
        src.missed_groups()
            .map(|g| {
                format!(
                    "the uncertainty budget's held-out check misses group {} as a whole: {} of \
                     its {} rows ({:.1} %) inside their 95 % region (p = {:.1e} were each \
                     inside with 95 %); the budget's 95 % holds over the groups, not within \
                     this one: a placement the other groups do not predict",
                    g.group,
                    g.covered,
                    g.rows,
                    100.0 * g.fraction(),
                    g.p
                )
            })
            .collect()
    }

    /// The text section.
    pub fn text(&self, s: &mut String) {
        let _ = writeln!(
            s,
            "\nuncertainty budget ([uncertainty] of the calibration file)"
        );
        for n in &self.notes {
            let _ = writeln!(s, "  {n}");
        }
        let _ = writeln!(
            s,
            "  U95 over {POSES} random poses: median {:.2} µm, largest {:.2} µm; median by \
             height (rows) and reach from the base axis (columns), µm:",
            self.u95_median_um, self.u95_max_um
        );
        let _ = write!(s, "  {:>19}", "height \\ reach (mm)");
        for w in self.reach_edges_mm.windows(2) {
            let _ = write!(s, " {:>11}", format!("{:.0}-{:.0}", w[0], w[1]));
        }
        let _ = writeln!(s);
        for (row, h) in self
            .workspace_u95_um
            .iter()
            .zip(self.height_edges_mm.windows(2))
        {
            let _ = write!(s, "  {:>19}", format!("{:.0} to {:.0}", h[1], h[0]));
            for c in row {
                match c {
                    Some(u) => {
                        let _ = write!(s, " {u:>11.2}");
                    }
                    None => {
                        let _ = write!(s, " {:>11}", "-");
                    }
                }
            }
            let _ = writeln!(s);
        }
        if let Some(x) = &self.extrapolation {
            let _ = writeln!(
                s,
                "  extrapolation: a reading is flagged (`eval --seen`) when its tip is farther \
                 than {:.1} mm from all {} calibration tips ({} × their spacing, {:.1} mm: the \
                 95th percentile of each row's distance to the nearest row of another point, \
                 bar end or group); the budget has no held-out evidence there",
                x.threshold_mm,
                x.rows,
                super::extrapolation::FACTOR,
                x.spacing_mm
            );
            if let Some(j) = x.joint_threshold {
                let _ = writeln!(
                    s,
                    "  new configuration: a reading is flagged (`eval --seen`, column far_joints) \
                     when its joint angles are farther than {j:.2} (Mahalanobis, the largest of \
                     the calibration's own rows) from the calibration's; on real arms the \
                     model's misfit grows there"
                );
            }
        }
    }
}

/// The budget is the section of the calibration report that the fit leaves to a higher layer.
impl crate::fit::report::Section for BudgetReport {
    fn text(&self, s: &mut String) {
        BudgetReport::text(self, s);
    }
}
