//! The pruning policy between passes of the solver ([`Next`]): an unknown the data determine
//! only beyond its plausible size is held, else (with a significance level) the least
//! significant extended effect, tested as a whole by its Wald statistic; the fit then refits
//! the smaller model, goes on with the same one, or accepts it.

use crate::fit::ident::{self, Fixed, Identifiability, Why};
use crate::fit::options::Options;
use crate::params::{Param, ParamExt};
use crate::stats::{chi2_tail, normal_tail_two_sided};
use nalgebra::{DMatrix, DVector};

/// What the pruning policy says after a pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Next {
    /// An unknown was held: fit the smaller model, with a fresh budget.
    Refit,
    /// The same model, further: the pass ran out of its budget while still improving.
    Continue,
    /// The model stands.
    Accept,
}

/// The pruning policy: holds the weakest unknown (`weak_check`), else the least significant
/// effect (`significance`, only on a converged pass), and says what to do next.
pub(crate) fn prune(
    opts: &Options,
    all: &[Param],
    id: &mut Identifiability,
    x: &mut [f64],
    jtj: &DMatrix<f64>,
    sigma: f64,
    unfinished: bool,
) -> Next {
    if opts.weak_check {
        if let Some((pos, u)) = ident::weakest(jtj, sigma, all, &id.kept, opts.weak_threshold) {
            let index = id.kept.remove(pos);
            x[index] = 0.0;
            id.fixed.push(Fixed {
                index,
                why: Why::Weak { uncertainty: u },
                absorbed_by: Vec::new(),
                unexplained: 1.0,
            });
            return Next::Refit;
        }
    }
    if opts.significance > 0.0 && !unfinished {
        if let Some(c) = ident::covariance(jtj, sigma) {
            if let Some((held, _)) = least_significant(all, &id.kept, x, &c, opts.significance) {
                for i in held {
                    let Some(pos) = id.kept.iter().position(|&k| k == i) else {
                        continue;
                    };
                    id.fixed.push(Fixed {
                        index: i,
                        why: Why::Insignificant {
                            value: x[i],
                            uncertainty: c[(pos, pos)].sqrt(),
                        },
                        absorbed_by: Vec::new(),
                        unexplained: 1.0,
                    });
                    x[i] = 0.0;
                }
                id.kept.retain(|k| !id.fixed.iter().any(|f| f.index == *k));
                return Next::Refit;
            }
        }
    }
    if unfinished {
        Next::Continue
    } else {
        Next::Accept
    }
}

/// The least significant extended effect among the kept unknowns, if it is below `t`
/// standard uncertainties: its unknowns (positions in `all`) and its p-value. An effect's
/// unknowns are tested together with the Wald statistic xᵀC⁻¹x against the χ² tail of their
/// count at the two-sided p-value of `t` for one unknown.
fn least_significant(
    all: &[Param],
    kept: &[usize],
    x: &[f64],
    cov: &DMatrix<f64>,
    t: f64,
) -> Option<(Vec<usize>, f64)> {
    let p_cut = normal_tail_two_sided(t);
    let mut effects: Vec<Vec<usize>> = Vec::new();
    for (pos, &i) in kept.iter().enumerate() {
        let p = all[i];
        if p.is_geometric() || p.is_frame() {
            continue;
        }
        let same = effects.iter_mut().find(|e| {
            let q = all[kept[e[0]]];
            p.effect().map(|(e, _)| e) == q.effect().map(|(e, _)| e)
        });
        match same {
            Some(e) => e.push(pos),
            None => effects.push(vec![pos]),
        }
    }
    let mut worst: Option<(Vec<usize>, f64)> = None;
    for e in effects {
        let k = e.len();
        let sub = DMatrix::from_fn(k, k, |a, b| cov[(e[a], e[b])]);
        let v = DVector::from_fn(k, |a, _| x[kept[e[a]]]);
        let Some(inv) = sub.try_inverse() else {
            continue;
        };
        let w = (v.transpose() * inv * &v)[(0, 0)];
        let p = chi2_tail(w, k);
        if p > p_cut && worst.as_ref().is_none_or(|(_, q)| p > *q) {
            worst = Some((e.iter().map(|&pos| kept[pos]).collect(), p));
        }
    }
    worst
}
