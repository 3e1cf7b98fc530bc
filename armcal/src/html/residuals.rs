//! The residual plots the calibration certificate and the diagnosis report share: each row's
//! residual as a vector in µm drawn at the ball's position (from above), and residual sizes
//! before and after (a fit, a diagnosis) against the ball's reach.

use super::svg::{Layer, Plot};
use nalgebra::Vector3;

/// Residual vectors (x, y; µm) at the ball centres `at` (x, y; mm), rows where `keep` is true;
/// the arrows scaled so that the longest is a tenth of the positions' extent, the scale said
/// in the legend.
pub fn vectors(
    title: &str,
    at: &[Vector3<f64>],
    residuals_mm: &[Vector3<f64>],
    keep: &dyn Fn(usize) -> bool,
) -> (Plot, String) {
    let rows: Vec<usize> = (0..at.len().min(residuals_mm.len()))
        .filter(|&i| keep(i))
        .collect();
    let extent = {
        let (mut lo, mut hi) = (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        );
        for &i in &rows {
            lo = lo.inf(&at[i]);
            hi = hi.sup(&at[i]);
        }
        (hi - lo).xy().amax().max(1.0)
    };
    let longest_um = rows
        .iter()
        .map(|&i| residuals_mm[i].xy().norm() * 1e3)
        .fold(0.0f64, f64::max);
    let scale = if longest_um > 0.0 {
        0.1 * extent / longest_um
    } else {
        1.0
    };
    let plot = Plot {
        title: title.into(),
        x_label: "ball x (mm)".into(),
        y_label: "ball y (mm)".into(),
        equal_aspect: true,
        layers: vec![Layer::Arrows {
            name: format!(
                "residual (x, y), 1 µm drawn as {scale:.2} mm; longest {longest_um:.1} µm"
            ),
            colour: "#1f5fa8",
            from: rows.iter().map(|&i| (at[i].x, at[i].y)).collect(),
            vector: rows
                .iter()
                .map(|&i| (residuals_mm[i].x * 1e3, residuals_mm[i].y * 1e3))
                .collect(),
            scale,
        }],
    };
    let caption = format!(
        "{} rows: each row's residual (model less reference, µm) drawn from the ball's \
         position, seen from above at equal scale; a pattern (a swirl, growth with reach) is a \
         model error, scattered arrows are noise.",
        rows.len()
    );
    (plot, caption)
}

/// Residual sizes (µm) against the ball's reach from the base axis (mm): `before` in grey,
/// `after` in blue, rows where `keep` is true.
pub(crate) fn before_after(
    title: &str,
    names: (&str, &str),
    at: &[Vector3<f64>],
    before_mm: &[Vector3<f64>],
    after_mm: &[Vector3<f64>],
    keep: &dyn Fn(usize) -> bool,
) -> (Plot, String) {
    let series = |r: &[Vector3<f64>]| -> Vec<(f64, f64)> {
        (0..at.len().min(r.len()))
            .filter(|&i| keep(i))
            .map(|i| (at[i].xy().norm(), r[i].norm() * 1e3))
            .collect()
    };
    let plot = Plot {
        title: title.into(),
        x_label: "reach from the base axis (mm)".into(),
        y_label: "residual (µm)".into(),
        equal_aspect: false,
        layers: vec![
            Layer::Points {
                name: names.0.into(),
                colour: "#999",
                points: series(before_mm),
            },
            Layer::Points {
                name: names.1.into(),
                colour: "#1f5fa8",
                points: series(after_mm),
            },
        ],
    };
    (
        plot,
        "Each row's residual distance (µm) against how far the ball is from the base axis.".into(),
    )
}
