//! The assumption under every gravity term, tested: is the arm's base level?
//!
//! A joint's gravity compliance bends it by g · a · ((p − o) × ẑ): the lever is computed with
//! gravity along the base's −z ([`quatarm_ref::forward::evaluate`]). The compliance is
//! identified only because the base is taken as level; with the base's rotation free it trades
//! against a tilt (issue 30: a fold fitted with the base free turned it by 2.7 rad and gave a
//! compliance of 3.0 instead of 0.84 µrad/mm). Where the data allow, the tilt can be measured
//! through the gravity terms themselves: tilting the base by (α, β) turns the direction of
//! gravity in the arm's frame, so every gravity deflection changes with the pose in a pattern
//! that no geometric unknown makes.
//!
//! **The estimate.** The base's tilt is the first joint's fixed tilt [δα, δβ] (the rotation
//! before joint 1, [`quatarm_ref::forward::tilt_matrix`]): it turns the whole arm about the
//! base's origin, which data without an instrument frame (`spat`, `length`) cannot see but
//! for gravity, and which a tracker's frame absorbs but for gravity. It is not a fitted unknown
//! (identifiability holds it: the frame takes the whole arm's rotation), so it is estimated by
//! profiling: the model (geometry and the gravity terms) is refitted with the tilt held at a
//! few values around the current one, the sum of squared residuals is fitted with a quadratic
//! in (α, β), and Newton steps go to its minimum ([`PROFILE_STEP`], at most
//! [`NEWTON_STEPS`]).
//!
//! **The test.** Sessions are the replications: the tilt is re-estimated without each session
//! in turn, and the jackknife covariance C = (n − 1)/n Σ (t₋ₛ − t̄)(t₋ₛ − t̄)ᵀ is the
//! estimate's. Level (α = β = 0) is tested with Hotelling's T² = t̂ᵀ C⁻¹ t̂, referred to
//! (2(n − 1)/(n − 2)) F(2, n − 2); each angle has its Student-t interval with n − 1 degrees of
//! freedom. The gravity compliances are reported level and tilted: what the assumption
//! changes.

use crate::data::Dataset;
use crate::fit::calib::{self};
use crate::fit::error::CalibError;
use crate::fit::finish::Fit;
use crate::fit::holdout::by_group;
use crate::params::{Effect, Param, ParamExt, Terms};
use crate::stats::MIN_UNITS;
use quatarm_ref::arm::Arm;

/// The assumption a gravity term is identified under, as a report says it beside the term.
pub const ASSUMPTION: &str = "a level base (gravity along the base's −z): with the base's \
    tilt free the compliance trades against it; the tilt is fitted and tested against level \
    where the data have 3 sessions or more";

/// The tilt step (rad) of the quadratic profile: large enough that the gravity deflections'
/// change is far above the refits' convergence noise on real data (a compliance of 1 µrad/mm
/// over a 500 mm lever and 0.05 rad moves the ball 25 µm), small enough that the profile is
/// still quadratic.
pub const PROFILE_STEP: f64 = 0.05;

/// Newton steps on the profile at most.
pub const NEWTON_STEPS: usize = 3;

/// A tilt larger than this (rad) is not an estimate but a flat profile.
pub const MAX_TILT: f64 = 0.5;

/// The base's tilt against level, measured through the gravity terms.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Level {
    /// The gravity terms it was measured with.
    pub terms: Vec<String>,
    /// Sessions (the jackknife's replications).
    pub sessions: usize,
    /// The tilt fitted on all sessions: [δα about the base x, δβ about y] (rad).
    pub tilt: [f64; 2],
    /// Jackknife standard errors of the two angles (rad).
    pub se: [f64; 2],
    /// Their correlation.
    pub correlation: f64,
    /// 95 % intervals of the two angles (Student's t, sessions − 1 degrees of freedom).
    pub interval: [[f64; 2]; 2],
    /// Each session's leave-one-out estimate: (group, tilt without it).
    pub without_session: Vec<(i64, [f64; 2])>,
    /// Hotelling's T² of level.
    pub t2: f64,
    /// Its p-value (F(2, sessions − 2)).
    pub p_value: f64,
    /// Whether level is rejected at 0.05.
    pub rejects_level: bool,
    /// Each gravity term's value with the base level and with the fitted tilt.
    pub gravity: Vec<(String, f64, f64)>,
    /// Residual RMS (µm, in sample) level and tilted.
    pub rms_um: [f64; 2],
}

/// The sum of squared residuals of `fit` on `data` (mm²).
fn ss(fit: &Fit, data: &Dataset) -> Result<f64, CalibError> {
    super::nested::session_ss(fit, data).map_err(CalibError::Mismatch)
}

/// The start arm with its base tilted to `tilt` (the first joint's fixed tilt).
fn at_tilt(start: &Arm, tilt: [f64; 2]) -> Arm {
    let mut a = start.clone();
    a.joints[0].tilt = tilt;
    a
}

/// The fit and its squared residuals with the tilt held at `tilt`.
fn fit_at(
    start: &Arm,
    data: &Dataset,
    opts: &crate::fit::options::Options,
    tilt: [f64; 2],
) -> Result<(Fit, f64), CalibError> {
    let fit = calib::calibrate(&at_tilt(start, tilt), data, opts)?;
    let s = ss(&fit, data)?;
    Ok((fit, s))
}

/// The profile's minimum from `from`: Newton steps on a quadratic fitted to six refits.
fn profile(
    start: &Arm,
    data: &Dataset,
    opts: &crate::fit::options::Options,
    from: [f64; 2],
) -> Result<[f64; 2], CalibError> {
    let h = PROFILE_STEP;
    let mut x = from;
    for _ in 0..NEWTON_STEPS {
        let f = |dx: f64, dy: f64| -> Result<f64, CalibError> {
            Ok(fit_at(start, data, opts, [x[0] + dx, x[1] + dy])?.1)
        };
        let f0 = f(0.0, 0.0)?;
        let (fap, fam, fbp, fbm, fab) =
            (f(h, 0.0)?, f(-h, 0.0)?, f(0.0, h)?, f(0.0, -h)?, f(h, h)?);
        let g = [(fap - fam) / (2.0 * h), (fbp - fbm) / (2.0 * h)];
        let haa = (fap - 2.0 * f0 + fam) / (h * h);
        let hbb = (fbp - 2.0 * f0 + fbm) / (h * h);
        let hab = (fab - fap - fbp + f0) / (h * h);
        let det = haa * hbb - hab * hab;
        if !(haa > 0.0 && det > 0.0) {
            return Err(CalibError::Mismatch(
                "the base tilt is not determined: the sum of squares has no minimum in it \
                 (the gravity terms are too small to see the direction of gravity)"
                    .into(),
            ));
        }
        let step = [
            -(hbb * g[0] - hab * g[1]) / det,
            -(haa * g[1] - hab * g[0]) / det,
        ];
        x = [x[0] + step[0], x[1] + step[1]];
        if x[0].hypot(x[1]) > MAX_TILT {
            return Err(CalibError::Mismatch(format!(
                "the base tilt is not determined: the profile's minimum runs beyond {MAX_TILT} \
                 rad"
            )));
        }
        if step[0].hypot(step[1]) < 1e-4 {
            break;
        }
    }
    Ok(x)
}

/// Measures the base's tilt with the gravity terms `gravity` (and the geometric model) on
/// `data`, and tests it against level (see the module's text). Refused with fewer than
/// [`MIN_UNITS`] sessions or no gravity term.
pub fn test_level(
    start: &Arm,
    data: &Dataset,
    opts: &crate::fit::options::Options,
    gravity: &[Effect],
) -> Result<Level, CalibError> {
    let folds = by_group(data);
    let n = folds.len();
    if n < MIN_UNITS {
        return Err(CalibError::Mismatch(format!(
            "the base tilt cannot be tested: {n} session{}, the jackknife needs {MIN_UNITS}",
            if n == 1 { "" } else { "s" }
        )));
    }
    let params: Vec<Param> = gravity.iter().flat_map(|e| e.params()).collect();
    if params.is_empty() || gravity.iter().any(|e| !matches!(e, Effect::Gravity(_))) {
        return Err(CalibError::Mismatch(
            "the base tilt is measured through gravity terms only".into(),
        ));
    }
    let mut hold = opts.hold.clone();
    hold.extend([Param::Tilt(0, 0), Param::Tilt(0, 1)]);
    let o = crate::fit::options::Options {
        terms: Terms::with(gravity),
        hold,
        ..opts.clone()
    };
    let level = start.joints[0].tilt;
    let tilt = profile(start, data, &o, level)?;
    let mut without = Vec::new();
    for out in &folds {
        let keep: Vec<usize> = (0..data.rows.len()).filter(|i| !out.contains(i)).collect();
        let t = profile(start, &data.subset(&keep), &o, tilt)?;
        without.push((data.rows[out[0]].group, t));
    }
    let (fit_level, ss_level) = fit_at(start, data, &o, level)?;
    let (fit_tilted, ss_tilted) = fit_at(start, data, &o, tilt)?;
    let rows = data.rows.len().max(1) as f64;
    let gravity_values = gravity
        .iter()
        .zip(&params)
        .map(|(e, p)| (e.spec(), p.value(&fit_level.arm), p.value(&fit_tilted.arm)))
        .collect();
    let d = [tilt[0] - level[0], tilt[1] - level[1]];
    Ok(jackknife(
        gravity.iter().map(|e| e.spec()).collect(),
        d,
        without
            .into_iter()
            .map(|(g, t)| (g, [t[0] - level[0], t[1] - level[1]]))
            .collect(),
        gravity_values,
        [
            1e3 * (ss_level / rows).sqrt(),
            1e3 * (ss_tilted / rows).sqrt(),
        ],
    ))
}

/// The jackknife covariance of the tilt `tilt` from its leave-one-out replicates, Hotelling's
/// test of level and the intervals.
fn jackknife(
    terms: Vec<String>,
    tilt: [f64; 2],
    without_session: Vec<(i64, [f64; 2])>,
    gravity: Vec<(String, f64, f64)>,
    rms_um: [f64; 2],
) -> Level {
    let n = without_session.len();
    let k = n as f64;
    let mean = [0, 1].map(|c| without_session.iter().map(|(_, t)| t[c]).sum::<f64>() / k);
    let cov = |a: usize, b: usize| {
        (k - 1.0) / k
            * without_session
                .iter()
                .map(|(_, t)| (t[a] - mean[a]) * (t[b] - mean[b]))
                .sum::<f64>()
    };
    let (caa, cbb, cab) = (cov(0, 0), cov(1, 1), cov(0, 1));
    let det = caa * cbb - cab * cab;
    let t2 = if det > 0.0 {
        (cbb * tilt[0] * tilt[0] - 2.0 * cab * tilt[0] * tilt[1] + caa * tilt[1] * tilt[1]) / det
    } else {
        f64::INFINITY
    };
    // T² (n − 2) / (2 (n − 1)) ~ F(2, n − 2).
    let p_value = if n > 2 && t2.is_finite() {
        let f = t2 * (k - 2.0) / (2.0 * (k - 1.0));
        crate::stats::f_tail(f, 2.0, k - 2.0)
    } else {
        0.0
    };
    let tc = crate::stats::t_critical(0.05, k - 1.0);
    let se = [caa.sqrt(), cbb.sqrt()];
    Level {
        terms,
        sessions: n,
        tilt,
        se,
        correlation: if se[0] > 0.0 && se[1] > 0.0 {
            cab / (se[0] * se[1])
        } else {
            0.0
        },
        interval: [0, 1].map(|c| [tilt[c] - tc * se[c], tilt[c] + tc * se[c]]),
        without_session,
        t2,
        p_value,
        rejects_level: p_value < 0.05,
        gravity,
        rms_um,
    }
}

impl Level {
    /// The result in words, for a report.
    pub fn summary(&self) -> String {
        let deg = 180.0 / std::f64::consts::PI;
        let g: Vec<String> = self
            .gravity
            .iter()
            .map(|(t, a, b)| format!("{t} {:.3} → {:.3} µrad/mm", a * 1e6, b * 1e6))
            .collect();
        format!(
            "base tilt fitted through {}: δα = {:+.2}° [{:+.2}, {:+.2}], δβ = {:+.2}° [{:+.2}, \
             {:+.2}] (95 %, jackknife over {} sessions); level {} (Hotelling T² = {:.2}, p = \
             {:.3}); with the tilt free: {}",
            self.terms.join(" "),
            self.tilt[0] * deg,
            self.interval[0][0] * deg,
            self.interval[0][1] * deg,
            self.tilt[1] * deg,
            self.interval[1][0] * deg,
            self.interval[1][1] * deg,
            self.sessions,
            if self.rejects_level {
                "rejected"
            } else {
                "not rejected"
            },
            self.t2,
            self.p_value,
            g.join(", ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hotelling_of_a_tilt_far_outside_its_scatter_rejects_level() {
        let rep: Vec<(i64, [f64; 2])> = (0..6)
            .map(|i| {
                (
                    i,
                    [
                        0.1 + 0.002 * (i as f64 - 2.5),
                        -0.05 + 0.001 * (i % 3) as f64,
                    ],
                )
            })
            .collect();
        let l = jackknife(vec![], [0.1, -0.05], rep.clone(), vec![], [0.0; 2]);
        assert!(l.rejects_level && l.p_value < 1e-3, "{l:?}");
        assert!(l.interval[0][0] > 0.0 && l.interval[1][1] < 0.0);
        // The same scatter around a tilt of zero: level stands.
        let l = jackknife(vec![], [0.001, 0.0005], rep, vec![], [0.0; 2]);
        assert!(!l.rejects_level && l.p_value > 0.3, "{l:?}");
        assert!(l.interval[0][0] < 0.0 && l.interval[0][1] > 0.0);
    }
}
