//! The fleet diagnosis report ([`super::fleet`]): text, or JSON (`--json`) of the shape
//!
//! ```json
//! {"design": {"causes": [{"effect", "joint", "order", "magnitude", "uncertainty", "unit",
//!                         "term", "units": [{"unit", "magnitude", "uncertainty"}],
//!                         "evidence": {"z", "p_value", "tau2", …}}],
//!             "tested_units", "alpha", "strongest": […]},
//!  "units": [{"unit": "panda_3", "sessions", "cannot_test", "causes": [{"level": "design",
//!             …the single-arm report's cause…}], "holdout_rms_um", "holdout_rms_um_after"}],
//!  "arms": [{"arm": "panda_3", "recordings": ["panda_3", "panda_3_bis", "panda_right"],
//!            "evidence": {"rule", "pairs": [{"a", "b", "chi2", "dof", "f", "p_value", "same"}]}}],
//!  "pairs": [every pair of recordings, as in "evidence"], "uncompared": [[recording, why]],
//!  "halves": [{"recording", "chi2", "dof"}], "overdispersion": {"phi", "dof"},
//!  "pooled": {"alpha", "model": "full" | "alone", "left_out": [[arm, "arm: recording R" or candidate, why]],
//!             "effects": [{"term", "named", "design": {"arms", "mean", "mean_se",
//!                          "mean_interval", "mean_p", "spread", "spread_interval", "named"},
//!                          "dispersion": {"ratios", "phi", "df", "bartlett", "p"},
//!                          "fleet_scaled", "arms": [{"arm", "recordings", "sessions", "per_recording":
//!                                    [{"value", "se", "df", "model_se"}], "combined":
//!                                    {"estimate", "se", "df", "recordings", "q", "q_p",
//!                                    "model_se"}, "estimate", "se",
//!                                    "se_df", "named_alone", "shrinkage", "pooled",
//!                                    "pooled_se", "pooled_se_plugin", "df", "named_pooled",
//!                                    "holdout"}]}]}}
//! ```
//!
//! `pooled` is [`super::fleet_pooled`]'s stage: an arm's `per_recording` estimates (each
//! recording fitted with its own probe and frame) combined into its `estimate`, then pooled
//! over the arms; `pooled_se` carries τ̂²'s uncertainty, `pooled_se_plugin` does not; an arm's
//! interval is `pooled` ± t_`df`·`pooled_se`, `df` its error's degrees of freedom (`se_df`)
//! or arms − 1 where fewer. `model_se` is the fit's in-sample error of the same value (null
//! where the fit gave none). With `fleet_scaled` (the default `--error-scale fleet`, where
//! Bartlett's test of the arms' ratios s²/v² in `dispersion` keeps one scale at `alpha`) an
//! arm's `se` is √`phi` × its `model_se` on the fleet's `df` (Σ sessions − 1); without it
//! (the test rejected, or `--error-scale own`, which has no `dispersion`), its jackknife
//! error on its sessions − 1 (docs/results/claims.md §7.10–§7.11). `model` is the model the
//! candidates were estimated in: `full` (the default `--pooled-model full`: every shared
//! candidate in one fit, each conditional on the others) or `alone` (each with the geometric
//! model alone; also where a recording's full fit could not be made, said in `left_out`).
//!
//! A unit is an arm ([`super::same_arm`]): recordings of one physical arm are one unit.
//!
//! A design cause's `magnitude` is the mean of the units' fitted magnitudes, its
//! `uncertainty` the standard error of that mean over the units (the units' spread / √k) and
//! `spread` their standard deviation: the design's typical size and how much units differ.

use super::fleet::{Fleet, Level, Pooled, Pooling, UnitResult, UnitTest};
use super::report::{cause_report, CauseReport};
use super::same_arm::{Arms, Pair};
use crate::fit::report::pretty_json;
use crate::params::Effect;
use serde::Serialize;
use serde_json::Value;
use std::fmt::Write as _;

/// The pooled evidence for a candidate.
#[derive(Clone, Debug, Serialize)]
pub struct PooledReport {
    /// `--terms` spelling.
    pub term: String,
    /// The pooled statistics.
    #[serde(flatten)]
    pub pooling: Pooling,
    /// Every pooled arm's own mean log-ratio (its recordings' sessions together) and its
    /// standard error.
    pub per_unit: Vec<UnitLogRatio>,
    /// Whether Holm's step-down over the step's candidates rejects "no gain" at `alpha`.
    pub significant: bool,
}

/// One unit's evidence in a pooled test.
#[derive(Clone, Debug, Serialize)]
pub struct UnitLogRatio {
    /// The unit.
    pub unit: String,
    /// Its mean ½ ln(held-out SS before / after) over its sessions.
    pub log_ratio: f64,
    /// Its standard error.
    pub se: f64,
}

/// A unit's magnitude of a design cause.
#[derive(Clone, Debug, Serialize)]
pub struct UnitMagnitude {
    /// The unit.
    pub unit: String,
    /// Its fitted magnitude.
    pub magnitude: f64,
    /// Its standard uncertainty.
    pub uncertainty: f64,
}

/// A design-level cause.
#[derive(Clone, Debug, Serialize)]
pub struct DesignCause {
    /// The spec's key of the effect.
    pub effect: String,
    /// 1-based joint (or `"probe"`).
    pub joint: Value,
    /// Harmonic order.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<u32>,
    /// Mean of the units' magnitudes.
    pub magnitude: f64,
    /// Standard error of that mean over the units.
    pub uncertainty: f64,
    /// Standard deviation of the units' magnitudes.
    pub spread: f64,
    /// Unit of the magnitude.
    pub unit: String,
    /// `--terms` spelling.
    pub term: String,
    /// In words.
    pub description: String,
    /// Every unit's magnitude.
    pub units: Vec<UnitMagnitude>,
    /// The pooled test when it was named.
    pub evidence: PooledReport,
}

/// The design level.
#[derive(Clone, Debug, Serialize)]
pub struct DesignReport {
    /// Causes named for the design.
    pub causes: Vec<DesignCause>,
    /// Arms with a held-out test (enough sessions over their recordings).
    pub tested_units: usize,
    /// Family-wise level of each step (Holm over the candidates).
    pub alpha: f64,
    /// The strongest candidates not named, at the last step.
    pub strongest_left_out: Vec<PooledReport>,
}

/// A unit's cause, with its level.
#[derive(Clone, Debug, Serialize)]
pub struct UnitCause {
    /// `design` or `unit`.
    pub level: &'static str,
    /// The cause as the single-arm report gives it.
    #[serde(flatten)]
    pub cause: CauseReport,
}

/// A unit's own evidence for a candidate (first step, against its geometric model plus the
/// design causes).
#[derive(Clone, Debug, Serialize)]
pub struct UnitTestReport {
    /// `--terms` spelling.
    pub term: String,
    /// Sessions compared.
    pub sessions: usize,
    /// Mean ½ ln(held-out SS before / after) over the sessions.
    pub log_ratio: f64,
    /// Its standard error.
    pub se: f64,
    /// One-sided t-test p-value.
    pub p_value: f64,
    /// Held-out RMS with it (µm).
    pub holdout_rms_um_with: f64,
}

/// One unit.
#[derive(Clone, Debug, Serialize)]
pub struct UnitReport {
    /// The unit's name.
    pub unit: String,
    /// Its file.
    pub file: String,
    /// Its sessions.
    pub sessions: usize,
    /// Why it contributes nothing, when it does not.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cannot_test: Option<String>,
    /// Its causes (design's and its own), fitted on its data.
    pub causes: Vec<UnitCause>,
    /// Held-out RMS of its geometric model, its sessions held out one at a time (µm).
    pub holdout_rms_um: Option<f64>,
    /// The same with its causes.
    pub holdout_rms_um_after: Option<f64>,
    /// Its strongest candidates by its own log-ratio test at the design's last step.
    pub strongest: Vec<UnitTestReport>,
}

/// One pair's same-arm statistic ([`super::same_arm`]).
#[derive(Clone, Debug, Serialize)]
pub struct PairReport {
    /// One recording.
    pub a: String,
    /// The other.
    pub b: String,
    /// The statistic and the decision.
    #[serde(flatten)]
    pub pair: Pair,
}

/// Why an arm's recordings are one arm.
#[derive(Clone, Debug, Serialize)]
pub struct ArmEvidence {
    /// The grouping rule.
    pub rule: String,
    /// The statistic of every pair of its recordings.
    pub pairs: Vec<PairReport>,
}

/// One physical arm: one unit of the fleet test.
#[derive(Clone, Debug, Serialize)]
pub struct ArmReport {
    /// The arm's name (the unit's in `units`).
    pub arm: String,
    /// Its recordings' names, file order.
    pub recordings: Vec<String>,
    /// Why they are one arm.
    pub evidence: ArmEvidence,
}

/// The whole report.
#[derive(Clone, Debug, Serialize)]
pub struct FleetReport {
    /// The design level.
    pub design: DesignReport,
    /// Every recording (its own geometric model and causes; `arms` says which are one arm).
    pub units: Vec<UnitReport>,
    /// How unit names were made.
    pub naming: String,
    /// The physical arms the recordings were grouped into.
    pub arms: Vec<ArmReport>,
    /// Every pair of recordings' same-arm statistic (none with `--each-file-an-arm`).
    pub pairs: Vec<PairReport>,
    /// Recordings that could not be compared, with why.
    pub uncompared: Vec<(String, String)>,
    /// Each recording's two halves compared (what one arm's scatter is).
    pub halves: Vec<HalvesReport>,
    /// φ̂, the halves' pooled χ²/k, and its degrees of freedom D.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub overdispersion: Option<Overdispersion>,
    /// Every one-unknown candidate pooled over the arms ([`super::fleet_pooled`]): the
    /// design's distribution, each arm's pooled value and, where named, its held-out gain.
    pub pooled: super::fleet_pooled::PooledFleet,
}

/// One recording's halves ([`super::same_arm::halves`]).
#[derive(Clone, Debug, Serialize)]
pub struct HalvesReport {
    /// The recording.
    pub recording: String,
    /// χ² of the halves' difference.
    pub chi2: f64,
    /// Unknowns compared.
    pub dof: usize,
}

/// The pooled halves' statistic.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Overdispersion {
    /// φ̂ = Σ χ² / Σ k.
    pub phi: f64,
    /// D = Σ k.
    pub dof: usize,
}

fn pooled_report(f: &Fleet, p: &Pooled, significant: bool) -> PooledReport {
    PooledReport {
        term: p.effect.spec(),
        pooling: p.pooling,
        per_unit: p
            .per_unit
            .iter()
            .map(|&(u, y, se)| UnitLogRatio {
                unit: f.arms[u].0.clone(),
                log_ratio: y,
                se,
            })
            .collect(),
        significant,
    }
}

fn unit_test_report(t: &UnitTest) -> UnitTestReport {
    UnitTestReport {
        term: t.effect.spec(),
        sessions: t.sessions,
        log_ratio: t.log_ratio,
        se: t.se,
        p_value: t.p,
        holdout_rms_um_with: t.holdout_rms_um_with,
    }
}

fn design_cause(f: &Fleet, e: Effect) -> DesignCause {
    let units: Vec<UnitMagnitude> = f
        .units
        .iter()
        .filter_map(|u| {
            let c = u.causes.iter().find(|(_, c)| c.effect == e)?;
            Some(UnitMagnitude {
                unit: u.name.clone(),
                magnitude: c.1.magnitude,
                uncertainty: c.1.magnitude_uncertainty,
            })
        })
        .collect();
    let k = units.len();
    let mean = units.iter().map(|u| u.magnitude).sum::<f64>() / k.max(1) as f64;
    let spread = if k > 1 {
        (units
            .iter()
            .map(|u| (u.magnitude - mean).powi(2))
            .sum::<f64>()
            / (k - 1) as f64)
            .sqrt()
    } else {
        f64::NAN
    };
    let evidence = f
        .steps
        .iter()
        .find(|s| s.named == Some(e))
        .and_then(|s| s.pooled.iter().find(|(p, _)| p.effect == e))
        .map(|(p, r)| pooled_report(f, p, *r))
        .expect("a design cause was named at a step");
    DesignCause {
        effect: e.key().into(),
        joint: e.with(|t| t.location()),
        order: e.with(|t| t.order()),
        magnitude: mean,
        uncertainty: spread / (k as f64).sqrt(),
        spread,
        unit: e.with(|t| t.unit()).into(),
        term: e.spec(),
        description: e.describe() + e.with(|t| t.physical()),
        units,
        evidence,
    }
}

fn unit_report(u: &UnitResult) -> UnitReport {
    UnitReport {
        unit: u.name.clone(),
        file: u.file.clone(),
        sessions: u.sessions,
        cannot_test: u.cannot_test.clone(),
        causes: u
            .causes
            .iter()
            .map(|(l, c)| UnitCause {
                level: match l {
                    Level::Design => "design",
                    Level::Unit => "unit",
                },
                cause: cause_report(c),
            })
            .collect(),
        holdout_rms_um: u.baseline.as_ref().map(|h| h.summary.all.rms_um),
        holdout_rms_um_after: u.extended.as_ref().map(|h| h.summary.all.rms_um),
        strongest: u.tests.iter().take(3).map(unit_test_report).collect(),
    }
}

fn pair_report(p: &Pair, names: &[String]) -> PairReport {
    PairReport {
        a: names[p.a].clone(),
        b: names[p.b].clone(),
        pair: p.clone(),
    }
}

/// Builds the report; `naming` says how unit names were made, `arms` how the recordings
/// (named `recordings`, file order) were grouped into the fleet's units.
pub fn build(
    f: &Fleet,
    naming: &str,
    arms: &Arms,
    recordings: &[String],
    pooled: &super::fleet_pooled::PooledFleet,
) -> FleetReport {
    let arm_reports = arms
        .groups
        .iter()
        .map(|g| ArmReport {
            arm: g.arm.clone(),
            recordings: g
                .recordings
                .iter()
                .map(|&i| recordings[i].clone())
                .collect(),
            evidence: ArmEvidence {
                rule: arms.rule.clone(),
                pairs: arms
                    .pairs
                    .iter()
                    .filter(|p| g.recordings.contains(&p.a) && g.recordings.contains(&p.b))
                    .map(|p| pair_report(p, recordings))
                    .collect(),
            },
        })
        .collect();
    let left = f
        .steps
        .last()
        .map(|s| {
            s.pooled
                .iter()
                .filter(|(p, _)| !f.design.contains(&p.effect))
                .take(5)
                .map(|(p, r)| pooled_report(f, p, *r))
                .collect()
        })
        .unwrap_or_default();
    FleetReport {
        design: DesignReport {
            causes: f.design.iter().map(|e| design_cause(f, *e)).collect(),
            tested_units: f.tested_units,
            alpha: f.alpha,
            strongest_left_out: left,
        },
        units: f.units.iter().map(unit_report).collect(),
        naming: naming.into(),
        arms: arm_reports,
        pairs: arms
            .pairs
            .iter()
            .map(|p| pair_report(p, recordings))
            .collect(),
        uncompared: arms
            .uncompared
            .iter()
            .map(|(i, why)| (recordings[*i].clone(), why.clone()))
            .collect(),
        halves: arms
            .splits
            .iter()
            .map(|h| HalvesReport {
                recording: recordings[h.recording].clone(),
                chi2: h.chi2,
                dof: h.dof,
            })
            .collect(),
        overdispersion: arms
            .overdispersion
            .map(|(phi, dof)| Overdispersion { phi, dof }),
        pooled: pooled.clone(),
    }
}

fn um(x: Option<f64>) -> String {
    x.map_or("—".into(), |x| format!("{x:.2}"))
}

fn pair_text(p: &PairReport) -> String {
    format!(
        "{} ~ {}: χ² = {:.1} on {}, F = {:.2}, p = {:.1e}{}",
        p.a,
        p.b,
        p.pair.chi2,
        p.pair.dof,
        p.pair.f,
        p.pair.p_value,
        p.pair.tip_rms_um.map_or(String::new(), |t| format!(
            "; predicted balls {t:.1} µm apart (RMS over both recordings' poses, probe and \
             frame out)"
        ))
    )
}

impl FleetReport {
    /// The arms section: each arm of several recordings with its pairs, the closest pairs
    /// left apart, and the recordings not compared.
    fn arms_text(&self, s: &mut String) {
        let Some(rule) = self.arms.first().map(|a| &a.evidence.rule) else {
            return;
        };
        // `--each-file-an-arm`: nothing to say beyond the rule.
        if self.pairs.is_empty() && self.arms.iter().all(|a| a.recordings.len() == 1) {
            let _ = writeln!(s, "\narms: {rule}");
            return;
        }
        let _ = writeln!(s, "\narms ({rule})");
        if let Some(o) = &self.overdispersion {
            let _ = writeln!(
                s,
                "  φ̂ = {:.2} on D = {} (alternate-session halves of {} recordings)",
                o.phi,
                o.dof,
                self.halves.len()
            );
        }
        for a in &self.arms {
            let _ = writeln!(s, "  {}: {}", a.arm, a.recordings.join(" + "));
            for p in &a.evidence.pairs {
                let _ = writeln!(s, "    {}", pair_text(p));
            }
        }
        let mut apart: Vec<&PairReport> = self
            .pairs
            .iter()
            .filter(|p| {
                !self
                    .arms
                    .iter()
                    .any(|a| a.recordings.contains(&p.a) && a.recordings.contains(&p.b))
            })
            .collect();
        apart.sort_by(|x, y| x.pair.f.total_cmp(&y.pair.f));
        if !apart.is_empty() {
            let _ = writeln!(s, "  closest pairs of different arms:");
            for p in apart.iter().take(3) {
                let _ = writeln!(s, "    {}", pair_text(p));
            }
        }
        for (r, why) in &self.uncompared {
            let _ = writeln!(s, "  {r}: not compared, {why}");
        }
    }

    /// The report as JSON.
    pub fn json(&self) -> String {
        pretty_json(self)
    }

    /// The report as text.
    pub fn text(&self) -> String {
        let mut s = String::new();
        let d = &self.design;
        let _ = writeln!(
            s,
            "fleet diagnosis: {} recordings of {} arms (the pooled test's units), {} arms with a \
             held-out test; names: {}",
            self.units.len(),
            self.arms.len(),
            d.tested_units,
            self.naming
        );
        self.arms_text(&mut s);
        let _ = writeln!(
            s,
            "\ndesign-level causes (random-effects pooling of each unit's held-out log RMS \
             ratio, Holm at α = {})",
            d.alpha
        );
        if d.causes.is_empty() {
            let _ = writeln!(s, "  none");
        }
        for c in &d.causes {
            let e = &c.evidence;
            let _ = writeln!(
                s,
                "  {}: {}\n    {} of {} units gain; pooled ln RMS ratio {:.3} ± {:.3} \
                 (τ² = {:.3}), t = {:.1}, p = {:.1e}\n    magnitude {:.3e} ± {:.1e} {} \
                 (units' spread {:.1e})",
                c.term,
                c.description,
                e.pooling.units_gaining,
                e.pooling.units,
                e.pooling.mean_log_ratio,
                e.pooling.se,
                e.pooling.tau2,
                e.pooling.t,
                e.pooling.p,
                c.magnitude,
                c.uncertainty,
                c.unit,
                c.spread
            );
        }
        if !d.strongest_left_out.is_empty() {
            let _ = writeln!(s, "  strongest not named:");
            for p in &d.strongest_left_out {
                let _ = writeln!(
                    s,
                    "    {:<26} {}/{} units gain; ln ratio {:+.3} ± {:.3} (τ² = {:.3}), t = \
                     {:.1}, p = {:.1e}",
                    p.term,
                    p.pooling.units_gaining,
                    p.pooling.units,
                    p.pooling.mean_log_ratio,
                    p.pooling.se,
                    p.pooling.tau2,
                    p.pooling.t,
                    p.pooling.p
                );
            }
        }
        self.pooled.write_text(&mut s);
        let _ = writeln!(
            s,
            "\nunits (held-out RMS, sessions held out one at a time, µm)"
        );
        for u in &self.units {
            let _ = writeln!(
                s,
                "  {} ({} session{}): {} → {}{}",
                u.unit,
                u.sessions,
                if u.sessions == 1 { "" } else { "s" },
                um(u.holdout_rms_um),
                um(u.holdout_rms_um_after),
                u.cannot_test
                    .as_ref()
                    .map_or(String::new(), |c| format!("; {c}"))
            );
            for c in &u.causes {
                let _ = writeln!(
                    s,
                    "    {} [{}]: {:.3e} ± {:.1e} {}; held-out RMS after {:.2} µm",
                    c.cause.term,
                    c.level,
                    c.cause.magnitude,
                    c.cause.uncertainty,
                    c.cause.unit,
                    c.cause.holdout_rms_um_after
                );
            }
        }
        s
    }
}
