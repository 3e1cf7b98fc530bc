//! The pictures of an acceptance check (`armcal check --plots DIR`), drawn by the diagnosis'
//! figure code (`crate::diagnose::plots`):
//!
//! - `sphere_deviations.png`: each sphere group's radial deviations from its least-squares
//!   sphere (µm) against the point's azimuth about the sphere's centre: P_Form's spread, and
//!   whether it is a pattern (a lobed sphere) or noise;
//! - `length_errors.png`: each bar position's length error (µm) against its length, its
//!   height and its reach from the base axis: E_Uni by where in the volume it grows;
//! - `spat_scatter.png`: each SPAT cone's ball centres about their mean, seen from above
//!   (x and y, µm): the single-point articulation test's scatter, and its direction.
//!
//! A file is written only where the data has the groups it shows.

use crate::data::{Dataset, LengthGroup, SpatGroup, SphereGroup};
use crate::effects::figure::{Figure, Legend, Panel};
use nalgebra::Vector3;

/// A panel of measured points only.
fn panel(title: String, x_label: &str, y_label: &str, points: Vec<(f64, f64)>) -> Panel {
    Panel {
        title,
        x_label: x_label.into(),
        y_label: y_label.into(),
        points,
        before: Vec::new(),
        after: None,
        own: None,
        named: false,
    }
}

fn figure(file: &str, title: &str, caption: String, panels: Vec<Panel>) -> Option<Figure> {
    (!panels.is_empty()).then(|| Figure {
        legend: Legend::Points,
        file: file.into(),
        title: title.into(),
        caption,
        panels,
    })
}

/// A bar position: its length (mm), its middle (mm) and its length error (µm).
struct Bar {
    length_mm: f64,
    middle: Vector3<f64>,
    error_um: f64,
}

/// Each point of a cone about the cone's mean, seen from above: (x, y) in µm, the SPAT
/// scatter this module's `spat_scatter.png` and the HTML report both draw.
pub(crate) fn from_above_um(rows: &[usize], centres: &[Vector3<f64>]) -> Vec<(f64, f64)> {
    let m = super::mean_of(rows, centres);
    rows.iter()
        .map(|&i| ((centres[i].x - m.x) * 1e3, (centres[i].y - m.y) * 1e3))
        .collect()
}

/// A point's place on a least-squares sphere and its distance from it.
pub(crate) struct Deviation {
    /// Azimuth about the sphere's centre (°).
    pub azimuth_deg: f64,
    /// Elevation from the centre's horizontal plane (°).
    pub elevation_deg: f64,
    /// Distance from the centre less the radius (µm): P_Form is their range.
    pub radial_um: f64,
}

/// Each point's [`Deviation`] from the free least-squares sphere through `points` (`None`
/// where no sphere fits): what both the PNG and the HTML report of a sphere group show.
pub(crate) fn sphere_deviations(points: &[Vector3<f64>]) -> Option<Vec<Deviation>> {
    let s = crate::geometry::sphere::free(points).ok()?;
    let each = points
        .iter()
        .map(|p| {
            let v = p - s.centre;
            Deviation {
                azimuth_deg: v.y.atan2(v.x).to_degrees(),
                elevation_deg: (v.z / v.norm()).clamp(-1.0, 1.0).asin().to_degrees(),
                radial_um: (v.norm() - s.radius) * 1e3,
            }
        })
        .collect();
    Some(each)
}

/// The figures for `data`, its ball centres `centres` by the calibrated model: each only
/// where the data has its groups.
pub fn figures(data: &Dataset, centres: &[Vector3<f64>]) -> Vec<Figure> {
    let layout = data.layout();
    [
        sphere_figure(&layout.sphere, centres),
        length_figure(&layout.length, centres),
        spat_figure(&layout.spat, centres),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// `sphere_deviations.png`: a panel a sphere group that a sphere fits.
fn sphere_figure(groups: &[SphereGroup], centres: &[Vector3<f64>]) -> Option<Figure> {
    let spheres: Vec<Panel> = groups
        .iter()
        .filter_map(|g| {
            let pts: Vec<Vector3<f64>> = g.rows.iter().map(|&i| centres[i]).collect();
            let points = sphere_deviations(&pts)?
                .iter()
                .map(|d| (d.azimuth_deg, d.radial_um))
                .collect();
            Some(panel(
                format!("sphere group {} (D = {} mm)", g.group, g.diameter_mm),
                "azimuth about the centre (°)",
                "radial deviation (µm)",
                points,
            ))
        })
        .collect();
    figure(
        "sphere_deviations.png",
        "Sphere tests: radial deviations from the least-squares sphere",
        "Each point's distance from its group's fitted centre less the fitted radius (P_Form is their range)".into(),
        spheres,
    )
}

/// `length_errors.png`: every bar position's error against its length, height and reach.
fn length_figure(groups: &[LengthGroup], centres: &[Vector3<f64>]) -> Option<Figure> {
    let bars: Vec<Bar> = groups
        .iter()
        .map(|g| {
            let (a, b) = (super::mean_of(&g.a, centres), super::mean_of(&g.b, centres));
            Bar {
                length_mm: g.length_mm,
                middle: 0.5 * (a + b),
                error_um: ((a - b).norm() - g.length_mm) * 1e3,
            }
        })
        .collect();
    let by = |f: &dyn Fn(&Bar) -> f64| bars.iter().map(|b| (f(b), b.error_um)).collect::<Vec<_>>();
    let panels = if bars.is_empty() {
        Vec::new()
    } else {
        vec![
            panel(
                "against length".into(),
                "bar length (mm)",
                "length error (µm)",
                by(&|b| b.length_mm),
            ),
            panel(
                "against height".into(),
                "height of the bar's middle (mm)",
                "length error (µm)",
                by(&|b| b.middle.z),
            ),
            panel(
                "against reach".into(),
                "reach of the bar's middle from the base axis (mm)",
                "length error (µm)",
                by(&|b| b.middle.xy().norm()),
            ),
        ]
    };
    figure(
        "length_errors.png",
        "Length tests: each bar position's error",
        format!(
            "{} bar positions: measured distance of the ball centres less the bar's length",
            bars.len()
        ),
        panels,
    )
}

/// `spat_scatter.png`: a panel a SPAT cone.
fn spat_figure(groups: &[SpatGroup], centres: &[Vector3<f64>]) -> Option<Figure> {
    let cones: Vec<Panel> = groups
        .iter()
        .map(|g| {
            panel(
                format!("SPAT cone {}", g.group),
                "x from the mean (µm)",
                "y from the mean (µm)",
                from_above_um(&g.rows, centres),
            )
        })
        .collect();
    figure(
        "spat_scatter.png",
        "Single-point articulation: ball centres about each cone's mean, from above",
        "Each articulation's ball centre less the cone's mean position (x, y)".into(),
        cones,
    )
}
