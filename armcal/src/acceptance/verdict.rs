//! The overall decision of a check (`armcal check --mpe`): one verdict over every value the
//! MPE file gives a limit for, so that a script can act on the exit code alone.
//!
//! Each value's own decision is ISO 14253-1's ([`super::mpe::Decision`]) with the value's U,
//! whatever its source (the MPE file's `test_uncertainty`, the calibration's budget, or a
//! propagated U another module computes): the verdict only reads the rows' decisions, so a
//! better U changes the decisions and the verdict without touching this code.

use super::mpe::Decision;
use super::Row;

/// ISO 14253-1's rule as the report states it.
pub const RULE: &str = "ISO 14253-1 with each value's expanded uncertainty U (k = 2): \
     conforms where |value| + U ≤ MPE, does not conform where |value| − U > MPE, \
     cannot decide in between";

/// The check's outcome, and its exit code.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Every value with an MPE is proven within it (exit 0).
    Conforms,
    /// At least one value is proven beyond its MPE (exit 1).
    DoesNotConform,
    /// No value is proven beyond its MPE, but at least one is not proven within it, or the
    /// MPE file limits none of the data's tests (exit 2).
    CannotDecide,
    /// No MPE file: values only, nothing decided (exit 0: the command did what was asked).
    NotAsked,
}

impl Outcome {
    /// The exit code of `armcal check` (errors are [`EXIT_ERROR`]).
    pub fn exit_code(self) -> i32 {
        match self {
            Outcome::Conforms | Outcome::NotAsked => 0,
            Outcome::DoesNotConform => 1,
            Outcome::CannotDecide => 2,
        }
    }

    /// In words.
    pub fn name(self) -> &'static str {
        match self {
            Outcome::Conforms => "conforms",
            Outcome::DoesNotConform => "does not conform",
            Outcome::CannotDecide => "cannot decide",
            Outcome::NotAsked => "no decision",
        }
    }
}

/// The exit code of `armcal check` when it could not run (bad arguments, a file that cannot
/// be read or is refused): distinct from 1 and 2 so that a script never takes a wrong file for
/// an arm that does not conform.
pub const EXIT_ERROR: i32 = 3;

/// The verdict of a check.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Verdict {
    /// The outcome.
    pub outcome: Outcome,
    /// The exit code it gives.
    pub exit_code: i32,
    /// The MPE file, as given on the command line.
    pub mpe_file: Option<String>,
    /// The decision rule.
    pub rule: &'static str,
    /// Values proven within their MPE.
    pub pass: usize,
    /// Values proven beyond their MPE.
    pub fail: usize,
    /// Values neither.
    pub cannot_decide: usize,
    /// Values whose test the MPE file gives no limit for (not decided, not counted).
    pub without_mpe: usize,
}

impl Verdict {
    /// The verdict over `rows`, decided against the MPE file `mpe_file` (`None`: no file).
    pub fn of(rows: &[Row], mpe_file: Option<&str>) -> Verdict {
        let count = |d: Decision| rows.iter().filter(|r| r.decision == Some(d)).count();
        let (pass, fail, cannot_decide) = (
            count(Decision::Pass),
            count(Decision::Fail),
            count(Decision::CannotDecide),
        );
        let without_mpe = rows.iter().filter(|r| r.decision.is_none()).count();
        let outcome = if mpe_file.is_none() {
            Outcome::NotAsked
        } else if fail > 0 {
            Outcome::DoesNotConform
        } else if cannot_decide > 0 || pass == 0 {
            Outcome::CannotDecide
        } else {
            Outcome::Conforms
        };
        Verdict {
            outcome,
            exit_code: outcome.exit_code(),
            mpe_file: mpe_file.map(str::to_string),
            rule: RULE,
            pass,
            fail,
            cannot_decide,
            without_mpe,
        }
    }

    /// The verdict line: the outcome, its exit code, the counts, the MPE file and the rule.
    pub fn line(&self) -> String {
        let Some(file) = &self.mpe_file else {
            return format!(
                "verdict: no decision (exit 0): no MPE file given (--mpe FILE); {} values computed",
                self.without_mpe
            );
        };
        let mut counts = format!(
            "{} pass, {} fail, {} cannot decide",
            self.pass, self.fail, self.cannot_decide
        );
        if self.without_mpe > 0 {
            counts.push_str(&format!(
                ", {} without an MPE in the file (not decided)",
                self.without_mpe
            ));
        }
        format!(
            "verdict: {} (exit {}): {counts}; MPE file {file}; decision rule {}",
            self.outcome.name(),
            self.exit_code,
            self.rule
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::acceptance::statistics::Test;

    fn row(decision: Option<Decision>) -> Row {
        Row {
            test: Test::EUni,
            group: 1,
            value_um: 1.0,
            length_mm: Some(500.0),
            mpe_um: decision.map(|_| 10.0),
            u_um: 1.0,
            u_source: crate::acceptance::USource::MpeFile,
            decision,
            predicted_um: None,
            outside_predicted: None,
        }
    }

    #[test]
    fn one_fail_decides_then_one_undecided_then_all_pass() {
        use Decision::*;
        let v = |ds: &[Option<Decision>]| {
            let rows: Vec<Row> = ds.iter().map(|&d| row(d)).collect();
            Verdict::of(&rows, Some("m.toml")).outcome
        };
        assert_eq!(
            v(&[Some(Pass), Some(CannotDecide), Some(Fail)]),
            Outcome::DoesNotConform
        );
        assert_eq!(v(&[Some(Pass), Some(CannotDecide)]), Outcome::CannotDecide);
        assert_eq!(v(&[Some(Pass), None]), Outcome::Conforms);
        // An MPE file that limits none of the data's tests decides nothing.
        assert_eq!(v(&[None, None]), Outcome::CannotDecide);
        let rows = [row(Some(Pass))];
        assert_eq!(Verdict::of(&rows, None).outcome, Outcome::NotAsked);
        let line = Verdict::of(&rows, Some("m.toml")).line();
        assert!(
            line.starts_with("verdict: conforms (exit 0)")
                && line.contains("MPE file m.toml")
                && line.contains("ISO 14253-1"),
            "{line}"
        );
    }
}
