//! The calibration report: what was fitted, how well, with what uncertainty, and what the data
//! could not determine — as text a person reads, or JSON a program reads (`--json`).

use crate::data::{Dataset, Kind};
use crate::fit::finish::Fit;
use crate::fit::holdout::Holdout;
use crate::fit::ident::{Fixed, Why};
use crate::fit::residuals::Summary;
use crate::params::{Param, ParamExt};
use serde::Serialize;
use std::fmt::Write as _;

/// The data a calibration used.
#[derive(Clone, Debug, Serialize)]
pub struct DataInfo {
    /// Where it came from.
    pub file: String,
    /// Rows in all.
    pub rows: usize,
    /// `point` rows.
    pub point_rows: usize,
    /// `spat` rows.
    pub spat_rows: usize,
    /// `spat` groups.
    pub spat_groups: usize,
    /// `length` rows.
    pub length_rows: usize,
    /// `length` groups (bar positions).
    pub length_groups: usize,
    /// `sphere` rows.
    pub sphere_rows: usize,
    /// `sphere` groups (test-sphere positions).
    pub sphere_groups: usize,
    /// Equations once the fixed points are eliminated.
    pub equations: usize,
}

/// One fitted parameter.
#[derive(Clone, Debug, Serialize)]
pub struct ParamReport {
    /// Calibration-file key.
    pub key: String,
    /// In words.
    pub description: String,
    /// Unit of value, change and uncertainty.
    pub unit: String,
    /// The key's value in the start arm.
    pub start: f64,
    /// The key's calibrated value.
    pub value: f64,
    /// value − start.
    pub change: f64,
    /// Standard uncertainty of the change.
    pub uncertainty: f64,
}

/// One kept unknown that absorbs a held one.
#[derive(Clone, Debug, Serialize)]
pub struct Absorbed {
    /// Its key.
    pub key: String,
    /// In words.
    pub description: String,
    /// Change of it per unit change of the held unknown.
    pub coefficient: f64,
    /// Unit of the coefficient.
    pub unit: String,
}

/// An unknown the data could not determine.
#[derive(Clone, Debug, Serialize)]
pub struct HeldReport {
    /// Its key.
    pub key: String,
    /// In words.
    pub description: String,
    /// `no_effect`, `inseparable`, `weak`, `requested` or `insignificant`.
    pub reason: String,
    /// The reason in a sentence.
    pub explanation: String,
    /// What absorbs it.
    pub absorbed_by: Vec<Absorbed>,
}

/// The instrument frame of `point` data.
#[derive(Clone, Debug, Serialize)]
pub struct FrameReport {
    /// Unit quaternion (w, x, y, z) of R_T: x_ref = R_T p + t_T.
    pub rotation: [f64; 4],
    /// t_T (mm).
    pub translation: [f64; 3],
}

/// Held-out validation in the report.
#[derive(Clone, Debug, Serialize)]
pub struct HoldoutReport {
    /// How the folds were made.
    pub method: String,
    /// Number of folds.
    pub folds: usize,
    /// Residuals of the held-out rows.
    pub residuals: Summary,
    /// Folds that could not be fitted.
    pub failed: Vec<String>,
}

/// Residual statistics before and after.
#[derive(Clone, Debug, Serialize)]
pub struct ResidualReport {
    /// The start arm on the fitting data (with its best frame and fixed points).
    pub before: Summary,
    /// The calibrated arm on the fitting data.
    pub after: Summary,
    /// The calibrated arm on data it did not fit.
    pub holdout: Option<HoldoutReport>,
    /// Why there is no held-out validation, when there is none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub holdout_note: Option<String>,
}

/// Files written.
#[derive(Clone, Debug, Default, Serialize)]
pub struct OutputReport {
    /// The calibration file.
    pub calibration: Option<String>,
    /// The firmware's binary table.
    pub table: Option<String>,
}

/// A section a higher layer adds to the calibration's report, written in the text after the
/// prior's section and in the JSON under `uncertainty`: the uncertainty budget
/// (`crate::uncertainty::report::BudgetReport`) is one. The fit names no such section, so
/// that it stands below the uncertainty; the command that has both puts them together.
pub trait Section: Serialize {
    /// The section's text, appended to `s`.
    fn text(&self, s: &mut String);
}

/// No section: the report of a fit alone.
#[derive(Clone, Copy, Debug)]
pub enum NoSection {}

impl Serialize for NoSection {
    fn serialize<S: serde::Serializer>(&self, _: S) -> Result<S::Ok, S::Error> {
        match *self {}
    }
}

impl Section for NoSection {
    fn text(&self, _: &mut String) {
        match *self {}
    }
}

/// A whole calibration report, with the section `U` a higher layer may add
/// (`uncertainty`).
#[derive(Clone, Debug, Serialize)]
pub struct Report<U = NoSection> {
    /// The data.
    pub data: DataInfo,
    /// The arm's name.
    pub arm: String,
    /// Joint count.
    pub joints: usize,
    /// What was fitted (`--terms` form).
    pub terms: String,
    /// Solver iterations.
    pub iterations: usize,
    /// How the solver stopped.
    pub solver: String,
    /// Time the fit took (ms).
    pub fit_ms: f64,
    /// Residual standard deviation per coordinate (µm).
    pub noise_um: f64,
    /// Condition number of the fitted unknowns (unit-norm Jacobian columns).
    pub condition_number: f64,
    /// Unknowns fitted / considered.
    pub fitted: usize,
    /// Unknowns considered.
    pub unknowns: usize,
    /// Residuals.
    pub residuals: ResidualReport,
    /// Fitted arm parameters.
    pub parameters: Vec<ParamReport>,
    /// The instrument frame (point data).
    pub frame: Option<FrameReport>,
    /// What the data could not determine.
    pub not_identifiable: Vec<HeldReport>,
    /// What the data's kinds leave to the start arm or the instrument frame
    /// ([`crate::kinds::notes`]).
    pub data_kinds: Vec<String>,
    /// Files written.
    pub output: OutputReport,
    /// Warnings (unknown columns, keys, a table not written…).
    pub warnings: Vec<String>,
    /// What the data determine poorly ([`weak_results`]): a reader must not take these
    /// estimates for measured errors of the arm.
    pub weak: Vec<String>,
    /// The uncertainty budget written with the calibration (`[uncertainty]`), added by the
    /// command that computes it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub uncertainty: Option<U>,
    /// The prior or penalty the fit used besides the data (none: plain least squares).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prior: Option<PriorReport>,
}

/// What pulled the fit besides the data: a fleet prior, a class prior, a ridge.
#[derive(Clone, Debug, Serialize)]
pub struct PriorReport {
    /// The rule for the unknowns without a fleet Gaussian, in words (`ridge λ = 1e-4`,
    /// `Gaussian 0 ± 0.002 rad, 0 ± 1 mm`, `none (least squares)`).
    pub rule: String,
    /// The fleet prior, when there is one: its units and every unknown's statistics.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fleet: Option<crate::fit::fleet_prior::FleetPrior>,
    /// Per-unknown priors the data contradicted, left to the rule for this fit.
    pub dropped: Vec<DroppedPrior>,
}

/// A per-unknown prior the data contradicted ([`crate::fit::priors::PRIOR_CONFLICT_SIGMAS`]).
#[derive(Clone, Debug, Serialize)]
pub struct DroppedPrior {
    /// The calibration-file key.
    pub key: String,
    /// The data-only estimate and its standard uncertainty (increments from the start arm).
    pub data: f64,
    /// Standard uncertainty of `data`.
    pub data_sd: f64,
    /// The prior's mean.
    pub prior_mean: f64,
    /// The prior's standard deviation.
    pub prior_sd: f64,
    /// Their distance in standard deviations of both.
    pub sigmas: f64,
}

impl DroppedPrior {
    /// The report of each prior a fit dropped.
    pub fn of(fit: &Fit) -> Vec<DroppedPrior> {
        fit.prior_conflicts
            .iter()
            .map(|c| DroppedPrior {
                key: fit.params[c.index].to_string(),
                data: c.data,
                data_sd: c.data_sd,
                prior_mean: c.prior.mean,
                prior_sd: c.prior.sd,
                sigmas: c.sigmas(),
            })
            .collect()
    }
}

/// A parameter in words, with the frame's rotations named for what they are without an
/// instrument.
fn words(p: Param, fit: &Fit, has_points: bool) -> String {
    match p {
        Param::FrameRotation(c) if !has_points => format!(
            "a rotation of the whole arm about the base {} axis (spat and length data fix no direction)",
            ["x", "y", "z"][c]
        ),
        _ => p.describe(&fit.start),
    }
}

fn unit_ratio(num: &str, den: &str) -> String {
    if num == den {
        String::new()
    } else {
        format!("{num}/{den}")
    }
}

/// A held unknown as the report gives it: why it was held, and what carries its effect.
fn held_report(f: &Fixed, fit: &Fit, has_points: bool) -> HeldReport {
    let p = fit.params[f.index];
    let absorbed_by: Vec<Absorbed> = f
        .absorbed_by
        .iter()
        .map(|&(k, c)| Absorbed {
            key: fit.params[k].to_string(),
            description: words(fit.params[k], fit, has_points),
            coefficient: c,
            unit: unit_ratio(fit.params[k].unit(), p.unit()),
        })
        .collect();
    let (reason, explanation) = match &f.why {
        Why::NoEffect => (
            "no_effect",
            "it does not change any residual of these data".to_string(),
        ),
        Why::Inseparable => (
            "inseparable",
            if absorbed_by.is_empty() {
                "its effect on these data equals a combination of the fitted parameters'".into()
            } else {
                format!(
                    "its effect on these data is exactly that of {}",
                    absorbed_by
                        .iter()
                        .map(|a| format!("{} (×{})", a.description, coef(a.coefficient, &a.unit)))
                        .collect::<Vec<_>>()
                        .join(" and ")
                )
            },
        ),
        Why::Weak { uncertainty } => (
            "weak",
            format!(
                "these data determine it only to ±{} {} (more than a plausible size, {} {})",
                sig(*uncertainty),
                p.unit(),
                sig(p.plausible()),
                p.unit()
            ),
        ),
        Why::Requested => ("requested", "held on request".to_string()),
        Why::Insignificant { value, uncertainty } => (
            "insignificant",
            format!(
                "its estimate {} ± {} {} does not differ significantly from its start value",
                sig(*value),
                sig(*uncertainty),
                p.unit()
            ),
        ),
    };
    HeldReport {
        key: p.to_string(),
        description: p.describe(&fit.start),
        reason: reason.into(),
        explanation,
        absorbed_by,
    }
}

/// Builds the report of a fit, its section `U` left empty.
pub fn build<U>(
    fit: &Fit,
    data: &Dataset,
    before: Summary,
    after: Summary,
    holdout: Option<(&str, &Holdout)>,
) -> Report<U> {
    let layout = data.layout();
    let has_points = !layout.points.is_empty();
    let mut parameters = Vec::new();
    for &k in &fit.ident.kept {
        let p = fit.params[k];
        if p.is_frame() {
            continue;
        }
        let start = p.value(&fit.start);
        let value = p.value(&fit.arm);
        parameters.push(ParamReport {
            key: p.to_string(),
            description: p.describe(&fit.start),
            unit: p.unit().into(),
            start,
            value,
            change: fit.values[k],
            uncertainty: fit.uncertainty[k].unwrap_or(f64::NAN),
        });
    }
    let held = fit
        .ident
        .fixed
        .iter()
        .map(|f| held_report(f, fit, has_points))
        .collect();
    Report {
        data: DataInfo {
            file: data.source.clone(),
            rows: data.rows.len(),
            point_rows: layout.points.len(),
            spat_rows: data.count(Kind::Spat),
            spat_groups: layout.spat.len(),
            length_rows: data.count(Kind::Length),
            length_groups: layout.length.len(),
            sphere_rows: data.count(Kind::Sphere),
            sphere_groups: layout.sphere.len(),
            equations: fit.equations,
        },
        arm: fit.start.name.clone().unwrap_or_else(|| "(unnamed)".into()),
        joints: fit.start.dof(),
        terms: String::new(),
        iterations: fit.iterations,
        solver: fit.solver.to_string(),
        fit_ms: fit.elapsed.as_secs_f64() * 1e3,
        noise_um: fit.sigma_mm * 1e3,
        condition_number: fit.ident.condition_number,
        fitted: fit.ident.kept.len(),
        unknowns: fit.ident.kept.len() + fit.ident.fixed.len(),
        residuals: ResidualReport {
            before,
            after,
            holdout: holdout.map(|(method, h)| HoldoutReport {
                method: method.into(),
                folds: h.folds,
                residuals: h.summary.clone(),
                failed: h.failed.clone(),
            }),
            holdout_note: None,
        },
        parameters,
        frame: fit.reference_frame().map(|f| FrameReport {
            rotation: f.rotation,
            translation: f.translation,
        }),
        not_identifiable: held,
        data_kinds: crate::kinds::notes(&layout),
        output: OutputReport::default(),
        warnings: data.warnings.clone(),
        weak: weak_results(fit),
        uncertainty: None,
        prior: None,
    }
}

/// Above this condition number the fit amplifies the data's noise this many times along
/// some combination of the unknowns: the combination is barely determined.
pub const WEAK_CONDITION: f64 = 1e4;
/// A link error larger than this fraction of its link's length is no manufacturing error
/// of a real arm: more likely a compensation between weakly determined unknowns (or a wrong
/// nominal model).
pub const WEAK_LINK_FRACTION: f64 = 0.05;

/// What a fit determines poorly, in words: a condition number above [`WEAK_CONDITION`],
/// each link error larger than [`WEAK_LINK_FRACTION`] of its link, and the estimates no
/// larger than their own standard uncertainty (counted, the first few named).
pub fn weak_results(fit: &Fit) -> Vec<String> {
    let mut weak = Vec::new();
    let cond = fit.ident.condition_number;
    if cond > WEAK_CONDITION {
        weak.push(format!(
            "condition number {cond:.0} (above {WEAK_CONDITION:.0}): some combinations of the \
             unknowns are barely determined by these data; add poses or artefact positions, or \
             a prior (--prior-angle/--prior-length, --ridge, --fleet-prior)"
        ));
    }
    let mut within = Vec::new();
    for &k in &fit.ident.kept {
        let p = fit.params[k];
        if p.is_frame() {
            continue;
        }
        let (v, u) = (fit.values[k], fit.uncertainty[k].unwrap_or(f64::NAN));
        if let crate::params::Param::LinkError(i, _) = p {
            let link = fit
                .start
                .joints
                .get(i)
                .map_or(0.0, |j| j.link.iter().map(|x| x * x).sum::<f64>().sqrt());
            if link > 0.0 && v.abs() > WEAK_LINK_FRACTION * link {
                weak.push(format!(
                    "{} {:+.4e} ± {:.2e} mm: more than {:.0} % of the link's {:.1} mm, no \
                     manufacturing error; likely a compensation between weakly determined unknowns",
                    p.describe(&fit.start),
                    v,
                    u,
                    WEAK_LINK_FRACTION * 100.0,
                    link
                ));
            }
        }
        if v.abs() <= u {
            within.push(p.to_string());
        }
    }
    if !within.is_empty() {
        let shown: Vec<&str> = within.iter().take(6).map(String::as_str).collect();
        weak.push(format!(
            "{} of {} estimates are no larger than their standard uncertainty (not told from \
             zero by these data): {}{}",
            within.len(),
            fit.ident.kept.len(),
            shown.join(", "),
            if within.len() > shown.len() {
                ", …"
            } else {
                ""
            }
        ));
    }
    weak
}

fn sig(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if (1e-3..1e4).contains(&x.abs()) {
        format!("{x:.4}")
    } else {
        format!("{x:.3e}")
    }
}

fn coef(c: f64, unit: &str) -> String {
    if unit.is_empty() {
        format!("{c:.4}")
    } else {
        format!("{} {unit}", sig(c))
    }
}

fn spread_line(s: &mut String, label: &str, sum: &Summary) {
    let _ = writeln!(
        s,
        "  {label:<28} {:>10.2} {:>10.2}   ({} rows)",
        sum.all.rms_um, sum.all.max_um, sum.all.n
    );
    let kinds = [
        ("point", &sum.point),
        ("spat", &sum.spat),
        ("length", &sum.length),
        ("sphere", &sum.sphere),
    ];
    let present = kinds.iter().filter(|(_, x)| x.is_some()).count();
    for (kind, sp) in kinds {
        if let (Some(sp), true) = (sp, present > 1) {
            let _ = writeln!(s, "    {kind:<26} {:>10.2} {:>10.2}", sp.rms_um, sp.max_um);
        }
    }
    if let Some(b) = &sum.bar_length {
        let _ = writeln!(
            s,
            "    {:<26} {:>10.2} {:>10.2}   ({} bars)",
            "bar length error", b.rms_um, b.max_um, b.n
        );
    }
}

impl DataInfo {
    /// The rows of each kind in words (`400 point rows`, `30 spat rows in 3 groups`).
    fn kinds(&self) -> Vec<String> {
        let mut kinds = Vec::new();
        if self.point_rows > 0 {
            kinds.push(format!("{} point rows", self.point_rows));
        }
        if self.spat_rows > 0 {
            kinds.push(format!(
                "{} spat rows in {} groups",
                self.spat_rows, self.spat_groups
            ));
        }
        if self.length_rows > 0 {
            kinds.push(format!(
                "{} length rows at {} bar positions",
                self.length_rows, self.length_groups
            ));
        }
        if self.sphere_rows > 0 {
            kinds.push(format!(
                "{} sphere rows at {} sphere positions",
                self.sphere_rows, self.sphere_groups
            ));
        }
        kinds
    }
}

impl<U: Section> Report<U> {
    /// The report as text.
    pub fn text(&self) -> String {
        let mut s = String::new();
        let d = &self.data;
        let _ = writeln!(s, "calibration of {} from {}", self.arm, d.file);
        let _ = writeln!(
            s,
            "  data: {} ({} equations)",
            d.kinds().join(", "),
            d.equations
        );
        for note in &self.data_kinds {
            let _ = writeln!(s, "  ({note})");
        }
        let _ = writeln!(
            s,
            "  model: {} ({} joints); fitted {} of {} unknowns in {} iterations, {:.1} ms ({})",
            self.terms,
            self.joints,
            self.fitted,
            self.unknowns,
            self.iterations,
            self.fit_ms,
            self.solver
        );
        let _ = writeln!(
            s,
            "  noise estimate {:.2} µm per coordinate; condition number {:.1}",
            self.noise_um, self.condition_number
        );
        let _ = writeln!(
            s,
            "\nresiduals (µm, distance of the ball from where it should be)"
        );
        let _ = writeln!(s, "  {:<28} {:>10} {:>10}", "", "RMS", "max");
        spread_line(&mut s, "before, fitting data", &self.residuals.before);
        spread_line(&mut s, "after, fitting data", &self.residuals.after);
        if let Some(h) = &self.residuals.holdout {
            spread_line(
                &mut s,
                &format!("after, held out ({})", h.method),
                &h.residuals,
            );
            for f in &h.failed {
                let _ = writeln!(s, "    not judged: {f}");
            }
        }
        if let Some(n) = &self.residuals.holdout_note {
            let _ = writeln!(s, "  held out: {n}");
        }
        let _ = writeln!(
            s,
            "\nparameters (change from the start arm ± standard uncertainty)"
        );
        for p in &self.parameters {
            let _ = writeln!(
                s,
                "  {:<38} {:<28} {:>+12.4e} ± {:.2e} {}",
                p.description, p.key, p.change, p.uncertainty, p.unit
            );
        }
        if let Some(f) = &self.frame {
            let _ = writeln!(
                s,
                "  instrument frame: rotation (w, x, y, z) = ({:.9}, {:.9}, {:.9}, {:.9}), translation = ({:.4}, {:.4}, {:.4}) mm",
                f.rotation[0], f.rotation[1], f.rotation[2], f.rotation[3],
                f.translation[0], f.translation[1], f.translation[2]
            );
        }
        if !self.not_identifiable.is_empty() {
            let _ = writeln!(
                s,
                "\nnot identifiable from these data (held at their start values)"
            );
            for h in &self.not_identifiable {
                let _ = writeln!(s, "  {}: {}", h.description, h.explanation);
            }
        }
        if let Some(p) = &self.prior {
            p.text(&mut s);
        }
        if let Some(u) = &self.uncertainty {
            u.text(&mut s);
        }
        if !self.weak.is_empty() {
            let _ = writeln!(s, "\nweak results (what these data determine poorly)");
            for w in &self.weak {
                let _ = writeln!(s, "  {w}");
            }
        }
        let o = &self.output;
        wrote(&mut s, o.calibration.iter().chain(&o.table));
        for w in &self.warnings {
            let _ = writeln!(s, "warning: {w}");
        }
        s
    }

    /// The report as JSON.
    pub fn json(&self) -> String {
        pretty_json(self)
    }
}

/// A report as pretty JSON; should serialising fail, a JSON object saying why, so that a
/// program reading stdout still gets JSON.
pub(crate) fn pretty_json(report: &impl Serialize) -> String {
    serde_json::to_string_pretty(report).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
}

/// The "wrote <file>" lines that close a report, set off by a blank line when there are any.
pub(crate) fn wrote<'a>(s: &mut String, files: impl IntoIterator<Item = &'a String>) {
    let mut files = files.into_iter().peekable();
    if files.peek().is_some() {
        let _ = writeln!(s);
    }
    for f in files {
        let _ = writeln!(s, "wrote {f}");
    }
}

impl PriorReport {
    /// The prior's section of the text report.
    fn text(&self, s: &mut String) {
        let _ = writeln!(s, "\nprior");
        for d in &self.dropped {
            let _ = writeln!(
                s,
                "  {}: prior {:+.4e} ± {:.2e} dropped, the data say {:+.4e} ± {:.2e} ({:.1} σ apart)",
                d.key, d.prior_mean, d.prior_sd, d.data, d.data_sd, d.sigmas
            );
        }
        let Some(f) = &self.fleet else {
            let _ = writeln!(s, "  {}", self.rule);
            return;
        };
        let used = f.entries.iter().filter(|e| e.fallback.is_none()).count();
        let _ = writeln!(
            s,
            "  fleet prior from {} units ({}): {} unknowns pulled towards the fleet's mean error",
            f.units.len(),
            f.units.join(", "),
            used
        );
        for e in f.entries.iter().filter(|e| e.fallback.is_none()) {
            let _ = writeln!(
                s,
                "    {:<28} {:>+12.4e} ± {:.2e} {} ({} units)",
                e.key, e.mean, e.sd, e.unit, e.units
            );
        }
        let back: Vec<String> = f
            .fallbacks()
            .map(|e| {
                let why = e.fallback.map_or("", |b| b.words());
                format!("{} ({why}, {} units)", e.key, e.units)
            })
            .collect();
        if !back.is_empty() {
            let _ = writeln!(s, "  left to the rule `{}`: {}", self.rule, back.join(", "));
        }
    }
}
