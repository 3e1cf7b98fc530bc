//! The held-out test of a whole diagnosis: the selection rerun inside each fold.
//!
//! A diagnosis chooses its causes by looking at every session (the in-sample F-test, the
//! linearised cross-validation, the refits that confirm each cause). Its own held-out figure
//! then judges the chosen model on sessions that took part in choosing it, so it is
//! optimistic by however much the choice fitted the noise of those sessions. The honest test
//! repeats the *whole* procedure without the session it scores: for each session s,
//!
//! 1. diagnose the other sessions ([`super::diagnose`], their own sessions held out one at a
//!    time inside), which names some causes E₋ₛ (possibly none, possibly other ones than on
//!    all data);
//! 2. the geometric model and the geometric model + E₋ₛ, both fitted on the other sessions,
//!    predict session s: its held-out mean squared error per row before and after.
//!
//! Session s never took part in choosing nor in fitting what it scores. The evidence is then
//! over sessions (the replications; rows of one session share its placement and its day):
//! - **sessions better**: on how many the diagnosed model predicts better (a fold that names
//!   nothing ties, and a tie counts as not better);
//! - **the paired t-test** of the per-session mean squared errors, sessions − 1 degrees of
//!   freedom ([`Paired`]);
//! - **the exact sign test** ([`sign_test_p`]), which assumes nothing about how the gains are
//!   distributed;
//! - **the smallest p the sessions allow** ([`min_sign_p`]): ½ⁿ; with 4 sessions no sign
//!   test can reach p < 0.0625, whatever the data;
//! - **how often each cause was chosen** across the folds: a cause chosen in every fold is
//!   stable, one chosen in half of them is the selection's noise as much as the arm's.

use super::{diagnose, FoldChoice, Options};
use crate::data::{Dataset, Kind};
use crate::fit::error::CalibError;
use crate::fit::finish::Fit;
use crate::fit::residuals::residuals;
use crate::params::Effect;
use crate::stats::{min_sign_p, sign_test_p, Paired};
use quatarm_ref::arm::Arm;
use std::collections::BTreeMap;

/// One session scored by the diagnosis of the others.
#[derive(Clone, Debug)]
pub struct Fold {
    /// The session held out (its group number).
    pub group: i64,
    /// Its rows.
    pub rows: usize,
    /// The causes the diagnosis of the other sessions named, in the order named.
    pub chosen: Vec<Effect>,
    /// Mean squared error per row (mm²) of the geometric model fitted on the others.
    pub before_ms: f64,
    /// The same for the geometric model + `chosen` fitted on the others (equal to
    /// `before_ms` when nothing was chosen).
    pub after_ms: f64,
    /// The geometric model fitted on the other sessions.
    pub geometric: Fit,
    /// The diagnosed model fitted on the other sessions.
    pub extended: Fit,
}

/// The nested held-out test of a diagnosis.
#[derive(Clone, Debug)]
pub struct Nested {
    /// Every session scored, in group order.
    pub folds: Vec<Fold>,
    /// Sessions that could not be scored (group, reason): their training part could not be
    /// diagnosed or fitted.
    pub failed: Vec<(i64, String)>,
    /// Every cause chosen in some fold, with how many folds chose it (most often first).
    pub chosen: Vec<(Effect, usize)>,
    /// Sessions on which the diagnosed model predicts strictly better.
    pub better: usize,
    /// Sessions with exactly the same error (the fold named nothing).
    pub ties: usize,
    /// Paired comparison of the per-session mean squared errors (before, after).
    pub paired: Paired,
    /// Exact one-sided sign-test p (ties counted as not better).
    pub sign_p: f64,
    /// The smallest p a sign test on this many sessions can give.
    pub min_p: f64,
}

impl Nested {
    /// Sessions scored.
    pub fn sessions(&self) -> usize {
        self.folds.len()
    }

    /// The paired t statistic.
    pub fn t(&self) -> f64 {
        self.paired.z()
    }

    /// Its degrees of freedom (sessions − 1).
    pub fn df(&self) -> usize {
        self.sessions().saturating_sub(1)
    }

    /// One-sided p of the paired t-test (1 below [`crate::stats::MIN_UNITS`] sessions).
    pub fn t_p(&self) -> f64 {
        self.paired.p_value()
    }

    /// Root of the mean over sessions of the per-row mean squared error, before and after
    /// (µm): every session weighs the same.
    pub fn rms_um(&self) -> (f64, f64) {
        let n = self.sessions().max(1) as f64;
        let b: f64 = self.folds.iter().map(|f| f.before_ms).sum::<f64>() / n;
        let a: f64 = self.folds.iter().map(|f| f.after_ms).sum::<f64>() / n;
        (1e3 * b.sqrt(), 1e3 * a.sqrt())
    }

    /// The headline in words: "better on 5 of 6 sessions, t = 3.1 (5 df), p = 0.013; sign
    /// test p = 0.109 (6 sessions: no sign test can reach p < 0.0156)".
    pub fn headline(&self) -> String {
        let n = self.sessions();
        if n == 0 {
            return "no session could be scored: the other sessions could not be diagnosed \
                    without it (a diagnosis needs two sessions to hold out)"
                .into();
        }
        let (b, a) = self.rms_um();
        let t = if self.df() >= 1 && self.paired.se.is_finite() {
            format!(
                "paired t = {:.2} ({} df, one-sided p = {:.2e})",
                self.t(),
                self.df(),
                self.t_p()
            )
        } else {
            "no paired t-test (fewer than two sessions)".into()
        };
        format!(
            "held-out RMS {b:.2} → {a:.2} µm; better on {} of {n} sessions ({} tied); {t}; \
             exact sign test p = {:.3} ({n} sessions: no sign test can reach p < {:.3})",
            self.better, self.ties, self.sign_p, self.min_p
        )
    }
}

/// Squared error of `fit` on `session` (mm²: every row's distance squared, and every bar's
/// length error squared), or why it cannot be judged.
pub fn session_ss(fit: &Fit, session: &Dataset) -> Result<f64, String> {
    if session.rows.iter().any(|r| r.kind == Kind::Point) && fit.frame.is_none() {
        return Err(
            "point rows held out, but the other sessions have none to fix the frame".into(),
        );
    }
    let r = residuals(&fit.arm, session, fit.frame);
    Ok(r.rows.iter().map(|v| v.norm_squared()).sum::<f64>()
        + r.lengths.iter().map(|(_, e)| e * e).sum::<f64>())
}

/// One fold: diagnose every session but `group`'s rows `out`, score them.
fn fold(
    start: &Arm,
    data: &Dataset,
    opts: &Options,
    group: i64,
    out: &[usize],
) -> Result<Fold, String> {
    let n = data.rows.len();
    let mut left = vec![false; n];
    out.iter().for_each(|&i| left[i] = true);
    let train: Vec<usize> = (0..n).filter(|&i| !left[i]).collect();
    let d = diagnose(start, &data.subset(&train), opts).map_err(|e| e.to_string())?;
    let session = data.subset(out);
    let before = session_ss(&d.baseline.fit, &session)?;
    let after = if d.extended.effects.is_empty() {
        before
    } else {
        session_ss(&d.extended.fit, &session)?
    };
    let rows = out.len().max(1) as f64;
    Ok(Fold {
        group,
        rows: out.len(),
        chosen: d.extended.effects.clone(),
        before_ms: before / rows,
        after_ms: after / rows,
        geometric: d.baseline.fit,
        extended: d.extended.fit,
    })
}

/// The nested held-out test of diagnosing `data` (see the module's text): one fold per group
/// number, each diagnosed with `opts` (its inner folds are forced to one group at a time).
/// Refused when the data have fewer than two groups.
pub fn nested(start: &Arm, data: &Dataset, opts: &Options) -> Result<Nested, CalibError> {
    let folds = crate::fit::holdout::by_group(data);
    if folds.len() < 2 {
        return Err(CalibError::Mismatch(
            "cannot rerun the selection inside held-out folds: the data form a single group".into(),
        ));
    }
    let inner = Options {
        folds: FoldChoice::ByGroup,
        ..opts.clone()
    };
    let mut scored = Vec::new();
    let mut failed = Vec::new();
    for out in &folds {
        let group = out.first().map_or(0, |&i| data.rows[i].group);
        match fold(start, data, &inner, group, out) {
            Ok(f) => scored.push(f),
            Err(e) => failed.push((group, e)),
        }
    }
    Ok(summarise(scored, failed))
}

/// The evidence over the scored folds.
pub fn summarise(folds: Vec<Fold>, failed: Vec<(i64, String)>) -> Nested {
    let mut counts: BTreeMap<Effect, usize> = BTreeMap::new();
    for f in &folds {
        for e in &f.chosen {
            *counts.entry(*e).or_default() += 1;
        }
    }
    let mut chosen: Vec<(Effect, usize)> = counts.into_iter().collect();
    chosen.sort_by_key(|c| std::cmp::Reverse(c.1));
    let better = folds.iter().filter(|f| f.after_ms < f.before_ms).count();
    let ties = folds.iter().filter(|f| f.after_ms == f.before_ms).count();
    let before: Vec<f64> = folds.iter().map(|f| f.before_ms).collect();
    let after: Vec<f64> = folds.iter().map(|f| f.after_ms).collect();
    let n = folds.len();
    Nested {
        paired: Paired::of(&before, &after),
        sign_p: sign_test_p(better, n),
        min_p: min_sign_p(n),
        better,
        ties,
        chosen,
        folds,
        failed,
    }
}

/// The nested test as a report gives it (the headline of `armcal diagnose --by-group`).
#[derive(Clone, Debug, serde::Serialize)]
pub struct NestedReport {
    /// Sessions scored.
    pub sessions: usize,
    /// Sessions on which the diagnosed model predicts strictly better.
    pub sessions_better: usize,
    /// Sessions tied (their fold named nothing).
    pub sessions_tied: usize,
    /// Held-out RMS before and after over the sessions (µm, every session weighing the same).
    pub rms_um: [f64; 2],
    /// Paired t statistic of the per-session mean squared errors.
    pub t: f64,
    /// Its degrees of freedom.
    pub t_df: usize,
    /// Its one-sided p.
    pub t_p_value: f64,
    /// Exact one-sided sign-test p (ties counted as not better).
    pub sign_test_p_value: f64,
    /// The smallest p a sign test on this many sessions can give.
    pub smallest_possible_p: f64,
    /// Each cause chosen in some fold, and in how many of the folds.
    pub chosen: Vec<(String, usize)>,
    /// Per session: (group, causes chosen without it, RMS before, RMS after in µm).
    pub per_session: Vec<(i64, Vec<String>, f64, f64)>,
    /// Sessions that could not be scored, with the reason.
    pub failed: Vec<(i64, String)>,
    /// The headline in words.
    pub summary: String,
}

impl Nested {
    /// The report's form.
    pub fn report(&self) -> NestedReport {
        let (b, a) = self.rms_um();
        NestedReport {
            sessions: self.sessions(),
            sessions_better: self.better,
            sessions_tied: self.ties,
            rms_um: [b, a],
            t: self.t(),
            t_df: self.df(),
            t_p_value: self.t_p(),
            sign_test_p_value: self.sign_p,
            smallest_possible_p: self.min_p,
            chosen: self.chosen.iter().map(|(e, k)| (e.spec(), *k)).collect(),
            per_session: self
                .folds
                .iter()
                .map(|f| {
                    (
                        f.group,
                        f.chosen.iter().map(|e| e.spec()).collect(),
                        1e3 * f.before_ms.sqrt(),
                        1e3 * f.after_ms.sqrt(),
                    )
                })
                .collect(),
            failed: self.failed.clone(),
            summary: self.headline(),
        }
    }
}

impl NestedReport {
    /// The text lines of the headline.
    pub fn write_text(&self, s: &mut String) {
        use std::fmt::Write;
        let _ = writeln!(
            s,
            "  the whole selection rerun without each session (nested held-out test): {}",
            self.summary
        );
        let chosen: Vec<String> = self
            .chosen
            .iter()
            .map(|(e, k)| format!("{e} in {k} of {}", self.sessions))
            .collect();
        let _ = writeln!(
            s,
            "    chosen across the folds: {}",
            if chosen.is_empty() {
                "nothing".to_string()
            } else {
                chosen.join(", ")
            }
        );
        for (g, reason) in &self.failed {
            let _ = writeln!(s, "    session {g} not scored: {reason}");
        }
    }
}
