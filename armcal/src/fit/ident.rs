//! Identifiability: which unknowns (or combinations) the data can determine.
//!
//! Everything here works on the triangular factor R of the Jacobian J = QR, accumulated block
//! by block ([`RFactor`]) so that a hundred thousand rows never sit in memory at once. R has
//! the singular values and right singular vectors of J, computed without squaring the
//! condition number as the normal equations would: exact dependencies come out at the level
//! of rounding (1e-15 relative) and not at 1e-8, so they are told from merely weak directions
//! with a wide margin.
//!
//! Columns are first scaled to unit norm, which makes the analysis independent of units.
//! Then, while the smallest singular value of the kept columns is below a tolerance, the
//! near-null right singular vectors name the unknowns taking part in a dependency; of those,
//! the one of lowest [`Param::priority`] (the later one on a tie) is fixed at its start value,
//! and the analysis repeats. Each fixed unknown is then regressed on the kept ones: the
//! coefficients say which kept unknowns absorb it, which is how a report puts a dependency
//! into words ("joint 1's zero offset is the instrument frame's rotation about z").
//!
//! A second, statistical test applies after a fit ([`weakest`]): a direction the data pin
//! down only to more than a plausible size of the terms involved is not identified either.

use crate::params::{Param, ParamExt};
use nalgebra::{DMatrix, SymmetricEigen};

/// Accumulates the R factor of a tall matrix given in blocks of rows (TSQR).
#[derive(Clone, Debug)]
pub struct RFactor {
    n: usize,
    r: DMatrix<f64>,
    buf: Vec<f64>,
    buf_rows: usize,
    rows: usize,
}

impl RFactor {
    /// Rows are buffered until this many, then folded into R with one QR.
    const BLOCK: usize = 1024;

    /// An empty factor for `n` columns.
    pub fn new(n: usize) -> RFactor {
        RFactor {
            n,
            r: DMatrix::zeros(0, n),
            buf: Vec::new(),
            buf_rows: 0,
            rows: 0,
        }
    }

    /// Adds rows given row-major (`rows.len()` a multiple of n).
    pub fn push(&mut self, rows: &[f64]) {
        if self.n == 0 {
            return;
        }
        self.buf.extend_from_slice(rows);
        let k = rows.len() / self.n;
        self.buf_rows += k;
        self.rows += k;
        if self.buf_rows >= Self::BLOCK {
            self.fold();
        }
    }

    fn fold(&mut self) {
        if self.buf_rows == 0 {
            return;
        }
        let n = self.n;
        let top = self.r.nrows();
        let mut m = DMatrix::zeros(top + self.buf_rows, n);
        m.view_mut((0, 0), (top, n)).copy_from(&self.r);
        for i in 0..self.buf_rows {
            for j in 0..n {
                m[(top + i, j)] = self.buf[i * n + j];
            }
        }
        self.r = m.qr().r();
        self.buf.clear();
        self.buf_rows = 0;
    }

    /// Rows pushed so far.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// The n × n upper-triangular factor (zero-padded when there were fewer rows than n).
    pub fn finish(mut self) -> DMatrix<f64> {
        self.fold();
        let n = self.n;
        let mut out = DMatrix::zeros(n, n);
        let k = self.r.nrows().min(n);
        out.view_mut((0, 0), (k, n))
            .copy_from(&self.r.view((0, 0), (k, n)));
        out
    }
}

/// Why an unknown is held at its start value.
#[derive(Clone, Debug, PartialEq)]
pub enum Why {
    /// It does not change any residual of these data (for instance a thermal term when every
    /// reading is at 20 °C).
    NoEffect,
    /// Its effect on the data equals a combination of the kept unknowns' effects.
    Inseparable,
    /// The data determine it, with the others, only to ± `uncertainty` (its unit), more than a
    /// plausible size of the term.
    Weak {
        /// Standard uncertainty of the direction it was part of, in the unknown's unit.
        uncertainty: f64,
    },
    /// The caller asked for it to be held.
    Requested,
    /// Its estimate did not differ significantly from its start value (|value| below the
    /// threshold times its standard uncertainty), so it was held there.
    Insignificant {
        /// The estimate before it was held.
        value: f64,
        /// Its standard uncertainty.
        uncertainty: f64,
    },
}

/// An unknown that is not fitted.
#[derive(Clone, Debug, PartialEq)]
pub struct Fixed {
    /// Index into the unknowns.
    pub index: usize,
    /// Why.
    pub why: Why,
    /// Kept unknowns that absorb its effect: (index, coefficient), meaning a change δ of the
    /// fixed unknown looks like changes coefficient·δ of these.
    pub absorbed_by: Vec<(usize, f64)>,
    /// Relative part of its effect the kept unknowns do not reproduce (0 for an exact
    /// dependency).
    pub unexplained: f64,
}

/// The outcome of the analysis.
#[derive(Clone, Debug, PartialEq)]
pub struct Identifiability {
    /// Unknowns fitted (indices, ascending).
    pub kept: Vec<usize>,
    /// Unknowns held at their start value, in the order they were fixed.
    pub fixed: Vec<Fixed>,
    /// Singular values of the kept, unit-norm columns, largest first.
    pub singular_values: Vec<f64>,
    /// Their ratio, largest over smallest: the condition number of the fit.
    pub condition_number: f64,
    /// Column norms of J (an unknown's overall effect on the data, residual units per unit).
    pub column_norms: Vec<f64>,
    /// Unknowns that stand for a symmetry of the data rather than a quantity (a rotation of
    /// the whole arm, which `spat` and `length` data cannot see): never fitted, but named
    /// when they absorb a held unknown.
    pub symmetries: Vec<usize>,
}

impl Identifiability {
    /// Whether unknown `i` is fitted.
    pub fn is_kept(&self, i: usize) -> bool {
        self.kept.binary_search(&i).is_ok()
    }
}

/// Unit-norm columns of R, and the norms.
fn normalised(r: &DMatrix<f64>) -> (DMatrix<f64>, Vec<f64>) {
    let n = r.ncols();
    let norms: Vec<f64> = (0..n).map(|j| r.column(j).norm()).collect();
    let rn = DMatrix::from_fn(r.nrows(), n, |i, j| {
        if norms[j] > 0.0 {
            r[(i, j)] / norms[j]
        } else {
            0.0
        }
    });
    (rn, norms)
}

/// Structural analysis of J (given by its R factor) for the unknowns `params`: singular values
/// below `tol` times the largest count as dependencies.
pub fn analyse(r: &DMatrix<f64>, params: &[Param], tol: f64) -> Identifiability {
    let n = params.len();
    let (rn, norms) = normalised(r);
    let max_norm = norms.iter().cloned().fold(0.0, f64::max);
    let mut kept: Vec<usize> = Vec::new();
    let mut fixed: Vec<Fixed> = Vec::new();
    for (j, &norm) in norms.iter().enumerate().take(n) {
        if norm > 1e-13 * max_norm && norm > 0.0 {
            kept.push(j);
        } else {
            fixed.push(Fixed {
                index: j,
                why: Why::NoEffect,
                absorbed_by: Vec::new(),
                unexplained: 1.0,
            });
        }
    }
    // One SVD finds the near-null space; its unknowns are held one at a time, the space
    // shrunk after each to its vectors that do not move the held one (what a fresh SVD of the
    // remaining columns would find, without its cost: the full vocabulary of a diagnosis holds
    // dozens). A fresh SVD then checks for near-null directions the holds uncovered.
    loop {
        let (s, vt) = svd_sorted(&rn, &kept);
        let Some(&smax) = s.first() else { break };
        let null: Vec<usize> = (0..s.len()).filter(|&i| s[i] < tol * smax).collect();
        if null.is_empty() {
            break;
        }
        // Rows: the kept unknowns; columns: an orthonormal basis of the near-null space.
        let mut basis = DMatrix::from_fn(kept.len(), null.len(), |c, k| vt[(null[k], c)]);
        while basis.ncols() > 0 {
            // Involvement of each kept unknown in the near-null space.
            let involvement: Vec<f64> = (0..kept.len()).map(|c| basis.row(c).norm()).collect();
            let cut = 0.05_f64.min(0.5 * involvement.iter().cloned().fold(0.0, f64::max));
            let candidates: Vec<usize> =
                (0..kept.len()).filter(|&c| involvement[c] >= cut).collect();
            let pick = choose_held(&candidates, |c| kept[c], params, &norms)
                .expect("a null vector has a non-zero component");
            let index = kept.remove(pick);
            fixed.push(Fixed {
                index,
                why: Why::Inseparable,
                absorbed_by: Vec::new(),
                unexplained: 0.0,
            });
            basis = without_component(&basis, pick);
        }
    }
    let mut out = Identifiability {
        kept,
        fixed,
        singular_values: Vec::new(),
        condition_number: 1.0,
        column_norms: norms,
        symmetries: Vec::new(),
    };
    refresh(r, &mut out);
    out
}

/// Of `candidates` (positions mapped to unknowns by `index`), the one to hold. An arm unknown
/// whose plausible change moves the data a thousand times less than a typical arm unknown's is
/// held first: it could only stand in for the others by absurd values (a last joint's zero
/// offset when the ball sits 0.1 mm off its axis, against the probe's own offset). Otherwise
/// the lowest priority is held, the later unknown on a tie.
fn choose_held(
    candidates: &[usize],
    index: impl Fn(usize) -> usize,
    params: &[Param],
    norms: &[f64],
) -> Option<usize> {
    let effect = |i: usize| norms[i] * params[i].plausible();
    let mut arm: Vec<f64> = (0..params.len())
        .filter(|&i| !params[i].is_frame() && norms[i] > 0.0)
        .map(effect)
        .collect();
    arm.sort_by(f64::total_cmp);
    let typical = arm.get(arm.len() / 2).copied().unwrap_or(0.0);
    let feeble = candidates
        .iter()
        .copied()
        .filter(|&c| !params[index(c)].is_frame() && effect(index(c)) < 1e-3 * typical)
        .min_by(|&a, &b| effect(index(a)).total_cmp(&effect(index(b))));
    feeble.or_else(|| {
        candidates
            .iter()
            .copied()
            .max_by_key(|&c| (params[index(c)].priority(), index(c)))
    })
}

/// Recomputes the singular values, the condition number and what absorbs each fixed unknown,
/// after `kept`, `fixed` or `symmetries` changed (for instance by the statistical test).
pub fn refresh(r: &DMatrix<f64>, id: &mut Identifiability) {
    let (rn, norms) = normalised(r);
    id.column_norms = norms;
    id.kept.sort_unstable();
    id.fixed.sort_by_key(|f| f.index);
    let (s, _) = svd_sorted(&rn, &id.kept);
    id.condition_number = match (s.first(), s.last()) {
        (Some(a), Some(b)) if *b > 0.0 => a / b,
        (Some(_), Some(_)) => f64::INFINITY,
        _ => 1.0,
    };
    id.singular_values = s;
    explain(id, &rn);
}

/// Fills `absorbed_by` of every fixed unknown by regressing its unit column on the kept ones
/// (and the symmetries).
fn explain(id: &mut Identifiability, rn: &DMatrix<f64>) {
    let basis: Vec<usize> = id.kept.iter().chain(&id.symmetries).copied().collect();
    if basis.is_empty() {
        return;
    }
    let a = DMatrix::from_fn(rn.nrows(), basis.len(), |i, c| rn[(i, basis[c])]);
    let svd = a.clone().svd(true, true);
    for f in &mut id.fixed {
        if f.why == Why::NoEffect {
            continue;
        }
        let b = rn.column(f.index).clone_owned();
        let Ok(beta) = svd.solve(&b, 1e-10 * svd.singular_values.max()) else {
            continue;
        };
        let fit = &a * &beta;
        f.unexplained = (&b - fit).norm() / b.norm().max(1e-300);
        let nf = id.column_norms[f.index];
        let mut by: Vec<(usize, f64)> = basis
            .iter()
            .enumerate()
            .filter(|(c, _)| beta[*c].abs() > 0.02)
            .map(|(c, &k)| (k, beta[c] * nf / id.column_norms[k]))
            .collect();
        by.sort_by(|x, y| {
            let wx = (x.1 * id.column_norms[x.0]).abs();
            let wy = (y.1 * id.column_norms[y.0]).abs();
            wy.total_cmp(&wx)
        });
        f.absorbed_by = by;
    }
}

/// The vectors of the space `basis` spans (orthonormal columns) whose component `row` is 0,
/// as an orthonormal basis of one dimension less, with that row removed: a Householder
/// reflection maps the row to a multiple of the first unit vector, and the other columns of
/// the reflected basis then have 0 there.
fn without_component(basis: &DMatrix<f64>, row: usize) -> DMatrix<f64> {
    let d = basis.ncols();
    let r = basis.row(row).transpose();
    let norm = r.norm();
    let mut u = r.clone();
    u[0] += if r[0] >= 0.0 { norm } else { -norm };
    let un = u.norm_squared();
    let reflected = if un > 0.0 {
        // B (I − 2 u uᵀ / uᵀu)
        basis - (basis * &u) * (u.transpose() * (2.0 / un))
    } else {
        basis.clone()
    };
    let kept_rows: Vec<usize> = (0..basis.nrows()).filter(|&i| i != row).collect();
    DMatrix::from_fn(kept_rows.len(), d - 1, |i, k| {
        reflected[(kept_rows[i], k + 1)]
    })
}

/// Singular values (descending) and the matching rows of Vᵀ of the columns `cols` of `rn`.
fn svd_sorted(rn: &DMatrix<f64>, cols: &[usize]) -> (Vec<f64>, DMatrix<f64>) {
    if cols.is_empty() {
        return (Vec::new(), DMatrix::zeros(0, 0));
    }
    let rows = rn.nrows().max(cols.len());
    let a = DMatrix::from_fn(rows, cols.len(), |i, c| {
        if i < rn.nrows() {
            rn[(i, cols[c])]
        } else {
            0.0
        }
    });
    let svd = a.svd(false, true);
    let vt = svd.v_t.expect("asked for V");
    let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
    order.sort_by(|&i, &j| svd.singular_values[j].total_cmp(&svd.singular_values[i]));
    let s = order.iter().map(|&i| svd.singular_values[i]).collect();
    let vt_sorted = DMatrix::from_fn(order.len(), cols.len(), |r, c| vt[(order[r], c)]);
    (s, vt_sorted)
}

/// The statistical test after a fit. `jtj` is JᵀJ of the kept unknowns `kept` (indices into
/// `params`), `sigma` the residual standard deviation. Returns the kept position of the unknown
/// to fix, with the standard uncertainty (its unit) of the direction it is part of, when some
/// direction is determined only to more than the plausible sizes ([`Param::plausible`]) of its
/// unknowns.
pub fn weakest(
    jtj: &DMatrix<f64>,
    sigma: f64,
    params: &[Param],
    kept: &[usize],
    threshold: f64,
) -> Option<(usize, f64)> {
    let k = kept.len();
    if k == 0 {
        return None;
    }
    let cov = covariance(jtj, sigma)?;
    let p: Vec<f64> = kept.iter().map(|&i| params[i].plausible()).collect();
    let cp = DMatrix::from_fn(k, k, |i, j| cov[(i, j)] / (p[i] * p[j]));
    let eig = SymmetricEigen::new(cp);
    let (imax, lmax) = eig
        .eigenvalues
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map(|(i, l)| (i, *l))?;
    if lmax.sqrt() <= threshold {
        return None;
    }
    let v = eig.eigenvectors.column(imax);
    let vmax = v.amax();
    let pick = (0..k)
        .filter(|&c| v[c].abs() >= 0.2 * vmax)
        .max_by_key(|&c| (params[kept[c]].priority(), kept[c]))?;
    Some((pick, cov[(pick, pick)].sqrt()))
}

/// σ² (JᵀJ)⁻¹, computed with unit-diagonal scaling; `None` when JᵀJ is singular.
pub fn covariance(jtj: &DMatrix<f64>, sigma: f64) -> Option<DMatrix<f64>> {
    let k = jtj.nrows();
    let (a, s) = crate::fit::lm::unit_diagonal(jtj);
    if s.contains(&0.0) {
        return None;
    }
    let inv = a.cholesky()?.inverse();
    Some(DMatrix::from_fn(k, k, |i, j| {
        sigma * sigma * inv[(i, j)] * s[i] * s[j]
    }))
}

/// The condition number of JᵀJ's unit-norm columns, from its eigenvalues (for a set already
/// known to be well-posed).
pub fn condition_from_normal(jtj: &DMatrix<f64>) -> f64 {
    let k = jtj.nrows();
    if k == 0 {
        return 1.0;
    }
    let s: Vec<f64> = (0..k)
        .map(|i| 1.0 / jtj[(i, i)].max(1e-300).sqrt())
        .collect();
    let a = DMatrix::from_fn(k, k, |i, j| jtj[(i, j)] * s[i] * s[j]);
    let e = SymmetricEigen::new(a).eigenvalues;
    let max = e.max();
    let min = e.min();
    if min <= 0.0 {
        f64::INFINITY
    } else {
        (max / min).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_null_space_shrinks_to_the_vectors_that_leave_a_held_unknown() {
        // Two null vectors of five unknowns; hold unknown 1.
        let n = DMatrix::from_row_slice(5, 2, &[0.5, 0.1, 0.5, -0.3, 0.5, 0.2, 0.5, 0.6, 0.0, 0.7]);
        let basis = n.clone().qr().q();
        let out = without_component(&basis, 1);
        assert_eq!((out.nrows(), out.ncols()), (4, 1));
        assert!((out.column(0).norm() - 1.0).abs() < 1e-12);
        // Put back in the full space with 0 at the held unknown, it lies in the old span.
        let mut v = nalgebra::DVector::zeros(5);
        for (i, r) in [0, 2, 3, 4].iter().enumerate() {
            v[*r] = out[(i, 0)];
        }
        let residual = &v - &basis * (basis.transpose() * &v);
        assert!(residual.norm() < 1e-12, "{residual}");
    }

    fn rows_of(m: &DMatrix<f64>) -> Vec<f64> {
        let mut v = Vec::with_capacity(m.len());
        for i in 0..m.nrows() {
            for j in 0..m.ncols() {
                v.push(m[(i, j)]);
            }
        }
        v
    }

    #[test]
    fn tsqr_matches_direct_qr() {
        let m = DMatrix::from_fn(3000, 5, |i, j| {
            ((i * 7 + j * 13) % 17) as f64 + (i as f64).sin()
        });
        let mut f = RFactor::new(5);
        for chunk in rows_of(&m).chunks(5 * 37) {
            f.push(chunk);
        }
        let r = f.finish();
        let direct = m.clone().qr().r();
        // R is unique up to the signs of its rows.
        for i in 0..5 {
            let s = (r[(i, i)] * direct[(i, i)]).signum();
            for j in 0..5 {
                assert!((r[(i, j)] - s * direct[(i, j)]).abs() < 1e-8 * direct.norm());
            }
        }
    }

    #[test]
    fn finds_and_names_a_dependency() {
        // Column 2 = column 0 − 3·column 1; the params give column 2 the lowest priority.
        let params = [
            Param::ZeroOffset(0),
            Param::LinkError(0, 0),
            Param::Tilt(1, 0),
            Param::Gravity(3),
        ];
        let m = DMatrix::from_fn(50, 4, |i, j| {
            let a = (i as f64 * 0.37).sin();
            let b = (i as f64 * 0.11).cos();
            match j {
                0 => a,
                1 => b,
                2 => a - 3.0 * b,
                _ => 0.0,
            }
        });
        let r = m.qr().r();
        let id = analyse(&r, &params, 1e-8);
        assert_eq!(id.kept, vec![0, 1]);
        assert_eq!(id.fixed.len(), 2);
        let no = id.fixed.iter().find(|f| f.index == 3).unwrap();
        assert_eq!(no.why, Why::NoEffect);
        let dep = id.fixed.iter().find(|f| f.index == 2).unwrap();
        assert_eq!(dep.why, Why::Inseparable);
        assert!(dep.unexplained < 1e-10);
        let coef: Vec<(usize, f64)> = dep.absorbed_by.clone();
        assert_eq!(coef.len(), 2);
        for (k, c) in coef {
            let want = if k == 0 { 1.0 } else { -3.0 };
            assert!((c - want).abs() < 1e-9, "{k}: {c}");
        }
        assert!(id.condition_number.is_finite());
    }
}
