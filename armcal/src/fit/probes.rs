//! Which probe each row was taken with, and the arm as it measured that row.
//!
//! An arm carries up to eight probes, one mounted at a time (the calibration file's
//! `[[probe]]`, the measured data's `probe` column). Every evaluation of the model is of one
//! mounted probe, so a row taken with the probe at index k is evaluated on
//! [`Arm::for_probe`]`(k)`: the same joints, that probe's vector, thermal term and ball. This
//! module is the one place that maps a row to its probe; the calibration, the residuals, the
//! diagnosis and the acceptance tests go through it.

use crate::data::{probe_name, DataError, Dataset, Row, SphereGroup};
use nalgebra::Vector3;
use quatarm_ref::arm::Arm;
use quatarm_ref::forward;
use std::borrow::Cow;

/// The index (in [`Arm::probes`] order) of the probe `row` was taken with: its id's, or 0
/// (the first probe) for a row without one. Rows are checked against the arm first
/// ([`check`]); an id the arm lacks counts as the first probe here.
pub fn index(arm: &Arm, row: &Row) -> usize {
    row.probe.and_then(|id| arm.probe_index(id)).unwrap_or(0)
}

/// Refuses data with a row whose probe the arm does not carry, naming the row's line and
/// the arm's probes: a probe's vector cannot be guessed.
pub fn check(arm: &Arm, data: &Dataset) -> Result<(), DataError> {
    for r in &data.rows {
        if let Some(id) = r.probe {
            if arm.probe_index(id).is_none() {
                let ids: Vec<String> = arm.probes().map(|p| p.id.to_string()).collect();
                return Err(DataError {
                    file: data.file_of(r).to_string(),
                    line: r.line,
                    column: "probe".into(),
                    message: format!(
                        "{} is not a probe of the arm (its probes: {}); add it to the \
                         calibration file as a [[probe]] with its nominal vector",
                        probe_name(Some(id)),
                        ids.join(", ")
                    ),
                });
            }
        }
    }
    Ok(())
}

/// The indices of the probes some row of `data` was taken with, ascending.
pub fn used(arm: &Arm, data: &Dataset) -> Vec<usize> {
    let mut v: Vec<usize> = data.rows.iter().map(|r| index(arm, r)).collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// The arm with each of its probes mounted, made once for many rows (a calibration's every
/// visit evaluates thousands): the first probe's is the arm itself, borrowed.
pub struct Mounted<'a> {
    arms: Vec<Cow<'a, Arm>>,
    whole: &'a Arm,
}

impl<'a> Mounted<'a> {
    /// The arm as each of its probes measures.
    pub fn new(arm: &'a Arm) -> Mounted<'a> {
        Mounted {
            arms: (0..arm.probe_count())
                .filter_map(|k| arm.for_probe(k))
                .collect(),
            whole: arm,
        }
    }

    /// The probe index `row` was taken with, and the arm as it measured the row.
    pub fn of(&self, row: &Row) -> (usize, &Arm) {
        let k = index(self.whole, row);
        (k, self.arms.get(k).map_or(self.whole, |a| a.as_ref()))
    }

    /// The model's ball centre for `row`.
    pub fn tip(&self, row: &Row) -> Vector3<f64> {
        forward::forward(self.of(row).1, &row.theta, row.temp_c).p
    }
}

/// The stylus ball diameter of the probe `row` was taken with (mm).
pub fn ball_diameter(arm: &Arm, row: &Row) -> f64 {
    arm.probe_at(index(arm, row))
        .map_or(arm.probe.ball_diameter, |p| p.ball_diameter)
}

/// The stylus ball diameter of the probe sphere group `g` of `data` was touched with (mm):
/// its first row's. A sphere is touched with one stylus ball (the data reader refuses a
/// group touched with two probes), so the first row's probe is every row's.
pub fn sphere_ball_diameter(arm: &Arm, data: &Dataset, g: &SphereGroup) -> f64 {
    ball_diameter(arm, &data.rows[g.rows[0]])
}

/// The radius (mm) of the sphere the ball centres of sphere group `g` lie on: (D + d) / 2,
/// D the sphere's diameter and d the ball's of the group's one probe
/// ([`sphere_ball_diameter`]).
pub fn sphere_radius(arm: &Arm, data: &Dataset, g: &SphereGroup) -> f64 {
    (g.diameter_mm + sphere_ball_diameter(arm, data, g)) / 2.0
}
