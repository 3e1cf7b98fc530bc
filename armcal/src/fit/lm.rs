//! Levenberg–Marquardt on normal equations, for problems that hand over JᵀJ and Jᵀr.
//!
//! Calibration problems are tall (thousands of residuals) and narrow (tens of unknowns), so a
//! problem accumulates the n × n normal equations as it evaluates its rows and never stores
//! its Jacobian. The unknowns are scaled so that JᵀJ has a unit diagonal before the damped
//! system is factored: this is Marquardt's scaling, which makes steps independent of the
//! units (radians against millimetres against 1/°C) and keeps the Cholesky factor accurate.
//! Unidentifiable directions must have been removed before (see [`crate::fit::ident`]); a system
//! that still cannot be factored is damped further rather than solved badly.
//!
//! States are opaque to the solver: the problem applies a step (`step`), so that a rotation
//! can be updated on its manifold while lengths and angles are simply added.

use nalgebra::{Cholesky, DMatrix, DVector};
use std::fmt;

/// Normal equations at a state: cost = ½‖r‖², JᵀJ and Jᵀr.
#[derive(Clone, Debug)]
pub struct Normal {
    /// ½‖r‖².
    pub cost: f64,
    /// JᵀJ.
    pub jtj: DMatrix<f64>,
    /// Jᵀr.
    pub jtr: DVector<f64>,
    /// Number of residuals.
    pub residuals: usize,
}

/// A least-squares problem.
pub trait Problem {
    /// The state the unknowns describe.
    type State: Clone;
    /// Number of unknowns.
    fn dim(&self) -> usize;
    /// ½‖r‖² at a state.
    fn cost(&self, s: &Self::State) -> f64;
    /// The normal equations at a state.
    fn normal(&self, s: &Self::State) -> Normal;
    /// The state moved by `dx` (same order as the unknowns).
    fn step(&self, s: &Self::State, dx: &[f64]) -> Self::State;
}

/// Solver settings.
#[derive(Clone, Debug)]
pub struct Options {
    /// Give up after this many linearisations.
    pub max_iterations: usize,
    /// Converged when a step changes the predictions by less than this fraction of the
    /// residual norm.
    pub step_tolerance: f64,
    /// Converged when a step lowers the cost by less than this fraction.
    pub cost_tolerance: f64,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            max_iterations: 100,
            step_tolerance: 1e-7,
            cost_tolerance: 1e-12,
        }
    }
}

/// Why a solve stopped. The words ([`fmt::Display`]) are the reports'.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Termination {
    /// No unknowns.
    NothingToFit,
    /// The residuals are zero.
    ExactFit,
    /// The residuals are not finite numbers.
    NotFinite,
    /// First-order optimality: the residual is orthogonal to every column.
    GradientVanished,
    /// The iteration budget ran out while the cost was still falling.
    Budget,
    /// The damped normal equations could not be factored at any damping.
    Unfactorable,
    /// The last step was below the step tolerance.
    StepTolerance,
    /// The last step lowered the cost by less than the cost tolerance.
    CostStalled,
    /// No step lowers the cost, and the steps tried were already negligible.
    RoundingFloor,
    /// No step lowers the cost at any damping.
    NoDescent,
}

impl Termination {
    /// Whether it is a convergence test that was met.
    pub fn converged(self) -> bool {
        matches!(
            self,
            Termination::NothingToFit
                | Termination::ExactFit
                | Termination::GradientVanished
                | Termination::StepTolerance
                | Termination::CostStalled
                | Termination::RoundingFloor
        )
    }
}

impl fmt::Display for Termination {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Termination::NothingToFit => "nothing to fit",
            Termination::ExactFit => "exact fit",
            Termination::NotFinite => "the residuals are not finite numbers",
            Termination::GradientVanished => "gradient vanished",
            Termination::Budget => "still improving",
            Termination::Unfactorable => "the normal equations cannot be factored",
            Termination::StepTolerance => "step below tolerance",
            Termination::CostStalled => "cost no longer decreasing",
            Termination::RoundingFloor => "no smaller cost within rounding",
            Termination::NoDescent => "no step lowers the cost",
        })
    }
}

/// How a solve ended.
#[derive(Clone, Debug)]
pub struct Outcome<S> {
    /// The final state (the best one seen).
    pub state: S,
    /// ½‖r‖² there.
    pub cost: f64,
    /// The cost at the start.
    pub start_cost: f64,
    /// Linearisations done.
    pub iterations: usize,
    /// Whether a convergence test was met.
    pub converged: bool,
    /// Whether it stopped only because the iteration budget ran out (still improving).
    pub exhausted: bool,
    /// Why it stopped.
    pub reason: Termination,
}

/// What watches the solver: told after every linearisation the iteration number and the
/// cost. The solver knows nothing of terminals or progress bars; a closure is an observer.
pub trait Observer {
    /// Iteration `iteration` has cost `cost`.
    fn iteration(&mut self, iteration: usize, cost: f64);
}

impl<F: FnMut(usize, f64)> Observer for F {
    fn iteration(&mut self, iteration: usize, cost: f64) {
        self(iteration, cost)
    }
}

/// Minimises ½‖r‖² from `start`, telling `observer` of every iteration.
pub fn solve<P: Problem>(
    problem: &P,
    start: P::State,
    options: &Options,
    observer: &mut dyn Observer,
) -> Outcome<P::State> {
    let n = problem.dim();
    let mut state = start;
    if n == 0 {
        let cost = problem.cost(&state);
        return Outcome {
            state,
            cost,
            start_cost: cost,
            iterations: 0,
            converged: true,
            exhausted: false,
            reason: Termination::NothingToFit,
        };
    }
    let mut normal = problem.normal(&state);
    let start_cost = normal.cost;
    let mut lambda = 1e-4;
    let mut iterations = 1;
    observer.iteration(iterations, normal.cost);
    // Every way out of the iteration says whether it converged and why; the outcome is the
    // state and normal equations it leaves.
    let reason = loop {
        if normal.cost == 0.0 {
            break Termination::ExactFit;
        }
        if !normal.cost.is_finite() {
            break Termination::NotFinite;
        }
        let scaled = Scaled::of(&normal);
        // First-order optimality: the residual is orthogonal to every column.
        if scaled.g.amax() <= 1e-13 * scaled.rnorm {
            break Termination::GradientVanished;
        }
        if iterations >= options.max_iterations {
            break Termination::Budget;
        }
        let step = match descend(problem, &state, &normal, &scaled, &mut lambda, options) {
            Ok(step) => step,
            Err(reason) => break reason,
        };
        state = step.state;
        normal = problem.normal(&state);
        iterations += 1;
        observer.iteration(iterations, normal.cost);
        if step.step_small {
            break Termination::StepTolerance;
        }
        if step.cost_small {
            break Termination::CostStalled;
        }
    };
    Outcome {
        state,
        cost: normal.cost,
        start_cost,
        iterations,
        converged: reason.converged(),
        exhausted: reason == Termination::Budget,
        reason,
    }
}

/// The normal equations scaled to a unit diagonal (an unknown with no effect, a zero column,
/// stays put), so that one damping suits every unknown whatever its units.
struct Scaled {
    /// JᵀJ scaled.
    a: DMatrix<f64>,
    /// The scale of each unknown (0 for one with no effect).
    scale: Vec<f64>,
    /// The scaled gradient, −Jᵀr.
    g: DVector<f64>,
    /// ‖r‖.
    rnorm: f64,
}

impl Scaled {
    fn of(normal: &Normal) -> Scaled {
        let (a, scale) = unit_diagonal(&normal.jtj);
        let g = DVector::from_fn(scale.len(), |i, _| -normal.jtr[i] * scale[i]);
        let rnorm = (2.0 * normal.cost).sqrt();
        Scaled { a, scale, g, rnorm }
    }
}

/// A step that lowered the cost: where it leads, and whether the step or the cost's fall was
/// below its tolerance (converged once the step is taken).
struct Accepted<S> {
    state: S,
    step_small: bool,
    cost_small: bool,
}

/// Tries damped steps from `state` until one lowers the cost, adapting `lambda` (eased after
/// a success by the gain ratio, raised after a failure). Stops without a step when the
/// damped matrix cannot be factored, when a negligible step no longer lowers the cost (the
/// minimum to rounding), or when no damping gives descent.
fn descend<P: Problem>(
    problem: &P,
    state: &P::State,
    normal: &Normal,
    scaled: &Scaled,
    lambda: &mut f64,
    options: &Options,
) -> Result<Accepted<P::State>, Termination> {
    let Scaled { a, scale, g, rnorm } = scaled;
    loop {
        let Some(ch) = Cholesky::new(damped(a, scale, *lambda)) else {
            *lambda *= 10.0;
            if *lambda > 1e16 {
                return Err(Termination::Unfactorable);
            }
            continue;
        };
        let y = ch.solve(g);
        let dx: Vec<f64> = (0..scale.len()).map(|i| y[i] * scale[i]).collect();
        let trial = problem.step(state, &dx);
        let trial_cost = problem.cost(&trial);
        let actual = normal.cost - trial_cost;
        let step_small = y.norm() <= options.step_tolerance * rnorm;
        if trial_cost.is_finite() && actual > 0.0 {
            // Gain ratio: actual against predicted reduction of the linear model.
            let predicted = y.dot(g) - 0.5 * y.dot(&(a * &y));
            let rho = if predicted > 0.0 {
                actual / predicted
            } else {
                0.0
            };
            *lambda = after_success(*lambda, rho);
            return Ok(Accepted {
                state: trial,
                step_small,
                cost_small: actual <= options.cost_tolerance * normal.cost,
            });
        }
        // The step does not lower the cost. If it is already negligible we are at the
        // minimum to rounding; otherwise damp harder.
        if step_small {
            return Err(Termination::RoundingFloor);
        }
        *lambda *= 8.0;
        if *lambda > 1e16 {
            return Err(Termination::NoDescent);
        }
    }
}

/// The scaled normal matrix `a` damped by `lambda` on its diagonal; an unknown with no effect
/// (scale 0) gets a 1 there, so that it stays put.
fn damped(a: &DMatrix<f64>, scale: &[f64], lambda: f64) -> DMatrix<f64> {
    let mut m = a.clone();
    for (i, &sc) in scale.iter().enumerate() {
        m[(i, i)] = if sc > 0.0 { m[(i, i)] + lambda } else { 1.0 };
    }
    m
}

/// The damping after a step that lowered the cost, from its gain ratio `rho` (actual against
/// predicted reduction): less damping where the linear model predicted well, more where not.
fn after_success(lambda: f64, rho: f64) -> f64 {
    let factor = if rho > 0.75 {
        0.2
    } else if rho > 0.25 {
        1.0
    } else {
        3.0
    };
    (lambda * factor).max(1e-12)
}

/// Marquardt's scaling of a symmetric positive semi-definite matrix `a`: the factors
/// sᵢ = 1/√aᵢᵢ (0 where aᵢᵢ = 0, an unknown with no effect) and the scaled matrix sᵢ aᵢⱼ sⱼ,
/// whose diagonal is 1 wherever aᵢᵢ > 0.
pub fn unit_diagonal(a: &DMatrix<f64>) -> (DMatrix<f64>, Vec<f64>) {
    let n = a.nrows();
    let s: Vec<f64> = (0..n)
        .map(|i| {
            let d = a[(i, i)];
            if d > 0.0 {
                1.0 / d.sqrt()
            } else {
                0.0
            }
        })
        .collect();
    (DMatrix::from_fn(n, n, |i, j| a[(i, j)] * s[i] * s[j]), s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock as residuals (1 − x, 10 (y − x²)): a classic bad start.
    struct Rosen;
    impl Problem for Rosen {
        type State = [f64; 2];
        fn dim(&self) -> usize {
            2
        }
        fn cost(&self, s: &[f64; 2]) -> f64 {
            let r = [1.0 - s[0], 10.0 * (s[1] - s[0] * s[0])];
            0.5 * (r[0] * r[0] + r[1] * r[1])
        }
        fn normal(&self, s: &[f64; 2]) -> Normal {
            let r = [1.0 - s[0], 10.0 * (s[1] - s[0] * s[0])];
            let j = DMatrix::from_row_slice(2, 2, &[-1.0, 0.0, -20.0 * s[0], 10.0]);
            let rv = DVector::from_row_slice(&r);
            Normal {
                cost: self.cost(s),
                jtj: j.transpose() * &j,
                jtr: j.transpose() * rv,
                residuals: 2,
            }
        }
        fn step(&self, s: &[f64; 2], dx: &[f64]) -> [f64; 2] {
            [s[0] + dx[0], s[1] + dx[1]]
        }
    }

    #[test]
    fn solves_rosenbrock_from_a_bad_start() {
        let out = solve(&Rosen, [-1.2, 1.0], &Options::default(), &mut |_, _| {});
        assert!(out.converged, "{}", out.reason);
        assert!(
            (out.state[0] - 1.0).abs() < 1e-6 && (out.state[1] - 1.0).abs() < 1e-6,
            "{:?}",
            out.state
        );
    }

    #[test]
    fn reports_non_convergence() {
        let opts = Options {
            max_iterations: 3,
            ..Options::default()
        };
        let out = solve(&Rosen, [-1.2, 1.0], &opts, &mut |_, _| {});
        assert!(!out.converged && out.exhausted);
        assert_eq!(out.iterations, 3);
        assert!(
            out.reason.to_string().contains("still improving"),
            "{}",
            out.reason
        );
    }
}
