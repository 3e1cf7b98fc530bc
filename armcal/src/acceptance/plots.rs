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

use crate::data::Dataset;
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

/// The figures for `data`, its ball centres `centres` by the calibrated model.
pub fn figures(data: &Dataset, centres: &[Vector3<f64>]) -> Vec<Figure> {
    let layout = data.layout();
    let mut out = Vec::new();
    let spheres: Vec<Panel> = layout
        .sphere
        .iter()
        .filter_map(|g| {
            let pts: Vec<Vector3<f64>> = g.rows.iter().map(|&i| centres[i]).collect();
            let s = crate::geometry::sphere::free(&pts).ok()?;
            let points = pts
                .iter()
                .map(|p| {
                    let d = p - s.centre;
                    (d.y.atan2(d.x).to_degrees(), (d.norm() - s.radius) * 1e3)
                })
                .collect();
            Some(panel(
                format!("sphere group {} (D = {} mm)", g.group, g.diameter_mm),
                "azimuth about the centre (°)",
                "radial deviation (µm)",
                points,
            ))
        })
        .collect();
    out.extend(figure(
        "sphere_deviations.png",
        "Sphere tests: radial deviations from the least-squares sphere",
        "Each point's distance from its group's fitted centre less the fitted radius (P_Form is their range)".into(),
        spheres,
    ));
    let bars: Vec<Bar> = layout
        .length
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
    if !bars.is_empty() {
        let by =
            |f: &dyn Fn(&Bar) -> f64| bars.iter().map(|b| (f(b), b.error_um)).collect::<Vec<_>>();
        let panels = vec![
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
        ];
        out.extend(figure(
            "length_errors.png",
            "Length tests: each bar position's error",
            format!(
                "{} bar positions: measured distance of the ball centres less the bar's length",
                bars.len()
            ),
            panels,
        ));
    }
    let cones: Vec<Panel> = layout
        .spat
        .iter()
        .map(|g| {
            let m = super::mean_of(&g.rows, centres);
            let points = g
                .rows
                .iter()
                .map(|&i| ((centres[i].x - m.x) * 1e3, (centres[i].y - m.y) * 1e3))
                .collect();
            panel(
                format!("SPAT cone {}", g.group),
                "x from the mean (µm)",
                "y from the mean (µm)",
                points,
            )
        })
        .collect();
    out.extend(figure(
        "spat_scatter.png",
        "Single-point articulation: ball centres about each cone's mean, from above",
        "Each articulation's ball centre less the cone's mean position (x, y)".into(),
        cones,
    ));
    out
}
