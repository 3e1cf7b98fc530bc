//! Where a diagnosis' sessions come from, and whether its nested held-out test
//! ([`super::nested`]) can run on them.
//!
//! The nested test holds out one group at a time (a `group` number: a session, an artefact
//! position) and reruns the whole diagnosis on the others. With `--by-group` the groups are
//! the diagnosis' own folds and the test always runs. With k folds of units it runs too when
//! the data have groups to hold out — several files are several groups, since every file's
//! groups are kept apart ([`crate::data::read_all`]) — unless there are more than
//! [`MAX_GROUPS_UNASKED`]: the test costs one whole diagnosis per group, which a user should
//! ask for (`--by-group`) rather than get unasked. Either way the report says where the
//! groups came from and, when the test did not run, why.

use super::FoldChoice;
use crate::data::Dataset;
use std::collections::BTreeSet;

/// Most groups the nested test runs on without `--by-group`.
pub const MAX_GROUPS_UNASKED: usize = 12;

/// The sessions' source in words: the column and the file(s) that defined them.
pub fn source(data: &Dataset) -> String {
    let groups: BTreeSet<i64> = data.rows.iter().map(|r| r.group).collect();
    let n = groups.len();
    let files: Vec<&str> = data.source.split(" + ").collect();
    let plural = if n == 1 { "" } else { "s" };
    if files.len() > 1 {
        format!(
            "the `group` column of each of {} files ({}), each file's groups kept apart (a \
             number an earlier file also has is renumbered): {n} group{plural}",
            files.len(),
            data.source
        )
    } else {
        format!("the `group` column of {}: {n} group{plural}", data.source)
    }
}

/// Whether the nested test runs on `data` diagnosed with `folds`: `Ok(())`, or why not.
pub fn nested_plan(data: &Dataset, folds: FoldChoice) -> Result<(), String> {
    let n = data
        .rows
        .iter()
        .map(|r| r.group)
        .collect::<BTreeSet<_>>()
        .len();
    if n < 2 {
        return Err(format!(
            "not run: the data form {n} group (no session or artefact position can be held out \
             whole, so the selection cannot be rerun without one); record the data in several \
             sessions (distinct `group` numbers, or one file per session)"
        ));
    }
    match folds {
        FoldChoice::ByGroup => Ok(()),
        FoldChoice::KFold { .. } if n <= MAX_GROUPS_UNASKED => Ok(()),
        FoldChoice::KFold { .. } => Err(format!(
            "not run: {n} groups, more than {MAX_GROUPS_UNASKED} (it reruns the whole \
             diagnosis once per group); ask for it with --by-group"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::parse;

    fn data(groups: &[i64], source: &str) -> Dataset {
        let mut csv = String::from("kind,group,j1,j2,j3,j4,j5,j6,x,y,z\n");
        for (i, g) in groups.iter().enumerate() {
            csv.push_str(&format!("point,{g},0,0.1,0.2,0.3,0.4,{}.0,1,2,3\n", i));
        }
        let mut d = parse(&csv, source, 6).unwrap();
        d.source = source.into();
        d
    }

    #[test]
    fn one_group_cannot_be_nested_and_says_why() {
        let d = data(&[1, 1, 1], "a.csv");
        let e = nested_plan(&d, FoldChoice::ByGroup).unwrap_err();
        assert!(e.contains("1 group"), "{e}");
        assert_eq!(source(&d), "the `group` column of a.csv: 1 group");
    }

    #[test]
    fn a_few_groups_are_nested_unasked_many_only_when_asked() {
        let k = FoldChoice::KFold { k: 5, seed: 1 };
        let few = data(&[1, 2, 3, 1, 2, 3], "a.csv + b.csv");
        assert_eq!(nested_plan(&few, k), Ok(()));
        assert!(source(&few).contains("each of 2 files"), "{}", source(&few));
        let groups: Vec<i64> = (0..=MAX_GROUPS_UNASKED as i64).collect();
        let many = data(&groups, "a.csv");
        let e = nested_plan(&many, k).unwrap_err();
        assert!(e.contains("--by-group") && e.contains("13 groups"), "{e}");
        assert_eq!(nested_plan(&many, FoldChoice::ByGroup), Ok(()));
    }
}
