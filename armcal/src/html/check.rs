//! The test report of `armcal check --report FILE.html`: the header, the verdict, every value
//! with its U and decision, and the plots a metrologist reads an acceptance test by.

use super::svg::{Layer, Plot};
use super::{header::Provenance, Cell, Document, Tone};
use crate::acceptance::mpe::{Decision, Limit, Mpe};
use crate::acceptance::plots::{from_above_um, sphere_deviations};
use crate::acceptance::statistics::{self, Test};
use crate::acceptance::verdict::Outcome;
use crate::acceptance::Check;
use crate::data::{Dataset, SpatGroup, SphereGroup};
use nalgebra::Vector3;
use quatarm_ref::arm::Arm;

/// The page.
pub fn page(c: &Check, arm: &Arm, data: &Dataset, mpe: Option<&Mpe>, prov: &Provenance) -> String {
    let tone = match c.verdict.outcome {
        Outcome::Conforms => Tone::Good,
        Outcome::DoesNotConform => Tone::Bad,
        Outcome::CannotDecide => Tone::Unsure,
        Outcome::NotAsked => Tone::Plain,
    };
    let headline = format!(
        "Verdict: {} (exit {})",
        c.verdict.outcome.name().to_uppercase(),
        c.verdict.exit_code
    );
    let mut d = Document::opening(
        "Acceptance test report (ISO 10360-12, ASME B89.4.22)",
        prov,
        (&headline, &c.verdict.line(), tone),
        &[],
    );
    d.heading("Values");
    let rows = c
        .tests
        .iter()
        .map(|r| {
            let decision = match r.decision {
                Some(Decision::Pass) => Cell("pass".into(), Tone::Good),
                Some(Decision::Fail) => Cell("fail".into(), Tone::Bad),
                Some(Decision::CannotDecide) => Cell("cannot decide".into(), Tone::Unsure),
                None => "no MPE".into(),
            };
            let predicted = match (r.predicted_um, r.outside_predicted) {
                (Some(p), Some(true)) => Cell(
                    format!("{:.2} [{:.2}, {:.2}] OUTSIDE", p.mean, p.lo, p.hi),
                    Tone::Unsure,
                ),
                (Some(p), _) => format!("{:.2} [{:.2}, {:.2}]", p.mean, p.lo, p.hi).into(),
                (None, _) => "-".into(),
            };
            vec![
                r.test.key().into(),
                r.group.to_string().into(),
                r.length_mm.map_or("-".into(), |l| format!("{l:.1}")).into(),
                format!("{:.2}", r.value_um).into(),
                format!("{:.2}", r.u_um).into(),
                r.u_source.words().into(),
                r.mpe_um.map_or("-".into(), |m| format!("{m:.2}")).into(),
                decision,
                predicted,
            ]
        })
        .collect();
    d.table(
        &[
            "test",
            "group",
            "bar length mm",
            "value µm",
            "U µm (k = 2)",
            "U from",
            "MPE µm",
            "decision",
            "predicted µm, mean [95 %]",
        ],
        rows,
    );
    if let Some(each) = c.effective_ball_list() {
        d.paragraph(&format!(
            "Effective stylus ball diameter (ASME B89.4.22): {each}; the calibration file says {} mm.",
            c.ball_diameter_mm
        ));
    }
    d.heading("Plots");
    d.figures(&plots(c, arm, data, mpe));
    d.finish()
}

const BLUE: &str = "#1f5fa8";
const RED: &str = "#c0392b";
const GREY: &str = "#777";

/// The plots, in the order a metrologist reads them: E_Uni against length, each SPAT cone,
/// then each sphere group (L_Dia's centres where articulated, else the deviations).
fn plots(c: &Check, arm: &Arm, data: &Dataset, mpe: Option<&Mpe>) -> Vec<(Plot, String)> {
    let centres = crate::acceptance::centres(arm, data);
    let layout = data.layout();
    let limit = |t: Test| mpe.and_then(|m| m.limit(t));
    let mut out = Vec::new();
    out.extend(length_plot(c, limit(Test::EUni)));
    for g in &layout.spat {
        out.push(spat_plot(g, &centres, limit(Test::SpatMax)));
    }
    for g in &layout.sphere {
        let articulated = data.rows[g.rows[0]]
            .sphere
            .and_then(|t| t.articulation)
            .is_some();
        let plot = if articulated {
            articulation_plot(arm, data, g, &centres, limit(Test::LDia))
        } else {
            deviation_plot(g, &centres)
        };
        out.extend(plot);
    }
    out
}

/// E_Uni against length, with the MPE envelope (`None`: no length test in the data).
fn length_plot(c: &Check, limit: Option<Limit>) -> Option<(Plot, String)> {
    let bars: Vec<(f64, f64)> = c
        .tests
        .iter()
        .filter(|r| r.test == Test::EUni)
        .filter_map(|r| r.length_mm.map(|l| (l, r.value_um)))
        .collect();
    if bars.is_empty() {
        return None;
    }
    let mut layers = vec![Layer::Points {
        name: "E_Uni of a bar position".into(),
        colour: BLUE,
        points: bars.clone(),
    }];
    if let Some(l) = limit {
        let top = bars.iter().map(|b| b.0).fold(0.0f64, f64::max) * 1.1;
        let xs: Vec<f64> = (0..=20).map(|i| top * i as f64 / 20.0).collect();
        for (sign, name) in [(1.0, "+MPE(L)"), (-1.0, "−MPE(L)")] {
            layers.push(Layer::Line {
                name: name.into(),
                colour: RED,
                dashed: false,
                points: xs
                    .iter()
                    .map(|&x| (x, sign * l.at(Some(x)) * 1e3))
                    .collect(),
            });
        }
    }
    Some((
        Plot {
            title: "Length error E_Uni against bar length".into(),
            x_label: "bar length (mm)".into(),
            y_label: "E_Uni (µm)".into(),
            equal_aspect: false,
            layers,
        },
        "Each bar position's measured length less the bar's calibrated length; red: the \
         MPE envelope of the MPE file."
            .into(),
    ))
}

/// An MPE drawn about the origin of a scatter about its mean: a solid red circle of
/// `radius_um`.
fn mpe_circle(name: String, radius_um: f64) -> Layer {
    Layer::Circle {
        name,
        colour: RED,
        dashed: false,
        centre: (0.0, 0.0),
        radius: radius_um,
    }
}

/// A SPAT cone's centres about their mean, equal aspect, with δ_max and the MPE circle.
fn spat_plot(g: &SpatGroup, centres: &[Vector3<f64>], limit: Option<Limit>) -> (Plot, String) {
    let p: Vec<Vector3<f64>> = g.rows.iter().map(|&i| centres[i]).collect();
    let (dmax, _) = statistics::spat(&p);
    let mut layers = vec![
        Layer::Points {
            name: "ball centre − mean (x, y)".into(),
            colour: BLUE,
            points: from_above_um(&g.rows, centres),
        },
        Layer::Circle {
            name: format!("δ_max = {:.2} µm", dmax * 1e3),
            colour: GREY,
            dashed: true,
            centre: (0.0, 0.0),
            radius: dmax * 1e3,
        },
    ];
    if let Some(l) = limit {
        layers.push(mpe_circle(
            format!("MPE SPAT_max = {:.2} µm", l.at(None) * 1e3),
            l.at(None) * 1e3,
        ));
    }
    (
        Plot {
            title: format!("SPAT cone {}: centres from above", g.group),
            x_label: "x from the mean (µm)".into(),
            y_label: "y from the mean (µm)".into(),
            equal_aspect: true,
            layers,
        },
        "Each articulation's ball centre less the cone's mean, x and y at equal scale; \
         δ_max is the largest 3D distance, so every point lies inside its circle."
            .into(),
    )
}

/// An articulated sphere group: each articulation's sphere centre about their mean, with
/// the L_Dia circle (`None` where the centres cannot be fitted).
fn articulation_plot(
    arm: &Arm,
    data: &Dataset,
    g: &SphereGroup,
    centres: &[Vector3<f64>],
    limit: Option<Limit>,
) -> Option<(Plot, String)> {
    let ball = crate::fit::probes::sphere_ball_diameter(arm, data, g);
    let cs = statistics::articulation_centres(data, g, centres, ball).ok()?;
    let mean = cs.iter().map(|c| c.1).sum::<Vector3<f64>>() / cs.len() as f64;
    let xy: Vec<(f64, f64)> = cs
        .iter()
        .map(|(_, c)| ((c.x - mean.x) * 1e3, (c.y - mean.y) * 1e3))
        .collect();
    let mut layers = vec![
        Layer::Points {
            name: "articulation's centre − mean (x, y)".into(),
            colour: BLUE,
            points: xy.clone(),
        },
        Layer::Labels {
            labels: cs
                .iter()
                .zip(&xy)
                .map(|((a, _), &(x, y))| (x, y, format!("art. {a}")))
                .collect(),
        },
    ];
    if let Some(l) = limit {
        layers.push(mpe_circle(
            format!("diameter MPE L_Dia = {:.2} µm", l.at(None) * 1e3),
            l.at(None) * 1e3 / 2.0,
        ));
    }
    Some((
        Plot {
            title: format!("L_Dia, sphere group {}: centre by articulation", g.group),
            x_label: "x from the mean (µm)".into(),
            y_label: "y from the mean (µm)".into(),
            equal_aspect: true,
            layers,
        },
        "Each articulation's sphere centre (radius fixed at (D + d)/2) less their \
         mean, from above; L_Dia is the largest distance between two of them."
            .into(),
    ))
}

/// A plain sphere group's radial deviations over the sphere (azimuth, elevation), coloured
/// (`None` where no sphere fits).
fn deviation_plot(g: &SphereGroup, centres: &[Vector3<f64>]) -> Option<(Plot, String)> {
    let p: Vec<Vector3<f64>> = g.rows.iter().map(|&i| centres[i]).collect();
    let points = sphere_deviations(&p)?
        .iter()
        .map(|d| (d.azimuth_deg, d.elevation_deg, d.radial_um))
        .collect();
    Some((
        Plot {
            title: format!("Sphere group {}: deviations over the sphere", g.group),
            x_label: "azimuth about the centre (°)".into(),
            y_label: "elevation (°)".into(),
            equal_aspect: false,
            layers: vec![Layer::Coloured {
                name: "radial deviation (µm)".into(),
                points,
            }],
        },
        format!(
            "Each point where it touched the sphere (D = {} mm), coloured by its distance \
             from the least-squares sphere less its radius: P_Form is their range.",
            g.diameter_mm
        ),
    ))
}
