//! The figures of a diagnosis (and of an acceptance check, `crate::acceptance::plots`) as PNG
//! files (plotters, bitmap backend).
//!
//! Text is drawn with a font compiled into the program (`assets/fonts/DejaVuSans-subset.ttf`,
//! DejaVu Sans cut to the characters the figures use, under its licence in the same folder)
//! through plotters' `ab_glyph` support, so the pictures come out the same on a machine with
//! no fonts installed (plotters' default `ttf` feature asks the system for them).

use crate::effects::figure::{Figure, Legend, Panel};
use plotters::prelude::*;
use plotters::style::FontStyle;
use std::path::{Path, PathBuf};
use std::sync::Once;

/// DejaVu Sans, the ASCII, Greek and a few symbols only (see `assets/fonts/README.md`).
const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans-subset.ttf");
const FAMILY: &str = "sans-serif";

/// Why a figure was not drawn.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The font compiled into the program did not load (a broken build).
    #[error("the embedded font does not load")]
    Font,
    /// The drawing backend failed on a file (plotters' own message).
    #[error("{}: {message}", .path.display())]
    Draw {
        /// The figure's file.
        path: PathBuf,
        /// What plotters said.
        message: String,
    },
    /// Its folder or file could not be staged.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
}

fn register_font() -> Result<(), PlotError> {
    static ONCE: Once = Once::new();
    let mut result = Ok(());
    ONCE.call_once(|| {
        result = plotters::style::register_font(FAMILY, FontStyle::Normal, FONT)
            .map_err(|_| PlotError::Font);
    });
    result
}

const GREY: RGBColor = RGBColor(140, 140, 140);
const GEOMETRIC: RGBColor = RGBColor(205, 35, 35);
const EXTENDED: RGBColor = RGBColor(25, 90, 210);
const OWN: RGBColor = RGBColor(20, 150, 60);
/// Most points drawn per panel (evenly thinned beyond).
const MAX_POINTS: usize = 4000;

/// Draws every figure for `dir` (created if needed) into `stage`, which puts them in place
/// when the command's other files are written too; returns the files' final paths.
pub fn write_all(
    figures: &[Figure],
    dir: &Path,
    stage: &mut crate::output::Staged,
) -> Result<Vec<PathBuf>, PlotError> {
    stage.create_dir(dir)?;
    let mut out = Vec::new();
    for f in figures {
        if f.panels.is_empty() {
            continue;
        }
        let path = dir.join(&f.file);
        let tmp = stage.path_for(&path);
        draw(f, &tmp).map_err(|e| match e {
            PlotError::Draw { message, .. } => PlotError::Draw {
                path: path.clone(),
                message,
            },
            other => other,
        })?;
        out.push(path);
    }
    Ok(out)
}

/// Draws one figure.
pub fn draw(fig: &Figure, path: &Path) -> Result<(), PlotError> {
    register_font()?;
    let n = fig.panels.len();
    let cols = if n <= 3 { n } else { n.div_ceil(2) };
    let rows = n.div_ceil(cols.max(1));
    let (w, h) = (
        (420 * cols.max(1)).max(1280) as u32,
        (130 + 330 * rows) as u32,
    );
    let root = BitMapBackend::new(path, (w, h)).into_drawing_area();
    let e = |e: &dyn std::fmt::Display| PlotError::Draw {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let (head, body) = root.split_vertically(130);
    head.draw_text(
        &fig.title,
        &(FAMILY, 26).into_font().color(&BLACK),
        (20, 14),
    )
    .map_err(|x| e(&x))?;
    head.draw_text(
        &fig.caption,
        &(FAMILY, 17).into_font().color(&BLACK),
        (20, 50),
    )
    .map_err(|x| e(&x))?;
    match fig.legend {
        Legend::Unexplained => legend_unexplained(&head, 20, 80).map_err(|x| e(&x))?,
        Legend::Models => legend(&head, 20, 80).map_err(|x| e(&x))?,
        Legend::Points => {}
    }
    let areas = body.split_evenly((rows, cols.max(1)));
    for (area, p) in areas.iter().zip(&fig.panels) {
        panel(area, p).map_err(|x| e(&x))?;
    }
    root.present().map_err(|x| e(&x))?;
    Ok(())
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;
type DrawResult =
    Result<(), DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>>;

fn legend(area: &Area, x: i32, y: i32) -> DrawResult {
    let font = (FAMILY, 16).into_font().color(&BLACK);
    // A line entry: a 28 px stroke of its colour, then its label.
    let line = |x: i32, y: i32, colour: RGBColor, label: &str| -> DrawResult {
        area.draw(&PathElement::new(
            vec![(x, y + 8), (x + 28, y + 8)],
            colour.stroke_width(3),
        ))?;
        area.draw_text(label, &font, (x + 36, y))
    };
    area.draw(&Circle::new((x + 6, y + 8), 3, GREY.mix(0.7).filled()))?;
    area.draw_text("geometric model, held-out residuals", &font, (x + 18, y))?;
    line(x + 330, y, GEOMETRIC, "their binned mean")?;
    line(
        x + 530,
        y,
        EXTENDED,
        "binned mean with the named causes (held out)",
    )?;
    line(
        x,
        y + 24,
        OWN,
        "a named cause's own part: its term's displacement plus what is left (binned mean)",
    )
}

/// The legend of [`super::unexplained::figure`]: its points are the extended model's
/// residuals and its second line the fitted pattern.
fn legend_unexplained(area: &Area, x: i32, y: i32) -> DrawResult {
    let font = (FAMILY, 16).into_font().color(&BLACK);
    area.draw(&Circle::new((x + 6, y + 8), 3, GREY.mix(0.7).filled()))?;
    area.draw_text(
        "residuals with the named causes (in sample)",
        &font,
        (x + 18, y),
    )?;
    for (dx, colour, label) in [
        (400, GEOMETRIC, "their binned mean"),
        (600, EXTENDED, "the fitted pattern (binned mean)"),
    ] {
        area.draw(&PathElement::new(
            vec![(x + dx, y + 8), (x + dx + 28, y + 8)],
            colour.stroke_width(3),
        ))?;
        area.draw_text(label, &font, (x + dx + 36, y))?;
    }
    Ok(())
}

fn panel(area: &Area, p: &Panel) -> DrawResult {
    let (x0, x1) = p
        .points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), q| {
            (a.min(q.0), b.max(q.0))
        });
    let (x0, x1) = if x1 > x0 { (x0, x1) } else { (-1.0, 1.0) };
    // The y range: the bulk of the points (2nd to 98th percentile) and every binned mean,
    // symmetric about 0 so that "no pattern" reads as a flat line in the middle.
    let mut ys: Vec<f64> = p.points.iter().map(|q| q.1.abs()).collect();
    ys.sort_by(f64::total_cmp);
    let bulk = ys.get(ys.len() * 98 / 100).copied().unwrap_or(1.0);
    let means = p
        .before
        .iter()
        .chain(p.after.iter().flatten())
        .chain(p.own.iter().flatten())
        .map(|q| q.1.abs())
        .fold(0.0, f64::max);
    let y = (bulk.max(means) * 1.15).max(1e-9);
    let title_style = if p.named {
        (FAMILY, 19).into_font().color(&OWN)
    } else {
        (FAMILY, 19).into_font().color(&BLACK)
    };
    let title = if p.named {
        format!("{} — named cause", p.title)
    } else {
        p.title.clone()
    };
    let mut chart = ChartBuilder::on(area)
        .caption(title, title_style)
        .margin(10)
        .x_label_area_size(42)
        .y_label_area_size(62)
        .build_cartesian_2d(x0..x1, -y..y)?;
    chart
        .configure_mesh()
        .x_desc(p.x_label.as_str())
        .y_desc(p.y_label.as_str())
        .label_style((FAMILY, 13))
        .axis_desc_style((FAMILY, 15))
        .light_line_style(WHITE)
        .bold_line_style(RGBColor(225, 225, 225))
        .x_labels(6)
        .y_labels(7)
        .x_label_formatter(&|v| tick(*v, x1 - x0))
        .y_label_formatter(&|v| tick(*v, 2.0 * y))
        .draw()?;
    chart.draw_series(LineSeries::new(
        vec![(x0, 0.0), (x1, 0.0)],
        BLACK.mix(0.5).stroke_width(1),
    ))?;
    let step = p.points.len().div_ceil(MAX_POINTS).max(1);
    chart.draw_series(
        p.points
            .iter()
            .step_by(step)
            .filter(|q| q.1.abs() <= y)
            .map(|&q| Circle::new(q, 2, GREY.mix(0.45).filled())),
    )?;
    chart.draw_series(LineSeries::new(
        p.before.iter().copied(),
        GEOMETRIC.stroke_width(3),
    ))?;
    if let Some(own) = &p.own {
        chart.draw_series(LineSeries::new(own.iter().copied(), OWN.stroke_width(3)))?;
    }
    if let Some(after) = &p.after {
        chart.draw_series(LineSeries::new(
            after.iter().copied(),
            EXTENDED.stroke_width(3),
        ))?;
    }
    Ok(())
}

/// A tick label with as many decimals as the axis span needs.
fn tick(v: f64, span: f64) -> String {
    let v = if v.abs() < 1e-9 * span.abs() { 0.0 } else { v };
    if span >= 20.0 {
        format!("{v:.0}")
    } else if span >= 2.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}
