//! How an effect's residual pattern is drawn: the figures, their panels and the patterns they
//! are drawn from.
//!
//! These are descriptions, computed by the diagnosis (`diagnose::patterns`) and read by each
//! effect's [`Draw`](super::Draw) implementation and by the plots; they live with the model so
//! that an effect can say how it shows without importing the diagnosis (which imports the
//! effects).

use super::Effect;
use crate::data::Dataset;
use nalgebra::Vector3;
use quatarm_ref::arm::Arm;

/// Per row: the directions of the candidate families at the model's pose.
#[derive(Clone, Debug)]
pub struct RowGeometry {
    /// t_k = a_k × (p − o_k) per joint (mm/rad).
    pub turn: Vec<Vector3<f64>>,
    /// a_k · ((p − o_k) × ẑ) per joint (mm).
    pub lever: Vec<f64>,
    /// The ball's motion per radian of each joint's δα and δβ (mm/rad,
    /// [`super::TipPoint::tilt_turn`]).
    pub tilt: Vec<[Vector3<f64>; 2]>,
    /// Unit direction of each link, then the probe (`None` for a zero-length link).
    pub links: Vec<Option<Vector3<f64>>>,
}

/// Means of `y` in `bins` equal bins of `x` holding at least `min` points: (bin centre, mean).
pub fn binned(points: &[(f64, f64)], bins: usize, min: usize) -> Vec<(f64, f64)> {
    let (lo, hi) = points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.0), b.max(p.0))
        });
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) || bins == 0 {
        return Vec::new();
    }
    let w = (hi - lo) / bins as f64;
    let mut sum = vec![0.0; bins];
    let mut count = vec![0usize; bins];
    for &(x, y) in points {
        let b = (((x - lo) / w) as usize).min(bins - 1);
        sum[b] += y;
        count[b] += 1;
    }
    (0..bins)
        .filter(|&b| count[b] >= min)
        .map(|b| (lo + (b as f64 + 0.5) * w, sum[b] / count[b] as f64))
        .collect()
}

/// One panel: a quantity against another, for the geometric model (points and binned mean)
/// and the extended one (binned mean).
#[derive(Clone, Debug)]
pub struct Panel {
    /// Title.
    pub title: String,
    /// X axis label with unit.
    pub x_label: String,
    /// Y axis label with unit.
    pub y_label: String,
    /// The geometric model's held-out points.
    pub points: Vec<(f64, f64)>,
    /// Their binned means.
    pub before: Vec<(f64, f64)>,
    /// The extended model's binned means (`None` when no cause was named).
    pub after: Option<Vec<(f64, f64)>>,
    /// For the panel of a named cause: binned means of its own part, the extended model's
    /// held-out residuals plus the displacement its term makes (a component-plus-residual
    /// view: the cause's signature as fitted, free of the other causes that overlap it).
    pub own: Option<Vec<(f64, f64)>>,
    /// Whether a named cause belongs to this panel (drawn with emphasis).
    pub named: bool,
}

impl Panel {
    /// RMS of the binned means before and after: the size of the pattern.
    pub fn pattern(&self) -> (f64, Option<f64>) {
        let rms = |v: &[(f64, f64)]| {
            if v.is_empty() {
                0.0
            } else {
                (v.iter().map(|p| p.1 * p.1).sum::<f64>() / v.len() as f64).sqrt()
            }
        };
        (rms(&self.before), self.after.as_deref().map(rms))
    }
}

/// What a figure's legend explains.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Legend {
    /// The geometric and the extended model's points and means (a diagnosis).
    Models,
    /// The residuals left and the structure fitted to them (the unexplained search).
    Unexplained,
    /// Measured points alone (the acceptance tests' pictures): no legend.
    Points,
}

/// A figure: panels under one title, written to one file.
#[derive(Clone, Debug)]
pub struct Figure {
    /// What its legend explains.
    pub legend: Legend,
    /// File name (PNG).
    pub file: String,
    /// Title.
    pub title: String,
    /// What the panels show, in a sentence.
    pub caption: String,
    /// The panels.
    pub panels: Vec<Panel>,
}

/// A panel's point for a row and its miss vector (`None`: the row says nothing here).
pub type RowPoint<'a> = dyn Fn(usize, &Vector3<f64>) -> Option<(f64, f64)> + 'a;

/// Bins of a panel's x axis.
const BINS: usize = 24;

/// What every effect's figure is drawn from: the diagnosis, its data, the geometry of each
/// row and what the models miss there.
///
/// The diagnosis fills it (`diagnose::patterns::of`); an effect's [`Draw::figure`](super::Draw::figure) reads it,
/// so that the effects need not know the diagnosis.
pub struct Patterns<'a> {
    /// The geometric model's arm.
    pub arm: &'a Arm,
    /// The data.
    pub data: &'a Dataset,
    /// Whether the data's temperatures spread enough to try thermal terms.
    pub thermal: bool,
    /// The named causes, each with the terms the data cannot tell from it.
    pub causes: Vec<Named>,
    /// The geometry of each row under the geometric model's arm.
    pub geo: Vec<RowGeometry>,
    /// Hinge or swivel, where the arm's frames say it (not for D–H style twisted frames).
    pub plain: bool,
    /// What the geometric model misses at each row (held out, base frame).
    pub before_all: Vec<Vector3<f64>>,
    /// What the extended model misses at each row (`None`: no cause was named).
    pub after_all: Option<Vec<Vector3<f64>>>,
    /// Whether each row was judged held out by both models.
    pub judged: Vec<bool>,
    /// Each named cause's own part at every row (its term's displacement plus what the
    /// extended model misses).
    pub own_parts: Vec<(Effect, Vec<Vector3<f64>>)>,
    /// The arm's reach (mm).
    pub reach: f64,
}

/// A named cause, as a figure needs it.
#[derive(Clone, Debug, PartialEq)]
pub struct Named {
    /// The term named.
    pub effect: Effect,
    /// The terms the data cannot tell from it.
    pub indistinguishable: Vec<Effect>,
}

impl Patterns<'_> {
    /// The geometric model's arm.
    pub fn arm(&self) -> &Arm {
        self.arm
    }

    /// Whether `e` is a named cause.
    pub fn named(&self, e: Effect) -> bool {
        self.causes.iter().any(|c| c.effect == e)
    }

    /// The lever below which joint k's angle cannot be read from the ball: its |t_k| at least
    /// half the median and 2 % of the arm's reach (the last joint of a Panda turns the ball
    /// about an axis 0.1 mm away: nothing to read). `None`: too few rows above it for a panel.
    pub fn cut_of(&self, k: usize) -> Option<f64> {
        let levers: Vec<f64> = self.geo.iter().map(|g| g.turn[k].norm()).collect();
        let cut = (0.5 * median(levers.clone())).max(0.02 * self.reach);
        let enough = levers.iter().filter(|l| **l >= cut).count() * 10 >= levers.len();
        enough.then_some(cut)
    }

    /// A panel from a per-row (x, y) function `f`, which gets the miss vector and returns
    /// `None` to skip the row; `cause` is the named cause the panel belongs to.
    pub fn panel(
        &self,
        title: String,
        x_label: String,
        y_label: String,
        cause: Option<Effect>,
        f: &RowPoint,
    ) -> Panel {
        let pts = |m: &[Vector3<f64>]| -> Vec<(f64, f64)> {
            (0..self.data.rows.len())
                .filter(|&i| self.judged[i])
                .filter_map(|i| f(i, &m[i]))
                .collect()
        };
        let own = cause
            .and_then(|e| self.own_parts.iter().find(|(x, _)| *x == e))
            .map(|(_, m)| binned(&pts(m), BINS, 4));
        let points = pts(&self.before_all);
        Panel {
            title,
            x_label,
            y_label,
            before: binned(&points, BINS, 4),
            points,
            after: self.after_all.as_ref().map(|m| binned(&pts(m), BINS, 4)),
            own,
            named: cause.is_some(),
        }
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binned_means_follow_the_pattern() {
        // y = x on [0, 10): bin means are the bin centres.
        let pts: Vec<(f64, f64)> = (0..1000)
            .map(|i| (i as f64 / 100.0, i as f64 / 100.0))
            .collect();
        let b = binned(&pts, 10, 4);
        assert_eq!(b.len(), 10);
        for (x, y) in &b {
            assert!((x - y).abs() < 0.01, "{x} {y}");
        }
        // Sparse bins are left out; a degenerate x range gives nothing.
        let few = [(0.0, 1.0), (0.1, 1.0), (9.9, 5.0)];
        assert!(binned(&few, 10, 2).iter().all(|b| b.1 == 1.0));
        assert!(binned(&[(1.0, 1.0), (1.0, 2.0)], 5, 1).is_empty());
    }
}
