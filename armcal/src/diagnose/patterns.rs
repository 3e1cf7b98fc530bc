//! Residuals turned into what a person reads: the signature each candidate family leaves.
//!
//! A residual is a 3-vector; each family of causes moves the ball in its own direction, so the
//! residual is projected onto that direction and expressed in the cause's own unit, as "what
//! the model misses" (measured − model):
//! - **apparent angle error of joint k** (µrad): m · t_k / |t_k|², t_k = a_k × (p − o_k) the
//!   ball's motion per radian of joint k. An encoder harmonic shows as a sinusoid against the
//!   joint's reading; a gravity compliance as a straight line through 0 against the joint's
//!   gravity lever a_k · ((p − o_k) × ẑ) (slope g). Rows where the ball passes close to the
//!   axis (|t_k| below half its median) say little about the angle and are left out.
//! - **apparent elongation of link i** (µm): m · d_i, d_i the link's unit direction. A thermal
//!   expansion shows as a line against temperature (slope κ L).
//!
//! Points are the geometric model's residuals on held-out folds, and the binned means of the
//! same quantity for the geometric and the extended model show the pattern and its removal.
//! In the panel of a named cause a third line shows the cause's own part (component plus
//! residual): the extended model's held-out residuals plus the displacement the cause's term
//! makes, i.e. the term as fitted and the scatter the data leave around it. Where the
//! geometric model had absorbed part of the cause into its parameters (on real data a gravity
//! compliance trades with link and offset errors), this line is steeper than the geometric
//! model's residuals show.

use super::Diagnosis;
use crate::data::{Dataset, Kind};
use crate::effects::{Effect, TipPoint, FAMILIES};
use crate::params::ParamExt as _;
use crate::probes::Mounted;
use crate::residuals::Rigid;
use nalgebra::Vector3;
use quatarm_ref::arm::Arm;
use quatarm_ref::forward;

/// Per row: the directions of the candidate families at the model's pose.
#[derive(Clone, Debug)]
pub struct RowGeometry {
    /// t_k = a_k × (p − o_k) per joint (mm/rad).
    pub turn: Vec<Vector3<f64>>,
    /// a_k · ((p − o_k) × ẑ) per joint (mm).
    pub lever: Vec<f64>,
    /// The ball's motion per radian of each joint's δα and δβ (mm/rad,
    /// [`crate::effects::TipPoint::tilt_turn`]).
    pub tilt: Vec<[Vector3<f64>; 2]>,
    /// Unit direction of each link, then the probe (`None` for a zero-length link).
    pub links: Vec<Option<Vector3<f64>>>,
}

/// The geometry of every row of `data` under `arm`.
pub fn geometry(arm: &Arm, data: &Dataset) -> Vec<RowGeometry> {
    let mounted = crate::probes::Mounted::new(arm);
    data.rows
        .iter()
        .map(|r| {
            let (probe, arm) = mounted.of(r);
            let c = forward::evaluate(arm, &r.theta, r.temp_c);
            let n = arm.dof();
            let turn = (0..n)
                .map(|k| c.axes[k].cross(&(c.p - c.origins[k])))
                .collect();
            let lever = (0..n)
                .map(|k| c.axes[k].dot(&(c.p - c.origins[k]).cross(&Vector3::z())))
                .collect();
            let mut links: Vec<Option<Vector3<f64>>> = (0..n)
                .map(|k| (c.origins[k + 1] - c.origins[k]).try_normalize(1e-9))
                .collect();
            links.push((c.p - c.origins[n]).try_normalize(1e-9));
            let at = TipPoint {
                arm,
                probe,
                chain: &c,
                theta: &r.theta,
                temp_c: r.temp_c,
            };
            let tilt = (0..n)
                .map(|k| [at.tilt_turn(k, 0), at.tilt_turn(k, 1)])
                .collect();
            RowGeometry {
                turn,
                lever,
                tilt,
                links,
            }
        })
        .collect()
}

/// What the model misses at each row (measured − model, mm), in the arm's base frame: `point`
/// residuals are turned back from the instrument frame by `frame`'s rotation.
pub fn missing(rows: &[Vector3<f64>], frame: Option<&Rigid>, data: &Dataset) -> Vec<Vector3<f64>> {
    rows.iter()
        .zip(&data.rows)
        .map(|(r, row)| match (row.kind, frame) {
            (Kind::Point, Some(f)) => -(f.rot.transpose() * r),
            _ => -r,
        })
        .collect()
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
pub struct Patterns<'a> {
    /// The diagnosis.
    pub d: &'a Diagnosis,
    /// Its data.
    pub data: &'a Dataset,
    /// The geometry of each row under the geometric model's arm.
    pub geo: Vec<RowGeometry>,
    /// Hinge or swivel, where the arm's frames say it (not for D–H style twisted frames).
    pub plain: bool,
    before_all: Vec<Vector3<f64>>,
    after_all: Option<Vec<Vector3<f64>>>,
    judged: Vec<bool>,
    own_parts: Vec<(Effect, Vec<Vector3<f64>>)>,
    reach: f64,
}

impl<'a> Patterns<'a> {
    /// The patterns of diagnosis `d` on `data`.
    pub fn new(d: &'a Diagnosis, data: &'a Dataset) -> Patterns<'a> {
        let arm = &d.baseline.fit.arm;
        let frame = d.baseline.fit.frame;
        let before_all = missing(&d.baseline.holdout.residuals.rows, frame.as_ref(), data);
        let after_all = (!d.causes.is_empty())
            .then(|| missing(&d.extended.holdout.residuals.rows, frame.as_ref(), data));
        let judged = d
            .baseline
            .holdout
            .judged
            .iter()
            .zip(&d.extended.holdout.judged)
            .map(|(a, b)| *a && *b)
            .collect();
        let own_parts = match &after_all {
            None => Vec::new(),
            Some(after) => d
                .causes
                .iter()
                .map(|c| own_part(d, c, data, after))
                .collect(),
        };
        Patterns {
            d,
            data,
            geo: geometry(arm, data),
            plain: arm
                .joints
                .iter()
                .all(|j| j.tilt.iter().all(|t| t.abs() < 1e-3)),
            before_all,
            after_all,
            judged,
            own_parts,
            reach: crate::sim::reach(arm),
        }
    }

    /// The geometric model's arm.
    pub fn arm(&self) -> &Arm {
        &self.d.baseline.fit.arm
    }

    /// Whether `e` is a named cause.
    pub fn named(&self, e: Effect) -> bool {
        self.d.causes.iter().any(|c| c.effect == e)
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

/// A named cause's own part at every row: the extended model's held-out miss plus the
/// displacement its term makes (the extended arm with and without the term, base frame).
fn own_part(
    d: &Diagnosis,
    c: &super::Cause,
    data: &Dataset,
    after: &[Vector3<f64>],
) -> (Effect, Vec<Vector3<f64>>) {
    let ext = &d.extended.fit.arm;
    let mut without = ext.clone();
    for (p, v, _) in &c.values {
        p.add_to(&mut without, p.value(&d.extended.fit.start) - v);
    }
    let (with, without) = (Mounted::new(ext), Mounted::new(&without));
    let part = data
        .rows
        .iter()
        .zip(after)
        .map(|(r, m)| m + with.tip(r) - without.tip(r))
        .collect();
    (c.effect, part)
}

/// The figures of a diagnosis, one per effect that has one for these data (residuals against
/// each joint's reading, against each joint's gravity lever, against temperature).
pub fn figures(d: &Diagnosis, data: &Dataset) -> Vec<Figure> {
    let at = Patterns::new(d, data);
    FAMILIES.iter().filter_map(|f| f.figure(&at)).collect()
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
