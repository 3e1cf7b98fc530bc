//! Calibration: the arm's parameters from any mix of `point`, `spat`, `length` and `sphere`
//! data. This file is the fit's loop; each step has a file of its own:
//!
//! 1. Identifiability, structural ([`crate::fit::structure`]): the Jacobian of every requested
//!    unknown at the arm's nominal skeleton (errors zeroed, tilts snapped to their nominal
//!    quarter turns) is analysed ([`crate::fit::ident`]); unknowns the data cannot separate
//!    are held at their start values. The same analysis on a small well-spread design of the
//!    same kinds tells a degenerate pose set (fewer identifiable unknowns than good poses
//!    give) from a limit of the data's kinds, and gives the count of equations needed.
//! 2. Levenberg–Marquardt ([`crate::fit::lm`]) on the least-squares problem
//!    ([`crate::fit::problem`]) from the start arm, with the instrument frame started by the
//!    best rigid alignment of the start arm's ball centres onto the measured ones.
//! 3. Identifiability, statistical ([`crate::fit::prune`]): a direction determined only to
//!    more than plausible sizes of its terms is also held, and the fit repeated.
//! 4. Standard uncertainties from σ̂² (JᵀJ)⁻¹ with σ̂ from the residuals
//!    ([`crate::fit::finish`]).
//!
//! A Gaussian prior or MUKCa's ridge penalty ([`crate::fit::priors`]) can join the cost as one
//! residual per unknown; under the ridge, step 1 holds nothing it penalises (the penalty
//! shares out what the data cannot separate), and JᵀJ in step 4 includes the penalty. The
//! settings are [`Options`], the refusals [`CalibError`].

use crate::data::Dataset;
use crate::fit::finish::{finish, Fitted};
use crate::fit::lm;
use crate::fit::priors::{prior_conflicts, prior_terms, PriorConflict};
use crate::fit::problem::start_frame;
use crate::fit::prune::{prune, Next};
use crate::fit::structure::{check_structure, Structure};
use crate::progress::{Observer, Silent};
use quatarm_ref::arm::Arm;
use std::time::Instant;

use crate::fit::error::CalibError;
use crate::fit::finish::Fit;
use crate::fit::options::Options;
use crate::fit::problem::{Problem, State};

/// Calibrates `start` on `data`.
pub fn calibrate(start: &Arm, data: &Dataset, opts: &Options) -> Result<Fit, CalibError> {
    calibrate_observed(start, data, opts, &mut Silent)
}

/// Calibrates `start` on `data`, telling `observer` what it is doing: the structural check
/// (`check_structure`), then fits ([`lm::solve`]) until the pruning policy (`prune`, saying
/// `Next`) accepts the model, then the uncertainties of what was kept (`finish`).
pub fn calibrate_observed(
    start: &Arm,
    data: &Dataset,
    opts: &Options,
    observer: &mut dyn Observer,
) -> Result<Fit, CalibError> {
    let t0 = Instant::now();
    let mut s = check_structure(start, data, opts, observer)?;
    let (all, layout, eqs) = (&s.all, &s.layout, s.eqs);
    let mut state = State {
        x: vec![0.0; all.len()],
        frame: start_frame(&s.base, data, layout),
    };
    let rms_before = rms_before(data, &s, &state)?;
    let mut run = Run {
        iterations: 0,
        passes: 0,
        model_iterations: 0,
        prior_noise: opts.prior.as_ref().and_then(|p| p.noise_mm),
        data_pass_done: false,
        conflicts: Vec::new(),
    };
    loop {
        let noise_pass = run.noise_pass(opts);
        let kept = pass_unknowns(opts, &s, data, noise_pass);
        let dropped: Vec<usize> = run.conflicts.iter().map(|c| c.index).collect();
        let problem = Problem::new(data, layout, &s.base, all, &kept).with_prior(prior_terms(
            opts.prior.as_ref(),
            opts.ridge,
            all,
            &kept,
            if noise_pass { None } else { run.prior_noise },
            &dropped,
            data,
        ));
        observer.stage(&format!(
            "fitting {} unknowns (pass {})",
            kept.len(),
            run.passes + 1
        ));
        let out = run.pass(&problem, state, opts, eqs, observer)?;
        let unfinished = !out.converged;
        state = out.state;
        let normal = lm::Problem::normal(&problem, &state);
        let data_cost = problem.data_cost(&state);
        let dof = eqs.saturating_sub(kept.len()).max(1);
        let sigma = (2.0 * data_cost / dof as f64).sqrt();
        if noise_pass {
            run.prior_noise = run.prior_noise.or(Some(sigma));
            run.data_pass_done = true;
            run.conflicts = prior_conflicts(
                opts.prior.as_ref(),
                all,
                &kept,
                &state.x,
                &normal.jtj,
                sigma,
                &s.shared_fixed,
            );
            run.model_iterations = 0;
            continue;
        }
        match prune(
            opts,
            all,
            &mut s.id,
            &mut state.x,
            &normal.jtj,
            sigma,
            unfinished,
        ) {
            Next::Refit => {
                run.model_iterations = 0;
                continue;
            }
            Next::Continue => continue,
            Next::Accept => {}
        }
        let fitted = Fitted {
            arm: problem.arm(&state),
            state,
            jtj: normal.jtj,
            sigma,
            data_cost,
            solver: out.reason,
        };
        let mut fit = finish(s, fitted, run.iterations, rms_before, t0);
        fit.prior_conflicts = run.conflicts;
        return Ok(fit);
    }
}

/// The RMS residual of the start arm over the data's equations; refused when it is not
/// finite.
fn rms_before(data: &Dataset, s: &Structure, state: &State) -> Result<f64, CalibError> {
    let p = Problem::new(data, &s.layout, &s.base, &s.all, &s.id.kept);
    let rms = (2.0 * lm::Problem::cost(&p, state) / s.eqs as f64).sqrt();
    if !rms.is_finite() {
        // The loaders bound every value, so this is an arm made in memory; a solver given NaN
        // would only report "did not converge" after its whole budget.
        return Err(CalibError::Mismatch(format!(
            "the start arm puts the ball at a non-finite position (RMS residual {rms}): \
             its values are beyond what can be evaluated"
        )));
    }
    Ok(rms)
}

/// The unknowns of the next pass: those the structure check kept, less (on the data-only
/// pass) those only their own prior lets the fit separate.
fn pass_unknowns(opts: &Options, s: &Structure, data: &Dataset, noise_pass: bool) -> Vec<usize> {
    if !noise_pass {
        return s.id.kept.clone();
    }
    let ridged = |i: usize| {
        opts.ridge
            .is_some_and(|r| r.weight(s.all[i], data.rows.len()) > 0.0)
    };
    s.id.kept
        .iter()
        .copied()
        .filter(|&i| !s.shared.contains(&i) || ridged(i))
        .collect()
}

/// The fit's passes: iterations in all and per model, and the prior's noise once estimated.
struct Run {
    iterations: usize,
    passes: usize,
    /// Iterations since the model last changed: the budget is per model.
    model_iterations: usize,
    prior_noise: Option<f64>,
    /// Whether the data-only pass has been run (noise estimated, priors tested).
    data_pass_done: bool,
    /// Per-unknown priors dropped after that pass.
    conflicts: Vec<PriorConflict>,
}

impl Run {
    /// Whether the next pass is the data-only one: a first pass without the prior estimates
    /// the noise it is weighed against and tests the per-unknown priors against what the data
    /// say alone; it leaves out what only the prior lets it fit (unknowns shared out by their
    /// own prior alone).
    fn noise_pass(&self, opts: &Options) -> bool {
        opts.prior.as_ref().is_some_and(|p| {
            !self.data_pass_done && (self.prior_noise.is_none() || !p.unknowns.is_empty())
        })
    }

    /// One pass of the solver, its iterations told to `observer`. Refused when it stopped
    /// without converging for another reason than its budget, or with the model's budget spent.
    fn pass(
        &mut self,
        problem: &Problem,
        state: State,
        opts: &Options,
        eqs: usize,
        observer: &mut dyn Observer,
    ) -> Result<lm::Outcome<State>, CalibError> {
        let done = self.iterations;
        let mut report = |it: usize, cost: f64| {
            observer.iteration(done + it, (2.0 * cost / eqs as f64).sqrt());
        };
        // A first pass gets a short budget: a direction the data barely determine makes the
        // solver crawl along its valley, and the statistical test removes it sooner.
        let budget = opts
            .lm
            .max_iterations
            .saturating_sub(self.model_iterations)
            .max(1);
        let pass = lm::Options {
            max_iterations: if self.passes == 0 {
                budget.min(12)
            } else {
                budget
            },
            ..opts.lm.clone()
        };
        self.passes += 1;
        let out = lm::solve(problem, state, &pass, &mut report);
        self.iterations += out.iterations;
        self.model_iterations += out.iterations;
        if !out.converged && (!out.exhausted || self.model_iterations >= opts.lm.max_iterations) {
            return Err(CalibError::NotConverged {
                iterations: self.model_iterations,
                reason: out.reason,
                rms_mm: (2.0 * problem.data_cost(&out.state) / eqs as f64).sqrt(),
            });
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::Kind;
    use crate::fit::design::poses::{limits, random_pose};
    use crate::fit::priors::Ridge;
    use crate::fit::residuals::compare_aligned;
    use crate::params::Param;
    use crate::rng::rng;
    use crate::sim::{self, perturb, simulate};

    #[test]
    fn the_ridge_shares_out_what_the_data_cannot_separate() {
        let nominal = Arm::default6();
        let truth = perturb(&nominal, 3e-4, 0.3, &mut rng(11));
        let data = simulate(&truth, &sim::Options::new(Kind::Point, 600), &mut rng(12))
            .unwrap()
            .data;
        let plain = calibrate(&nominal, &data, &Options::default()).unwrap();
        let opts = Options {
            ridge: Some(Ridge::MUKCA),
            ..Options::default()
        };
        let fit = calibrate(&nominal, &data, &opts).unwrap();
        let at = |p: Param| fit.params.iter().position(|q| *q == p).unwrap();
        // Links 1 and 2 along x move the tip alike: least squares holds one, the ridge fits
        // both and, their weights being equal, splits the effect evenly.
        let (l1x, l2x) = (at(Param::LinkError(0, 0)), at(Param::LinkError(1, 0)));
        assert!(!plain.ident.kept.contains(&l2x));
        assert!(fit.ident.kept.contains(&l1x) && fit.ident.kept.contains(&l2x));
        assert!(
            (fit.values[l1x] - fit.values[l2x]).abs() < 1e-6,
            "{} {}",
            fit.values[l1x],
            fit.values[l2x]
        );
        assert!(fit.values[l1x].abs() > 1e-3, "{}", fit.values[l1x]);
        // Link 1 along z is the instrument frame's translation, which is free: it stays at 0.
        assert!(fit.values[at(Param::LinkError(0, 2))].abs() < 1e-6);
        // The condition number is the data's own, over what they determine.
        assert_eq!(fit.ident.singular_values.len(), plain.ident.kept.len());
        assert!(fit.ident.condition_number.is_finite());
        // On data this precise the penalty hardly moves the fit: fresh poses still within the
        // round-trip target (measured 0.79 µm RMS, least squares 0.86).
        let lim = limits(&nominal);
        let mut r = rng(13);
        let poses: Vec<(Vec<f64>, f64)> = (0..2000)
            .map(|_| (random_pose(&lim, &mut r), 20.0))
            .collect();
        let after = compare_aligned(&fit.arm, &truth, &poses);
        assert!(after.rms_um < 2.5, "{}", after.rms_um);
    }
}
