//! Acceptance and reverification tests (`spec/acceptance-tests.md`): ISO 10360-12's P_Size,
//! P_Form and L_Dia, the length error E_Uni, and ASME B89.4.22's single-point articulation,
//! computed from the ball centres the calibrated model gives for measured rows, with the
//! ISO 14253-1 decision against maximum permissible errors.
//!
//! - `geometry::sphere` (a leaf module, shared with the fit): least-squares spheres (free, and
//!   with a known radius).
//! - [`statistics`]: each test's value per group and the test's result.
//! - [`mpe`]: the MPE file and the decision rule.
//! - [`virtual_test`]: each statistic predicted from the calibration's uncertainty budget.
//! - [`verdict`]: the overall decision and `armcal check`'s exit code.

pub mod mpe;
pub mod plots;
pub mod statistics;
pub mod verdict;
pub mod virtual_test;

use crate::data::Dataset;
use mpe::{Decision, Mpe};
use nalgebra::Vector3;
use quatarm_ref::arm::Arm;
use statistics::{StatError, Test, Value};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use virtual_test::Interval;

/// One group's test in the report (µm).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Row {
    /// The test.
    pub test: Test,
    /// The data's group.
    pub group: i64,
    /// The value (µm).
    pub value_um: f64,
    /// The bar length of an E_Uni value (mm).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub length_mm: Option<f64>,
    /// The MPE (µm), where given.
    pub mpe_um: Option<f64>,
    /// The value's expanded uncertainty U (k = 2, µm).
    #[serde(rename = "U_um")]
    pub u_um: f64,
    /// Where U comes from.
    pub u_source: USource,
    /// The decision, where an MPE is given.
    pub decision: Option<Decision>,
    /// The virtual test's prediction (µm), where the calibration has a budget.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub predicted_um: Option<Interval>,
    /// Whether the measured value lies outside its predicted 95 % interval: the arm, the
    /// artefact or the budget is not what the calibration says.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub outside_predicted: Option<bool>,
}

/// A whole check.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Check {
    /// Each test's result (µm): the worst group, sign kept for P_Size and E_Uni.
    pub results: BTreeMap<&'static str, f64>,
    /// The group each result comes from.
    pub worst_group: BTreeMap<&'static str, i64>,
    /// Every group's value.
    pub tests: Vec<Row>,
    /// The stylus ball diameter used (mm).
    pub ball_diameter_mm: f64,
    /// The effective stylus ball diameter each plain sphere group measures (B89.4.22).
    pub effective_ball_diameter: Vec<EffectiveDiameter>,
    /// The overall decision against the MPE file.
    pub verdict: verdict::Verdict,
}

/// ASME B89.4.22's effective diameter test: the stylus ball's diameter as the arm probes with
/// it, d_eff = 2 R − D from the free sphere through the ball centres (R) of a test sphere of
/// calibrated diameter D. It is P_Size's own fit read the other way (d_eff = d + P_Size), so
/// it is taken from the P_Size value, not fitted again: the diameter to write into
/// `[probe] ball_diameter` after a probe change.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct EffectiveDiameter {
    /// The sphere group.
    pub group: i64,
    /// d_eff (mm).
    pub diameter_mm: f64,
}

/// The ball centres of every row by the calibrated model (the f64 reference, as
/// `armcal eval` gives them).
pub fn centres(arm: &Arm, data: &Dataset) -> Vec<Vector3<f64>> {
    let mounted = crate::fit::probes::Mounted::new(arm);
    data.rows.iter().map(|r| mounted.tip(r)).collect()
}

/// The mean of the centres of `rows`: a bar end's, a cone's or a sphere's centroid.
pub fn mean_of(rows: &[usize], centres: &[Vector3<f64>]) -> Vector3<f64> {
    rows.iter().map(|&i| centres[i]).sum::<Vector3<f64>>() / rows.len() as f64
}

/// Where a test value's expanded uncertainty U comes from (`spec/acceptance-tests.md`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum USource {
    /// The MPE file's `test_uncertainty`.
    MpeFile,
    /// Propagated from the calibration's `[uncertainty]` budget: twice the standard
    /// deviation of the value over the virtual test's Monte Carlo draws (k = 2).
    Budget,
    /// Neither: U = 0, the value taken as exact.
    None,
}

impl USource {
    /// As the report prints it beside U.
    pub fn words(self) -> &'static str {
        match self {
            USource::MpeFile => "from the MPE file",
            USource::Budget => "from the budget",
            USource::None => "none: U = 0",
        }
    }
}

/// Runs every test the data supports. U is the MPE file's `test_uncertainty` where it gives
/// one; else, with the calibration's budget (`prediction`, the virtual test over it), the
/// value's propagated uncertainty: twice its standard deviation under the budget (k = 2;
/// why Monte Carlo and not first order: `docs/spec-reading.md`, "A test value's
/// uncertainty"); else 0, said as such (`u_source`). `show_prediction`: the virtual test's
/// interval is printed beside the value (`check --predict`); without it the prediction only
/// gives U.
pub fn check(
    arm: &Arm,
    data: &Dataset,
    mpe: Option<&Mpe>,
    prediction: Option<&BTreeMap<(Test, i64), Interval>>,
    show_prediction: bool,
) -> Result<Check, StatError> {
    let values = measure(arm, data)?;
    Ok(decide(arm, data, &values, mpe, prediction, show_prediction))
}

/// Every test value the data supports, with the calibrated model: what [`check`] decides on,
/// computed once where a command looks at the values before deciding (`check`'s misfit rail).
pub fn measure(arm: &Arm, data: &Dataset) -> Result<Vec<Value>, StatError> {
    let ball = |r: &crate::data::Row| crate::fit::probes::ball_diameter(arm, r);
    statistics::values(data, &centres(arm, data), &ball)
}

/// The report and decision of [`check`] on values already [`measure`]d.
pub fn decide(
    arm: &Arm,
    data: &Dataset,
    values: &[Value],
    mpe: Option<&Mpe>,
    prediction: Option<&BTreeMap<(Test, i64), Interval>>,
    show_prediction: bool,
) -> Check {
    let d = arm.probe.ball_diameter;
    // The ball of a sphere group's probe (one per group: the data reader's rule).
    let spheres = data.layout().sphere;
    let group_ball = |group: i64| {
        spheres.iter().find(|g| g.group == group).map_or(d, |g| {
            crate::fit::probes::sphere_ball_diameter(arm, data, g)
        })
    };
    let mut results = BTreeMap::new();
    let mut worst_group = BTreeMap::new();
    for t in Test::ALL {
        if let Some(v) = statistics::result(values, t) {
            results.insert(t.key(), v.value_mm * 1e3);
            worst_group.insert(t.key(), v.group);
        }
    }
    let tests: Vec<Row> = values
        .iter()
        .map(|v| {
            let predicted = prediction.and_then(|p| p.get(&(v.test, v.group)));
            let mut r = row(v, mpe, predicted);
            if !show_prediction {
                r.predicted_um = None;
            }
            r
        })
        .collect();
    let verdict = verdict::Verdict::of(&tests, mpe.map(Mpe::path));
    let effective_ball_diameter = values
        .iter()
        .filter(|v| v.test == Test::PSize)
        .map(|v| EffectiveDiameter {
            group: v.group,
            diameter_mm: group_ball(v.group) + v.value_mm,
        })
        .collect();
    Check {
        results,
        worst_group,
        tests,
        ball_diameter_mm: d,
        effective_ball_diameter,
        verdict,
    }
}

fn row(v: &Value, mpe: Option<&Mpe>, predicted: Option<&Interval>) -> Row {
    let limit = mpe.and_then(|m| m.of(v));
    let given = mpe.and_then(|m| m.test_uncertainty(v.test));
    let (u, source) = match (given, predicted) {
        (Some(u), _) => (u, USource::MpeFile),
        (None, Some(p)) => (2.0 * p.sd, USource::Budget),
        (None, None) => (0.0, USource::None),
    };
    let um = |i: &Interval| Interval {
        mean: i.mean * 1e3,
        lo: i.lo * 1e3,
        hi: i.hi * 1e3,
        sd: i.sd * 1e3,
    };
    let value_um = v.value_mm * 1e3;
    let predicted_um = predicted.map(um);
    Row {
        test: v.test,
        group: v.group,
        value_um,
        length_mm: v.length_mm,
        mpe_um: limit.map(|l| l * 1e3),
        u_um: u * 1e3,
        u_source: source,
        decision: limit.map(|l| Decision::of(v.value_mm, u, l)),
        outside_predicted: predicted_um.map(|p| value_um < p.lo || value_um > p.hi),
        predicted_um,
    }
}

impl Check {
    /// The report a metrologist reads: the tests by their standard names, each group's value
    /// with the MPE and the decision, then each test's result and its worst group, the notes
    /// and the verdict.
    pub fn text(&self) -> String {
        let mut s = String::new();
        self.values_text(&mut s);
        self.results_text(&mut s);
        self.notes_text(&mut s);
        let _ = writeln!(s, "{}", self.verdict.line());
        s
    }

    /// The effective stylus ball diameters as the reports list them: `d mm (group g), …`
    /// (`None` where no plain sphere group measures one).
    pub(crate) fn effective_ball_list(&self) -> Option<String> {
        if self.effective_ball_diameter.is_empty() {
            return None;
        }
        let each: Vec<String> = self
            .effective_ball_diameter
            .iter()
            .map(|e| format!("{:.4} mm (group {})", e.diameter_mm, e.group))
            .collect();
        Some(each.join(", "))
    }

    /// The heading and a line a group's value: bar length, value, MPE, U and its source, the
    /// decision and the predicted interval.
    fn values_text(&self, s: &mut String) {
        let _ = writeln!(
            s,
            "acceptance tests (spec/acceptance-tests.md), stylus ball {} mm",
            self.ball_diameter_mm
        );
        let _ = writeln!(
            s,
            "{:<9} {:>6} {:>9} {:>11} {:>9} {:>8} {:<18} {:<14} predicted µm (95 %)",
            "test", "group", "bar mm", "value µm", "MPE µm", "U µm", "U source", "decision"
        );
        for r in &self.tests {
            let mpe = r.mpe_um.map_or("-".to_string(), |m| format!("{m:.2}"));
            let bar = r.length_mm.map_or("-".to_string(), |l| format!("{l:.1}"));
            let decision = r.decision.map_or("-", Decision::name);
            let predicted = r.predicted_um.map_or(String::new(), |p| {
                let flag = if r.outside_predicted == Some(true) {
                    "  OUTSIDE the predicted interval"
                } else {
                    ""
                };
                format!("{:.2} [{:.2}, {:.2}]{flag}", p.mean, p.lo, p.hi)
            });
            let _ = writeln!(
                s,
                "{:<9} {:>6} {:>9} {:>11.2} {:>9} {:>8.2} {:<18} {decision:<14} {predicted}",
                r.test.key(),
                r.group,
                bar,
                r.value_um,
                mpe,
                r.u_um,
                r.u_source.words()
            );
        }
    }

    /// Each test's result, its worst group and its decision over the groups: any fail fails,
    /// else any undecided is undecided.
    fn results_text(&self, s: &mut String) {
        let _ = writeln!(s, "results:");
        for (k, v) in &self.results {
            let decisions: Vec<&str> = self
                .tests
                .iter()
                .filter(|r| r.test.key() == *k)
                .filter_map(|r| r.decision.map(Decision::name))
                .collect();
            let overall = if decisions.is_empty() {
                "no MPE"
            } else if decisions.contains(&"fail") {
                "fail"
            } else if decisions.contains(&"cannot decide") {
                "cannot decide"
            } else {
                "pass"
            };
            let _ = writeln!(
                s,
                "  {k:<9} {v:>10.2} µm (worst group {}): {overall}",
                self.worst_group[k]
            );
        }
    }

    /// What the reader must know beside the values: the effective ball, decisions taken
    /// with U = 0, and values outside what the budget predicts.
    fn notes_text(&self, s: &mut String) {
        if let Some(each) = self.effective_ball_list() {
            let _ = writeln!(
                s,
                "effective stylus ball diameter (B89.4.22): {each}; the calibration file says {} mm",
                self.ball_diameter_mm
            );
        }
        if self
            .tests
            .iter()
            .any(|r| r.decision.is_some() && r.u_source == USource::None)
        {
            let _ = writeln!(
                s,
                "note: U = 0 where the MPE file gives no test_uncertainty and the calibration \
                 file has no [uncertainty] budget: the decision then takes the value as exact"
            );
        }
        let outside: Vec<String> = self
            .tests
            .iter()
            .filter(|r| r.outside_predicted == Some(true))
            .filter_map(|r| {
                r.predicted_um.map(|p| {
                    format!(
                        "{} group {}: {:.2} µm against [{:.2}, {:.2}]",
                        r.test.key(),
                        r.group,
                        r.value_um,
                        p.lo,
                        p.hi
                    )
                })
            })
            .collect();
        if !outside.is_empty() {
            let _ = writeln!(
                s,
                "warning: {} measured value(s) outside the 95 % interval the calibration's \
                 budget predicts ({}): the arm, the artefact or the budget is not what the \
                 calibration says",
                outside.len(),
                outside.join("; ")
            );
        }
    }
}
