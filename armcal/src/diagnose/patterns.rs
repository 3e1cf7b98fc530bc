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
use crate::params::Effect;
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
    /// Unit direction of each link, then the probe (`None` for a zero-length link).
    pub links: Vec<Option<Vector3<f64>>>,
}

/// The geometry of every row of `data` under `arm`.
pub fn geometry(arm: &Arm, data: &Dataset) -> Vec<RowGeometry> {
    data.rows
        .iter()
        .map(|r| {
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
            RowGeometry { turn, lever, links }
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

/// A figure: panels under one title, written to one file.
#[derive(Clone, Debug)]
pub struct Figure {
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
type RowPoint<'a> = dyn Fn(usize, &Vector3<f64>) -> Option<(f64, f64)> + 'a;

/// Bins of a panel's x axis.
const BINS: usize = 24;

/// The figures of a diagnosis: residuals against each joint's reading, against each joint's
/// gravity lever, against temperature (when the data have a spread).
pub fn figures(d: &Diagnosis, data: &Dataset) -> Vec<Figure> {
    let arm = &d.baseline.fit.arm;
    let geo = geometry(arm, data);
    let frame = d.baseline.fit.frame;
    let before_all = missing(&d.baseline.holdout.residuals.rows, frame.as_ref(), data);
    let after_all = (!d.causes.is_empty())
        .then(|| missing(&d.extended.holdout.residuals.rows, frame.as_ref(), data));
    let judged: Vec<bool> = d
        .baseline
        .holdout
        .judged
        .iter()
        .zip(&d.extended.holdout.judged)
        .map(|(a, b)| *a && *b)
        .collect();
    let named = |e: Effect| d.causes.iter().any(|c| c.effect == e);
    let n = data.dof;
    // Each named cause's own part at every row: the extended model's held-out miss plus the
    // displacement its term makes (the extended arm with and without the term, base frame).
    let own_parts: Vec<(Effect, Vec<Vector3<f64>>)> = match &after_all {
        None => Vec::new(),
        Some(after) => d
            .causes
            .iter()
            .map(|c| {
                let ext = &d.extended.fit.arm;
                let mut without = ext.clone();
                for (p, v, _) in &c.values {
                    p.add_to(&mut without, p.value(&d.extended.fit.start) - v);
                }
                let part = data
                    .rows
                    .iter()
                    .zip(after)
                    .map(|(r, m)| {
                        m + forward::forward(ext, &r.theta, r.temp_c).p
                            - forward::forward(&without, &r.theta, r.temp_c).p
                    })
                    .collect();
                (c.effect, part)
            })
            .collect(),
    };
    let own_of = |e: Option<Effect>| -> Option<&Vec<Vector3<f64>>> {
        Some(&own_parts.iter().find(|(x, _)| Some(*x) == e)?.1)
    };
    // A panel from a per-row (x, y) function; `y` gets the miss vector and returns None to skip.
    let panel =
        |title: String, x_label: String, y_label: String, cause: Option<Effect>, f: &RowPoint| {
            let pts = |m: &[Vector3<f64>]| -> Vec<(f64, f64)> {
                (0..data.rows.len())
                    .filter(|&i| judged[i])
                    .filter_map(|i| f(i, &m[i]))
                    .collect()
            };
            let points = pts(&before_all);
            let before = binned(&points, BINS, 4);
            let after = after_all.as_ref().map(|m| binned(&pts(m), BINS, 4));
            let own = own_of(cause).map(|m| binned(&pts(m), BINS, 4));
            Panel {
                title,
                x_label,
                y_label,
                points,
                before,
                after,
                own,
                named: cause.is_some(),
            }
        };
    let mut figs = Vec::new();

    // Rows where joint k's angle can be read from the ball: its lever |t_k| at least half
    // the median and 2 % of the arm's reach (the last joint of a Panda turns the ball about
    // an axis 0.1 mm away: nothing to read). `None`: too few such rows for a panel.
    let reach = crate::sim::reach(arm);
    let cut_of = |k: usize| -> Option<f64> {
        let levers: Vec<f64> = geo.iter().map(|g| g.turn[k].norm()).collect();
        let cut = (0.5 * median(levers.clone())).max(0.02 * reach);
        let enough = levers.iter().filter(|l| **l >= cut).count() * 10 >= levers.len();
        enough.then_some(cut)
    };
    // Hinge or swivel, where the arm's frames say it (not for D–H style twisted frames).
    let plain = arm
        .joints
        .iter()
        .all(|j| j.tilt.iter().all(|t| t.abs() < 1e-3));
    let mut skipped = Vec::new();

    // Against each joint's reading.
    let mut panels = Vec::new();
    for k in 0..n {
        let Some(cut) = cut_of(k) else {
            skipped.push(k + 1);
            continue;
        };
        let kind = match (plain, arm.is_hinge(k)) {
            (false, _) => String::new(),
            (true, true) => " (hinge)".to_string(),
            (true, false) => " (swivel)".to_string(),
        };
        let harmonic = (1..=super::candidates::MAX_ORDER)
            .map(|order| Effect::Harmonic { joint: k, order })
            .find(|e| named(*e));
        panels.push(panel(
            format!("joint {}{kind}", k + 1),
            format!("joint {} reading θ{} (deg)", k + 1, k + 1),
            "apparent angle error (µrad)".into(),
            harmonic,
            &|i, m| {
                let t = geo[i].turn[k];
                let t2 = t.norm_squared();
                (t2.sqrt() >= cut && t2 > 0.0)
                    .then(|| (data.rows[i].theta[k].to_degrees(), 1e6 * t.dot(m) / t2))
            },
        ));
    }
    let mut caption =
        "An encoder harmonic shows as a wave of its order (cycles per turn)".to_string();
    if !skipped.is_empty() {
        caption += &format!(
            "; no panel for joint {}: the ball passes too close to its axis to show its angle",
            skipped
                .iter()
                .map(|k| k.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    figs.push(Figure {
        file: "residuals_vs_joint_angle.png".into(),
        title: "What the model misses, as each joint's angle error, against the joint's reading"
            .into(),
        caption,
        panels,
    });

    // Against each joint's gravity lever.
    let mut panels = Vec::new();
    for k in 0..n {
        let span = geo.iter().map(|g| g.lever[k].abs()).fold(0.0, f64::max);
        if span < 1.0 {
            continue;
        }
        let Some(cut) = cut_of(k) else { continue };
        panels.push(panel(
            format!("joint {}", k + 1),
            format!("joint {} gravity lever a·((p − o) × z) (mm)", k + 1),
            "apparent angle error (µrad)".into(),
            Some(Effect::Gravity(k)).filter(|e| named(*e)),
            &|i, m| {
                let t = geo[i].turn[k];
                let t2 = t.norm_squared();
                (t2.sqrt() >= cut && t2 > 0.0).then(|| (geo[i].lever[k], 1e6 * t.dot(m) / t2))
            },
        ));
    }
    figs.push(Figure {
        file: "residuals_vs_gravity_lever.png".into(),
        title: "What the model misses, as each joint's angle error, against its gravity lever"
            .into(),
        caption: "A gravity compliance shows as a straight line through 0 (slope g in µrad/mm)"
            .into(),
        panels,
    });

    // Against temperature.
    if d.candidates.thermal {
        let mut panels = Vec::new();
        for l in 0..=n {
            if geo.iter().all(|g| g.links[l].is_none()) {
                continue;
            }
            let (name, link) = if l == n {
                ("probe".to_string(), crate::params::Link::Probe)
            } else {
                (format!("link {}", l + 1), crate::params::Link::Joint(l))
            };
            let cause = d
                .causes
                .iter()
                .find(|c| {
                    c.effect == Effect::Thermal(link)
                        || c.indistinguishable.contains(&Effect::Thermal(link))
                })
                .map(|c| c.effect);
            panels.push(panel(
                name.clone(),
                "temperature (°C)".into(),
                format!("apparent {name} elongation (µm)"),
                cause,
                &|i, m| geo[i].links[l].map(|dir| (data.rows[i].temp_c, 1e3 * dir.dot(m))),
            ));
        }
        figs.push(Figure {
            file: "residuals_vs_temperature.png".into(),
            title: "What the model misses, as each link's elongation, against temperature".into(),
            caption: "A thermal expansion shows as a line rising with temperature (slope κ·L)"
                .into(),
            panels,
        });
    }
    figs
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
