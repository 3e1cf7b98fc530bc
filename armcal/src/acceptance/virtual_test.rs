//! The virtual test (`spec/acceptance-tests.md`, Sładek's "virtual arm"): each statistic's
//! distribution under the calibration's uncertainty budget, by Monte Carlo, at the test's own
//! readings.
//!
//! The artefact is made ideal first, as the calibrated model sees it: each sphere group's
//! centres moved radially onto a sphere of the true radius (D + d)/2 about its fitted centre,
//! each bar's two ball centres to exactly `length_mm` apart, each SPAT group onto its mean. A
//! draw then measures that ideal artefact with an arm drawn from the budget: a parameter error
//! δ ~ N(0, C) shared by every reading (the arm is one arm during a test), and each reading's
//! own angle, temperature, probing and model errors, all to first order through the reading's
//! Jacobians (`uncertainty::propagate`). A leverage-scaled pose part P (issue 27) is a second
//! shared draw δ_P ~ N(0, P), which reading i sees times √(max(1, ℓ_i) − 1): its variance is
//! the first order's J cov Jᵀ + (max(1, ℓ) − 1) J P Jᵀ, and the readings of one test share it
//! as they share δ. The statistics of each draw are computed exactly as
//! the test computes them, so their non-linearity (a form is a range, a location a maximum) is
//! kept: an expected P_Form is not zero even on a perfect model.

use super::statistics::{self, StatError, Test};
use crate::data::Dataset;
use crate::rng::{normal, rng};
use crate::uncertainty::montecarlo::{pose_draw, pose_scale_at, sqrt_cov};
use crate::uncertainty::propagate::{jacobians, Jacobians};
use crate::uncertainty::Budget;
use nalgebra::{DVector, Vector3};
use quatarm_ref::arm::Arm;
use std::collections::BTreeMap;

/// A statistic's predicted distribution (mm).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Interval {
    /// Mean over the draws.
    pub mean: f64,
    /// 2.5th percentile.
    pub lo: f64,
    /// 97.5th percentile.
    pub hi: f64,
    /// Standard deviation over the draws.
    pub sd: f64,
}

/// Each (test, group)'s predicted distribution over `draws` draws (seeded).
pub fn predict(
    arm: &Arm,
    budget: &Budget,
    data: &Dataset,
    draws: usize,
    seed: u64,
) -> Result<BTreeMap<(Test, i64), Interval>, StatError> {
    let ideal = ideal_centres(arm, data)?;
    let jac: Vec<Jacobians> = data
        .rows
        .iter()
        .map(|r| {
            jacobians(
                arm,
                crate::fit::probes::index(arm, r),
                budget,
                &r.theta,
                r.temp_c,
            )
        })
        .collect();
    let root = sqrt_cov(&budget.cov);
    let widen: Vec<f64> = jac.iter().map(|j| pose_scale_at(budget, j)).collect();
    let sigma_theta = budget.sigma_theta(arm);
    let own = (budget.probing_mm.powi(2) + budget.model_mm.powi(2)).sqrt();
    let mut g = rng(seed);
    let mut samples: BTreeMap<(Test, i64), Vec<f64>> = BTreeMap::new();
    for _ in 0..draws {
        let z = DVector::from_fn(budget.params.len(), |_, _| normal(&mut g));
        let delta = &root * z;
        // Drawn only where a reading sees it: a budget whose every reading is at ℓ ≤ 1
        // draws as one without a pose part.
        let delta_pose = if widen.iter().any(|w| *w > 0.0) {
            pose_draw(budget, &root, &mut g)
        } else {
            DVector::zeros(budget.params.len())
        };
        let p: Vec<Vector3<f64>> = ideal
            .iter()
            .zip(jac.iter().zip(&widen))
            .map(|(x, (j, w))| {
                let mut p = *x;
                for (col, (dk, pk)) in j.pi.iter().zip(delta.iter().zip(delta_pose.iter())) {
                    p -= col * (*dk + w * pk);
                }
                for (col, s) in j.theta.iter().zip(&sigma_theta) {
                    p += col * (s * normal(&mut g));
                }
                p += j.temp * (budget.temperature_c * normal(&mut g));
                p + Vector3::new(normal(&mut g), normal(&mut g), normal(&mut g)) * own
            })
            .collect();
        for v in statistics::values(data, &p, &|r| crate::fit::probes::ball_diameter(arm, r))? {
            samples
                .entry((v.test, v.group))
                .or_default()
                .push(v.value_mm);
        }
    }
    Ok(samples
        .into_iter()
        .map(|(k, mut v)| {
            v.sort_by(f64::total_cmp);
            let n = v.len() as f64;
            let mean = v.iter().sum::<f64>() / n;
            let sd =
                (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
            let at = |q: f64| v[((q * (n - 1.0)).round() as usize).min(v.len() - 1)];
            (
                k,
                Interval {
                    mean,
                    lo: at(0.025),
                    hi: at(0.975),
                    sd,
                },
            )
        })
        .collect())
}

/// The model's centres of every row, moved onto the ideal artefact.
fn ideal_centres(arm: &Arm, data: &Dataset) -> Result<Vec<Vector3<f64>>, StatError> {
    let mut x = super::centres(arm, data);
    let layout = data.layout();
    for g in &layout.sphere {
        let p: Vec<Vector3<f64>> = g.rows.iter().map(|&i| x[i]).collect();
        let c = crate::geometry::sphere::free(&p)
            .map_err(|source| StatError::Fit {
                group: g.group,
                source,
            })?
            .centre;
        let r = crate::fit::probes::sphere_radius(arm, data, g);
        for &i in &g.rows {
            x[i] = c + (x[i] - c).normalize() * r;
        }
    }
    for g in &layout.length {
        let (a, b) = (super::mean_of(&g.a, &x), super::mean_of(&g.b, &x));
        let b_ideal = a + (b - a).normalize() * g.length_mm;
        for &i in &g.a {
            x[i] = a;
        }
        for &i in &g.b {
            x[i] = b_ideal;
        }
    }
    for g in &layout.spat {
        let m = super::mean_of(&g.rows, &x);
        for &i in &g.rows {
            x[i] = m;
        }
    }
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::Kind;
    use crate::sim::{self, Options};

    fn test_set(arm: &Arm) -> Dataset {
        let mut o = Options::new(Kind::Point, 1);
        o.noise_mm = 0.0;
        sim::protocol::iso_10360_12(arm, &o, &mut rng(4))
            .unwrap()
            .data
    }

    #[test]
    fn a_budget_of_nothing_predicts_the_ideal_artefact() {
        let arm = Arm::default6();
        let data = test_set(&arm);
        let p = predict(&arm, &Budget::zero(6), &data, 20, 1).unwrap();
        assert_eq!(p.len(), 3 * 2 - 1 + 15 + 2 * 3, "every (test, group)");
        for ((t, g), i) in &p {
            assert!(i.mean.abs() < 1e-9 && i.sd < 1e-9, "{t:?} {g}: {i:?}");
        }
    }

    #[test]
    fn probing_noise_spreads_the_prediction_as_it_should() {
        let arm = Arm::default6();
        let data = test_set(&arm);
        let mut b = Budget::zero(6);
        b.probing_mm = 0.002;
        let p = predict(&arm, &b, &data, 400, 2).unwrap();
        // A bar's error is the difference of two means of five probings each, along the bar:
        // sd = σ √(1/5 + 1/5) = 1.26 µm.
        let e = p[&(Test::EUni, 11)];
        assert!((e.sd - 0.002 * 0.4f64.sqrt()).abs() < 0.2e-3, "{e:?}");
        assert!(e.lo < 0.0 && e.hi > 0.0 && e.mean.abs() < 0.3e-3);
        // A form is a range: positive, of a few σ for 25 points.
        let f = p[&(Test::PForm, 1)];
        assert!(f.lo > 0.002 && f.hi < 0.02, "{f:?}");
    }

    /// Issue 27: a pose part kept apart widens the prediction where the readings' leverage
    /// is above the calibration's mean, and leaves it as it was where it is below (the
    /// draws then the same to the bit: no pose draw is seen by any reading).
    #[test]
    fn the_leverage_scaled_pose_part_widens_the_prediction() {
        use crate::params::Param;
        use nalgebra::DMatrix;
        let arm = Arm::default6();
        let data = test_set(&arm);
        let params: Vec<Param> = (0..6).map(Param::ZeroOffset).collect();
        let n = params.len();
        let mut b = Budget::zero(6);
        b.params = params;
        b.cov = DMatrix::from_diagonal_element(n, n, 4e-10);
        let d = DMatrix::from_fn(n, 1, |i, _| if i == 1 { 1e-5 } else { 0.0 });
        b.cov += &d * d.transpose();
        let at = |mean: f64| {
            let mut w = b.clone();
            w.pose = Some(crate::uncertainty::PoseSplit {
                factor: d.clone(),
                shrink: 0.0,
                leverage_mean: mean,
                joints: None,
            });
            predict(&arm, &w, &data, 400, 3).unwrap()
        };
        let plain = predict(&arm, &b, &data, 400, 3).unwrap();
        // Each reading's tr(J C_fit Jᵀ): ℓ at a mean of 1.
        let unit = Budget {
            pose: Some(crate::uncertainty::PoseSplit {
                factor: d.clone(),
                shrink: 0.0,
                leverage_mean: 1.0,
                joints: None,
            }),
            ..b.clone()
        };
        let traces: Vec<f64> = data
            .rows
            .iter()
            .map(|r| {
                let j = jacobians(&arm, 0, &unit, &r.theta, r.temp_c);
                crate::uncertainty::propagate::leverage_at(&unit, &j).unwrap()
            })
            .collect();
        let most = traces.iter().copied().fold(0.0, f64::max);
        let least = traces.iter().copied().fold(f64::INFINITY, f64::min);
        // Every reading at ℓ ≤ 0.5, then every one at ℓ ≥ 10.
        let (low, high) = (at(2.0 * most), at(least / 10.0));
        let key = (Test::EUni, 11);
        assert_eq!(low[&key], plain[&key]);
        assert!(
            high[&key].sd > 1.2 * plain[&key].sd,
            "{:?} {:?}",
            high[&key],
            plain[&key]
        );
    }
}
