//! Issue 29, data in as they come: `calibrate`, `diagnose` and `check` read several files
//! (each file's groups kept apart), encoder counts as `eval` does, a spreadsheet's BOM and
//! CRLF; the realistic mistakes of a new user are refused with the file, the line and what
//! looks wrong. Every case runs `armcal check` (no fit: seconds) on copies of
//! `armcal/tests/data/data-in/`, made from `data/acceptance/iso10360-12.csv` with its joint
//! readings on the 2^20-count grid, so that counts and radians are the same numbers.

#[allow(dead_code)]
mod common;

use common::{armcal, armcal_ok, refused_with, stderr, with_copies};
use std::path::Path;

/// `check FILES… --calib default-6.toml --json` in `d`, required to succeed; its JSON.
fn check_json(d: &Path, files: &[&str]) -> serde_json::Value {
    let mut args = vec!["check"];
    args.extend_from_slice(files);
    args.extend_from_slice(&["--calib", "default-6.toml", "--json"]);
    serde_json::from_slice(&armcal_ok(&args, d).stdout).unwrap()
}

#[test]
fn one_kind_per_file_gives_the_values_of_the_whole_file() {
    let d = with_copies(
        "data-in",
        "split",
        &["whole.csv", "sphere.csv", "spat.csv", "length.csv"],
    );
    let whole = check_json(&d, &["whole.csv"]);
    let split = check_json(&d, &["sphere.csv", "spat.csv", "length.csv"]);
    assert_eq!(whole, split);
    assert_eq!(whole["tests"].as_array().map(Vec::len), Some(26));
}

#[test]
fn count_columns_read_as_the_same_angles() {
    let d = with_copies("data-in", "counts", &["length.csv", "length-counts.csv"]);
    assert_eq!(
        check_json(&d, &["length.csv"]),
        check_json(&d, &["length-counts.csv"])
    );
}

#[test]
fn a_group_number_in_two_files_is_renumbered_and_said() {
    let files = [
        "whole.csv",
        "sphere.csv",
        "spat.csv",
        "length-a.csv",
        "length-b.csv",
    ];
    let d = with_copies("data-in", "clash", &files);
    let whole = check_json(&d, &["whole.csv"]);
    let o = armcal_ok(
        &[
            "check",
            "sphere.csv",
            "spat.csv",
            "length-a.csv",
            "length-b.csv",
            "--calib",
            "default-6.toml",
            "--json",
        ],
        &d,
    );
    let e = stderr(&o);
    assert!(
        e.contains("length-b.csv: groups 11, 12") && e.contains("renumbered + 1000"),
        "{e}"
    );
    assert_eq!(e.matches("length-b.csv").count(), 1, "{e}");
    let parts: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    // The 15 bar positions stay 15 (merged, 8 groups would have two lengths' rows each).
    assert_eq!(whole["results"], parts["results"]);
    assert_eq!(
        whole["tests"].as_array().map(Vec::len),
        parts["tests"].as_array().map(Vec::len)
    );
}

#[test]
fn a_spreadsheets_bom_and_crlf_are_read() {
    let d = with_copies("data-in", "bom", &["whole.csv", "whole-bom-crlf.csv"]);
    assert_eq!(
        check_json(&d, &["whole.csv"]),
        check_json(&d, &["whole-bom-crlf.csv"])
    );
}

/// `check FILES… --calib default-6.toml` in a folder with copies of `files`.
fn check_of(name: &str, files: &[&str], extra: &[&str]) -> std::process::Output {
    let d = with_copies("data-in", name, files);
    let mut args = vec!["check"];
    args.extend_from_slice(files);
    args.extend_from_slice(&["--calib", "default-6.toml"]);
    args.extend_from_slice(extra);
    armcal(&args, &d)
}

#[test]
fn decimal_commas_are_named_with_their_place() {
    let o = check_of("comma", &["comma-decimal.csv"], &[]);
    refused_with(
        &o,
        3,
        &["comma-decimal.csv: line 3, column j1", "a decimal comma?"],
    );
}

#[test]
fn an_empty_file_is_said_to_be_empty() {
    let o = check_of("empty", &["empty.csv"], &[]);
    let e = refused_with(&o, 3, &["empty.csv: empty"]);
    assert_eq!(e.matches("empty.csv").count(), 1, "{e}");
}

#[test]
fn radians_and_counts_together_or_a_count_past_a_turn_are_refused_with() {
    let o = check_of("both", &["both-j-and-c.csv"], &[]);
    refused_with(
        &o,
        3,
        &[
            "both-j-and-c.csv: line 1, column c1",
            "give one reading per joint",
        ],
    );
    let o = check_of("turn", &["count-past-a-turn.csv"], &[]);
    refused_with(
        &o,
        3,
        &[
            "count-past-a-turn.csv: line 3, column c3",
            "not below the joint's 1048576",
        ],
    );
}

#[test]
fn a_row_pasted_twice_is_refused_unless_accepted() {
    let o = check_of("dup", &["sphere-duplicate.csv"], &[]);
    refused_with(
        &o,
        3,
        &[
            "sphere-duplicate.csv: line 13 repeats line 6",
            "--accept-duplicates",
        ],
    );
    let o = check_of(
        "dup-ok",
        &["sphere-duplicate.csv"],
        &["--accept-duplicates"],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

#[test]
fn one_recording_twice_is_refused_with() {
    let o = check_of("twice", &["sphere.csv", "./sphere.csv"], &[]);
    refused_with(&o, 3, &["./sphere.csv: given twice (also as sphere.csv)"]);
    // A copy under another name: its rows repeat the first file's.
    let d = with_copies("data-in", "copy", &["sphere.csv"]);
    std::fs::copy(d.join("sphere.csv"), d.join("again.csv")).unwrap();
    let o = armcal(
        &[
            "check",
            "sphere.csv",
            "again.csv",
            "--calib",
            "default-6.toml",
        ],
        &d,
    );
    refused_with(&o, 3, &["again.csv: line 3 repeats line 3 of sphere.csv"]);
}

#[test]
fn point_rows_in_two_files_are_refused_with() {
    let o = check_of("points", &["points-a.csv", "points-b.csv"], &[]);
    refused_with(
        &o,
        3,
        &[
            "points-b.csv: line 2, column kind",
            "points-a.csv",
            "one instrument frame",
        ],
    );
}

/// F8 (issue 29, round 2): `E_Uni = { a, per_m, per_km }` read as { a, per_m }.
#[test]
fn an_unknown_key_inside_an_mpe_limit_is_refused_with() {
    let d = with_copies("data-in", "per-km-mpe", &["whole.csv", "mpe-per-km.toml"]);
    let o = armcal(
        &[
            "check",
            "whole.csv",
            "--calib",
            "default-6.toml",
            "--mpe",
            "mpe-per-km.toml",
        ],
        &d,
    );
    refused_with(
        &o,
        3,
        &[
            "mpe-per-km.toml",
            "line 2",
            "unknown key `per_km` in a limit",
        ],
    );
}

#[test]
fn eval_refuses_degrees_and_fahrenheit_unless_accepted() {
    let d = with_copies(
        "data-in",
        "eval",
        &["eval-degrees.csv", "eval-fahrenheit.csv"],
    );
    let run = |f: &str, extra: &[&str]| {
        let mut args = vec!["eval", "--calib", "default-6.toml", f];
        args.extend_from_slice(extra);
        armcal(&args, &d)
    };
    refused_with(
        &run("eval-degrees.csv", &[]),
        1,
        &[
            "eval-degrees.csv: joint 1 reads",
            "in degrees?",
            "--accept-units",
        ],
    );
    refused_with(
        &run("eval-fahrenheit.csv", &[]),
        1,
        &[
            "eval-fahrenheit.csv: temp_c = 68 °C on data row 1",
            "--accept-temperature",
        ],
    );
    let o = run("eval-fahrenheit.csv", &["--accept-temperature"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(String::from_utf8_lossy(&o.stdout).lines().count(), 5);
}
