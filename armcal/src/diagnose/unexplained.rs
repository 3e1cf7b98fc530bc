//! What the named causes leave: a search of the extended model's residuals for structure
//! against every variable the data have, reported as unexplained, without naming a cause.
//!
//! The vocabulary can only name what it holds; an effect outside it (a link sagging under its
//! own weight, a bearing's wobble, a drift of the instrument) leaves structure that no
//! candidate removes. Each variable of the data gets a small regression of the residuals on a
//! basis of that variable, and a partial F-test:
//! - `joint:K` — the apparent angle error of joint K against its reading: for every order h up
//!   to what the readings resolve ([`crate::effects::harmonic::resolvable_order`]) the columns
//!   t_K sin hθ_K, t_K cos hθ_K (t_K = a_K × (p − o_K)); one test per order;
//! - `lever:K` — a displacement (3 components) quadratic in joint K's gravity lever
//!   a_K · ((p − o_K) × ẑ) (what [`super::patterns`] calls the lever);
//! - `link:K` — a displacement against link K's elevation above the horizontal ε (sin ε,
//!   cos ε, sin 2ε, cos 2ε): what a link bending under its own weight leaves. Collinear links
//!   share their elevation and are one test (`link:2+3`);
//! - `temperature` — a displacement quadratic in the temperature (with a spread of at least
//!   [`super::candidates::MIN_TEMP_SPREAD_C`]);
//! - `session` — a displacement per group of `point` rows (with two groups or more);
//! - `time` — a displacement against the row's place in the file (cos πjt, j = 1…4): drift.
//!
//! The residuals are the extended model's own (in sample, base frame): the fit has already
//! taken out what its parameters can, so what a test finds is structure the model cannot
//! hold. Under no structure, the explained sum of squares of residuals already projected off
//! the fit's columns is at most that of pure noise, so the F-test (denominator degrees of
//! freedom 3n − fitted unknowns − group centrings − test columns) is conservative. Every
//! test of every variable is one family: Holm's step-down at level `alpha` (default
//! [`ALPHA`], the selection's in-sample level), and the p reported is Holm-adjusted.

use super::patterns::{geometry, missing};
use super::Model;
use crate::data::{Dataset, Kind};
use crate::effects::figure::{binned, Figure, Panel, RowGeometry};
use crate::effects::TipPoint;
use crate::fit::jacobian::tip_jacobian;
use crate::fit::probes::Mounted;
use crate::fit::residuals::residuals;
use crate::params::{Param, ParamExt};
use crate::stats::f_tail;
use nalgebra::{DMatrix, DVector, Vector3};
use quatarm_ref::forward;
use serde::Serialize;

/// Default family-wise level of the search.
pub const ALPHA: f64 = 1e-3;

/// Most panels in the figure (the most significant structures).
const MAX_PANELS: usize = 6;

/// Two links whose elevations differ by less than this on every row are one variable (rad).
const TWIN_ELEVATION_RAD: f64 = 0.01;

/// The figure's file.
pub const FILE: &str = "residuals_unexplained.png";

/// Bins of a panel's binned mean.
const BINS: usize = 24;

/// Significant structure in the residuals.
#[derive(Clone, Debug, Serialize)]
pub struct Structure {
    /// The variable: `joint:K`, `lever:K`, `link:K` (1-based), `temperature`, `session`,
    /// `time`.
    pub variable: String,
    /// Its shape in words.
    pub pattern: String,
    /// RMS over the rows of the displacement the fitted pattern makes (µm).
    pub rms_um: f64,
    /// Holm-adjusted p of its F-test.
    pub p: f64,
    /// The F statistic.
    pub f: f64,
    /// Its degrees of freedom (test columns, residual).
    pub df: (usize, usize),
    /// The residual against the variable, for the figure: (x, y) per row.
    #[serde(skip)]
    pub points: Vec<(f64, f64)>,
    /// The fitted pattern at each row, same axes.
    #[serde(skip)]
    pub fitted: Vec<(f64, f64)>,
    /// X axis label.
    #[serde(skip)]
    pub x_label: String,
    /// Y axis label.
    #[serde(skip)]
    pub y_label: String,
}

/// The search's record.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Search {
    /// Tests made (the Holm family).
    pub tests: usize,
    /// Family-wise level.
    pub alpha: f64,
    /// The variables tested, each once.
    pub variables: Vec<String>,
    /// Named causes that the strongest structure explains as well: they may stand in for it
    /// (the report lists them apart, as `doubtful`).
    #[serde(skip)]
    pub doubtful: Vec<Doubt>,
    /// Significant structures, most significant first (the report lists them apart, as
    /// `unexplained`).
    #[serde(skip)]
    pub found: Vec<Structure>,
}

/// A named cause that may be a partial stand-in for unexplained structure: with the
/// structure's columns in the regression, the cause's own columns no longer explain its part
/// of the residuals (partial F-test at the search's level, Bonferroni over the causes).
#[derive(Clone, Debug, Serialize)]
pub struct Doubt {
    /// The cause, as `--terms` spells it.
    pub cause: String,
    /// The structure's variable.
    pub stand_in_for: String,
    /// p of the cause's columns given the structure's (Bonferroni over the causes).
    pub p: f64,
}

/// How a test's columns move the ball.
enum Form {
    /// Along joint k's turn t_k: the pattern is an angle (reported in µrad).
    Angle(usize),
    /// Any direction: one column per basis function and axis.
    Displacement,
}

/// One test before its verdict.
struct Test {
    variable: String,
    /// Short name of the basis, for the pattern's words.
    basis: String,
    form: Form,
    /// The variable's value per row (for the figure), and its label.
    x: Vec<f64>,
    x_label: String,
    /// Basis functions per row: `basis[b][i]`.
    functions: Vec<Vec<f64>>,
}

/// A test's regression.
struct Fitted {
    f: f64,
    p: f64,
    df: (usize, usize),
    ss: f64,
    beta: DVector<f64>,
    /// Fitted displacement per row (mm).
    pattern: Vec<Vector3<f64>>,
}

/// Searches the residuals of `model` on `data` at family-wise level `alpha`.
pub fn search(model: &Model, data: &Dataset, alpha: f64) -> Search {
    let n = data.rows.len();
    let fit = &model.fit;
    let res = residuals(&fit.arm, data, fit.frame);
    let miss = missing(&res.rows, fit.frame.as_ref(), data);
    let geo = geometry(&fit.arm, data);
    let layout = data.layout();
    let held = fit.params.len()
        + 3 * layout.spat.len()
        + 6 * layout.length.len()
        + 3 * layout.sphere.len();
    let tests = tests(model, data, &geo);
    let mut variables: Vec<String> = Vec::new();
    for t in &tests {
        if !variables.contains(&t.variable) {
            variables.push(t.variable.clone());
        }
    }
    let fitted: Vec<Option<Fitted>> = tests
        .iter()
        .map(|t| regress(t, &miss, &geo, held))
        .collect();
    let m = fitted.len();
    // Holm's step-down: the i-th smallest p (0-based) times (m − i), kept monotone.
    let mut order: Vec<usize> = (0..m).collect();
    let p_of = |i: usize| fitted[i].as_ref().map_or(1.0, |f| f.p);
    order.sort_by(|a, b| p_of(*a).total_cmp(&p_of(*b)));
    let mut adjusted = vec![1.0; m];
    let mut running: f64 = 0.0;
    for (rank, &i) in order.iter().enumerate() {
        running = running.max(((m - rank) as f64 * p_of(i)).min(1.0));
        adjusted[i] = running;
    }
    let mut found: Vec<Structure> = order
        .iter()
        .filter(|&&i| adjusted[i] <= alpha)
        .filter_map(|&i| {
            let f = fitted[i].as_ref()?;
            Some(structure(&tests[i], f, adjusted[i], &miss, &geo, n))
        })
        .collect();
    found.sort_by(|a, b| a.p.total_cmp(&b.p).then(b.f.total_cmp(&a.f)));
    let strongest = order
        .iter()
        .find(|&&i| adjusted[i] <= alpha && fitted[i].is_some())
        .map(|&i| &tests[i]);
    let doubtful = match strongest {
        Some(t) => doubts(model, data, &miss, &geo, held - fit.params.len(), t, alpha),
        None => Vec::new(),
    };
    Search {
        tests: m,
        alpha,
        variables,
        doubtful,
        found,
    }
}

/// The named causes of `model` that the structure of test `s` explains as well: for each, the
/// residuals plus its own part (the extended arm with and without its term) regressed on the
/// structure's columns and the fit's other unknowns (linearised at the fit: what the geometry
/// absorbed of the structure is allowed back), then on those and the cause's; the cause is
/// doubtful when its columns add nothing significant (p > `alpha` / causes). `centrings`:
/// degrees of freedom the spat and length groups' centring takes.
fn doubts(
    model: &Model,
    data: &Dataset,
    miss: &[Vector3<f64>],
    geo: &[RowGeometry],
    centrings: usize,
    s: &Test,
    alpha: f64,
) -> Vec<Doubt> {
    let fit = &model.fit;
    let n = data.rows.len();
    let causes = model.effects.len().max(1) as f64;
    let mut out = Vec::new();
    let with = Mounted::new(&fit.arm);
    for e in &model.effects {
        let mut without = fit.arm.clone();
        for p in e.params() {
            p.add_to(&mut without, p.value(&fit.start) - p.value(&fit.arm));
        }
        let mut y = Vec::with_capacity(n);
        let mut own: Vec<Vec<Vector3<f64>>> = Vec::with_capacity(n);
        let without = Mounted::new(&without);
        for (i, r) in data.rows.iter().enumerate() {
            let (probe, arm) = with.of(r);
            let chain = forward::evaluate(arm, &r.theta, r.temp_c);
            let part = chain.p - without.tip(r);
            y.push(miss[i] + part);
            let at = TipPoint {
                arm,
                probe,
                chain: &chain,
                theta: &r.theta,
                temp_c: r.temp_c,
            };
            own.push(e.with(|t| (0..t.coefficients()).map(|c| t.column(c, &at)).collect()));
        }
        // Nuisance columns: the structure's, the fit's other unknowns (geometry and the
        // other causes, ∂p by [`tip_jacobian`]) and, for point rows, the instrument frame's.
        let own_params = e.params();
        let others: Vec<Param> = fit
            .ident
            .kept
            .iter()
            .map(|&k| fit.params[k])
            .filter(|p| !own_params.contains(p))
            .collect();
        let base: Vec<Vec<Vector3<f64>>> = data
            .rows
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let mut c = columns(s, i, geo);
                let mut g = vec![Vector3::zeros(); others.len()];
                let (probe, arm) = with.of(r);
                let p = tip_jacobian(arm, probe, &others, &r.theta, r.temp_c, &mut g);
                c.extend(g);
                let point = r.kind == Kind::Point;
                for ax in [Vector3::x(), Vector3::y(), Vector3::z()] {
                    c.push(if point { ax } else { Vector3::zeros() });
                    c.push(if point {
                        ax.cross(&p)
                    } else {
                        Vector3::zeros()
                    });
                }
                c
            })
            .collect();
        let both: Vec<Vec<Vector3<f64>>> = base
            .iter()
            .zip(&own)
            .map(|(a, b)| a.iter().chain(b).copied().collect())
            .collect();
        let (Some(a), Some(b)) = (least_squares(&base, &y), least_squares(&both, &y)) else {
            continue;
        };
        let Some(d2) = (3 * n).checked_sub(centrings + b.rank).filter(|d| *d > 0) else {
            continue;
        };
        let d1 = b.rank.saturating_sub(a.rank);
        let f = ((b.ss - a.ss).max(0.0) / d1.max(1) as f64) / (b.rss / d2 as f64).max(1e-300);
        let p = (causes * f_tail(f, d1 as f64, d2 as f64)).min(1.0);
        if d1 == 0 || p > alpha {
            out.push(Doubt {
                cause: e.spec(),
                stand_in_for: s.variable.clone(),
                p,
            });
        }
    }
    out
}

/// A least-squares fit of `y` on per-row columns.
struct Solved {
    rank: usize,
    ss: f64,
    rss: f64,
    beta: DVector<f64>,
    yhat: DVector<f64>,
}

fn least_squares(cols: &[Vec<Vector3<f64>>], y: &[Vector3<f64>]) -> Option<Solved> {
    let n = y.len();
    let m = cols.first().map_or(0, Vec::len);
    if m == 0 {
        return None;
    }
    let x = DMatrix::from_fn(3 * n, m, |r, c| cols[r / 3][c][r % 3]);
    let yv = DVector::from_fn(3 * n, |r, _| y[r / 3][r % 3]);
    let svd = x.clone().svd(true, true);
    let top = svd.singular_values.max();
    if top.is_nan() || top <= 0.0 {
        return None;
    }
    let rank = svd
        .singular_values
        .iter()
        .filter(|s| **s > 1e-10 * top)
        .count();
    let beta = svd.solve(&yv, 1e-10 * top).ok()?;
    let yhat = &x * &beta;
    let ss = yhat.norm_squared();
    Some(Solved {
        rank,
        ss,
        rss: (yv.norm_squared() - ss).max(0.0),
        beta,
        yhat,
    })
}

/// Every test the data support.
fn tests(model: &Model, data: &Dataset, geo: &[RowGeometry]) -> Vec<Test> {
    let n = data.rows.len();
    let dof = data.dof;
    let reach = crate::geometry::reach(&model.fit.arm);
    let mut out = Vec::new();
    for k in 0..dof {
        // A joint whose axis passes through the ball (|t_k| ≈ 0) shows no angle.
        let mut turns: Vec<f64> = geo.iter().map(|g| g.turn[k].norm()).collect();
        turns.sort_by(f64::total_cmp);
        if turns.get(n / 2).copied().unwrap_or(0.0) < 0.02 * reach {
            continue;
        }
        let theta: Vec<f64> = data.rows.iter().map(|r| r.theta[k]).collect();
        for h in 1..=crate::effects::harmonic::resolvable_order(data, k) {
            let a: Vec<f64> = theta.iter().map(|t| f64::from(h) * t).collect();
            out.push(Test {
                variable: format!("joint:{}", k + 1),
                basis: format!("order-{h}"),
                form: Form::Angle(k),
                x: theta.iter().map(|t| t.to_degrees()).collect(),
                x_label: format!("joint {} reading (deg)", k + 1),
                functions: vec![
                    a.iter().map(|v| v.sin()).collect(),
                    a.iter().map(|v| v.cos()).collect(),
                ],
            });
        }
    }
    for k in 0..dof {
        let x: Vec<f64> = geo.iter().map(|g| g.lever[k]).collect();
        if let Some(q) = quadratic(&x, 1.0) {
            out.push(Test {
                variable: format!("lever:{}", k + 1),
                basis: "quadratic".into(),
                form: Form::Displacement,
                x,
                x_label: format!("joint {} gravity lever (mm)", k + 1),
                functions: q,
            });
        }
    }
    for k in 0..=dof {
        let el: Option<Vec<f64>> = geo
            .iter()
            .map(|g| g.links[k].map(|d| d.z.clamp(-1.0, 1.0).asin()))
            .collect();
        let Some(el) = el else { continue };
        let (lo, hi) = span(&el);
        if hi - lo < 5f64.to_radians() {
            continue;
        }
        let name = if k == dof {
            "probe".to_string()
        } else {
            (k + 1).to_string()
        };
        // Collinear links (2 and 3 of `default-6`) share their elevation (to
        // [`TWIN_ELEVATION_RAD`] on every row: the fitted links are nearly collinear): one
        // test, both named, since the data cannot tell them apart.
        let twin = out.iter_mut().find(|t| {
            t.basis == "elevation"
                && t.x
                    .iter()
                    .zip(&el)
                    .all(|(a, b)| (a.to_radians() - b).abs() < TWIN_ELEVATION_RAD)
        });
        if let Some(t) = twin {
            t.variable += &format!("+{name}");
            continue;
        }
        out.push(Test {
            variable: format!("link:{name}"),
            basis: "elevation".into(),
            form: Form::Displacement,
            x: el.iter().map(|e| e.to_degrees()).collect(),
            x_label: if k == dof {
                "probe elevation (deg)".into()
            } else {
                format!("link {} elevation (deg)", k + 1)
            },
            functions: vec![
                el.iter().map(|e| e.sin()).collect(),
                el.iter().map(|e| e.cos()).collect(),
                el.iter().map(|e| (2.0 * e).sin()).collect(),
                el.iter().map(|e| (2.0 * e).cos()).collect(),
            ],
        });
    }
    if data.has_temperature {
        let x: Vec<f64> = data.rows.iter().map(|r| r.temp_c).collect();
        if let Some(q) = quadratic(&x, super::candidates::MIN_TEMP_SPREAD_C) {
            out.push(Test {
                variable: "temperature".into(),
                basis: "quadratic".into(),
                form: Form::Displacement,
                x,
                x_label: "temperature (°C)".into(),
                functions: q,
            });
        }
    }
    let mut groups: Vec<i64> = data
        .rows
        .iter()
        .filter(|r| r.kind == Kind::Point)
        .map(|r| r.group)
        .collect();
    groups.sort_unstable();
    groups.dedup();
    if groups.len() >= 2 {
        out.push(Test {
            variable: "session".into(),
            basis: format!("{} groups", groups.len()),
            form: Form::Displacement,
            x: data.rows.iter().map(|r| r.group as f64).collect(),
            x_label: "group (session)".into(),
            functions: groups
                .iter()
                .map(|g| {
                    data.rows
                        .iter()
                        .map(|r| f64::from(u8::from(r.kind == Kind::Point && r.group == *g)))
                        .collect()
                })
                .collect(),
        });
    }
    if n >= 16 {
        let t: Vec<f64> = (0..n).map(|i| i as f64 / (n - 1) as f64).collect();
        out.push(Test {
            variable: "time".into(),
            basis: "slow drift".into(),
            form: Form::Displacement,
            x: (0..n).map(|i| i as f64).collect(),
            x_label: "row (file order)".into(),
            functions: (1..=4)
                .map(|j| {
                    t.iter()
                        .map(|v| (std::f64::consts::PI * f64::from(j) * v).cos())
                        .collect()
                })
                .collect(),
        });
    }
    out
}

/// Centred and scaled x, x² (`None` when x spans less than `min_span`).
fn quadratic(x: &[f64], min_span: f64) -> Option<Vec<Vec<f64>>> {
    let (lo, hi) = span(x);
    if (hi - lo).is_nan() || hi - lo < min_span {
        return None;
    }
    let (c, h) = (0.5 * (lo + hi), 0.5 * (hi - lo));
    let u: Vec<f64> = x.iter().map(|v| (v - c) / h).collect();
    Some(vec![u.clone(), u.iter().map(|v| v * v).collect()])
}

fn span(x: &[f64]) -> (f64, f64) {
    x.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        })
}

/// The test's columns at row i: 3-vectors.
fn columns(t: &Test, i: usize, geo: &[RowGeometry]) -> Vec<Vector3<f64>> {
    match t.form {
        Form::Angle(k) => t.functions.iter().map(|f| geo[i].turn[k] * f[i]).collect(),
        Form::Displacement => t
            .functions
            .iter()
            .flat_map(|f| {
                [Vector3::x(), Vector3::y(), Vector3::z()]
                    .into_iter()
                    .map(move |e| e * f[i])
            })
            .collect(),
    }
}

/// The least-squares fit of the residuals `miss` on the test's columns and its F-test; `held`
/// counts the degrees of freedom the model's fit took. `None`: nothing to fit.
fn regress(t: &Test, miss: &[Vector3<f64>], geo: &[RowGeometry], held: usize) -> Option<Fitted> {
    let n = miss.len();
    let cols: Vec<Vec<Vector3<f64>>> = (0..n).map(|i| columns(t, i, geo)).collect();
    let Solved {
        rank,
        ss,
        rss,
        beta,
        yhat,
    } = least_squares(&cols, miss)?;
    let d2 = (3 * n).checked_sub(held + rank).filter(|d| *d > 0)?;
    let f = (ss / rank as f64) / (rss / d2 as f64).max(1e-300);
    let pattern = (0..n)
        .map(|i| Vector3::new(yhat[3 * i], yhat[3 * i + 1], yhat[3 * i + 2]))
        .collect();
    Some(Fitted {
        f,
        p: f_tail(f, rank as f64, d2 as f64),
        df: (rank, d2),
        ss,
        beta,
        pattern,
    })
}

/// A significant test in words, with its figure's points.
fn structure(
    t: &Test,
    f: &Fitted,
    p: f64,
    miss: &[Vector3<f64>],
    geo: &[RowGeometry],
    n: usize,
) -> Structure {
    let rms_um = 1e3 * (f.ss / n.max(1) as f64).sqrt();
    let (pattern, y_label, y, fit): (String, String, Vec<Option<f64>>, Vec<Option<f64>>) =
        match t.form {
            Form::Angle(k) => {
                let amp = 1e6 * f.beta.iter().map(|b| b * b).sum::<f64>().sqrt();
                let angle = |v: &Vector3<f64>, i: usize| {
                    let tk = geo[i].turn[k];
                    let t2 = tk.norm_squared();
                    (t2 > 0.0).then(|| 1e6 * tk.dot(v) / t2)
                };
                (
                    format!(
                        "an {} wave in joint {}'s angle error, {amp:.1} µrad",
                        t.basis,
                        k + 1
                    ),
                    format!("joint {} apparent angle error (µrad)", k + 1),
                    (0..n).map(|i| angle(&miss[i], i)).collect(),
                    (0..n).map(|i| angle(&f.pattern[i], i)).collect(),
                )
            }
            Form::Displacement => {
                // The pattern's main direction: the top eigenvector of Σ f fᵀ.
                let s: nalgebra::Matrix3<f64> = f.pattern.iter().map(|v| v * v.transpose()).sum();
                let e = s.symmetric_eigen();
                let top = e.eigenvalues.imax();
                let d: Vector3<f64> = e.eigenvectors.column(top).into();
                let d = if d.z < 0.0 { -d } else { d };
                (
                    format!(
                        "a displacement against {} ({}), mostly along ({:.2}, {:.2}, {:.2}) of \
                         the base",
                        t.variable, t.basis, d.x, d.y, d.z
                    ),
                    format!("residual along ({:.2}, {:.2}, {:.2}) (µm)", d.x, d.y, d.z),
                    (0..n).map(|i| Some(1e3 * miss[i].dot(&d))).collect(),
                    (0..n).map(|i| Some(1e3 * f.pattern[i].dot(&d))).collect(),
                )
            }
        };
    let pair = |v: &[Option<f64>]| -> Vec<(f64, f64)> {
        v.iter()
            .zip(&t.x)
            .filter_map(|(y, x)| y.map(|y| (*x, y)))
            .collect()
    };
    Structure {
        variable: t.variable.clone(),
        pattern,
        rms_um,
        p,
        f: f.f,
        df: f.df,
        points: pair(&y),
        fitted: pair(&fit),
        x_label: t.x_label.clone(),
        y_label,
    }
}

/// The figure of the search: each significant structure's residuals against its variable,
/// with their binned mean and the fitted pattern's (`None`: nothing found).
pub fn figure(s: &Search) -> Option<Figure> {
    if s.found.is_empty() {
        return None;
    }
    let panels = s
        .found
        .iter()
        .take(MAX_PANELS)
        .map(|x| Panel {
            title: format!("{} (p = {:.1e})", x.variable, x.p),
            x_label: x.x_label.clone(),
            y_label: x.y_label.clone(),
            before: binned(&x.points, BINS, 4),
            points: x.points.clone(),
            after: Some(binned(&x.fitted, BINS, 4)),
            own: None,
            named: false,
        })
        .collect();
    Some(Figure {
        legend: crate::effects::figure::Legend::Unexplained,
        file: FILE.into(),
        title: "What the named causes leave, against the variables it depends on".into(),
        caption: format!(
            "Residuals of the model with the named causes (in sample); {} tests, Holm at {:.0e}",
            s.tests, s.alpha
        ),
        panels,
    })
}

impl Search {
    /// The report's lines, one per structure.
    pub fn lines(&self) -> Vec<String> {
        self.found
            .iter()
            .map(|x| {
                format!(
                    "{}: {}; {:.2} µm RMS, p = {:.1e} (F = {:.1}, {}/{} df)",
                    x.variable, x.pattern, x.rms_um, x.p, x.f, x.df.0, x.df.1
                )
            })
            .collect()
    }
}

/// The report's section.
pub fn write_text(s: &mut String, search: &Search) {
    use std::fmt::Write;
    let _ = writeln!(
        s,
        "\nunexplained structure (what the named causes leave, {} tests over {} variables, \
         Holm at {:.0e}; no cause named)",
        search.tests,
        search.variables.len(),
        search.alpha
    );
    if search.found.is_empty() {
        let _ = writeln!(s, "  none found");
    }
    for l in search.lines() {
        let _ = writeln!(s, "  {l}");
    }
    for d in &search.doubtful {
        let _ = writeln!(
            s,
            "  doubtful cause {}: the structure against {} explains its part as well (p = \
             {:.1e}); it may stand in for an effect outside the vocabulary",
            d.cause, d.stand_in_for, d.p
        );
    }
}
