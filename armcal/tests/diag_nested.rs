//! The nested held-out test of a diagnosis ([`armcal::diagnose::nested`]): the whole selection
//! rerun without each session finds a real cause in every fold and predicts every held-out
//! session better; on an arm with nothing hidden it names nothing and claims nothing.

mod common;

use armcal::data::{Dataset, Kind};
use armcal::diagnose::{nested, Options};
use armcal::params::Effect;
use armcal::sim;
use quatarm_ref::arm::Arm;

/// A `default-6` arm with its own geometric errors (seed `seed`) and a shoulder compliance
/// `g` (rad/mm), measured by a tracker: `rows` points in `sessions` sessions.
fn arm_data(seed: u64, g: f64, rows: usize, sessions: usize) -> Dataset {
    let mut rng = armcal::rng::rng(seed);
    let mut truth = sim::perturb(&Arm::default6(), 3e-4, 0.3, &mut rng);
    truth.joints[1].gravity = g;
    let d = sim::simulate(&truth, &sim::Options::new(Kind::Point, rows), &mut rng)
        .unwrap()
        .data;
    common::in_sessions(d, sessions, "(simulated arm)")
}

fn options() -> Options {
    Options {
        // Enough harmonics for the shoulder's first-order wave (a near alias of its
        // compliance) to compete, few enough for a short run.
        max_order: 1,
        ..Options::default()
    }
}

#[test]
fn a_real_cause_holds_with_the_selection_inside_each_fold() {
    let data = arm_data(300, 4.0e-8, 200, 5);
    let n = nested::nested(&Arm::default6(), &data, &options()).unwrap();
    assert!(n.failed.is_empty(), "{:?}", n.failed);
    assert_eq!(n.sessions(), 5);
    assert_eq!(n.df(), 4);
    // Every fold, diagnosing the four others, names the compliance, and nothing else.
    assert_eq!(n.chosen, vec![(Effect::Gravity(1), 5)], "{}", n.headline());
    assert_eq!(n.better, 5, "{}", n.headline());
    assert_eq!(n.ties, 0);
    assert!((n.sign_p - 1.0 / 32.0).abs() < 1e-12);
    assert_eq!(n.sign_p, n.min_p);
    assert!(n.t() > 3.0 && n.t_p() < 0.01, "{}", n.headline());
    let (before, after) = n.rms_um();
    assert!(after < 0.7 * before, "{before} → {after}");
    assert!(n
        .headline()
        .contains("5 sessions: no sign test can reach p < 0.031"));
}

#[test]
fn nothing_hidden_claims_nothing() {
    let data = arm_data(301, 0.0, 160, 4);
    let n = nested::nested(&Arm::default6(), &data, &options()).unwrap();
    assert_eq!(n.sessions(), 4);
    assert!(n.chosen.is_empty(), "{}", n.headline());
    // Every fold ties: no session better, the sign test gives 1, and the t-test nothing.
    assert_eq!((n.better, n.ties), (0, 4));
    assert_eq!(n.sign_p, 1.0);
    assert_eq!(n.min_p, 0.0625);
    assert!(n.t_p() >= 0.5, "{}", n.headline());
}

#[test]
fn one_session_is_refused() {
    let data = arm_data(302, 0.0, 40, 1);
    let e = nested::nested(&Arm::default6(), &data, &options()).unwrap_err();
    assert!(e.to_string().contains("single group"), "{e}");
}

#[test]
fn diagnose_by_group_reports_the_nested_test() {
    let dir = common::workdir("nested-cli");
    let data = arm_data(303, 4.0e-8, 160, 4);
    std::fs::write(dir.join("arm.csv"), data.to_csv(&["simulated arm"])).unwrap();
    let out = common::armcal_ok(
        &[
            "diagnose",
            "arm.csv",
            "--by-group",
            "--json",
            "--max-order",
            "1",
        ],
        &dir,
    );
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let n = &j["nested"];
    assert_eq!(n["sessions"], 4, "{j:#}");
    assert_eq!(n["t_df"], 3);
    assert_eq!(n["smallest_possible_p"], 0.0625);
    assert_eq!(n["per_session"].as_array().unwrap().len(), 4);
    assert!(n["summary"]
        .as_str()
        .unwrap()
        .contains("4 sessions: no sign test can reach p < 0.062"));
    assert!(
        j["sessions_from"]
            .as_str()
            .unwrap()
            .contains("the `group` column of arm.csv: 4 groups"),
        "{j:#}"
    );
    // The named compliance rests on a level base: said beside it, and tested or why not.
    let causes = j["causes"].as_array().unwrap();
    assert!(causes
        .iter()
        .all(|c| c["effect"] != "gravity_compliance" || c["assumption"].is_string()));
    if causes.iter().any(|c| c["effect"] == "gravity_compliance") {
        assert!(
            j.get("level").is_some() || j["level_not_tested"].is_string(),
            "{j:#}"
        );
    }
    // Without --by-group (k folds of rows) the sessions are still there: the nested test runs
    // on them.
    let out = common::armcal_ok(&["diagnose", "arm.csv", "--json", "--max-order", "1"], &dir);
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["nested"]["sessions"], 4, "{j:#}");
    assert!(j.get("nested_not_run").is_none());
    // One session: no nested test, and the report says why.
    let one = arm_data(304, 0.0, 40, 1);
    std::fs::write(dir.join("one.csv"), one.to_csv(&["one session"])).unwrap();
    let out = common::armcal_ok(&["diagnose", "one.csv", "--json", "--max-order", "1"], &dir);
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(j.get("nested").is_none());
    let why = j["nested_not_run"].as_str().unwrap();
    assert!(why.contains("1 group"), "{why}");
    let text = common::armcal_ok(&["diagnose", "one.csv", "--max-order", "1"], &dir);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(
        text.contains("sessions: the `group` column of one.csv: 1 group")
            && text.contains("nested held-out test): not run"),
        "{text}"
    );
}
