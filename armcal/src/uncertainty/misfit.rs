//! The budget's model term, estimated from held-out residuals (`spec/uncertainty.md`, "What
//! honest means": never assumed 0 by default).
//!
//! Each held-out row (a `point` row of a k-fold, a probing of a held-out `spat` or `length`
//! group, a whole held-out session) has a residual r_i that the model fitted without it left,
//! and the rest of the budget predicts a covariance S_i for it: the parameters and the
//! reading as Σ_p does, the instrument's own noise for a `point` row, and for a probing the
//! deviation from its group's centre (what the group's probings share cancels; see
//! [`propagate::group_deviations`]). An isotropic model variance τ² adds m_i τ² I to S_i
//! (m_i = 1 for a point, 1 − 1/n for one of a group's n probings about their mean).
//!
//! Row i is inside its predicted 95 % region when |r_i| ≤ U95(S_i + m_i τ² I), which only gets
//! truer as τ grows: each row has a threshold τ_i, the least τ that covers it. The model
//! term is their split-conformal quantile: the k-th smallest of the n thresholds, k = ⌈0.95
//! (n + 1)⌉. Were the held-out rows and a fresh reading exchangeable, a fresh reading would be
//! inside with probability ≥ 95 % (Vovk et al.; Lei et al. 2018, distribution-free: no
//! Gaussian tail assumed, which is the point — a geometric model's misfit is heavier-tailed
//! than a Gaussian). Rows of a held-out session are not independent of each other; that is
//! why the report gives the number of held-out groups beside the number of rows.
//!
//! Why isotropic and not a covariance: a misfit's direction depends on the pose, and one
//! matrix for every pose would be a worse description than one radius; and the table and the
//! hub carry `model_mm` already, so the hub streams the same U95 as `eval` with no new key.

use super::{propagate, u95, Budget};
use crate::data::Dataset;
use nalgebra::{Matrix3, Vector3};
use quatarm_ref::arm::Arm;

/// √χ²₃(0.95): U95 of an isotropic N(0, σ² I) is this many σ.
const CHI3_95: f64 = 2.795_483_482_915_108;

/// One held-out row's evidence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Score {
    /// |r_i| (mm).
    pub deviation: f64,
    /// Eigenvalues of S_i, largest first (mm²).
    pub lambda: [f64; 3],
    /// The factor of τ² in the row's covariance.
    pub m: f64,
}

impl Score {
    /// Is the row inside U95 with the model term τ (mm)?
    pub fn covered(&self, tau: f64) -> bool {
        let add = self.m * tau * tau;
        let l = self.lambda.map(|x| x.max(0.0) + add);
        if l[0] <= 0.0 {
            return self.deviation <= 0.0;
        }
        // Inside the 95 % radius ⇔ the ball of radius |r| holds at most 95 %.
        u95::probability_within(l, self.deviation) <= u95::LEVEL
    }

    /// (lower, upper) bounds of the threshold τ_i: U95 lies between CHI3_95·√λ_min and
    /// CHI3_95·√λ_max of the covariance with the model term.
    fn bounds(&self) -> (f64, f64) {
        let d2 = (self.deviation / CHI3_95).powi(2);
        let m = self.m.max(1e-12);
        let lo = ((d2 - self.lambda[0].max(0.0)) / m).max(0.0).sqrt();
        let hi = ((d2 - self.lambda[2].max(0.0)) / m).max(0.0).sqrt();
        (lo, hi)
    }

    /// The least τ that covers the row, to a relative 1e-4 of the bracket.
    pub fn threshold(&self) -> f64 {
        let (mut lo, mut hi) = self.bounds();
        if self.covered(lo) {
            return lo;
        }
        while hi - lo > 1e-4 * hi.max(1e-9) {
            let mid = 0.5 * (lo + hi);
            if self.covered(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        hi
    }
}

/// The scores of the held-out rows of `data` (`judged`), their residuals `res` from the
/// folds' fits, against `budget` (its model term ignored) on the calibrated `arm`;
/// `instrument_mm` the reference instrument's noise per axis, in a `point` row's residual but
/// not in a reading's error. `sphere` rows (a radial residual) are not used.
pub fn scores(
    arm: &Arm,
    budget: &Budget,
    data: &Dataset,
    res: &[Vector3<f64>],
    judged: &[bool],
    instrument_mm: f64,
) -> Vec<Score> {
    row_covariances(arm, budget, data, judged, instrument_mm)
        .into_iter()
        .map(|r| r.score(res, &Matrix3::zeros()))
        .collect()
}

/// The held-out residuals of `h` with each fold's rigid part taken out of its `point` rows
/// (the best rigid motion of the fold's predicted points onto the reference's, over its held-out
/// `point` rows; folds with fewer than [`FRAME_ROWS`] of them unchanged). A fold's fit places
/// the reference instrument's frame from the other folds, and that placement's error is in
/// every held-out `point` residual of the fold, while the rest of the budget (C marginal over
/// the frame) does not predict it: the model term would take it for misfit. A fresh reading
/// of the arm carries no instrument frame (its coordinates are the arm's), so the frame's
/// error is not the model's. Taking out a rigid motion fitted to n rows removes 6 of their
/// 3n degrees of freedom, and with them the rigid-looking part of the parameters' error in
/// those rows, which S_i still counts: the term errs small by at most that share.
pub fn without_frame(data: &Dataset, h: &crate::fit::holdout::Holdout) -> Vec<Vector3<f64>> {
    let mut out = h.residuals.rows.clone();
    for fit in &h.fits {
        let rows: Vec<usize> = fit
            .rows
            .iter()
            .copied()
            .filter(|&i| h.judged[i] && data.rows[i].kind == crate::data::Kind::Point)
            .filter(|&i| data.rows[i].xyz.is_some())
            .collect();
        if rows.len() < FRAME_ROWS {
            continue;
        }
        let x: Vec<Vector3<f64>> = rows
            .iter()
            .map(|&i| Vector3::from(data.rows[i].xyz.unwrap_or([0.0; 3])))
            .collect();
        let r: Vec<Vector3<f64>> = rows.iter().map(|&i| out[i]).collect();
        for (&i, v) in rows.iter().zip(rigid_part_removed(&x, &r)) {
            out[i] = v;
        }
    }
    out
}

/// Residuals r_i = q_i − x_i of predicted points q_i against reference points x_i, less
/// their best rigid part: g(q_i) − x_i with g the rigid motion that best maps the q onto the x.
fn rigid_part_removed(x: &[Vector3<f64>], r: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    let q: Vec<Vector3<f64>> = x.iter().zip(r).map(|(x, r)| x + r).collect();
    let g = crate::fit::residuals::best_rigid(&q, x);
    q.iter().zip(x).map(|(q, x)| g.apply(q) - x).collect()
}

/// Fewest held-out `point` rows of a fold whose rigid part [`without_frame`] takes out: a
/// rigid motion has 6 degrees of freedom, and fewer rows would lose most of theirs to it.
pub const FRAME_ROWS: usize = 12;

/// One held-out row's predicted covariance.
#[derive(Clone, Copy, Debug)]
pub struct RowCov {
    /// The row in the data.
    pub row: usize,
    /// What the budget predicts for its residual (mm²).
    pub s: Matrix3<f64>,
    /// The factor of an isotropic term's variance in it.
    pub m: f64,
}

impl RowCov {
    /// The row's score with `extra` added to its covariance.
    pub fn score(&self, res: &[Vector3<f64>], extra: &Matrix3<f64>) -> Score {
        Score {
            deviation: res[self.row].norm(),
            lambda: u95::eigenvalues(&(self.s + extra)),
            m: self.m,
        }
    }
}

/// What `budget` (its model term ignored) predicts for each held-out row's residual (see
/// [`scores`]), in the order `point` rows, then the `spat` groups and bar ends judged whole.
pub fn row_covariances(
    arm: &Arm,
    budget: &Budget,
    data: &Dataset,
    judged: &[bool],
    instrument_mm: f64,
) -> Vec<RowCov> {
    let mut b = budget.clone();
    b.model_mm = 0.0;
    let mut out = Vec::new();
    let layout = data.layout();
    let inst = instrument_mm * instrument_mm;
    for &i in layout.points.iter().filter(|&&i| judged[i]) {
        let r = &data.rows[i];
        let probe = crate::fit::probes::index(arm, r);
        let (_, s) = propagate::point(arm, probe, &b, &r.theta, r.temp_c);
        out.push(RowCov {
            row: i,
            s: s + Matrix3::identity() * inst,
            m: 1.0,
        });
    }
    let groups = layout
        .spat
        .iter()
        .map(|g| g.rows.clone())
        .chain(layout.length_ends().cloned());
    for rows in groups {
        if rows.len() < 2 || !rows.iter().all(|&i| judged[i]) {
            continue;
        }
        let n = rows.len() as f64;
        for (i, s) in propagate::group_deviations(arm, &b, data, &rows) {
            out.push(RowCov {
                row: i,
                s,
                m: 1.0 - 1.0 / n,
            });
        }
    }
    out
}

/// The conformal model term of `scores`: (τ mm, the rank k used, whether k ≤ n, i.e. the
/// finite-sample guarantee holds; with fewer than 19 rows it cannot, and τ is the largest
/// threshold). `None` without scores.
pub fn conformal(scores: &[Score], level: f64) -> Option<(f64, usize, bool)> {
    let n = scores.len();
    if n == 0 {
        return None;
    }
    let k = ((level * (n + 1) as f64).ceil() as usize).max(1);
    let exact = k <= n;
    let k = k.min(n);
    // Only rows whose bracket can hold the k-th threshold need their exact threshold.
    let bounds: Vec<(f64, f64)> = scores.iter().map(Score::bounds).collect();
    let kth = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[k - 1]
    };
    let lo_k = kth(bounds.iter().map(|b| b.0).collect());
    let hi_k = kth(bounds.iter().map(|b| b.1).collect());
    let thresholds: Vec<f64> = scores
        .iter()
        .zip(&bounds)
        .map(|(s, &(lo, hi))| {
            if hi < lo_k {
                hi
            } else if lo > hi_k {
                lo
            } else {
                s.threshold()
            }
        })
        .collect();
    Some((kth(thresholds), k, exact))
}

/// Fraction of `scores` covered with the model term τ.
pub fn coverage(scores: &[Score], tau: f64) -> f64 {
    scores.iter().filter(|s| s.covered(tau)).count() as f64 / scores.len().max(1) as f64
}

/// A held-out group's rows are said to be missed as a whole when so few of them are inside
/// their 95 % region that rows inside with 95 % each would leave that few with this chance
/// at most.
pub const GROUP_MISSED_P: f64 = 0.01;

/// One held-out group's rows inside their predicted 95 % region under the whole budget.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct GroupCoverage {
    /// The group (session, placement) number of the data.
    pub group: i64,
    /// Its held-out rows scored.
    pub rows: usize,
    /// How many of them are inside.
    pub covered: usize,
    /// P(no more than `covered` inside) were each row inside with 95 % on its own. Rows of
    /// one session share its placement, so this is a yardstick for "missed as a whole", not a
    /// test of the budget: a session's rows are not independent.
    pub p: f64,
}

impl GroupCoverage {
    /// Fraction of its rows inside.
    pub fn fraction(&self) -> f64 {
        self.covered as f64 / self.rows.max(1) as f64
    }

    /// Is the group missed as a whole ([`GROUP_MISSED_P`])?
    pub fn missed(&self) -> bool {
        self.p < GROUP_MISSED_P
    }
}

/// Each held-out group's coverage with the model term τ: `groups[k]` the group of the row
/// scored `scores[k]`; in ascending group number. A session the budget misses as a whole
/// shows here and nowhere in the pooled figure, which the conformal term holds at 95 % over
/// all rows (issue 27: MUKCa's raised placements).
pub fn group_coverage(groups: &[i64], scores: &[Score], tau: f64) -> Vec<GroupCoverage> {
    let mut by: std::collections::BTreeMap<i64, (usize, usize)> = Default::default();
    for (&g, s) in groups.iter().zip(scores) {
        let e = by.entry(g).or_default();
        e.0 += 1;
        e.1 += usize::from(s.covered(tau));
    }
    by.into_iter()
        .map(|(group, (n, c))| GroupCoverage {
            group,
            rows: n,
            covered: c,
            // P(inside ≤ c) = P(outside ≥ n − c), each row outside with 5 %.
            p: crate::stats::binomial_at_least(n - c, n, 1.0 - u95::LEVEL),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Isotropic Gaussian residuals of σ = 50 µm over a budget of 5 µm: the conformal term
    /// recovers about σ, and covers 95 % of the rows it came from.
    #[test]
    fn the_conformal_term_recovers_an_isotropic_misfit() {
        let mut rng = crate::rng::rng(3);
        let sigma = 0.05;
        let scores: Vec<Score> = (0..4000)
            .map(|_| {
                let v = Vector3::from_fn(|_, _| sigma * crate::rng::normal(&mut rng));
                Score {
                    deviation: v.norm(),
                    lambda: [25e-6, 25e-6, 25e-6],
                    m: 1.0,
                }
            })
            .collect();
        let (tau, k, exact) = conformal(&scores, 0.95).unwrap();
        assert!(exact && k == 3801);
        let expect = (sigma * sigma - 25e-6f64).sqrt();
        assert!((tau / expect - 1.0).abs() < 0.05, "{tau} vs {expect}");
        let c = coverage(&scores, tau);
        assert!((0.945..0.96).contains(&c), "{c}");
        // A row already inside needs no term; a far one needs more than its own distance/χ.
        let near = Score {
            deviation: 1e-3,
            lambda: [1e-4; 3],
            m: 1.0,
        };
        assert_eq!(near.threshold(), 0.0);
        let far = Score {
            deviation: 1.0,
            lambda: [1e-4, 1e-6, 1e-6],
            m: 1.0,
        };
        let t = far.threshold();
        assert!(far.covered(t) && !far.covered(0.99 * t), "{t}");
    }

    /// Each group's rows counted apart: a group whose rows are all far is missed as a
    /// whole, one with a row or two outside (as 95 % leaves) is not.
    #[test]
    fn a_group_missed_as_a_whole_is_told_from_one_missed_by_chance() {
        let row = |deviation: f64| Score {
            deviation,
            lambda: [1e-4; 3],
            m: 1.0,
        };
        // Group 1: 40 rows, 2 far (95 % leaves 2); group 2: 20 rows, 12 far.
        let mut groups = vec![1; 40];
        groups.extend([2; 20]);
        let scores: Vec<Score> = (0..60)
            .map(|k| row(if (2..48).contains(&k) { 1e-3 } else { 1.0 }))
            .collect();
        let g = group_coverage(&groups, &scores, 0.0);
        assert_eq!(g.len(), 2);
        assert_eq!((g[0].group, g[0].rows, g[0].covered), (1, 40, 38));
        assert!(!g[0].missed() && g[0].p > 0.5, "{:?}", g[0]);
        assert_eq!((g[1].group, g[1].rows, g[1].covered), (2, 20, 8));
        assert!(g[1].missed() && g[1].p < 1e-9, "{:?}", g[1]);
        assert!((g[1].fraction() - 0.4).abs() < 1e-12);
        // A model term that covers the far rows leaves no group missed.
        assert!(group_coverage(&groups, &scores, 1.0)
            .iter()
            .all(|g| g.covered == g.rows && g.p == 1.0));
    }

    /// A fold's frame error (a rigid motion of its predictions) is taken out of its held-out
    /// residuals and a misfit that is not rigid (a scale error of 1e-4 about the centroid)
    /// is kept.
    #[test]
    fn the_rigid_part_of_a_folds_residuals_is_taken_out_and_no_more() {
        let mut rng = crate::rng::rng(5);
        let x: Vec<Vector3<f64>> = (0..120)
            .map(|_| Vector3::from_fn(|_, _| 800.0 * crate::rng::normal(&mut rng)))
            .collect();
        let rot = nalgebra::Rotation3::from_scaled_axis(Vector3::new(2e-5, -1e-5, 3e-5));
        let t = Vector3::new(0.004, -0.002, 0.003);
        let frame: Vec<Vector3<f64>> = x.iter().map(|p| rot * p + t - p).collect();
        let rms = |v: &[Vector3<f64>]| {
            (v.iter().map(|r| r.norm_squared()).sum::<f64>() / v.len() as f64).sqrt()
        };
        let left = rigid_part_removed(&x, &frame);
        assert!(rms(&frame) > 0.02 && rms(&left) < 1e-9, "{}", rms(&left));
        // A scale error about the points' centroid has no rigid part (one about another
        // centre has a translation, which goes with the frame).
        let c = x.iter().sum::<Vector3<f64>>() / x.len() as f64;
        let scale: Vec<Vector3<f64>> = x.iter().map(|p| (p - c) * 1e-4).collect();
        let both: Vec<Vector3<f64>> = frame.iter().zip(&scale).map(|(a, b)| a + b).collect();
        let left = rigid_part_removed(&x, &both);
        let d: Vec<Vector3<f64>> = left.iter().zip(&scale).map(|(a, b)| a - b).collect();
        assert!(
            rms(&d) < 1e-3 * rms(&scale),
            "{} of {}",
            rms(&d),
            rms(&scale)
        );
    }
}
