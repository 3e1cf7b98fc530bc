//! Extrapolation: a reading far from every place the calibration saw.
//!
//! The budget's model term is estimated from held-out residuals near the calibration's
//! poses; a reading far from all of them (a new placement of the arm's work, a raised
//! artefact) has no such evidence behind it, and on MUKCa that is where the budget fails
//! (a session at a new, raised placement). Such a reading is flagged rather than silently
//! given the same U95.
//!
//! "Far" is measured where the misfit lives, in tip space: the distance from the reading's
//! tip to the nearest calibration tip (each row's model ball centre, base frame), against
//! the calibration set's own spacing — for each calibration row, the distance to the nearest
//! row of another unit of evidence (another `point` row, another `spat` point or bar end:
//! probings of one point are one place), and the spacing the 95th percentile of those. A
//! reading is far beyond [`FACTOR`] spacings: twice what the calibration's own rows are from
//! their nearest neighbour in 95 % of cases, so a reading among them is never flagged and
//! one outside their cloud by more than their own gaps is.
//!
//! On MUKCa every held-out session is far in tip space (each is a new placement of the
//! block), failing or not; what singles out the failing, raised sessions better is a new
//! *joint configuration*: [`JointSupport`], the Mahalanobis distance of the joint angles from
//! the calibration's, flagged beyond every calibration row's own (measured in
//! docs/results/uncertainty.md).

use crate::data::Dataset;
use nalgebra::Vector3;
use quatarm_ref::arm::Arm;
use quatarm_ref::uncertainty::{wrap, JointLeverage};
use serde::Serialize;

/// A reading is far beyond this many spacings.
pub const FACTOR: f64 = 2.0;

/// The calibration's tips and its spacing.
#[derive(Clone, Debug)]
pub struct Support {
    tips: Vec<Vector3<f64>>,
    /// The calibration's joint-space spread, when it has one.
    pub joints: Option<JointSupport>,
    /// The 95th percentile of each calibration row's distance to the nearest row of another
    /// unit (mm).
    pub spacing_mm: f64,
}

/// What the report says of it.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ExtrapolationReport {
    /// Calibration rows (tips) the distance is measured to.
    pub rows: usize,
    /// Their spacing (mm).
    pub spacing_mm: f64,
    /// Beyond this distance (mm) from every calibration tip a reading is flagged.
    pub threshold_mm: f64,
    /// Beyond this Mahalanobis distance from the calibration's joint angles a reading is
    /// flagged as a new configuration (`None`: no joint spread to judge by).
    pub joint_threshold: Option<f64>,
}

impl Support {
    /// The support of `data` under the calibrated `arm`; `None` with fewer than two units.
    pub fn of(arm: &Arm, data: &Dataset) -> Option<Support> {
        let mounted = crate::fit::probes::Mounted::new(arm);
        // One place per point row, spat point and bar end: probings of one place are one
        // unit, a bar's two ends two.
        let layout = data.layout();
        let mut unit = vec![usize::MAX; data.rows.len()];
        let places = layout
            .points
            .iter()
            .map(|&i| vec![i])
            .chain(layout.spat.iter().map(|g| g.rows.clone()))
            .chain(layout.length_ends().cloned())
            .chain(layout.sphere.iter().map(|g| g.rows.clone()));
        let mut count = 0;
        for (k, rows) in places.enumerate() {
            rows.iter().for_each(|&i| unit[i] = k);
            count += 1;
        }
        if count < 2 {
            return None;
        }
        let tips: Vec<Vector3<f64>> = data.rows.iter().map(|r| mounted.tip(r)).collect();
        let mut nn: Vec<f64> = (0..tips.len())
            .filter_map(|i| {
                (0..tips.len())
                    .filter(|&j| unit[j] != unit[i])
                    .map(|j| (tips[i] - tips[j]).norm())
                    .min_by(f64::total_cmp)
            })
            .collect();
        if nn.is_empty() {
            return None;
        }
        nn.sort_by(f64::total_cmp);
        let spacing_mm = nn[((nn.len() - 1) as f64 * 0.95).round() as usize];
        Some(Support {
            tips,
            spacing_mm,
            joints: JointSupport::of(data),
        })
    }

    /// Distance (mm) from `p` to the nearest calibration tip.
    pub fn distance(&self, p: &Vector3<f64>) -> f64 {
        self.tips
            .iter()
            .map(|t| (t - p).norm())
            .fold(f64::INFINITY, f64::min)
    }

    /// The distance beyond which a reading is far (mm).
    pub fn threshold_mm(&self) -> f64 {
        FACTOR * self.spacing_mm
    }

    /// Is a reading with tip `p` far from every calibration tip?
    pub fn far(&self, p: &Vector3<f64>) -> bool {
        self.distance(p) > self.threshold_mm()
    }

    /// The report's figures.
    pub fn report(&self) -> ExtrapolationReport {
        ExtrapolationReport {
            rows: self.tips.len(),
            spacing_mm: self.spacing_mm,
            threshold_mm: self.threshold_mm(),
            joint_threshold: self.joints.as_ref().map(|j| j.threshold),
        }
    }
}

/// The cheapest extrapolation check a hub could run: each joint's [min, max] over the
/// calibration's rows. Measured (not used) as the candidate for the hub's flag, which would
/// need the ranges in the table (issue 27; the table's format has no room for them today).
#[derive(Clone, Debug)]
pub struct JointRange {
    /// Per joint: (least, greatest) angle of the calibration (rad).
    pub range: Vec<(f64, f64)>,
}

impl JointRange {
    /// The ranges of `data`'s joint angles; `None` without rows.
    pub fn of(data: &Dataset) -> Option<JointRange> {
        (!data.rows.is_empty()).then(|| JointRange {
            range: (0..data.dof)
                .map(|j| {
                    data.rows
                        .iter()
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
                            (a.min(r.theta[j]), b.max(r.theta[j]))
                        })
                })
                .collect(),
        })
    }

    /// How far (rad) the farthest joint of `theta` lies outside its range (0 inside).
    pub fn excess(&self, theta: &[f64]) -> f64 {
        self.range
            .iter()
            .zip(theta)
            .map(|(&(lo, hi), &t)| (lo - t).max(t - hi).max(0.0))
            .fold(0.0, f64::max)
    }
}

/// The calibration's poses in joint space: a reading is outside when its Mahalanobis
/// distance from their mean, in their own covariance, exceeds every calibration row's.
///
/// Tip distance (above) flags every new placement of the work, near or far in what the arm
/// does; the model's error at a new placement grows with how different the *joint
/// configuration* is (a raised artefact bends the shoulder and elbow the other way), which is
/// what this measures. Rows of a joint that never moved carry no spread and are ignored.
///
/// Built on the budget's joint leverage ([`JointLeverage`], the file's `pose_joint_mean` and
/// `pose_joint_weight`): the one place the calibration's joint mean, covariance and inverse
/// are computed. The squared distance is ℓJ · k (n − 1)/n (ℓJ's normaliser, the sample
/// covariance's identity: the mean d² over the rows is k (n − 1)/n).
#[derive(Clone, Debug)]
pub struct JointSupport {
    /// ℓJ of the calibration's rows: μ and W = Σ⁻¹ · n/(k (n − 1)), zero rows and columns
    /// for the joints that did not move.
    pub leverage: JointLeverage,
    /// The joints that moved (indices into the rows' angles).
    pub moving: Vec<usize>,
    /// The rows the spread was taken over.
    pub rows: usize,
    /// k (n − 1)/n: d² = ℓJ times this.
    d2_per_ratio: f64,
    /// The largest Mahalanobis distance of a calibration row.
    pub threshold: f64,
}

/// The joint leverage of a calibration `data` (the rows' joint angles), `None` without two
/// rows or with a singular spread: what `calibrate --by-group` and `diagnose -o` write beside
/// the pose part.
pub fn joint_leverage(data: &Dataset) -> Option<JointLeverage> {
    JointSupport::of(data).map(|s| s.leverage)
}

/// The joint leverage of `data`'s rows outside `group`: what a fit without that group (a
/// held-out session) saw, against which its rows' ℓJ is scored when κ is validated.
pub fn joint_leverage_without(data: &Dataset, group: i64) -> Option<JointLeverage> {
    let others = Dataset {
        rows: data
            .rows
            .iter()
            .filter(|r| r.group != group)
            .cloned()
            .collect(),
        ..data.clone()
    };
    joint_leverage(&others)
}

impl JointSupport {
    /// The support of `data`'s joint angles; `None` without two rows or with a singular
    /// spread.
    pub fn of(data: &Dataset) -> Option<JointSupport> {
        let n = data.rows.len();
        if n < 2 {
            return None;
        }
        let dof = data.dof;
        let col = |j: usize| data.rows.iter().map(move |r| r.theta[j]);
        let moving: Vec<usize> = (0..dof)
            .filter(|&j| {
                let (lo, hi) = col(j).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                    (a.min(x), b.max(x))
                });
                hi - lo > 1e-9
            })
            .collect();
        let k = moving.len();
        if k == 0 {
            return None;
        }
        // Each joint's mean on the circle: the deviations from the circular mean direction,
        // each taken to the nearest turn, averaged — the plain mean for a joint away from
        // the ±π branch, and one that does not split a joint's spread across it (the hub's
        // angles are in [0, 2π), a data file's often in (−π, π]).
        let mean: Vec<f64> = (0..dof)
            .map(|j| {
                let (s, c) = col(j).fold((0.0, 0.0), |(s, c), t| (s + t.sin(), c + t.cos()));
                let centre = s.atan2(c);
                centre + col(j).map(|t| wrap(t - centre)).sum::<f64>() / n as f64
            })
            .collect();
        let x = |r: &crate::data::Row| {
            nalgebra::DVector::from_iterator(k, moving.iter().map(|&j| wrap(r.theta[j] - mean[j])))
        };
        let mut cov = nalgebra::DMatrix::zeros(k, k);
        for r in &data.rows {
            let d = x(r);
            cov += &d * d.transpose();
        }
        cov /= (n - 1) as f64;
        let inv = cov.try_inverse()?;
        let d2_per_ratio = k as f64 * (n - 1) as f64 / n as f64;
        let mut weight = vec![0.0; dof * dof];
        for (a, &i) in moving.iter().enumerate() {
            for (b, &j) in moving.iter().enumerate() {
                weight[i * dof + j] = 0.5 * (inv[(a, b)] + inv[(b, a)]) / d2_per_ratio;
            }
        }
        if !weight.iter().all(|w| w.is_finite()) {
            return None;
        }
        let mut s = JointSupport {
            leverage: JointLeverage { mean, weight },
            moving,
            rows: n,
            d2_per_ratio,
            threshold: 0.0,
        };
        s.threshold = data
            .rows
            .iter()
            .map(|r| s.distance(&r.theta))
            .fold(0.0, f64::max);
        Some(s)
    }

    /// Mahalanobis distance of joint angles `theta` from the calibration's.
    pub fn distance(&self, theta: &[f64]) -> f64 {
        (self.leverage.ratio(theta) * self.d2_per_ratio).sqrt()
    }

    /// Is `theta` outside every calibration row's distance?
    pub fn far(&self, theta: &[f64]) -> bool {
        self.distance(theta) > self.threshold
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::Row;

    /// A joint whose calibration angles straddle the ±π branch (a data file's (−π, π]) has
    /// its mean near π and the spread of its nearest-turn deviations: the same ℓJ for every
    /// reading as the same rows a turn on (the hub's [0, 2π)), and a mean ℓJ of 1 over them.
    #[test]
    fn a_joint_across_the_branch_has_one_spread() {
        let pi = std::f64::consts::PI;
        let data = |shift: bool| Dataset {
            rows: (0..20)
                .map(|k| {
                    let t = f64::from(k) * 0.61;
                    let mut a = pi - 0.3 + 0.5 * (t.sin() + 1.0) * 0.6; // π − 0.3 … π + 0.3
                    if !shift && a > pi {
                        a -= std::f64::consts::TAU;
                    }
                    Row::point(0, vec![a, (1.3 * t).cos()], [0.0; 3], 20.0, None)
                })
                .collect(),
            dof: 2,
            has_temperature: false,
            warnings: Vec::new(),
            source: "test".into(),
        };
        let (file, turned) = (data(false), data(true));
        let a = JointSupport::of(&file).unwrap().leverage;
        let b = JointSupport::of(&turned).unwrap().leverage;
        assert!(wrap(a.mean[0] - pi).abs() < 0.3, "{}", a.mean[0]);
        assert!(
            a.weight[0] > 1.0,
            "the joint's spread is its 0.6 rad, not 2π: {}",
            a.weight[0]
        );
        for (ra, rb) in file.rows.iter().zip(&turned.rows) {
            let (x, y) = (a.ratio(&ra.theta), b.ratio(&rb.theta));
            assert!((x - y).abs() < 1e-9 * (1.0 + x), "{x} against {y}");
            assert!((a.ratio(&rb.theta) - x).abs() < 1e-9 * (1.0 + x));
        }
        let mean = file.rows.iter().map(|r| a.ratio(&r.theta)).sum::<f64>() / 20.0;
        assert!((mean - 1.0).abs() < 1e-12, "{mean}");
    }

    /// ℓJ's contract on the rows it was estimated from: its mean over them is 1, a joint
    /// that never moved has zero rows and columns in W (its angle changes nothing) and its
    /// mean is the rows' value, and the support's distance is the plain Mahalanobis one of
    /// the moving joints in their sample covariance.
    #[test]
    fn the_joint_leverages_mean_over_its_rows_is_one() {
        let rows: Vec<Row> = (0..25)
            .map(|k| {
                let t = f64::from(k) * 0.37;
                Row::point(
                    0,
                    vec![t.sin() * 0.3, 0.8, (1.7 * t).cos() * 0.2 + 0.1 * t],
                    [0.0; 3],
                    20.0,
                    None,
                )
            })
            .collect();
        let data = Dataset {
            rows,
            dof: 3,
            has_temperature: false,
            warnings: Vec::new(),
            source: "test".into(),
        };
        let s = JointSupport::of(&data).expect("two joints moved");
        let l = &s.leverage;
        assert_eq!(s.moving, vec![0, 2]);
        assert_eq!(s.rows, 25);
        let mean = data.rows.iter().map(|r| l.ratio(&r.theta)).sum::<f64>() / 25.0;
        assert!((mean - 1.0).abs() < 1e-12, "{mean}");
        assert!((l.mean[1] - 0.8).abs() < 1e-12);
        for k in 0..3 {
            assert_eq!(l.weight[3 + k], 0.0);
            assert_eq!(l.weight[3 * k + 1], 0.0);
        }
        let th = [0.5, -3.0, 1.0];
        let mut moved = th;
        moved[1] = 2.0;
        assert_eq!(l.ratio(&th), l.ratio(&moved));
        // The direct Mahalanobis d² of joints 1 and 3 in their sample covariance.
        let x: Vec<[f64; 2]> = data.rows.iter().map(|r| [r.theta[0], r.theta[2]]).collect();
        let m = [0, 1].map(|a| x.iter().map(|v| v[a]).sum::<f64>() / 25.0);
        let c = |a: usize, b: usize| {
            x.iter().map(|v| (v[a] - m[a]) * (v[b] - m[b])).sum::<f64>() / 24.0
        };
        let det = c(0, 0) * c(1, 1) - c(0, 1) * c(0, 1);
        let d = [th[0] - m[0], th[2] - m[1]];
        let d2 =
            (c(1, 1) * d[0] * d[0] - 2.0 * c(0, 1) * d[0] * d[1] + c(0, 0) * d[1] * d[1]) / det;
        assert!((s.distance(&th).powi(2) - d2).abs() < 1e-9 * d2, "{d2}");
        assert!((l.ratio(&th) - d2 * 25.0 / (2.0 * 24.0)).abs() < 1e-9 * d2);
        // The rows outside one group: the same estimate on fewer rows.
        let mut grouped = data.clone();
        grouped.rows.iter_mut().take(5).for_each(|r| r.group = 1);
        let without = joint_leverage_without(&grouped, 1).expect("spread");
        let rest = Dataset {
            rows: data.rows[5..].to_vec(),
            ..data.clone()
        };
        assert_eq!(Some(without), joint_leverage(&rest));
        let still = Dataset {
            rows: vec![data.rows[0].clone(); 4],
            ..data.clone()
        };
        assert!(joint_leverage(&still).is_none());
    }

    /// A joint inside its calibration range has no excess; outside, its distance to the
    /// nearer end, the largest over the joints.
    #[test]
    fn the_range_excess_is_the_farthest_joints_distance_outside() {
        let row = |theta: Vec<f64>| Row::point(0, theta, [0.0; 3], 20.0, None);
        let data = Dataset {
            rows: vec![row(vec![0.0, -1.0]), row(vec![0.5, 1.0])],
            dof: 2,
            has_temperature: false,
            warnings: Vec::new(),
            source: "test".into(),
        };
        let r = JointRange::of(&data).unwrap();
        assert_eq!(r.excess(&[0.25, 0.0]), 0.0);
        assert!((r.excess(&[0.7, -1.1]) - 0.2).abs() < 1e-12);
        assert!((r.excess(&[-0.3, 1.05]) - 0.3).abs() < 1e-12);
    }
}
