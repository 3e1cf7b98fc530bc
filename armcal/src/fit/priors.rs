//! What pulls a fit besides the data: a Gaussian prior on the unknowns ([`Prior`]: a rule by
//! class, or each unknown's own [`Gaussian`], e.g. a fleet's), MUKCa's ridge penalty
//! ([`Ridge`]), and the test that drops an unknown's own prior when the data contradict it
//! ([`PriorConflict`]). Each becomes one residual per unknown (`prior_terms`, the weights
//! [`crate::fit::problem::Problem::with_prior`] takes); the fit's loop decides when they apply.

use crate::data::Dataset;
use crate::fit::ident::{self, Fixed};
use crate::params::Param;
use nalgebra::DMatrix;

/// MUKCa's regulariser (`ParameterOptimizer._add_regularization_terms` of
/// github.com/platonics-delft/kinematics_calibration): λ Σ Δp² over the origin parameters of
/// every joint (metres and radians; the ball's position is not penalised), added to each
/// session's mean squared scatter (m²). It is a fixed penalty, not a prior: its pull relative
/// to the data does not fade as rows are added.
///
/// In this fit's cost (½ Σ r², mm, summed over rows) the same objective is a residual w·Δp
/// per unknown with w² = λ·n·10⁶ for zero offsets and tilts (rad) and w² = λ·n for link errors
/// (mm), n the rows of the data: MUKCa's cost times n·10⁶ (its sessions have equal row counts
/// to within a few rows). Zero offset and two tilts are three small rotations about orthogonal
/// axes at the joint, the link error a translation of the next joint's origin: to first order
/// the same penalty as MUKCa's on roll, pitch, yaw (pitch 0 in the Panda's file) and x, y, z of
/// each joint's origin. Penalising every such unknown, including those the data cannot
/// separate, is what makes the penalty MUKCa's: holding one of a pair instead puts the whole
/// effect on the other and doubles its penalty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ridge {
    /// λ (m⁻² against the squared scatter in m²; MUKCa's default is 1e-4).
    pub lambda: f64,
}

impl Ridge {
    /// MUKCa's default weight, `ParameterOptimizer._regulizer_weight`.
    pub const MUKCA: Ridge = Ridge { lambda: 1e-4 };

    /// The ridge weight of an unknown in a fit of `rows` rows (0: not penalised).
    pub fn weight(&self, p: Param, rows: usize) -> f64 {
        let n = rows as f64;
        match p {
            Param::ZeroOffset(_) | Param::Tilt(..) => (self.lambda * n * 1e6).sqrt(),
            Param::LinkError(..) => (self.lambda * n).sqrt(),
            _ => 0.0,
        }
    }
}

/// A Gaussian prior on the geometric errors: what is known of them before any measurement.
/// It regularises directions the data determine only weakly (a calibration from one artefact
/// position) and barely moves the well-determined ones.
///
/// Two sources, one implementation: a rule by class (`angle_rad`, `length_mm`: what an arm's
/// drawings and tolerances say, centred on the start arm), and per-unknown Gaussians
/// (`unknowns`: e.g. [`crate::fit::fleet_prior`], the mean and spread of other units' errors) that
/// replace the class rule and the ridge for their unknowns. Each prior unknown adds the
/// residual (σ/s)·(x − m) to the cost, σ the data's noise, m and s the prior's mean and
/// standard deviation.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Prior {
    /// Zero offsets and tilts (rad); `None`: no class prior on them.
    pub angle_rad: Option<f64>,
    /// Link and probe errors (mm); `None`: no class prior on them.
    pub length_mm: Option<f64>,
    /// The noise the prior is weighed against (mm per equation); `None`: estimated by a first
    /// fit without the prior.
    pub noise_mm: Option<f64>,
    /// Per-unknown priors, increments from the start arm: they take precedence over the class
    /// rule and over the ridge. An unknown the data cannot separate from others is fitted
    /// under such a prior (the prior decides how the effect is shared), as under the ridge.
    pub unknowns: Vec<(Param, Gaussian)>,
    /// How far (standard deviations) the data-only estimate may stand from an unknown's own
    /// prior before the prior is dropped; `None`: [`PRIOR_CONFLICT_SIGMAS`], `f64::INFINITY`:
    /// never.
    pub conflict_sigmas: Option<f64>,
}

/// A normal distribution of one unknown's increment from the start arm.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Gaussian {
    /// The mean (the unknown's unit).
    pub mean: f64,
    /// The standard deviation (> 0).
    pub sd: f64,
}

impl Prior {
    /// The prior of an unknown, if it has one: its own Gaussian, else the class rule's
    /// (mean 0: the start arm).
    pub fn of(&self, p: Param) -> Option<Gaussian> {
        if let Some(g) = self.own(p) {
            return Some(g);
        }
        let sd = match p {
            Param::ZeroOffset(_) | Param::Tilt(..) => self.angle_rad,
            Param::LinkError(..) | Param::ProbeError(..) => self.length_mm,
            _ => None,
        }?;
        Some(Gaussian { mean: 0.0, sd })
    }

    /// The unknown's own Gaussian (`unknowns`), if it has one.
    pub fn own(&self, p: Param) -> Option<Gaussian> {
        self.unknowns.iter().find(|(q, _)| *q == p).map(|(_, g)| *g)
    }
}

/// A prior standing this many standard deviations (of the prior and the data-only estimate
/// together) from what the data say alone is taken to be wrong for this unit: its Gaussian is
/// dropped, and the unknown is left to the class rule or the ridge. A fleet's spread from a few
/// units can be far narrower than one unit's departure (a unit with another tool mounted).
pub const PRIOR_CONFLICT_SIGMAS: f64 = 3.0;

/// An unknown's own prior dropped because the data contradict it ([`PRIOR_CONFLICT_SIGMAS`]).
///
/// The data-only pass holds what only the prior lets the fit separate, so its estimate of an
/// unknown includes what the unknown absorbs of those (the structural analysis' coefficients):
/// `prior` is the prior's prediction of that same combination.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PriorConflict {
    /// The unknown (index into the fit's `params`).
    pub index: usize,
    /// The data-only estimate (increment from the start arm).
    pub data: f64,
    /// Its standard uncertainty from the data alone.
    pub data_sd: f64,
    /// The prior's prediction of the data-only estimate: the unknown's own prior plus what it
    /// absorbs of the priors of unknowns the data-only pass held.
    pub prior: Gaussian,
}

impl PriorConflict {
    /// The distance between data and prior in standard deviations of both.
    pub fn sigmas(&self) -> f64 {
        (self.data - self.prior.mean).abs() / self.data_sd.hypot(self.prior.sd)
    }
}

/// The per-unknown priors the data-only pass contradicts: its estimate x and covariance σ²
/// (JᵀJ)⁻¹ against each prior's prediction of it (the unknown's own Gaussian plus coefficient ×
/// the Gaussian of each unknown `held` that it absorbs, independent). Nothing when JᵀJ is
/// singular (the data then determine too little to contradict anything reliably).
pub(crate) fn prior_conflicts(
    prior: Option<&Prior>,
    all: &[Param],
    kept: &[usize],
    x: &[f64],
    jtj: &DMatrix<f64>,
    sigma: f64,
    held: &[Fixed],
) -> Vec<PriorConflict> {
    let Some(prior) = prior else {
        return Vec::new();
    };
    let Some(cov) = ident::covariance(jtj, sigma) else {
        return Vec::new();
    };
    let limit = prior.conflict_sigmas.unwrap_or(PRIOR_CONFLICT_SIGMAS);
    kept.iter()
        .enumerate()
        .filter_map(|(pos, &i)| {
            let own = prior.own(all[i])?;
            let (mut mean, mut var) = (own.mean, own.sd.powi(2));
            for f in held.iter().filter(|f| !kept.contains(&f.index)) {
                let Some(h) = prior.own(all[f.index]) else {
                    continue;
                };
                for &(_, c) in f.absorbed_by.iter().filter(|(by, _)| *by == i) {
                    mean += c * h.mean;
                    var += (c * h.sd).powi(2);
                }
            }
            let g = Gaussian {
                mean,
                sd: var.sqrt(),
            };
            let c = PriorConflict {
                index: i,
                data: x[i],
                data_sd: cov[(pos, pos)].max(0.0).sqrt(),
                prior: g,
            };
            (c.sigmas() > limit).then_some(c)
        })
        .collect()
}

/// The prior's weight and centre on each kept unknown (`Problem::with_prior`): an unknown's own
/// Gaussian alone where it has one (and the data did not contradict it: `dropped`); else the
/// class rule (centred on the start arm) and the ridge together, both pulling towards the start
/// arm. Without a noise (the data-only pass), the prior weighs nothing and the ridge alone is
/// applied.
pub(crate) fn prior_terms(
    prior: Option<&Prior>,
    ridge: Option<Ridge>,
    all: &[Param],
    kept: &[usize],
    prior_noise: Option<f64>,
    dropped: &[usize],
    data: &Dataset,
) -> Vec<(f64, f64)> {
    let ridge = |p: Param| ridge.map_or(0.0, |r| r.weight(p, data.rows.len()));
    kept.iter()
        .map(|&i| {
            let p = all[i];
            let own = prior
                .and_then(|q| q.own(p))
                .filter(|_| !dropped.contains(&i));
            match (own, prior_noise) {
                (Some(g), Some(noise)) => (noise / g.sd, g.mean),
                (Some(_), None) => (0.0, 0.0),
                (None, _) => {
                    let w = match (prior.and_then(|q| q.of(p)), prior_noise) {
                        (Some(g), Some(noise)) => noise / g.sd,
                        _ => 0.0,
                    };
                    (w.hypot(ridge(p)), 0.0)
                }
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ridge_is_mukcas_penalty_in_millimetres() {
        // MUKCa: λ (θ² + (x / 1000 mm)²) against a mean squared scatter in m²; here the cost is
        // summed over n rows in mm², i.e. MUKCa's times n·10⁶.
        let r = Ridge::MUKCA;
        let n = 60;
        let (theta, x_mm) = (2e-3, 0.7);
        let wt = r.weight(Param::Tilt(2, 0), n);
        let wl = r.weight(Param::LinkError(3, 1), n);
        let ours = (wt * theta).powi(2) + (wl * x_mm).powi(2);
        let mukca = r.lambda * (theta.powi(2) + (x_mm / 1e3).powi(2)) * n as f64 * 1e6;
        assert!((ours - mukca).abs() < 1e-12 * mukca, "{ours} {mukca}");
        assert_eq!(
            r.weight(Param::ZeroOffset(1), n),
            r.weight(Param::Tilt(1, 1), n)
        );
        // The ball (probe), extended effects and the instrument frame are not penalised.
        for p in [
            Param::ProbeError(0, 2),
            Param::Gravity(1),
            Param::FrameTranslation(0),
        ] {
            assert_eq!(r.weight(p, n), 0.0, "{p}");
        }
    }
}
