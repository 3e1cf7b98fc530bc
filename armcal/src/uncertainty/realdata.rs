//! Coverage on real recordings (MUKCa, `data/mukca/`): whole sessions held out.
//!
//! For each session of a unit, the unit is calibrated on all its other sessions and the
//! budget estimated as `armcal calibrate` does (probing from the training sessions' scatter
//! about their socket centres: on these data that also holds what the model leaves
//! unexplained). The held-out session's probings are then compared with their socket's
//! centre, the mean of the calibrated model's ball centres over that socket's n probings in
//! the session (the authors' metric). The deviation r_i = p_i − (1/n) Σ_j p_j is predicted
//! to first order with its own covariance: the parameters' part through J_i − J̄ (what all
//! the socket's probings share cancels), the readings' own parts as (1 − 2/n) Σ_i +
//! (1/n²) Σ_j Σ_j. A probing is covered when |r_i| is within the U95 of that covariance.

use super::estimate::{self, Settings};
use super::{propagate, u95, Budget};
use crate::data::Dataset;
use crate::mukca::{self, Unit};
use crate::residuals::residuals;
use nalgebra::{DVector, Matrix3, Vector3};
use quatarm_ref::arm::Arm;
use serde::Serialize;

/// One unit's figures.
#[derive(Clone, Debug, Serialize)]
pub struct UnitCoverage {
    /// The unit.
    pub unit: String,
    /// Sessions held out and judged.
    pub sessions: usize,
    /// Sessions whose training fit failed, with the reason.
    pub failed: Vec<String>,
    /// Probings judged.
    pub probings: usize,
    /// Fraction within their predicted 95 % region.
    pub covered: f64,
    /// Median U95 of the probings (mm).
    pub median_u95_mm: f64,
    /// RMS distance of the probings from their socket's centre (mm).
    pub rms_deviation_mm: f64,
    /// Mean probing term the training sessions gave (mm per axis).
    pub probing_mm: f64,
}

/// Leave-one-session-out coverage of a unit (`None` with fewer than two sessions).
pub fn unit_coverage(unit: &Unit) -> Option<UnitCoverage> {
    let groups = unit.groups();
    if groups.len() < 2 {
        return None;
    }
    let opts = mukca::options(None);
    let (mut judged, mut inside, mut sessions) = (0usize, 0usize, 0usize);
    let (mut u95s, mut ss, mut probing, mut failed) = (Vec::new(), 0.0, 0.0, Vec::new());
    for &g in &groups {
        let train: Vec<i64> = groups.iter().copied().filter(|x| *x != g).collect();
        let name = unit.sessions.get(&g).cloned().unwrap_or_default();
        let train_data = unit.sessions_data(&train);
        let fit = match crate::calib::calibrate(&unit.arm, &train_data, &opts) {
            Ok(f) => f,
            Err(e) => {
                failed.push(format!("{name}: {e}"));
                continue;
            }
        };
        let est = match estimate::from_fit(&fit, &train_data, None, 0.0, &Settings::default()) {
            Ok(e) => e,
            Err(e) => {
                failed.push(format!("{name}: {e}"));
                continue;
            }
        };
        sessions += 1;
        probing += est.budget.probing_mm;
        let test = unit.sessions_data(&[g]);
        let res = residuals(&fit.arm, &test, None);
        let layout = test.layout();
        for end in layout.length.iter().flat_map(|l| [&l.a, &l.b]) {
            for (i, u) in socket_u95(&fit.arm, &est.budget, &test, end) {
                let d = res.rows[i].norm();
                judged += 1;
                inside += usize::from(d <= u);
                ss += d * d;
                u95s.push(u);
            }
        }
    }
    u95s.sort_by(f64::total_cmp);
    Some(UnitCoverage {
        unit: unit.name.clone(),
        sessions,
        failed,
        probings: judged,
        covered: inside as f64 / judged.max(1) as f64,
        median_u95_mm: u95s.get(u95s.len() / 2).copied().unwrap_or(f64::NAN),
        rms_deviation_mm: (ss / judged.max(1) as f64).sqrt(),
        probing_mm: probing / sessions.max(1) as f64,
    })
}

/// (row, U95 of its deviation from the socket's centre) for the probings `rows` of a socket.
fn socket_u95(arm: &Arm, b: &Budget, data: &Dataset, rows: &[usize]) -> Vec<(usize, f64)> {
    let n = rows.len() as f64;
    let st = b.sigma_theta(arm);
    let js: Vec<propagate::Jacobians> = rows
        .iter()
        .map(|&i| propagate::jacobians(arm, b, &data.rows[i].theta, data.rows[i].temp_c))
        .collect();
    let own: Vec<Matrix3<f64>> = js.iter().map(|j| propagate::own_terms(b, &st, j)).collect();
    let own_mean = own.iter().sum::<Matrix3<f64>>() / (n * n);
    let k = b.params.len();
    let mean_j: Vec<Vector3<f64>> = (0..k)
        .map(|c| js.iter().map(|j| j.pi[c]).sum::<Vector3<f64>>() / n)
        .collect();
    rows.iter()
        .zip(js.iter().zip(&own))
        .map(|(&i, (j, o))| {
            let mut s = o * (1.0 - 2.0 / n) + own_mean;
            let g: Vec<DVector<f64>> = (0..3)
                .map(|axis| DVector::from_fn(k, |c, _| j.pi[c][axis] - mean_j[c][axis]))
                .collect();
            for a in 0..3 {
                for c in 0..3 {
                    s[(a, c)] += (g[a].transpose() * &b.cov * &g[c])[(0, 0)];
                }
            }
            (i, u95::u95(&s))
        })
        .collect()
}
