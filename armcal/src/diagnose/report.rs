//! The diagnosis report: text a person reads, or JSON (`--json`) of the shape
//!
//! ```json
//! {"baseline": {"model": "geometric", "rms_um", "holdout_rms_um", "max_um"},
//!  "causes": [{"effect": "<key>", "joint": 2, "order": 1, "magnitude",
//!              "unit": "rad", "holdout_rms_um_after"}],
//!  "extended": {"rms_um", "holdout_rms_um", "max_um"},
//!  "gain_percent"}
//! ```
//!
//! with more keys. `effect` is the spec's key of the effect's family ([`crate::effects`]).
//! `joint` is 1-based; for a thermal expansion it is the link's joint or
//! `"probe"`, and a link whose expansion the data cannot tell from another's lists that one in
//! `indistinguishable_from`. `magnitude` is a harmonic's amplitude √(s² + c²) (rad), a
//! compliance g (rad/mm) or an expansion coefficient κ (1/°C), as the extended calibration file
//! holds it (for an indistinguishable pair: the named link carrying the pair's expansion).

use super::{Diagnosis, Model};
use crate::data::{Dataset, Kind};
use crate::effects::figure::Figure;
use crate::effects::{Effect, FAMILIES};
use crate::fit::report::{pretty_json, wrote};
use crate::params::Link;
use serde::Serialize;
use serde_json::Value;
use std::fmt::Write as _;

/// A model's residuals.
#[derive(Clone, Debug, Serialize)]
pub struct ModelReport {
    /// `geometric`, or `geometric+<term>…` in `--terms` spelling.
    pub model: String,
    /// RMS distance of the ball from where it should be, on the data fitted (µm).
    pub rms_um: f64,
    /// The same on held-out data, each fold refitted without it (µm).
    pub holdout_rms_um: f64,
    /// Largest distance on the data fitted (µm).
    pub max_um: f64,
    /// Largest distance on held-out data (µm).
    pub holdout_max_um: f64,
    /// Residual standard deviation per coordinate of the fit (µm): the noise it leaves.
    pub noise_um: f64,
    /// Unknowns fitted.
    pub fitted: usize,
    /// Bar length errors on held-out data (µm RMS), for `length` data.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub holdout_bar_rms_um: Option<f64>,
}

/// The evidence for a cause.
#[derive(Clone, Debug, Serialize)]
pub struct Evidence {
    /// F statistic of its unknowns when it entered the model (in sample).
    pub f_statistic: f64,
    /// Its p-value (to compare with `p_cut` of the selection).
    pub p_value: f64,
    /// Held-out gain of the linearised k-fold validation, in standard errors.
    pub holdout_z_linearised: f64,
    /// Held-out gain of the real refits, in standard errors of the paired per-unit
    /// differences.
    pub holdout_z: f64,
    /// Its one-sided p-value (paired t-test over the held-out units).
    pub holdout_p_value: f64,
}

/// A named cause.
#[derive(Clone, Debug, Serialize)]
pub struct CauseReport {
    /// The spec's key of the effect ([`crate::effects::Family::key`]).
    pub effect: String,
    /// 1-based joint; for thermal expansion the link's joint or `"probe"`.
    pub joint: Value,
    /// Harmonic order.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<u32>,
    /// Its size (see the module text).
    pub magnitude: f64,
    /// Standard uncertainty of the magnitude.
    pub uncertainty: f64,
    /// Unit of the magnitude.
    pub unit: String,
    /// Held-out RMS (µm) with this cause and those before it.
    pub holdout_rms_um_after: f64,
    /// When several causes are named: held-out RMS (µm) of the extended model without this
    /// one (the others kept), what it adds beyond them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub holdout_rms_um_without: Option<f64>,
    /// Links the data cannot tell from this one (joint numbers or `"probe"`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub indistinguishable_from: Vec<Value>,
    /// The `--terms` spelling.
    pub term: String,
    /// In words.
    pub description: String,
    /// Harmonic: the sin coefficient s (rad).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sin: Option<f64>,
    /// Harmonic: the cos coefficient c (rad).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cos: Option<f64>,
    /// Harmonic: φ with e = A sin(hθ + φ), i.e. atan2(c, s) (rad).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub phase_rad: Option<f64>,
    /// RMS distance the term moves the ball over the data's poses (µm).
    pub rms_effect_um: f64,
    /// What the term is identified under, when it rests on an assumption (a gravity
    /// compliance: a level base, [`super::level`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub assumption: Option<String>,
    /// Why it is named.
    pub evidence: Evidence,
}

/// A candidate that entered the selection but did not hold on held-out refits.
#[derive(Clone, Debug, Serialize)]
pub struct Rejected {
    /// `--terms` spelling.
    pub term: String,
    /// Held-out gain of the real refits, in standard errors.
    pub holdout_z: f64,
    /// Its one-sided p-value (paired t-test over the held-out units).
    pub holdout_p_value: f64,
    /// Held-out RMS with it (µm).
    pub holdout_rms_um_with: f64,
}

/// A candidate not tested, and why.
#[derive(Clone, Debug, Serialize)]
pub struct NotTestable {
    /// `--terms` spelling.
    pub term: String,
    /// Why.
    pub reason: String,
}

/// How a candidate scored.
#[derive(Clone, Debug, Serialize)]
pub struct ScoreReport {
    /// `--terms` spelling.
    pub term: String,
    /// F statistic.
    pub f_statistic: f64,
    /// p-value.
    pub p_value: f64,
    /// Linearised held-out gain in standard errors.
    pub holdout_z: f64,
    /// Its one-sided p-value (paired t-test over the held-out units).
    pub holdout_p_value: f64,
}

/// One step of the selection.
#[derive(Clone, Debug, Serialize)]
pub struct StepReport {
    /// `add` or `remove`.
    pub action: String,
    /// Its scores.
    #[serde(flatten)]
    pub score: ScoreReport,
}

/// The selection's record.
#[derive(Clone, Debug, Serialize)]
pub struct SelectionReport {
    /// Candidates tested.
    pub candidates: usize,
    /// Family-wise level of the in-sample test at each step.
    pub alpha: f64,
    /// p-value a candidate must beat (alpha / candidates, Bonferroni).
    pub p_cut: f64,
    /// Held-out errors must drop at the one-sided level of this many normal standard errors.
    pub z: f64,
    /// That level (a p-value of the paired t-test).
    pub holdout_p_cut: f64,
    /// Steps taken.
    pub steps: Vec<StepReport>,
    /// The strongest candidates left out at the end.
    pub strongest_left_out: Vec<ScoreReport>,
}

/// Held-out validation.
#[derive(Clone, Debug, Serialize)]
pub struct HoldoutInfo {
    /// How the folds were made.
    pub method: String,
    /// Folds.
    pub folds: usize,
    /// Folds that could not be fitted (baseline and extended).
    pub failed: Vec<String>,
}

/// The data.
#[derive(Clone, Debug, Serialize)]
pub struct DataReport {
    /// File.
    pub file: String,
    /// Rows.
    pub rows: usize,
    /// `point` rows.
    pub point_rows: usize,
    /// `spat` rows.
    pub spat_rows: usize,
    /// `length` rows.
    pub length_rows: usize,
    /// `sphere` rows.
    pub sphere_rows: usize,
    /// Groups (sessions, artefact positions) of `spat`, `length` and `sphere` rows.
    pub groups: usize,
    /// Temperature range (°C), when recorded.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub temperature_c: Option<[f64; 2]>,
}

/// Files written.
#[derive(Clone, Debug, Default, Serialize)]
pub struct OutputReport {
    /// The extended calibration file.
    pub calibration: Option<String>,
    /// Its binary table.
    pub table: Option<String>,
    /// Why the table could not be written (a term outside the table's limits).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub table_error: Option<String>,
    /// Figures.
    pub plots: Vec<String>,
}

/// A residual pattern and its size before and after.
#[derive(Clone, Debug, Serialize)]
pub struct PatternReport {
    /// Figure file.
    pub figure: String,
    /// Panel.
    pub panel: String,
    /// Unit of the sizes.
    pub unit: String,
    /// RMS of the binned means, geometric model.
    pub before: f64,
    /// The same with the named causes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub after: Option<f64>,
}

/// The whole report.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// The geometric model.
    pub baseline: ModelReport,
    /// The causes named (empty: none).
    pub causes: Vec<CauseReport>,
    /// The geometric model with the causes (the baseline again when none).
    pub extended: ModelReport,
    /// Held-out RMS gain, 100 (1 − extended / baseline) (%).
    pub gain_percent: f64,
    /// The finding in a sentence.
    pub verdict: String,
    /// The headline test with sessions: the whole selection rerun without each session
    /// ([`super::nested`]); absent when the folds are not whole groups.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub nested: Option<super::nested::NestedReport>,
    /// Why the nested test did not run (one group, or many without `--by-group`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub nested_not_run: Option<String>,
    /// The base's tilt against level, measured through the named gravity terms
    /// ([`super::level`]), when tested.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub level: Option<super::level::Level>,
    /// Why the base's tilt was not tested though a gravity term is named.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub level_not_tested: Option<String>,
    /// Where the sessions (groups) come from: the column and the file(s)
    /// ([`super::sessions::source`]).
    pub sessions_from: String,
    /// Degrees of freedom of the held-out paired t-tests: the held-out units less one.
    pub holdout_t_df: usize,
    /// The arm's name.
    pub arm: String,
    /// The data.
    pub data: DataReport,
    /// Held-out validation.
    pub holdout: HoldoutInfo,
    /// How the causes were chosen.
    pub selection: SelectionReport,
    /// Candidates that passed the selection but not the real held-out refits.
    pub rejected: Vec<Rejected>,
    /// Candidates these data cannot test.
    pub not_testable: Vec<NotTestable>,
    /// The residual patterns of the figures.
    pub patterns: Vec<PatternReport>,
    /// Structure the named causes leave, against the data's variables, no cause named
    /// ([`super::unexplained`]).
    pub unexplained: Vec<super::unexplained::Structure>,
    /// Named causes the strongest unexplained structure explains as well.
    pub doubtful: Vec<super::unexplained::Doubt>,
    /// How it was searched.
    pub unexplained_search: super::unexplained::Search,
    /// Files written.
    pub output: OutputReport,
    /// Warnings.
    pub warnings: Vec<String>,
    /// The uncertainty budget written with the calibration (`[uncertainty]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub uncertainty: Option<crate::uncertainty::report::BudgetReport>,
}

fn location(e: Effect) -> Value {
    e.with(|t| t.location())
}

/// The `--terms` spelling of a model's effects.
pub fn model_name(m: &Model) -> String {
    let mut s = "geometric".to_string();
    for e in &m.effects {
        s += &e.spec();
    }
    s
}

fn model_report(m: &Model) -> ModelReport {
    ModelReport {
        model: model_name(m),
        rms_um: m.in_sample.all.rms_um,
        holdout_rms_um: m.holdout.summary.all.rms_um,
        max_um: m.in_sample.all.max_um,
        holdout_max_um: m.holdout.summary.all.max_um,
        noise_um: m.fit.sigma_mm * 1e3,
        fitted: m.fit.ident.kept.len(),
        holdout_bar_rms_um: m.holdout.summary.bar_length.map(|b| b.rms_um),
    }
}

fn score_report(s: &super::select::Score) -> ScoreReport {
    ScoreReport {
        term: s.effect.spec(),
        f_statistic: s.f,
        p_value: s.p,
        holdout_z: s.z,
        holdout_p_value: s.p_holdout,
    }
}

/// Builds the report of a diagnosis.
pub fn build(d: &Diagnosis, data: &Dataset, figures: &[Figure]) -> Report {
    let arm = &d.baseline.fit.start;
    let causes: Vec<CauseReport> = d.causes.iter().map(cause_report).collect();
    let rejected = d
        .confirmations
        .iter()
        .filter(|c| !c.named)
        .map(|c| Rejected {
            term: c.effect.spec(),
            holdout_z: c.paired.z(),
            holdout_p_value: c.paired.p_value(),
            holdout_rms_um_with: c.holdout.summary.all.rms_um,
        })
        .collect();
    let layout = data.layout();
    let mut failed: Vec<String> = d.baseline.holdout.failed.clone();
    if !d.causes.is_empty() {
        failed.extend(
            d.extended
                .holdout
                .failed
                .iter()
                .map(|f| format!("extended model, {f}")),
        );
    }
    let patterns = pattern_reports(figures);
    let b = &d.baseline;
    let verdict = verdict(d);
    Report {
        baseline: model_report(b),
        causes,
        extended: model_report(&d.extended),
        gain_percent: d.gain_percent(),
        verdict,
        nested: None,
        nested_not_run: None,
        level: None,
        level_not_tested: None,
        sessions_from: super::sessions::source(data),
        holdout_t_df: d.held_out_units.saturating_sub(1),
        arm: arm.name.clone().unwrap_or_else(|| "(unnamed)".into()),
        data: DataReport {
            file: data.source.clone(),
            rows: data.rows.len(),
            point_rows: layout.points.len(),
            spat_rows: data.count(Kind::Spat),
            length_rows: data.count(Kind::Length),
            sphere_rows: data.count(Kind::Sphere),
            groups: layout.spat.len() + layout.length.len() + layout.sphere.len(),
            temperature_c: d.candidates.temp_range.map(|(a, b)| [a, b]),
        },
        holdout: HoldoutInfo {
            method: d.folds_method.clone(),
            folds: d.folds.len(),
            failed,
        },
        selection: selection_report(d),
        rejected,
        not_testable: d
            .candidates
            .untestable
            .iter()
            .map(|u| NotTestable {
                term: u.effect.spec(),
                reason: u.reason.clone(),
            })
            .collect(),
        patterns,
        unexplained: d.unexplained.found.clone(),
        doubtful: d.unexplained.doubtful.clone(),
        unexplained_search: d.unexplained.clone(),
        output: OutputReport::default(),
        warnings: data.warnings.clone(),
        uncertainty: None,
    }
}

/// A named cause as the report gives it.
pub fn cause_report(c: &super::Cause) -> CauseReport {
    let coefficients: Vec<f64> = c.values.iter().map(|v| v.1).collect();
    let phasor = c.effect.with(|t| t.phasor(&coefficients));
    let (s, co) = (phasor.map(|p| p.0), phasor.map(|p| p.1));
    let mut description = c.effect.describe() + c.effect.with(|t| t.physical());
    if !c.indistinguishable.is_empty() {
        description += &format!(
            "; indistinguishable from {} (collinear: the data see only their combined \
             expansion, carried here by the named link)",
            c.indistinguishable
                .iter()
                .map(|e| e.describe())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    CauseReport {
        effect: c.effect.key().into(),
        joint: location(c.effect),
        order: c.effect.with(|t| t.order()),
        magnitude: c.magnitude,
        uncertainty: c.magnitude_uncertainty,
        unit: c.unit.into(),
        holdout_rms_um_after: c.holdout_rms_um_after,
        holdout_rms_um_without: c.without.as_ref().map(|h| h.summary.all.rms_um),
        indistinguishable_from: c.indistinguishable.iter().map(|e| location(*e)).collect(),
        term: c.effect.spec(),
        description,
        sin: s,
        cos: co,
        phase_rad: s.zip(co).map(|(s, c)| c.atan2(s)),
        rms_effect_um: c.rms_effect_um,
        assumption: matches!(c.effect, Effect::Gravity(_))
            .then(|| super::level::ASSUMPTION.to_string()),
        evidence: Evidence {
            f_statistic: c.score.as_ref().map_or(f64::NAN, |s| s.f),
            p_value: c.score.as_ref().map_or(f64::NAN, |s| s.p),
            holdout_z_linearised: c.score.as_ref().map_or(f64::NAN, |s| s.z),
            holdout_z: c.paired.z(),
            holdout_p_value: c.paired.p_value(),
        },
    }
}

/// The size of the pattern in every panel of the figures.
fn pattern_reports(figures: &[Figure]) -> Vec<PatternReport> {
    figures
        .iter()
        .flat_map(|f| {
            f.panels.iter().map(move |p| {
                let (before, after) = p.pattern();
                let unit = if p.y_label.contains("µrad") {
                    "µrad"
                } else {
                    "µm"
                };
                PatternReport {
                    figure: f.file.clone(),
                    panel: p.title.clone(),
                    unit: unit.into(),
                    before,
                    after,
                }
            })
        })
        .collect()
}

/// How the causes were chosen.
fn selection_report(d: &Diagnosis) -> SelectionReport {
    SelectionReport {
        candidates: d.candidates.testable.len(),
        alpha: d.settings.alpha,
        p_cut: d.selection.p_cut,
        z: d.settings.z,
        holdout_p_cut: super::stats::normal_tail(d.settings.z),
        steps: d
            .selection
            .steps
            .iter()
            .map(|s| StepReport {
                action: if s.added { "add" } else { "remove" }.into(),
                score: score_report(&s.score),
            })
            .collect(),
        strongest_left_out: d
            .selection
            .left_out
            .iter()
            .filter(|s| s.separable)
            .take(5)
            .map(score_report)
            .collect(),
    }
}

fn verdict(d: &Diagnosis) -> String {
    let b = d.baseline.holdout.summary.all.rms_um;
    let e = d.extended.holdout.summary.all.rms_um;
    if d.causes.is_empty() && d.cannot_test() {
        let n = d.held_out_units;
        format!(
            "cannot test: {n} held-out unit{} ({}); a held-out test needs at least {} (with \
             --by-group: record {} more session{} or artefact position{}), so no cause can be \
             confirmed or ruled out — this is not evidence that the model is fine; held-out \
             RMS {b:.2} µm",
            if n == 1 { "" } else { "s" },
            d.folds_method,
            crate::stats::MIN_UNITS,
            crate::stats::MIN_UNITS - n,
            if crate::stats::MIN_UNITS - n == 1 {
                ""
            } else {
                "s"
            },
            if crate::stats::MIN_UNITS - n == 1 {
                ""
            } else {
                "s"
            },
        )
    } else if d.causes.is_empty() {
        let extra = if d.confirmations.is_empty() {
            String::new()
        } else {
            format!(
                " ({} candidate{} passed the in-sample test but did not hold on held-out data)",
                d.confirmations.len(),
                if d.confirmations.len() == 1 { "" } else { "s" }
            )
        };
        format!(
            "none: no candidate explains the geometric model's residuals with evidence on \
             held-out data{extra}; held-out RMS stays {b:.2} µm"
        )
    } else {
        let names: Vec<String> = d.causes.iter().map(|c| c.effect.spec()).collect();
        format!(
            "{} cause{} named ({}): held-out RMS {b:.2} → {e:.2} µm ({:.1} % less)",
            d.causes.len(),
            if d.causes.len() == 1 { "" } else { "s" },
            names.join(" "),
            d.gain_percent()
        )
    }
}

/// The terms of `arm` the firmware's binary table cannot hold, in words (its limits,
/// `quatarm::table::limits`, as `docs/spec-reading.md` lists them).
pub fn beyond_table(arm: &quatarm_ref::arm::Arm) -> Vec<String> {
    let at = (0..arm.dof()).map(Link::Joint).chain([Link::Probe]);
    at.flat_map(|l| FAMILIES.iter().flat_map(move |f| f.beyond_table(arm, l)))
        .collect()
}

fn sig(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        format!("{x}")
    } else if (1e-2..1e4).contains(&x.abs()) {
        format!("{x:.3}")
    } else {
        format!("{x:.3e}")
    }
}

impl Report {
    /// The report as text.
    pub fn text(&self) -> String {
        let mut s = String::new();
        self.write_data(&mut s);
        self.write_headline(&mut s);
        self.write_models(&mut s);
        self.write_causes(&mut s);
        self.write_selection(&mut s);
        super::unexplained::write_text(&mut s, &self.unexplained_search);
        if !self.not_testable.is_empty() {
            let _ = writeln!(s, "\nnot testable on these data");
            for n in &self.not_testable {
                let _ = writeln!(s, "  {}: {}", n.term, n.reason);
            }
        }
        for f in &self.holdout.failed {
            let _ = writeln!(s, "  held-out fold not fitted: {f}");
        }
        if let Some(u) = &self.uncertainty {
            u.text(&mut s);
        }
        let o = &self.output;
        wrote(&mut s, o.calibration.iter().chain(&o.table).chain(&o.plots));
        if let Some(e) = &o.table_error {
            let _ = writeln!(s, "binary table NOT written: {e}");
        }
        for w in &self.warnings {
            let _ = writeln!(s, "warning: {w}");
        }
        s
    }

    /// The data and how they were held out.
    fn write_data(&self, s: &mut String) {
        let d = &self.data;
        let mut kinds = Vec::new();
        if d.point_rows > 0 {
            kinds.push(format!("{} point", d.point_rows));
        }
        if d.spat_rows > 0 {
            kinds.push(format!("{} spat", d.spat_rows));
        }
        if d.length_rows > 0 {
            kinds.push(format!("{} length", d.length_rows));
        }
        if d.sphere_rows > 0 {
            kinds.push(format!("{} sphere", d.sphere_rows));
        }
        let _ = writeln!(s, "diagnosis of {} from {}", self.arm, d.file);
        let _ = write!(s, "  data: {} rows ({})", d.rows, kinds.join(", "));
        if d.groups > 0 {
            let _ = write!(s, " in {} groups", d.groups);
        }
        match d.temperature_c {
            Some([lo, hi]) => {
                let _ = writeln!(s, "; {lo:.1}–{hi:.1} °C");
            }
            None => {
                let _ = writeln!(s, "; no temperature column");
            }
        }
        let _ = writeln!(
            s,
            "  held out: {} ({} folds)",
            self.holdout.method, self.holdout.folds
        );
        let _ = writeln!(s, "  sessions: {}", self.sessions_from);
    }

    /// The models' residuals and the residual patterns.
    fn write_models(&self, s: &mut String) {
        let _ = writeln!(
            s,
            "\nwhat the model gets wrong (µm, distance of the ball from where it should be)"
        );
        let _ = writeln!(
            s,
            "  {:<10} {:>9} {:>9} {:>9} {:>9}   model",
            "", "RMS", "max", "held-out", "h-o max"
        );
        for (label, m) in [("geometric", &self.baseline), ("extended", &self.extended)] {
            let _ = writeln!(
                s,
                "  {:<10} {:>9.2} {:>9.2} {:>9.2} {:>9.2}   {}",
                label, m.rms_um, m.max_um, m.holdout_rms_um, m.holdout_max_um, m.model
            );
        }
        let _ = writeln!(
            s,
            "  noise left per coordinate: {:.2} µm (geometric), {:.2} µm (extended)",
            self.baseline.noise_um, self.extended.noise_um
        );
        if !self.patterns.is_empty() {
            let _ = writeln!(
                s,
                "\nresidual patterns (RMS of binned means of held-out residuals; geometric → extended)"
            );
            for p in &self.patterns {
                let after = p.after.map_or(String::new(), |a| format!(" → {a:.2}"));
                let _ = writeln!(
                    s,
                    "  {:<28} {:<22} {:>8.2}{after} {}",
                    p.figure
                        .trim_end_matches(".png")
                        .trim_start_matches("residuals_"),
                    p.panel,
                    p.before,
                    p.unit
                );
            }
        }
    }

    /// The causes named, with their evidence, and the verdict.
    fn write_causes(&self, s: &mut String) {
        let _ = writeln!(s, "\ncauses");
        if self.causes.is_empty() {
            // Too few held-out units is not "no cause": the verdict below says what would decide.
            let none = if self.verdict.starts_with("cannot test") {
                "  none named: cannot test (the verdict below)"
            } else {
                "  none"
            };
            let _ = writeln!(s, "{none}");
        }
        for c in &self.causes {
            let _ = writeln!(s, "  {}", c.description);
            let _ = writeln!(
                s,
                "    {}: magnitude {} ± {} {}; moves the ball by {:.2} µm RMS; held-out RMS after: {:.2} µm",
                c.term,
                sig(c.magnitude),
                sig(c.uncertainty),
                c.unit,
                c.rms_effect_um,
                c.holdout_rms_um_after
            );
            if let Some(a) = &c.assumption {
                let _ = writeln!(s, "    assumes: {a}");
            }
            if let Some(w) = c.holdout_rms_um_without {
                let _ = writeln!(
                    s,
                    "    without it, the other causes kept: held-out RMS {w:.2} µm"
                );
            }
            let _ = writeln!(
                s,
                "    evidence: in sample F = {:.1} (p = {:.1e}); on held-out data (refits) paired t = {:.1} \
                 on {} degrees of freedom (one-sided p = {:.1e})",
                c.evidence.f_statistic,
                c.evidence.p_value,
                c.evidence.holdout_z,
                self.holdout_t_df,
                c.evidence.holdout_p_value
            );
        }
    }

    /// The headline, first: the verdict and the held-out gain.
    fn write_headline(&self, s: &mut String) {
        let _ = writeln!(s, "\n{}", self.verdict);
        let _ = writeln!(
            s,
            "  gain on held-out data: {:.1} % ({:.2} → {:.2} µm RMS)",
            self.gain_percent, self.baseline.holdout_rms_um, self.extended.holdout_rms_um
        );
        if let Some(n) = &self.nested {
            n.write_text(s);
        }
        if let Some(l) = &self.level {
            let _ = writeln!(
                s,
                "  assumption of the gravity terms tested: {}",
                l.summary()
            );
        }
        if let Some(why) = &self.level_not_tested {
            let _ = writeln!(
                s,
                "  assumption of the gravity terms (a level base) not tested: {why}"
            );
        }
        if let Some(why) = &self.nested_not_run {
            let _ = writeln!(
                s,
                "  the whole selection rerun without each session (nested held-out test): {why}"
            );
        }
    }

    /// The selection's steps, the strongest left out and the rejected.
    fn write_selection(&self, s: &mut String) {
        let sel = &self.selection;
        let _ = writeln!(
            s,
            "\nselection: {} candidates; a cause needs in sample p < {:.1e} (F-test, α = {} \
             over the candidates) and on held-out data p < {:.3} (paired t-test over the held-out units, \
             their number less one degrees of freedom)",
            sel.candidates, sel.p_cut, sel.alpha, sel.holdout_p_cut
        );
        for st in &sel.steps {
            let _ = writeln!(
                s,
                "  {:<6} {:<28} F = {:>9.1}  p = {:.1e}  held-out t = {:>5.1}  p = {:.1e} (at this step)",
                st.action,
                st.score.term,
                st.score.f_statistic,
                st.score.p_value,
                st.score.holdout_z,
                st.score.holdout_p_value
            );
        }
        if !sel.strongest_left_out.is_empty() {
            let _ = writeln!(s, "  strongest left out:");
            for c in &sel.strongest_left_out {
                let _ = writeln!(
                    s,
                    "    {:<28} F = {:>9.2}  p = {:.1e}  held-out t = {:>5.1}  p = {:.1e}",
                    c.term, c.f_statistic, c.p_value, c.holdout_z, c.holdout_p_value
                );
            }
        }
        for r in &self.rejected {
            let _ = writeln!(
                s,
                "  rejected {}: did not hold on held-out refits (paired t = {:.1}, p = {:.2})",
                r.term, r.holdout_z, r.holdout_p_value
            );
        }
    }

    /// The report as JSON.
    pub fn json(&self) -> String {
        pretty_json(self)
    }
}
