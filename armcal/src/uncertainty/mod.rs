//! The uncertainty of every measured point (`spec/uncertainty.md`).
//!
//! - [`Budget`]: the `[uncertainty]` section as armcal holds it (the same [`Param`]s as the
//!   file's reader, `quatarm_ref::uncertainty`, which owns their text names).
//! - [`estimate`]: the budget a calibration leaves (`armcal calibrate`, `diagnose -o`).
//! - [`misfit`]: its model term, from held-out residuals.
//! - [`pose`]: the model term's pose-dependent part, the parameters' spread between groups.
//! - [`extrapolation`]: a reading far from every place the calibration saw.
//! - [`propagate`]: first-order Σ_p of a reading, and of the distance between two readings.
//! - [`u95`]: the radius of the sphere holding 95 % of N(0, Σ).
//! - [`montecarlo`]: GUM Supplement 1 propagation of the same budget, to check the first order.
//! - [`report`]: the budget and a picture of U95 across the workspace, in the report.
//! - [`columns`]: `armcal eval --uncertainty`'s columns, by either method.
//! - [`coverage`]: simulated arms, calibrated and read afresh: how often the truth is inside.
//! - [`realdata`]: the same question on MUKCa recordings, whole sessions held out.

pub mod columns;
pub mod coverage;
pub mod estimate;
pub mod extrapolation;
pub mod load;
pub mod misfit;
pub mod montecarlo;
pub mod pose;
pub mod propagate;
pub mod realdata;
pub mod report;
pub mod u95;

use crate::params::Param;
use nalgebra::DMatrix;
use quatarm_ref::arm::Arm;
use quatarm_ref::calfile::Uncertainty;
use quatarm_ref::uncertainty;

/// Why no budget (or no coverage trial) could be made.
#[derive(Debug, thiserror::Error)]
pub enum BudgetError {
    /// The fit's normal matrix is singular: no covariance to write.
    #[error("the fit's normal matrix is singular: no covariance")]
    NoCovariance,
    /// An unknown the calibration file has no key for.
    #[error("{0} cannot be listed in [uncertainty]")]
    NotListable(crate::params::Param),
    /// The calibration behind a budget failed.
    #[error(transparent)]
    Fit(#[from] crate::fit::error::CalibError),
    /// The simulated data of a coverage trial.
    #[error(transparent)]
    Sim(#[from] crate::sim::SimError),
    /// The terms of a coverage trial.
    #[error(transparent)]
    Terms(#[from] crate::effects::TermsError),
    /// The truth arm of a coverage trial could not be read.
    #[error("the truth arm: {0}")]
    Truth(String),
}

/// Pure quantisation: the standard deviation of a uniform error of one count, 1/√12.
pub const QUANTISATION_COUNTS: f64 = 0.288_675_134_594_812_9;

/// An uncertainty budget over armcal's unknowns.
#[derive(Clone, Debug, PartialEq)]
pub struct Budget {
    /// The identified parameters (increments of the calibrated arm's keys).
    pub params: Vec<Param>,
    /// Their covariance (units²).
    pub cov: DMatrix<f64>,
    /// Standard uncertainty of each joint's reading (counts).
    pub encoder_counts: Vec<f64>,
    /// Probing, per axis (mm).
    pub probing_mm: f64,
    /// Temperature reading (°C).
    pub temperature_c: f64,
    /// Model, per axis (mm).
    pub model_mm: f64,
    /// The pose part of `cov` kept apart, which a reading scales by its leverage ratio
    /// ([`propagate`]); `None`: `cov` alone, the same at every reading's leverage.
    pub pose: Option<PoseSplit>,
}

/// The pose part P = D Dᵀ + b C_fit of a budget's `cov` = C_fit + P (the file's
/// `pose_factor`, `pose_shrink`, `pose_leverage_mean`: `quatarm_ref::uncertainty::PoseLeverage`,
/// whose doc comment is the contract). Kept as D and b rather than P so that a reading's
/// J P Jᵀ costs J D (3 × r per parameter) beside the J cov Jᵀ it already has.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseSplit {
    /// D, one row per parameter, r ≤ [`uncertainty::POSE_RANK_MAX`] columns (units).
    pub factor: DMatrix<f64>,
    /// b ≥ 0.
    pub shrink: f64,
    /// The calibration rows' mean tr(J C_fit Jᵀ) of the tip (mm²), > 0.
    pub leverage_mean: f64,
    /// The joint-space leverage, when the budget has one (the file's `pose_joint_mean`,
    /// `pose_joint_weight`).
    pub joints: Option<uncertainty::JointLeverage>,
}

impl PoseSplit {
    /// The pose part P = (D Dᵀ + b cov)/(1 + b) of `cov`.
    pub fn matrix(&self, cov: &DMatrix<f64>) -> DMatrix<f64> {
        (&self.factor * self.factor.transpose() + cov * self.shrink) / (1.0 + self.shrink)
    }

    /// The pose part m² P of the same C_fit: D m, b m² (what a budget whose pose part is
    /// scaled by m carries; its `cov` is C_fit + m² P).
    pub fn scaled(&self, m: f64) -> PoseSplit {
        PoseSplit {
            factor: &self.factor * m,
            shrink: self.shrink * m * m,
            leverage_mean: self.leverage_mean,
            joints: self.joints.clone(),
        }
    }

    /// The fit's own covariance C_fit = (cov − D Dᵀ)/(1 + b).
    pub fn fit_covariance(&self, cov: &DMatrix<f64>) -> DMatrix<f64> {
        (cov - &self.factor * self.factor.transpose()) / (1.0 + self.shrink)
    }
}

impl Budget {
    /// No uncertainty at all (a file without `[uncertainty]`).
    pub fn zero(dof: usize) -> Budget {
        Budget {
            params: Vec::new(),
            cov: DMatrix::zeros(0, 0),
            encoder_counts: vec![0.0; dof],
            probing_mm: 0.0,
            temperature_c: 0.0,
            model_mm: 0.0,
            pose: None,
        }
    }

    /// Only the parameters' covariance `cov` (no pose part, no reading's own terms): what
    /// a covariance of the parameters alone predicts at the tip.
    pub fn of_parameters(params: &[Param], cov: DMatrix<f64>, dof: usize) -> Budget {
        Budget {
            params: params.to_vec(),
            cov,
            ..Budget::zero(dof)
        }
    }

    /// From the file's section.
    pub fn from_file(u: &Uncertainty) -> Budget {
        Budget {
            params: u.parameters.clone(),
            cov: u.matrix(),
            encoder_counts: u.encoder_counts.clone(),
            probing_mm: u.probing_mm,
            temperature_c: u.temperature_c,
            model_mm: u.model_mm,
            pose: u.pose.as_ref().map(|p| PoseSplit {
                factor: p.factor_matrix(u.parameters.len()),
                shrink: p.shrink,
                leverage_mean: p.leverage_mean,
                joints: p.joints.clone(),
            }),
        }
    }

    /// The file's section for `arm`; `Err` names an unknown the file cannot list (the
    /// instrument frame's, a periodic term the arm has no entry for).
    pub fn to_file(&self, arm: &Arm) -> Result<Uncertainty, BudgetError> {
        if let Some(p) = self
            .params
            .iter()
            .find(|p| uncertainty::name(**p, arm).is_none())
        {
            return Err(BudgetError::NotListable(*p));
        }
        let parameters = self.params.clone();
        let n = self.params.len();
        Ok(Uncertainty {
            parameters,
            // Symmetric to the bit: a computed inverse is only symmetric to rounding.
            covariance: (0..n * n)
                .map(|k| 0.5 * (self.cov[(k / n, k % n)] + self.cov[(k % n, k / n)]))
                .collect(),
            encoder_counts: self.encoder_counts.clone(),
            probing_mm: self.probing_mm,
            temperature_c: self.temperature_c,
            model_mm: self.model_mm,
            pose: self.pose.as_ref().map(|p| uncertainty::PoseLeverage {
                factor: p
                    .factor
                    .column_iter()
                    .map(|c| c.iter().copied().collect())
                    .collect(),
                shrink: p.shrink,
                leverage_mean: p.leverage_mean,
                joints: p.joints.clone(),
            }),
        })
    }

    /// σ_θ of each joint (rad): 2π · encoder_counts / counts per revolution.
    pub fn sigma_theta(&self, arm: &Arm) -> Vec<f64> {
        self.encoder_counts
            .iter()
            .zip(&arm.joints)
            .map(|(c, j)| std::f64::consts::TAU * c / f64::from(j.encoder_counts))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{Effect, Link, Terms};

    #[test]
    fn names_map_both_ways_and_the_file_round_trips() {
        let effects = [
            Effect::Harmonic { joint: 2, order: 3 },
            Effect::Gravity(1),
            Effect::Thermal(Link::Joint(4)),
            Effect::Thermal(Link::Probe),
        ];
        let params = Terms::with(&effects).params(6);
        let mut arm = Arm::default6();
        // A harmonic ahead of the fitted one: the file's index (2) is not its order (3).
        arm.joints[2].harmonics.push(quatarm_ref::arm::Harmonic {
            order: 1,
            sin: 0.0,
            cos: 0.0,
        });
        for e in &effects {
            e.with(|t| t.add_entry(&mut arm));
        }
        let n = params.len();
        let b = Budget {
            params: params.clone(),
            cov: DMatrix::from_fn(n, n, |i, j| if i == j { 1e-8 } else { 1e-10 }),
            encoder_counts: vec![QUANTISATION_COUNTS; 6],
            probing_mm: 0.002,
            temperature_c: 0.1,
            model_mm: 0.0,
            pose: Some(PoseSplit {
                factor: DMatrix::from_fn(n, 2, |i, k| if i == k { 5e-5 } else { 0.0 }),
                shrink: 0.5,
                leverage_mean: 2e-4,
                joints: Some(uncertainty::JointLeverage {
                    mean: vec![0.25; 6],
                    weight: (0..36)
                        .map(|k| if k % 7 == 0 { 3.0 } else { 0.0 })
                        .collect(),
                }),
            }),
        };
        for p in &params {
            let name = uncertainty::name(*p, &arm).unwrap();
            assert_eq!(uncertainty::parse_name(&name, &arm), Ok(*p));
        }
        let file = b.to_file(&arm).unwrap();
        let text = quatarm_ref::calfile::write_with(&arm, Some(&file), &[]);
        let back = quatarm_ref::calfile::parse(&text).unwrap();
        assert_eq!(Budget::from_file(&back.uncertainty.unwrap()), b);
        assert!(uncertainty::name(Param::FrameRotation(0), &arm).is_none());
        let mut bad = b.clone();
        bad.params[0] = Param::Harmonic {
            joint: 0,
            order: 2,
            cos: false,
        };
        assert!(matches!(
            bad.to_file(&arm),
            Err(BudgetError::NotListable(Param::Harmonic { joint: 0, .. }))
        ));
    }
}
