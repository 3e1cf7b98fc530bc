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
use crate::effects::figure::{Figure, Named, Patterns, RowGeometry};
use crate::effects::{Effect, TipPoint, FAMILIES};
use crate::fit::probes::Mounted;
use crate::fit::residuals::Rigid;
use crate::params::ParamExt as _;
use nalgebra::Vector3;
use quatarm_ref::arm::Arm;
use quatarm_ref::forward;

/// The geometry of every row of `data` under `arm`.
pub fn geometry(arm: &Arm, data: &Dataset) -> Vec<RowGeometry> {
    let mounted = crate::fit::probes::Mounted::new(arm);
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

/// The patterns of diagnosis `d` on `data`, which the effects' figures are drawn from.
pub fn of<'a>(d: &'a Diagnosis, data: &'a Dataset) -> Patterns<'a> {
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
        arm,
        data,
        thermal: d.candidates.thermal,
        causes: d
            .causes
            .iter()
            .map(|c| Named {
                effect: c.effect,
                indistinguishable: c.indistinguishable.clone(),
            })
            .collect(),
        geo: geometry(arm, data),
        plain: arm
            .joints
            .iter()
            .all(|j| j.tilt.iter().all(|t| t.abs() < 1e-3)),
        before_all,
        after_all,
        judged,
        own_parts,
        reach: crate::geometry::reach(arm),
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
    let at = of(d, data);
    FAMILIES.iter().filter_map(|f| f.figure(&at)).collect()
}
