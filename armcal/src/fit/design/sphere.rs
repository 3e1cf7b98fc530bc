//! `sphere` data: the stylus ball touching a calibrated test sphere, as the sphere tests of
//! ISO 10360-12 (P_Size, P_Form, L_Dia) record it (`spec/acceptance-tests.md`).
//!
//! The touch points follow a golden-angle spiral over the upper hemisphere (pole to equator),
//! which spreads any number of points evenly; ISO 10360-12 asks for 25 points over at least a
//! hemisphere, which this gives. An L_Dia group is `articulations` sets of points, each set
//! probed in one arm configuration: every pose of a set starts its inverse kinematics from the
//! same random pose, so the elbow and wrist stay in one posture within a set and differ
//! between sets, as the standard's "articulations" do.

use super::groups::row;
use super::poses::{inverse, random_pose, Limits};
use crate::data::{Kind, Row, Touch};
use crate::rng::{normal, SimRng};
use nalgebra::Vector3;
use quatarm_ref::arm::Arm;
use quatarm_ref::forward;

/// One sphere test to record.
#[derive(Clone, Copy, Debug)]
pub struct Test {
    /// Touch points in the group.
    pub points: usize,
    /// The test sphere's diameter D (mm).
    pub diameter_mm: f64,
    /// Articulations (L_Dia), `None` for a plain group.
    pub articulations: Option<usize>,
    /// Probing noise per axis (mm).
    pub noise_mm: f64,
}

/// `n` unit directions spread over the upper hemisphere by a golden-angle spiral, the first
/// near the pole; `turn` rotates the pattern about the pole (radians).
pub fn directions(n: usize, turn: f64) -> Vec<Vector3<f64>> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = turn + golden * i as f64;
            Vector3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// The rows of one sphere group touched with one probe (`probe`: its id, `None` for the
/// first; `truth`: the arm as it measures with it), or `None` if no placement tried reaches
/// every touch point.
pub fn group(
    (probe, truth): (Option<u8>, &Arm),
    lim: &Limits,
    test: &Test,
    group: i64,
    temp: &mut dyn FnMut(&mut SimRng) -> f64,
    rng: &mut SimRng,
) -> Option<Vec<Row>> {
    let sets = test.articulations.unwrap_or(1).max(1);
    let per_set = test.points / sets;
    let radius = (test.diameter_mm + truth.probe.ball_diameter) / 2.0;
    'placement: for _ in 0..20 {
        let centre = forward::forward(truth, &random_pose(lim, rng), forward::REFERENCE_TEMP_C).p;
        let mut rows = Vec::with_capacity(test.points);
        for set in 0..sets {
            let count = if set + 1 == sets {
                test.points - per_set * set
            } else {
                per_set
            };
            let start = random_pose(lim, rng);
            let turn = set as f64 * 2.0 * std::f64::consts::PI / sets as f64;
            for dir in directions(count, turn) {
                let tc = temp(rng);
                let noise = Vector3::new(normal(rng), normal(rng), normal(rng)) * test.noise_mm;
                let aim = centre + dir * radius + noise;
                let Some(th) = inverse(truth, &aim, &start, tc, lim) else {
                    continue 'placement;
                };
                let mut r = row(Kind::Sphere, group, &th, None, tc);
                r.probe = probe;
                r.sphere = Some(Touch {
                    diameter_mm: test.diameter_mm,
                    articulation: test.articulations.map(|_| set as i64 + 1),
                });
                rows.push(r);
            }
        }
        return Some(rows);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_cover_the_upper_hemisphere() {
        let d = directions(25, 0.0);
        assert_eq!(d.len(), 25);
        for v in &d {
            assert!((v.norm() - 1.0).abs() < 1e-12);
            assert!(v.z > 0.0);
        }
        // From near the pole to near the equator, all around.
        assert!(d[0].z > 0.97 && d[24].z < 0.03);
        let mean: Vector3<f64> = d.iter().sum::<Vector3<f64>>() / 25.0;
        assert!(mean.x.abs() < 0.1 && mean.y.abs() < 0.1, "{mean:?}");
    }
}
