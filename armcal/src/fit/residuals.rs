//! What a model leaves unexplained in data, row by row, and its summary statistics.
//!
//! A row's residual is a 3-vector (mm): for `point` rows the model's ball centre through the
//! instrument frame minus the measured one; for `spat` rows the model's ball centre minus the
//! group's mean centre; for `length` rows the same against the mean of its end. Each `length`
//! group adds one scalar: the model's distance between the two mean centres minus the bar's
//! length. A `sphere` row's residual is radial: its distance from the group's sphere centre
//! (fitted with the known radius, (diameter + ball diameter)/2) minus that radius, along the
//! direction from the centre. These are what a metrologist reads (how far the ball is from where it should be),
//! and what diagnosis plots against joint angles, temperature and gravity levers.

use crate::data::{Dataset, Kind};
use nalgebra::{Matrix3, Vector3};
use quatarm_ref::arm::Arm;
use quatarm_ref::forward;
use serde::Serialize;

/// A rigid transform x = R p + t.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rigid {
    /// R.
    pub rot: Matrix3<f64>,
    /// t.
    pub trans: Vector3<f64>,
}

impl Rigid {
    /// The identity.
    pub fn identity() -> Rigid {
        Rigid {
            rot: Matrix3::identity(),
            trans: Vector3::zeros(),
        }
    }

    /// R p + t.
    pub fn apply(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.rot * p + self.trans
    }
}

/// The rigid transform that best maps `from` onto `to` in the least-squares sense (Kabsch):
/// the "one rigid alignment" used to compare models, and the start of an instrument frame.
/// Fewer than three points, or all on one line, give a transform that is exact on them but
/// not unique.
pub fn best_rigid(from: &[Vector3<f64>], to: &[Vector3<f64>]) -> Rigid {
    let n = from.len().min(to.len());
    if n == 0 {
        return Rigid::identity();
    }
    let cf = from[..n].iter().sum::<Vector3<f64>>() / n as f64;
    let ct = to[..n].iter().sum::<Vector3<f64>>() / n as f64;
    let mut h = Matrix3::zeros();
    for (a, b) in from[..n].iter().zip(&to[..n]) {
        h += (a - cf) * (b - ct).transpose();
    }
    let svd = h.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return Rigid {
            rot: Matrix3::identity(),
            trans: ct - cf,
        };
    };
    let mut d = Matrix3::identity();
    if (vt.transpose() * u.transpose()).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let rot = vt.transpose() * d * u.transpose();
    Rigid {
        rot,
        trans: ct - rot * cf,
    }
}

/// Residuals of a model on a data set.
#[derive(Clone, Debug)]
pub struct Residuals {
    /// One 3-vector per row (mm), in row order.
    pub rows: Vec<Vector3<f64>>,
    /// Per `length` group: (group, model distance − bar length) (mm).
    pub lengths: Vec<(i64, f64)>,
    /// The frame used for `point` rows.
    pub frame: Option<Rigid>,
}

/// Residuals of `arm` on `data`. `point` rows go through `frame`, or through the best rigid
/// frame for this arm when `None` (how an uncalibrated arm is judged fairly).
pub fn residuals(arm: &Arm, data: &Dataset, frame: Option<Rigid>) -> Residuals {
    let mounted = crate::fit::probes::Mounted::new(arm);
    let ps: Vec<Vector3<f64>> = data.rows.iter().map(|r| mounted.tip(r)).collect();
    residuals_of(&ps, data, frame, arm)
}

/// As [`residuals`], from the model's ball centres `ps` (one per row) already computed;
/// `arm` gives the stylus balls' diameters (mm) for `sphere` rows.
pub fn residuals_of(
    ps: &[Vector3<f64>],
    data: &Dataset,
    frame: Option<Rigid>,
    arm: &Arm,
) -> Residuals {
    let layout = data.layout();
    let mut rows = vec![Vector3::zeros(); data.rows.len()];
    let mut used = None;
    if !layout.points.is_empty() {
        let xs: Vec<Vector3<f64>> = layout
            .points
            .iter()
            .map(|&i| Vector3::from(data.rows[i].xyz.unwrap_or([0.0; 3])))
            .collect();
        let f = frame.unwrap_or_else(|| {
            let from: Vec<Vector3<f64>> = layout.points.iter().map(|&i| ps[i]).collect();
            best_rigid(&from, &xs)
        });
        for (k, &i) in layout.points.iter().enumerate() {
            rows[i] = f.apply(&ps[i]) - xs[k];
        }
        used = Some(f);
    }
    let mean = |idx: &[usize]| idx.iter().map(|&i| ps[i]).sum::<Vector3<f64>>() / idx.len() as f64;
    for g in &layout.spat {
        let m = mean(&g.rows);
        for &i in &g.rows {
            rows[i] = ps[i] - m;
        }
    }
    let mut lengths = Vec::new();
    for g in &layout.length {
        let (ma, mb) = (mean(&g.a), mean(&g.b));
        for &i in &g.a {
            rows[i] = ps[i] - ma;
        }
        for &i in &g.b {
            rows[i] = ps[i] - mb;
        }
        lengths.push((g.group, (ma - mb).norm() - g.length_mm));
    }
    for g in &layout.sphere {
        let q: Vec<Vector3<f64>> = g.rows.iter().map(|&i| ps[i]).collect();
        let radius = crate::fit::probes::sphere_radius(arm, data, g);
        // A group whose points fix no sphere (coplanar, too few) was refused by the loader's
        // callers; its rows keep no residual rather than an invented one.
        if let Ok(c) = crate::geometry::sphere::centre_of(&q, radius) {
            for (&i, p) in g.rows.iter().zip(&q) {
                let d = p - c;
                let dist = d.norm();
                if dist > 0.0 {
                    rows[i] = d * ((dist - radius) / dist);
                }
            }
        }
    }
    Residuals {
        rows,
        lengths,
        frame: used,
    }
}

/// RMS and maximum of a set of distances (µm in reports).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Spread {
    /// How many.
    pub n: usize,
    /// Root mean square (µm).
    pub rms_um: f64,
    /// Largest (µm).
    pub max_um: f64,
}

impl Spread {
    /// From distances in mm.
    pub fn of_mm(d: impl IntoIterator<Item = f64>) -> Spread {
        let mut n = 0;
        let mut ss = 0.0;
        let mut max: f64 = 0.0;
        for x in d {
            n += 1;
            ss += x * x;
            max = max.max(x.abs());
        }
        Spread {
            n,
            rms_um: if n > 0 {
                1e3 * (ss / n as f64).sqrt()
            } else {
                0.0
            },
            max_um: 1e3 * max,
        }
    }
}

/// Summary statistics of residuals: overall (3D distance per row), per kind, and the bar
/// length errors.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Summary {
    /// Every row's 3D residual distance.
    pub all: Spread,
    /// `point` rows.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub point: Option<Spread>,
    /// `spat` rows.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spat: Option<Spread>,
    /// `length` rows (distance from their ball's mean centre).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub length: Option<Spread>,
    /// `sphere` rows (radial distance from their sphere of known diameter).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sphere: Option<Spread>,
    /// Bar length errors, one per `length` group.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bar_length: Option<Spread>,
}

/// Summarises residuals of `data`.
pub fn summarise(res: &Residuals, data: &Dataset) -> Summary {
    let of = |kind: Kind| -> Option<Spread> {
        let d: Vec<f64> = data
            .rows
            .iter()
            .zip(&res.rows)
            .filter(|(r, _)| r.kind == kind)
            .map(|(_, v)| v.norm())
            .collect();
        (!d.is_empty()).then(|| Spread::of_mm(d))
    };
    Summary {
        all: Spread::of_mm(res.rows.iter().map(|v| v.norm())),
        point: of(Kind::Point),
        spat: of(Kind::Spat),
        length: of(Kind::Length),
        sphere: of(Kind::Sphere),
        bar_length: (!res.lengths.is_empty())
            .then(|| Spread::of_mm(res.lengths.iter().map(|l| l.1))),
    }
}

/// How far one model's ball is from another's over `poses` (at 20 °C unless given), after
/// the best rigid alignment of the first onto the second: the measure of a calibration
/// against the truth it was simulated from.
pub fn compare_aligned(model: &Arm, truth: &Arm, poses: &[(Vec<f64>, f64)]) -> Spread {
    let a: Vec<Vector3<f64>> = poses
        .iter()
        .map(|(t, c)| forward::forward(model, t, *c).p)
        .collect();
    let b: Vec<Vector3<f64>> = poses
        .iter()
        .map(|(t, c)| forward::forward(truth, t, *c).p)
        .collect();
    let f = best_rigid(&a, &b);
    Spread::of_mm(a.iter().zip(&b).map(|(p, q)| (f.apply(p) - q).norm()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    #[test]
    fn kabsch_recovers_a_transform() {
        let r = Rotation3::from_euler_angles(0.3, -1.2, 2.5).into_inner();
        let t = Vector3::new(10.0, -20.0, 30.0);
        let from: Vec<Vector3<f64>> = (0..20)
            .map(|i| {
                Vector3::new(
                    (i as f64).sin() * 100.0,
                    (i as f64 * 0.7).cos() * 50.0,
                    i as f64,
                )
            })
            .collect();
        let to: Vec<Vector3<f64>> = from.iter().map(|p| r * p + t).collect();
        let f = best_rigid(&from, &to);
        assert!((f.rot - r).norm() < 1e-12);
        assert!((f.trans - t).norm() < 1e-9);
    }
}
