//! The model linearised at a fit: what adding or removing terms would do, in sample and on
//! held-out folds, without refitting.
//!
//! At a converged fit the residuals r and the Jacobian J of the model's unknowns together with
//! every candidate's are evaluated once (one pass of the analytic Jacobian), and summed per
//! held-out fold into the normal equations A_f = J_fᵀJ_f, b_f = J_fᵀr_f, c_f = r_fᵀr_f. For
//! any set S of columns the least-squares step on the training folds is then
//! dx = −(A − A_f)_S⁻¹ (b − b_f)_S and the held-out errors are r_f + J_f dx: k-fold
//! cross-validation of every candidate model at the cost of small dense solves. A second pass
//! evaluates the held-out error of every unit ([`crate::data::Layout::units`]) for
//! the paired test of [`super::stats::Paired`].
//!
//! The linearisation is accurate here because the steps are tiny: a candidate effect of
//! 100 µrad changes the model's other unknowns by amounts of the same order, and the arm's
//! model is linear in them to ~1e-8 relative over such steps (0.01 µm at the tip). The names a
//! diagnosis gives are still checked with real refits on held-out data before they are
//! reported ([`super::select`]).

use crate::data::Dataset;
use crate::fit::finish::Fit;
use crate::fit::holdout::Folds;
use crate::fit::lm::unit_diagonal;
use crate::fit::problem::{Problem, State};
use crate::fit::residuals::Rigid;
use crate::params::Param;
use nalgebra::{DMatrix, DVector, SymmetricEigen};

/// A linear model around the fit: the columns fitted freely, and columns held at a fixed step
/// (a term removed: its unknowns moved back to their start values).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Set {
    /// Columns fitted.
    pub free: Vec<usize>,
    /// Columns moved by a fixed step: (column, step).
    pub fixed: Vec<(usize, f64)>,
}

impl Set {
    /// Free columns only.
    pub fn of(free: Vec<usize>) -> Set {
        Set {
            free,
            fixed: Vec::new(),
        }
    }
}

/// Sums of one fold.
#[derive(Clone, Debug)]
struct Sums {
    a: DMatrix<f64>,
    b: DVector<f64>,
    c: f64,
}

impl Sums {
    fn new(n: usize) -> Sums {
        Sums {
            a: DMatrix::zeros(n, n),
            b: DVector::zeros(n),
            c: 0.0,
        }
    }
}

/// The model linearised at a fit, its columns summed per held-out fold.
pub struct Linearisation {
    /// The columns: the fit's kept unknowns (the instrument frame included), then the extra
    /// ones asked for.
    pub cols: Vec<Param>,
    /// How many of `cols` are the fit's own.
    pub model_cols: usize,
    folds: Vec<Sums>,
    total: Sums,
    /// Held-out fold of each unit, in the order the problem visits them (`None`: never held
    /// out).
    unit_fold: Vec<Option<usize>>,
    /// Equations (residual components) in all.
    pub equations: usize,
    arm: quatarm_ref::arm::Arm,
    frame: Rigid,
}

impl Linearisation {
    /// Linearises `fit` on `data` with the extra columns `extra`, summed per fold of `folds`
    /// (row indices left out by each fold).
    pub fn at(fit: &Fit, data: &Dataset, extra: &[Param], folds: &Folds) -> Linearisation {
        let mut cols: Vec<Param> = fit.ident.kept.iter().map(|&i| fit.params[i]).collect();
        let model_cols = cols.len();
        for p in extra {
            if !cols.contains(p) {
                cols.push(*p);
            }
        }
        let n = cols.len();
        let frame = fit.frame.unwrap_or_else(Rigid::identity);
        let mut row_fold = vec![None; data.rows.len()];
        for (f, rows) in folds.iter().enumerate() {
            for &i in rows {
                row_fold[i] = Some(f);
            }
        }
        let layout = data.layout();
        let unit_fold: Vec<Option<usize>> = layout
            .units()
            .iter()
            .map(|u| u.rows.first().and_then(|&i| row_fold[i]))
            .collect();
        let mut lin = Linearisation {
            cols,
            model_cols,
            folds: vec![Sums::new(n); folds.len()],
            total: Sums::new(n),
            unit_fold,
            equations: 0,
            arm: fit.arm.clone(),
            frame,
        };
        let all: Vec<usize> = (0..n).collect();
        let problem = Problem::new(data, &layout, &lin.arm, &lin.cols, &all);
        let state = State {
            x: vec![0.0; n],
            frame,
        };
        let mut unit = 0;
        let mut eqs = 0;
        let (folds_sums, total, unit_fold) = (&mut lin.folds, &mut lin.total, &lin.unit_fold);
        problem.visit(&state, true, &mut |r, j| {
            let f = unit_fold[unit];
            unit += 1;
            for (k, rv) in r.iter().enumerate() {
                let jr = &j[k * n..(k + 1) * n];
                eqs += 1;
                accumulate(total, jr, *rv);
                if let Some(f) = f {
                    accumulate(&mut folds_sums[f], jr, *rv);
                }
            }
        });
        lin.equations = eqs;
        for s in lin.folds.iter_mut().chain(std::iter::once(&mut lin.total)) {
            symmetrise(&mut s.a);
        }
        lin
    }

    /// Column positions of the unknowns `params` (those present).
    pub fn positions(&self, params: &[Param]) -> Vec<usize> {
        params
            .iter()
            .filter_map(|p| self.cols.iter().position(|q| q == p))
            .collect()
    }

    /// The model's own columns.
    pub fn model(&self) -> Vec<usize> {
        (0..self.model_cols).collect()
    }

    /// The residual sum of squares (mm²) of the least-squares fit of a set on all the data,
    /// from this linearisation.
    pub fn rss(&self, set: &Set) -> f64 {
        let (a, b, c) = reduced(&self.total, set);
        let x = solve_spd(&a, &b);
        (c - b.dot(&x)).max(0.0)
    }

    /// The fixed steps that move the unknowns `params` of `fit` back to their start values
    /// (removing a fitted term from the model).
    pub fn removal(&self, fit: &Fit, params: &[Param]) -> Vec<(usize, f64)> {
        params
            .iter()
            .filter_map(|p| {
                let col = self.cols.iter().position(|q| q == p)?;
                let k = fit.params.iter().position(|q| q == p)?;
                Some((col, -fit.values[k]))
            })
            .collect()
    }

    /// Part of each column of `cols` that the columns `given` do not reproduce (relative, 0
    /// for an exact dependency): whether a candidate can be told from the model at all.
    pub fn unexplained(&self, cols: &[usize], given: &[usize]) -> f64 {
        let (agg, _) = sub(&self.total, given);
        cols.iter()
            .map(|&c| {
                let acc = self.total.a[(c, c)];
                if acc <= 0.0 {
                    return 0.0;
                }
                let agc = DVector::from_iterator(
                    given.len(),
                    given.iter().map(|&g| self.total.a[(g, c)]),
                );
                let y = solve_spd(&agg, &agc);
                ((acc - agc.dot(&y)).max(0.0) / acc).sqrt()
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// For a set, the least-squares step of its free columns on every fold's training part.
    fn steps(&self, set: &Set) -> Vec<DVector<f64>> {
        self.folds
            .iter()
            .map(|f| {
                let mut train = self.total.clone();
                train.a -= &f.a;
                train.b -= &f.b;
                train.c -= f.c;
                let (a, b, _) = reduced(&train, set);
                -solve_spd(&a, &b)
            })
            .collect()
    }

    /// Held-out squared error of every unit (visit order; units never held out are left
    /// out) for each set of columns: one more pass over the data.
    pub fn heldout(&self, data: &Dataset, sets: &[Set]) -> Vec<Vec<f64>> {
        let steps: Vec<Vec<DVector<f64>>> = sets.iter().map(|s| self.steps(s)).collect();
        let n = self.cols.len();
        let layout = data.layout();
        let all: Vec<usize> = (0..n).collect();
        let problem = Problem::new(data, &layout, &self.arm, &self.cols, &all);
        let state = State {
            x: vec![0.0; n],
            frame: self.frame,
        };
        let mut out: Vec<Vec<f64>> = vec![Vec::new(); sets.len()];
        let mut unit = 0;
        problem.visit(&state, true, &mut |r, j| {
            let f = self.unit_fold[unit];
            unit += 1;
            let Some(f) = f else { return };
            for (s, set) in sets.iter().enumerate() {
                let dx = &steps[s][f];
                let mut ss = 0.0;
                for (k, rv) in r.iter().enumerate() {
                    let jr = &j[k * n..(k + 1) * n];
                    let e = rv
                        + set
                            .free
                            .iter()
                            .zip(dx.iter())
                            .map(|(&c, d)| jr[c] * d)
                            .sum::<f64>()
                        + set.fixed.iter().map(|&(c, d)| jr[c] * d).sum::<f64>();
                    ss += e * e;
                }
                out[s].push(ss);
            }
        });
        out
    }
}

fn accumulate(s: &mut Sums, jr: &[f64], r: f64) {
    let n = jr.len();
    s.c += r * r;
    for a in 0..n {
        let ja = jr[a];
        if ja == 0.0 {
            continue;
        }
        s.b[a] += ja * r;
        for (b, jb) in jr.iter().enumerate().skip(a) {
            s.a[(a, b)] += ja * jb;
        }
    }
}

fn symmetrise(a: &mut DMatrix<f64>) {
    let n = a.nrows();
    for i in 0..n {
        for j in 0..i {
            a[(i, j)] = a[(j, i)];
        }
    }
}

/// The normal equations of a set's free columns, with its fixed steps folded into the
/// residuals: r' = r + J_E δ gives b' = b_S + A_SE δ and c' = c + 2 δᵀ b_E + δᵀ A_EE δ.
fn reduced(s: &Sums, set: &Set) -> (DMatrix<f64>, DVector<f64>, f64) {
    let (a, mut b) = sub(s, &set.free);
    let mut c = s.c;
    for &(e, d) in &set.fixed {
        c += 2.0 * d * s.b[e];
        for &(f, g) in &set.fixed {
            c += d * g * s.a[(e, f)];
        }
        for (i, &col) in set.free.iter().enumerate() {
            b[i] += s.a[(col, e)] * d;
        }
    }
    (a, b, c)
}

fn sub(s: &Sums, set: &[usize]) -> (DMatrix<f64>, DVector<f64>) {
    let k = set.len();
    (
        DMatrix::from_fn(k, k, |i, j| s.a[(set[i], set[j])]),
        DVector::from_fn(k, |i, _| s.b[set[i]]),
    )
}

/// Solves A x = b for a symmetric positive semi-definite A, scaled to a unit diagonal; a
/// singular direction (a fold whose training part cannot determine some combination) gets no
/// step, as a calibration holds what its data cannot determine.
pub fn solve_spd(a: &DMatrix<f64>, b: &DVector<f64>) -> DVector<f64> {
    let k = a.nrows();
    if k == 0 {
        return DVector::zeros(0);
    }
    let (m, s) = unit_diagonal(a);
    let bs = DVector::from_fn(k, |i, _| b[i] * s[i]);
    let y = match m.clone().cholesky() {
        Some(ch) if min_pivot_ok(&ch.l()) => ch.solve(&bs),
        _ => {
            let e = SymmetricEigen::new(m);
            let max = e.eigenvalues.max().max(0.0);
            let mut y = DVector::zeros(k);
            for (i, &l) in e.eigenvalues.iter().enumerate() {
                if l > 1e-12 * max {
                    let v = e.eigenvectors.column(i);
                    y += v * (v.dot(&bs) / l);
                }
            }
            y
        }
    };
    DVector::from_fn(k, |i, _| y[i] * s[i])
}

/// A Cholesky factor whose smallest pivot is not at rounding level (else the eigen route).
fn min_pivot_ok(l: &DMatrix<f64>) -> bool {
    (0..l.nrows()).all(|i| l[(i, i)] > 1e-6)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_and_survives_singularity() {
        let a = DMatrix::from_row_slice(2, 2, &[4.0, 2.0, 2.0, 3.0]);
        let b = DVector::from_row_slice(&[2.0, 1.0]);
        let x = solve_spd(&a, &b);
        assert!((&a * &x - &b).norm() < 1e-12);
        // Rank one: the minimum-norm (scaled) solution, finite.
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0]);
        let b = DVector::from_row_slice(&[2.0, 2.0]);
        let x = solve_spd(&a, &b);
        assert!(
            (x[0] - 1.0).abs() < 1e-9 && (x[1] - 1.0).abs() < 1e-9,
            "{x}"
        );
    }
}
