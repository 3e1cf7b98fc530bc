//! The fleet diagnosis report ([`super::fleet`]): text, or JSON (`--json`) of the shape
//!
//! ```json
//! {"design": {"causes": [{"effect", "joint", "order", "magnitude", "uncertainty", "unit",
//!                         "term", "units": [{"unit", "magnitude", "uncertainty"}],
//!                         "evidence": {"z", "p_value", "tau2", …}}],
//!             "tested_units", "alpha", "strongest": […]},
//!  "units": [{"unit": "panda_3", "sessions", "cannot_test", "causes": [{"level": "design",
//!             …the single-arm report's cause…}], "holdout_rms_um", "holdout_rms_um_after"}]}
//! ```
//!
//! A design cause's `magnitude` is the mean of the units' fitted magnitudes, its
//! `uncertainty` the standard error of that mean over the units (the units' spread / √k) and
//! `spread` their standard deviation: the design's typical size and how much units differ.

use super::fleet::{Fleet, Level, Pooled, Pooling, UnitResult, UnitTest};
use super::report::{cause_report, CauseReport};
use crate::params::Effect;
use crate::report::pretty_json;
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
    /// Every pooled unit's own mean log-ratio and its standard error.
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
    /// Units with a held-out test (enough sessions).
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

/// The whole report.
#[derive(Clone, Debug, Serialize)]
pub struct FleetReport {
    /// The design level.
    pub design: DesignReport,
    /// Every unit.
    pub units: Vec<UnitReport>,
    /// How unit names were made.
    pub naming: String,
}

fn pooled_report(f: &Fleet, p: &Pooled, significant: bool) -> PooledReport {
    PooledReport {
        term: p.effect.spec(),
        pooling: p.pooling,
        per_unit: p
            .per_unit
            .iter()
            .map(|&(u, y, se)| UnitLogRatio {
                unit: f.units[u].name.clone(),
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

/// Builds the report; `naming` says how unit names were made.
pub fn build(f: &Fleet, naming: &str) -> FleetReport {
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
    }
}

fn um(x: Option<f64>) -> String {
    x.map_or("—".into(), |x| format!("{x:.2}"))
}

impl FleetReport {
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
            "fleet diagnosis: {} units, {} with a held-out test; names: {}",
            self.units.len(),
            d.tested_units,
            self.naming
        );
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
