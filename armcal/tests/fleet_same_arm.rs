//! `armcal diagnose --fleet`: recordings of one physical arm are told from the data and made
//! one unit of the fleet test; a hand grouping is honoured; bad groupings are refused with the
//! option and the recording named.

mod common;

use armcal::data::{Dataset, Kind};
use armcal::diagnose::fleet::{self, UnitData};
use armcal::diagnose::same_arm::{self, Grouping};
use armcal::sim;
use quatarm_ref::arm::Arm;
use serde_json::Value;

/// An arm of `default-6` with its own geometric errors (seed `arm`).
fn arm(seed: u64) -> Arm {
    sim::perturb(&Arm::default6(), 3e-4, 0.3, &mut armcal::rng::rng(seed))
}

/// A recording of `truth` by a tracker in a frame of its own: `rows` points of new poses and
/// noise (seed `seed`), `sessions` sessions as groups.
fn record(truth: &Arm, seed: u64, rows: usize, sessions: usize) -> Dataset {
    let mut rng = armcal::rng::rng(seed);
    let d = sim::simulate(truth, &sim::Options::new(Kind::Point, rows), &mut rng)
        .unwrap()
        .data;
    common::in_sessions(d, sessions, "(simulated recording)")
}

/// Five recordings: `a` and `c` of one arm (the second with its tool remounted: another probe
/// error), `b`, `d`, `e` of three others.
fn fleet_of_five(rows: usize, sessions: usize) -> Vec<(&'static str, Dataset)> {
    let same = arm(1);
    let mut remounted = same.clone();
    remounted.probe.error[0] += 0.5;
    remounted.probe.error[2] -= 0.8;
    vec![
        ("a", record(&same, 11, rows, sessions)),
        ("b", record(&arm(2), 12, rows, sessions)),
        ("c", record(&remounted, 13, rows, sessions)),
        ("d", record(&arm(3), 14, rows, sessions)),
        ("e", record(&arm(4), 15, rows, sessions)),
    ]
}

fn units(recs: Vec<(&'static str, Dataset)>) -> Vec<UnitData> {
    recs.into_iter()
        .map(|(n, data)| UnitData {
            name: n.into(),
            file: format!("{n}.csv"),
            data,
        })
        .collect()
}

#[test]
fn detection_groups_exactly_the_two_recordings_of_one_arm() {
    let files = units(fleet_of_five(120, 4));
    let arms = same_arm::group(
        &Arm::default6(),
        &files,
        &fleet::Options::default(),
        &Grouping::Detect {
            alpha: same_arm::ALPHA,
        },
    )
    .unwrap();
    let groups: Vec<Vec<usize>> = arms.groups.iter().map(|g| g.recordings.clone()).collect();
    assert_eq!(groups, vec![vec![0, 2], vec![1], vec![3], vec![4]]);
    assert_eq!(arms.groups[0].arm, "a", "named by its first recording");
    // Honest noise: one recording's halves scatter as their covariances say.
    let (phi, d) = arms.overdispersion.unwrap();
    assert_eq!(arms.splits.len(), 5);
    assert!((0.5..2.0).contains(&phi), "φ̂ = {phi} on {d}");
    assert_eq!(arms.pairs.len(), 10);
    // What the calibrations predict, probe and frame out, tells the same way: the two
    // recordings of one arm are closer than any two arms.
    let tip = |p: &same_arm::Pair| p.tip_rms_um.expect("both fitted");
    let same = arms.pairs.iter().find(|p| (p.a, p.b) == (0, 2)).unwrap();
    let closest_apart = arms
        .pairs
        .iter()
        .filter(|p| (p.a, p.b) != (0, 2))
        .map(tip)
        .fold(f64::INFINITY, f64::min);
    assert!(
        3.0 * tip(same) < closest_apart,
        "same arm {} µm, closest different arms {closest_apart} µm",
        tip(same)
    );
    for p in &arms.pairs {
        if (p.a, p.b) == (0, 2) {
            assert!(p.f < 3.0 && p.same, "{p:?}");
        } else {
            // Different arms: many σ apart.
            assert!(p.f > 50.0 && !p.same, "{p:?}");
        }
    }
    // Detection off: every file an arm, no statistics.
    let off = same_arm::group(
        &Arm::default6(),
        &files,
        &fleet::Options::default(),
        &Grouping::EachFile,
    )
    .unwrap();
    assert_eq!(off.groups.len(), 5);
    assert!(off.pairs.is_empty());
}

/// Writes the recordings as `fleet-<name>.csv` into `dir`.
fn write(dir: &std::path::Path, recs: &[(&str, Dataset)]) -> Vec<String> {
    recs.iter()
        .map(|(n, d)| {
            let f = format!("fleet-{n}.csv");
            std::fs::write(dir.join(&f), d.to_csv(&["simulated recording"])).unwrap();
            f
        })
        .collect()
}

#[test]
fn a_hand_grouping_is_honoured_and_counts_arms() {
    let dir = common::workdir("hand");
    let files = write(&dir, &fleet_of_five(60, 3));
    let mut args = vec!["diagnose", "--fleet"];
    args.extend(files.iter().map(String::as_str));
    // Against the data: b and d are different arms, given as one.
    args.extend(["--same-arm", "bd=b,d", "--json", "--max-order", "1"]);
    let out = common::armcal_ok(&args, &dir);
    let j: Value = serde_json::from_slice(&out.stdout).unwrap();
    let arms: Vec<(String, Vec<String>)> = j["arms"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| {
            let recs = a["recordings"].as_array().unwrap();
            (
                a["arm"].as_str().unwrap().to_string(),
                recs.iter()
                    .map(|r| r.as_str().unwrap().to_string())
                    .collect(),
            )
        })
        .collect();
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    assert_eq!(
        arms,
        vec![
            ("a".into(), s(&["a"])),
            ("bd".into(), s(&["b", "d"])),
            ("c".into(), s(&["c"])),
            ("e".into(), s(&["e"])),
        ],
        "a and c, one arm by the data, stay apart: the hand grouping sets it wholly"
    );
    assert!(j["arms"][0]["evidence"]["rule"]
        .as_str()
        .unwrap()
        .starts_with("by hand"));
    // The pair's statistic is still reported, and says the data disagree.
    let bd = &j["arms"][1]["evidence"]["pairs"][0];
    assert_eq!((bd["a"].as_str(), bd["b"].as_str()), (Some("b"), Some("d")));
    assert_eq!(bd["same"], false);
    // The pooled test counts four arms, and names them.
    assert_eq!(j["design"]["tested_units"], 4, "{:#}", j["design"]);
    let pooled = &j["design"]["strongest_left_out"][0]["per_unit"];
    let names: Vec<&str> = pooled
        .as_array()
        .unwrap()
        .iter()
        .map(|u| u["unit"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["a", "bd", "c", "e"]);
}

#[test]
fn bad_groupings_are_refused_with_the_option_and_recording_named() {
    let dir = common::workdir("bad");
    let recs = fleet_of_five(30, 3);
    let files = write(&dir, &recs[..3]);
    let run = |extra: &[&str]| {
        let mut args = vec!["diagnose", "--fleet"];
        args.extend(files.iter().map(String::as_str));
        args.extend(extra);
        let o = common::armcal(&args, &dir);
        assert!(!o.status.success(), "{extra:?} accepted");
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let err = run(&["--same-arm", "x=a,zz"]);
    assert!(
        err.contains("--same-arm x=") && err.contains("`zz`") && err.contains("a, b, c"),
        "{err}"
    );
    let err = run(&["--same-arm", "x=a,b", "--same-arm", "y=b,c"]);
    assert!(err.contains("`b`") && err.contains("fleet-b.csv"), "{err}");
    let err = run(&["--same-arm", "c=a,b"]);
    assert!(
        err.contains("--same-arm c=") && err.contains("fleet-c.csv"),
        "{err}"
    );
    let err = run(&["--same-arm", "x=a,b", "--same-arm", "x=c"]);
    assert!(err.contains("arm `x` is given twice"), "{err}");
    let err = run(&["--same-arm", "a,b"]);
    assert!(err.contains("ARM=RECORDING"), "{err}");
    let err = run(&["--same-arm", "x=a,b", "--each-file-an-arm"]);
    assert!(err.contains("--each-file-an-arm"), "{err}");
}

/// Issue 29, F8: a "fleet" whose recordings are all one arm has no spread between arms (its
/// pooled test printed `± inf, p = 1.0`): refused, with what to run instead.
#[test]
fn a_fleet_of_one_arm_is_refused_with_what_to_run() {
    let dir = common::workdir("one-arm");
    let recs = fleet_of_five(30, 3);
    let files = write(&dir, &recs[..2]);
    let mut args = vec!["diagnose", "--fleet"];
    args.extend(files.iter().map(String::as_str));
    args.extend(["--same-arm", "ab=a,b", "--max-order", "1"]);
    let o = common::armcal(&args, &dir);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("the 2 recordings are all one arm (ab)")
            && err.contains("armcal diagnose fleet-a.csv fleet-b.csv")
            && err.contains("--each-file-an-arm"),
        "{err}"
    );
    assert!(o.stdout.is_empty(), "a report was printed: {err}");
}
