//! Least-squares spheres through probed centres: the free fit of P_Size and P_Form (centre and
//! radius), and the fit with a known radius of L_Dia (centre only), both minimising
//! Σ (|p_i − c| − R)² as `spec/acceptance-tests.md` writes it.
//!
//! An algebraic fit (|p|² = 2 c·p + k, linear in c and k) starts the free fit; Gauss–Newton on
//! the geometric distances finishes it, which the algebraic fit alone does not minimise.

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// Why no sphere was fitted.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FitError {
    /// Fewer points than unknowns.
    #[error("{have} points: a sphere needs {need} or more")]
    TooFew { have: usize, need: usize },
    /// The points lie in one plane (or on one line): no sphere, or every sphere, fits.
    #[error("the points are coplanar: they fix no sphere (probe over at least a hemisphere)")]
    Coplanar,
    /// Gauss–Newton did not settle.
    #[error("the sphere fit did not converge")]
    NoConvergence,
    /// A point is infinite or not a number: no fit is tried (an SVD of such points may never
    /// return, issue 27 F3).
    #[error("point {index} of the group is not finite ({x}, {y}, {z}): no sphere fitted")]
    NonFinite {
        /// 0-based index in the group.
        index: usize,
        /// Its coordinates (mm).
        x: f64,
        /// y (mm).
        y: f64,
        /// z (mm).
        z: f64,
    },
}

/// Refuses points that are not all finite, naming the first.
fn finite(points: &[Vector3<f64>]) -> Result<(), FitError> {
    match points.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
        None => Ok(()),
        Some(index) => Err(FitError::NonFinite {
            index,
            x: points[index].x,
            y: points[index].y,
            z: points[index].z,
        }),
    }
}

/// A fitted sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre (mm).
    pub centre: Vector3<f64>,
    /// Radius (mm).
    pub radius: f64,
}

/// Smallest spread across the points' best plane, relative to the largest spread, below which
/// they count as coplanar. A 25-point hemisphere is near 0.3; a cap of ±5° is near 2e-4.
const FLATNESS: f64 = 1e-9;

/// The least-squares sphere of `points` (centre and radius free).
pub fn free(points: &[Vector3<f64>]) -> Result<Sphere, FitError> {
    finite(points)?;
    if points.len() < 4 {
        return Err(FitError::TooFew {
            have: points.len(),
            need: 4,
        });
    }
    let n = points.len() as f64;
    let mean = points.iter().sum::<Vector3<f64>>() / n;
    let scatter: Matrix3<f64> = points
        .iter()
        .map(|p| (p - mean) * (p - mean).transpose())
        .sum();
    let eig = scatter.symmetric_eigenvalues();
    let (lo, hi) = (eig.min(), eig.max());
    if hi <= 0.0 || lo <= FLATNESS * hi {
        return Err(FitError::Coplanar);
    }
    // Algebraic start, about the mean for conditioning.
    let a = DMatrix::from_fn(points.len(), 4, |i, k| {
        let q = points[i] - mean;
        if k < 3 {
            2.0 * q[k]
        } else {
            1.0
        }
    });
    let b = DVector::from_fn(points.len(), |i, _| (points[i] - mean).norm_squared());
    let x = a
        .svd(true, true)
        .solve(&b, 1e-14)
        .map_err(|_| FitError::Coplanar)?;
    let c0 = Vector3::new(x[0], x[1], x[2]);
    let r0 = (x[3] + c0.norm_squared()).max(0.0).sqrt();
    let mut s = Sphere {
        centre: mean + c0,
        radius: r0,
    };
    for _ in 0..100 {
        let (mut jtj, mut jtr) = (nalgebra::Matrix4::zeros(), nalgebra::Vector4::zeros());
        for p in points {
            let d = p - s.centre;
            let dist = d.norm();
            let u = if dist > 0.0 { d / dist } else { Vector3::z() };
            let row = nalgebra::Vector4::new(-u.x, -u.y, -u.z, -1.0);
            jtj += row * row.transpose();
            jtr += row * (dist - s.radius);
        }
        let step = jtj.lu().solve(&(-jtr)).ok_or(FitError::Coplanar)?;
        s.centre += Vector3::new(step[0], step[1], step[2]);
        s.radius += step[3];
        if step.norm() < 1e-13 * (1.0 + s.radius) {
            return Ok(s);
        }
    }
    Err(FitError::NoConvergence)
}

/// The least-squares centre of `points` on a sphere of known `radius`, from `start` (a centre
/// on the right side of the points: a cap of points also fits the mirror sphere).
pub fn with_radius(
    points: &[Vector3<f64>],
    radius: f64,
    start: Vector3<f64>,
) -> Result<Vector3<f64>, FitError> {
    finite(points)?;
    if points.len() < 3 {
        return Err(FitError::TooFew {
            have: points.len(),
            need: 3,
        });
    }
    let mut c = start;
    for _ in 0..100 {
        let (mut jtj, mut jtr) = (Matrix3::zeros(), Vector3::zeros());
        for p in points {
            let d = p - c;
            let dist = d.norm();
            let u = if dist > 0.0 { d / dist } else { Vector3::z() };
            jtj += u * u.transpose();
            jtr += -u * (dist - radius);
        }
        let step = jtj.lu().solve(&(-jtr)).ok_or(FitError::Coplanar)?;
        c += step;
        if step.norm() < 1e-13 * (1.0 + radius) {
            return Ok(c);
        }
    }
    Err(FitError::NoConvergence)
}

/// The least-squares centre of `points` on a sphere of known `radius`, started from their free
/// sphere's centre (the right side of a cap): what calibration and residuals take a `sphere`
/// group's unknown centre to be.
pub fn centre_of(points: &[Vector3<f64>], radius: f64) -> Result<Vector3<f64>, FitError> {
    with_radius(points, radius, free(points)?.centre)
}

/// Distances of the points from a centre.
pub fn distances(points: &[Vector3<f64>], centre: &Vector3<f64>) -> Vec<f64> {
    points.iter().map(|p| (p - centre).norm()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_points_never_reach_a_fit() {
        let mut p = cap(Vector3::zeros(), 12.7, 80);
        p[3].y = f64::NAN;
        let e = free(&p).unwrap_err();
        assert!(matches!(e, FitError::NonFinite { index: 3, .. }), "{e}");
        p[3].y = f64::INFINITY;
        let e = with_radius(&p, 12.7, Vector3::zeros()).unwrap_err();
        assert!(matches!(e, FitError::NonFinite { index: 3, .. }), "{e}");
    }

    fn cap(centre: Vector3<f64>, r: f64, n: usize) -> Vec<Vector3<f64>> {
        crate::sim::sphere_directions(n)
            .into_iter()
            .map(|d| centre + d * r)
            .collect()
    }

    #[test]
    fn recovers_an_exact_sphere() {
        let c = Vector3::new(100.0, -50.0, 300.0);
        let s = free(&cap(c, 12.7, 25)).unwrap();
        assert!((s.centre - c).norm() < 1e-9, "{:?}", s.centre);
        assert!((s.radius - 12.7).abs() < 1e-9);
        let c2 = with_radius(&cap(c, 12.7, 5), 12.7, c + Vector3::new(0.5, 0.3, -0.2)).unwrap();
        assert!((c2 - c).norm() < 1e-9);
    }

    #[test]
    fn minimises_geometric_distances() {
        // Four points on a unit circle's sphere plus one 0.1 outside: the geometric fit
        // balances the distances (their sum of signed residuals is zero at the optimum).
        let mut p = cap(Vector3::zeros(), 1.0, 24);
        p.push(Vector3::new(0.0, 0.0, 1.1));
        let s = free(&p).unwrap();
        let sum: f64 = p.iter().map(|q| (q - s.centre).norm() - s.radius).sum();
        assert!(sum.abs() < 1e-9, "{sum}");
    }

    #[test]
    fn refuses_coplanar_and_too_few() {
        let flat: Vec<Vector3<f64>> = (0..25)
            .map(|i| {
                let a = i as f64 * 0.7;
                Vector3::new(a.cos() * 10.0, a.sin() * 10.0, 5.0)
            })
            .collect();
        assert_eq!(free(&flat), Err(FitError::Coplanar));
        assert_eq!(free(&flat[..3]), Err(FitError::TooFew { have: 3, need: 4 }));
    }
}
