//! Plots as inline SVG text for the HTML reports: no file beside the report, no font or
//! network, text the browser renders and prints sharply at any size. A plot is a set of
//! layers on one pair of axes; `equal_aspect` gives both axes the same scale (a SPAT scatter,
//! a map of positions), so that a circle is drawn as a circle.

use super::escape;
use std::fmt::Write as _;

/// What a plot draws, in data units.
#[derive(Clone, Debug)]
pub enum Layer {
    /// Dots, one colour, with a legend name.
    Points {
        /// Legend name.
        name: String,
        /// CSS colour.
        colour: &'static str,
        /// The points (data units).
        points: Vec<(f64, f64)>,
    },
    /// A polyline (an envelope, a limit).
    Line {
        /// Legend name.
        name: String,
        /// CSS colour.
        colour: &'static str,
        /// Drawn dashed.
        dashed: bool,
        /// The points (data units).
        points: Vec<(f64, f64)>,
    },
    /// A circle of a radius in data units (needs `equal_aspect`).
    Circle {
        /// Legend name.
        name: String,
        /// CSS colour.
        colour: &'static str,
        /// Drawn dashed.
        dashed: bool,
        /// Centre (data units).
        centre: (f64, f64),
        /// Radius (data units).
        radius: f64,
    },
    /// Arrows from each point by its vector (data units of the vector: `scale` maps them to
    /// the axes' units), the vector's length named in the legend.
    Arrows {
        /// Legend name.
        name: String,
        /// CSS colour.
        colour: &'static str,
        /// Where each arrow starts.
        from: Vec<(f64, f64)>,
        /// Each arrow's vector.
        vector: Vec<(f64, f64)>,
        /// Axis units per vector unit.
        scale: f64,
    },
    /// Dots coloured by a value on a diverging scale (blue − / red +), symmetric about 0.
    Coloured {
        /// Legend name.
        name: String,
        /// The points and their values (x, y, value).
        points: Vec<(f64, f64, f64)>,
    },
    /// Text labels at points.
    Labels {
        /// Each label's place and text.
        labels: Vec<(f64, f64, String)>,
    },
}

/// One plot.
#[derive(Clone, Debug)]
pub struct Plot {
    /// Title.
    pub title: String,
    /// X axis label with unit.
    pub x_label: String,
    /// Y axis label with unit.
    pub y_label: String,
    /// One unit the same length on both axes (circles stay round).
    pub equal_aspect: bool,
    /// What it draws, in order.
    pub layers: Vec<Layer>,
}

const W: f64 = 560.0;
const H: f64 = 400.0;
const LEFT: f64 = 70.0;
const RIGHT: f64 = 20.0;
const TOP: f64 = 36.0;
const BOTTOM: f64 = 96.0;

/// A "nice" tick step (1, 2 or 5 × 10^k) giving about `n` ticks over `span`.
fn tick_step(span: f64, n: f64) -> f64 {
    let raw = (span / n).max(f64::MIN_POSITIVE);
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    mag * if f < 1.5 {
        1.0
    } else if f < 3.5 {
        2.0
    } else if f < 7.5 {
        5.0
    } else {
        10.0
    }
}

/// Formats a tick without float noise.
fn tick_label(v: f64, step: f64) -> String {
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    let s = format!("{v:.decimals$}");
    // A tick at zero reached by adding steps may be −1e-17: no "-0.0".
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

/// The plot area's place on the page and the data ranges it shows: maps data units to SVG
/// pixels, so that the axes, the layers and the legend all draw with one scale.
struct Frame {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    /// The plot area's width and height (pixels).
    pw: f64,
    ph: f64,
}

impl Frame {
    /// The frame of `plot`: its extent, with one scale for both axes where it asks for
    /// equal aspect (the larger of the two, the other span widened about its middle).
    fn of(plot: &Plot) -> Frame {
        let (mut x0, mut x1, mut y0, mut y1) = plot.extent();
        let (pw, ph) = (W - LEFT - RIGHT, H - TOP - BOTTOM);
        if plot.equal_aspect {
            let s = ((x1 - x0) / pw).max((y1 - y0) / ph);
            let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
            (x0, x1) = (cx - s * pw / 2.0, cx + s * pw / 2.0);
            (y0, y1) = (cy - s * ph / 2.0, cy + s * ph / 2.0);
        }
        Frame {
            x0,
            x1,
            y0,
            y1,
            pw,
            ph,
        }
    }

    /// A data x as a pixel x.
    fn sx(&self, x: f64) -> f64 {
        LEFT + (x - self.x0) / (self.x1 - self.x0) * self.pw
    }

    /// A data y as a pixel y (down the page).
    fn sy(&self, y: f64) -> f64 {
        TOP + (self.y1 - y) / (self.y1 - self.y0) * self.ph
    }

    /// The vertical grid lines and the x ticks' labels, at round steps.
    fn x_ticks(&self, s: &mut String) {
        let xs = tick_step(self.x1 - self.x0, 6.0);
        let mut v = (self.x0 / xs).ceil() * xs;
        while v <= self.x1 {
            let _ = write!(
                s,
                r##"<line x1="{x:.1}" y1="{TOP}" x2="{x:.1}" y2="{b}" stroke="#e4e4e4"/><text x="{x:.1}" y="{ty}" text-anchor="middle">{l}</text>"##,
                x = self.sx(v),
                b = TOP + self.ph,
                ty = TOP + self.ph + 16.0,
                l = tick_label(v, xs)
            );
            v += xs;
        }
    }

    /// The horizontal grid lines and the y ticks' labels, at round steps.
    fn y_ticks(&self, s: &mut String) {
        let ys = tick_step(self.y1 - self.y0, 5.0);
        let mut v = (self.y0 / ys).ceil() * ys;
        while v <= self.y1 {
            let _ = write!(
                s,
                r##"<line x1="{LEFT}" y1="{y:.1}" x2="{r}" y2="{y:.1}" stroke="#e4e4e4"/><text x="{tx}" y="{ty:.1}" text-anchor="end">{l}</text>"##,
                y = self.sy(v),
                r = LEFT + self.pw,
                tx = LEFT - 6.0,
                ty = self.sy(v) + 4.0,
                l = tick_label(v, ys)
            );
            v += ys;
        }
    }
}

/// A legend entry: its name, its colour, and whether it is drawn as a line (else a dot).
type Entry = (String, &'static str, bool);

impl Plot {
    /// The data extent of every layer, widened a little (a zero span is widened to 1).
    fn extent(&self) -> (f64, f64, f64, f64) {
        let mut b = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        let mut add = |x: f64, y: f64| {
            if x.is_finite() && y.is_finite() {
                b = (b.0.min(x), b.1.max(x), b.2.min(y), b.3.max(y));
            }
        };
        for l in &self.layers {
            match l {
                Layer::Points { points, .. } | Layer::Line { points, .. } => {
                    points.iter().for_each(|&(x, y)| add(x, y))
                }
                Layer::Circle { centre, radius, .. } => {
                    add(centre.0 - radius, centre.1 - radius);
                    add(centre.0 + radius, centre.1 + radius);
                }
                Layer::Arrows {
                    from,
                    vector,
                    scale,
                    ..
                } => {
                    for (p, v) in from.iter().zip(vector) {
                        add(p.0, p.1);
                        add(p.0 + v.0 * scale, p.1 + v.1 * scale);
                    }
                }
                Layer::Coloured { points, .. } => points.iter().for_each(|&(x, y, _)| add(x, y)),
                Layer::Labels { labels } => labels.iter().for_each(|(x, y, _)| add(*x, *y)),
            }
        }
        if !b.0.is_finite() {
            b = (0.0, 1.0, 0.0, 1.0);
        }
        let widen = |lo: f64, hi: f64| {
            let span = if hi > lo { hi - lo } else { lo.abs().max(1.0) };
            (lo - 0.06 * span, hi + 0.06 * span)
        };
        let (x0, x1) = widen(b.0, b.1);
        let (y0, y1) = widen(b.2, b.3);
        (x0, x1, y0, y1)
    }

    /// The SVG element: the frame (title, grid, axes), the layers clipped to the plot area,
    /// then the legend below it.
    pub fn svg(&self) -> String {
        let f = Frame::of(self);
        let mut s = String::new();
        self.open(&f, &mut s);
        // Each plot's clip path has an id of its own: ids are page-wide in HTML.
        static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let id = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let (pw, ph) = (f.pw, f.ph);
        let _ = write!(
            s,
            r#"<defs><clipPath id="clip{id}"><rect x="{LEFT}" y="{TOP}" width="{pw}" height="{ph}"/></clipPath></defs><g clip-path="url(#clip{id})">"#
        );
        let legend: Vec<Entry> = self
            .layers
            .iter()
            .filter_map(|l| l.draw(&f, &mut s))
            .collect();
        s.push_str("</g>");
        draw_legend(&legend, &f, &mut s);
        s.push_str("</svg>");
        s
    }

    /// The opening tag, the title, the grid with its ticks, the plot area's border and the
    /// axes' labels.
    fn open(&self, f: &Frame, s: &mut String) {
        let _ = write!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {W} {H}" width="{W}" height="{H}" font-family="sans-serif" font-size="12" role="img"><title>{t}</title><rect width="{W}" height="{H}" fill="white"/><text x="{cx}" y="20" text-anchor="middle" font-size="14" font-weight="bold">{t}</text>"#,
            t = escape(&self.title),
            cx = W / 2.0
        );
        f.x_ticks(s);
        f.y_ticks(s);
        let (pw, ph) = (f.pw, f.ph);
        let _ = write!(
            s,
            r##"<rect x="{LEFT}" y="{TOP}" width="{pw}" height="{ph}" fill="none" stroke="#444"/><text x="{cx}" y="{xl}" text-anchor="middle">{xlab}</text><text transform="translate(16 {cy}) rotate(-90)" text-anchor="middle">{ylab}</text>"##,
            cx = LEFT + pw / 2.0,
            xl = TOP + ph + 34.0,
            cy = TOP + ph / 2.0,
            xlab = escape(&self.x_label),
            ylab = escape(&self.y_label)
        );
    }
}

impl Layer {
    /// Draws the layer into `s` and returns its legend entry (labels have none).
    fn draw(&self, f: &Frame, s: &mut String) -> Option<Entry> {
        match self {
            Layer::Points {
                name,
                colour,
                points,
            } => {
                for &(x, y) in points {
                    let _ = write!(
                        s,
                        r#"<circle cx="{:.1}" cy="{:.1}" r="3" fill="{colour}" fill-opacity="0.8"/>"#,
                        f.sx(x),
                        f.sy(y)
                    );
                }
                Some((name.clone(), colour, false))
            }
            Layer::Line {
                name,
                colour,
                dashed,
                points,
            } => {
                let d: Vec<String> = points
                    .iter()
                    .map(|&(x, y)| format!("{:.1},{:.1}", f.sx(x), f.sy(y)))
                    .collect();
                let _ = write!(
                    s,
                    r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.5"{}/>"#,
                    d.join(" "),
                    dash(*dashed)
                );
                Some((name.clone(), colour, true))
            }
            Layer::Circle {
                name,
                colour,
                dashed,
                centre,
                radius,
            } => {
                let _ = write!(
                    s,
                    r#"<circle cx="{:.1}" cy="{:.1}" r="{:.1}" fill="none" stroke="{colour}" stroke-width="1.5"{}/>"#,
                    f.sx(centre.0),
                    f.sy(centre.1),
                    radius / (f.x1 - f.x0) * f.pw,
                    dash(*dashed)
                );
                Some((name.clone(), colour, true))
            }
            Layer::Arrows {
                name,
                colour,
                from,
                vector,
                scale,
            } => {
                draw_arrows(colour, from, vector, *scale, f, s);
                Some((name.clone(), colour, true))
            }
            Layer::Coloured { name, points } => Some(draw_coloured(name, points, f, s)),
            Layer::Labels { labels } => {
                for (x, y, t) in labels {
                    let _ = write!(
                        s,
                        r#"<text x="{:.1}" y="{:.1}" dx="6" dy="-6">{}</text>"#,
                        f.sx(*x),
                        f.sy(*y),
                        escape(t)
                    );
                }
                None
            }
        }
    }
}

/// Each arrow as a line from its point to the point plus its scaled vector, a dot at the head.
fn draw_arrows(
    colour: &str,
    from: &[(f64, f64)],
    vector: &[(f64, f64)],
    scale: f64,
    f: &Frame,
    s: &mut String,
) {
    for (p, v) in from.iter().zip(vector) {
        let (a, b) = (
            (f.sx(p.0), f.sy(p.1)),
            (f.sx(p.0 + v.0 * scale), f.sy(p.1 + v.1 * scale)),
        );
        let _ = write!(
            s,
            r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{colour}" stroke-width="1.2"/><circle cx="{:.1}" cy="{:.1}" r="1.6" fill="{colour}"/>"#,
            a.0, a.1, b.0, b.1, b.0, b.1
        );
    }
}

/// Dots coloured on one diverging scale whose ends are the largest |value|; the legend
/// entry names that range.
fn draw_coloured(name: &str, points: &[(f64, f64, f64)], f: &Frame, s: &mut String) -> Entry {
    let m = points.iter().map(|p| p.2.abs()).fold(0.0f64, f64::max);
    for &(x, y, v) in points {
        let _ = write!(
            s,
            r#"<circle cx="{:.1}" cy="{:.1}" r="4" fill="{}"/>"#,
            f.sx(x),
            f.sy(y),
            diverging(v, m)
        );
    }
    (
        format!("{name}: blue −{m:.2} … red +{m:.2}"),
        "#b2182b",
        false,
    )
}

/// The legend below the plot area, two entries a row, each with its mark (a line or a dot).
fn draw_legend(legend: &[Entry], f: &Frame, s: &mut String) {
    for (i, (name, colour, line)) in legend.iter().enumerate() {
        let (col, row) = ((i % 2) as f64, (i / 2) as f64);
        let (x, y) = (LEFT + col * f.pw / 2.0, TOP + f.ph + 52.0 + row * 16.0);
        let mark = if *line {
            format!(
                r#"<line x1="{x}" y1="{y}" x2="{}" y2="{y}" stroke="{colour}" stroke-width="2"/>"#,
                x + 18.0
            )
        } else {
            format!(
                r#"<circle cx="{}" cy="{y}" r="4" fill="{colour}"/>"#,
                x + 9.0
            )
        };
        let _ = write!(
            s,
            r#"{mark}<text x="{}" y="{}">{}</text>"#,
            x + 24.0,
            y + 4.0,
            escape(name)
        );
    }
}

fn dash(dashed: bool) -> &'static str {
    if dashed {
        r#" stroke-dasharray="6 4""#
    } else {
        ""
    }
}

/// A blue–white–red colour for `v` in [−m, m].
fn diverging(v: f64, m: f64) -> String {
    let t = if m > 0.0 {
        (v / m).clamp(-1.0, 1.0)
    } else {
        0.0
    };
    let (r, g, b) = if t >= 0.0 {
        (255.0, 255.0 * (1.0 - t), 255.0 * (1.0 - t))
    } else {
        (255.0 * (1.0 + t), 255.0 * (1.0 + t), 255.0)
    };
    format!("rgb({:.0},{:.0},{:.0})", r * 0.85, g * 0.85, b * 0.85)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_text_is_escaped() {
        assert_eq!(tick_step(10.0, 5.0), 2.0);
        assert_eq!(tick_step(0.7, 6.0), 0.1);
        assert_eq!(tick_label(-0.0001, 0.1), "0.0");
        assert_eq!(tick_label(-0.5, 0.1), "-0.5");
        let p = Plot {
            title: "a <b> & \"c\"".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            equal_aspect: true,
            layers: vec![Layer::Circle {
                name: "r".into(),
                colour: "red",
                dashed: false,
                centre: (0.0, 0.0),
                radius: 1.0,
            }],
        };
        let svg = p.svg();
        assert!(svg.contains("a &lt;b&gt; &amp; &quot;c&quot;") && !svg.contains("<b>"));
        // Equal aspect: the circle's radius in pixels is the same whichever axis is longer,
        // and the whole circle is inside the plot area's height.
        let r: f64 = svg
            .split(" r=\"")
            .nth(1)
            .and_then(|t| t.split('"').next())
            .unwrap()
            .parse()
            .unwrap();
        assert!(r > 100.0 && 2.0 * r <= H - TOP - BOTTOM, "{r}");
    }
}
