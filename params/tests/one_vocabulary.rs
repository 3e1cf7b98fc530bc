//! The parameters' identity is spelt once, in this crate: no second enum of parameters, no
//! conversion between two, and no old spelling returns in the crates that use it (`armcal`,
//! `reference`, `wire`, the firmware `src`). Reads the sources of the workspace, so it needs
//! nothing outside the repository.

use std::fs;
use std::path::{Path, PathBuf};

/// An old spelling, and why it must not come back.
const FORBIDDEN: &[(&str, &str)] = &[
    (
        "ParamKey",
        "the reference's second enum of parameters: use quatarm_params::Param",
    ),
    (
        "fn key_of(",
        "a conversion between two enums of parameters: there is one",
    ),
    (
        "fn param_of(",
        "a conversion between two enums of parameters: there is one",
    ),
    ("enum Param ", "a second enum of parameters"),
    ("enum Param{", "a second enum of parameters"),
    ("enum ParamKind", "a second enum of parameters' kinds"),
    (
        "Thermal(None)",
        "the probe's expansion spelt as `None`: it is `Thermal(Link::Probe)`",
    ),
    (
        "Thermal(Some(",
        "a joint's expansion spelt as `Some`: it is `Thermal(Link::Joint(j))`",
    ),
    (
        "fn key(&self, c: usize)",
        "an effect's own spelling of its parameters' keys: the key is Param's Display",
    ),
    (
        "fn key(&self, _c: usize)",
        "an effect's own spelling of its parameters' keys: the key is Param's Display",
    ),
    (
        "TurnGravity",
        "the table's column kind of `gravity` spelt another way: it is `Kind::Gravity` (byte 3)",
    ),
    (
        "P::G",
        "the number format of `gravity` spelt `G`: it is `Physics::Gravity`",
    ),
    (
        "Self::G",
        "the number format of `gravity` spelt `G`: it is `Physics::Gravity`",
    ),
    (
        "type G",
        "the number format of `gravity` spelt `G`: it is `Physics::Gravity`",
    ),
    (
        "g_from_f64",
        "the conversion of `gravity` spelt `g`: it is `Physics::gravity_from_f64`",
    ),
];

/// Whether `line` holds `pattern` as written, not as the start of a longer name: `P::G` is
/// an old spelling, `P::Gravity` is not.
fn holds(line: &str, pattern: &str) -> bool {
    let word = |c: char| c.is_alphanumeric() || c == '_';
    let ends_in_name = pattern.chars().last().is_some_and(word);
    line.match_indices(pattern).any(|(at, _)| {
        !ends_in_name || !line[at + pattern.len()..].chars().next().is_some_and(word)
    })
}

/// The crates that use the vocabulary, from the workspace root.
const CRATES: &[&str] = &["armcal", "reference", "wire", "src"];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            if p.file_name().is_some_and(|n| n == "target") {
                continue;
            }
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Every line of the crates' Rust sources holding an old spelling, as `file:line: text`.
fn offences(root: &Path) -> Vec<String> {
    let mut files = Vec::new();
    for c in CRATES {
        rust_files(&root.join(c), &mut files);
    }
    assert!(
        files.len() > 100,
        "found only {} Rust files under {root:?}: not the workspace",
        files.len()
    );
    let mut found = Vec::new();
    for f in files {
        let text = fs::read_to_string(&f).unwrap_or_default();
        for (n, line) in text.lines().enumerate() {
            for (s, why) in FORBIDDEN {
                if holds(line, s) {
                    found.push(format!("{}:{}: `{s}`: {why}", f.display(), n + 1));
                }
            }
        }
    }
    found
}

#[test]
fn no_second_spelling_of_the_parameters() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let found = offences(&root);
    assert!(found.is_empty(), "old spellings:\n{}", found.join("\n"));
}

/// The check can fail: a file holding an old spelling is found.
#[test]
fn the_check_finds_an_old_spelling() {
    let dir = std::env::temp_dir().join(format!("one-vocabulary-{}", std::process::id()));
    for c in CRATES {
        fs::create_dir_all(dir.join(c)).unwrap();
        for k in 0..30 {
            fs::write(dir.join(c).join(format!("f{k}.rs")), "// nothing\n").unwrap();
        }
    }
    fs::write(
        dir.join("wire").join("budget.rs"),
        "fn column(key: ParamKey) {}\n",
    )
    .unwrap();
    let found = offences(&dir);
    let _ = fs::remove_dir_all(&dir);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].contains("budget.rs:1") && found[0].contains("ParamKey"));
}

/// The firmware's old spellings of `gravity` are found, and the new ones are not taken for
/// them (`P::Gravity` starts with `P::G`).
#[test]
fn the_check_finds_the_old_gravity_spellings_only() {
    let dir = std::env::temp_dir().join(format!("one-vocabulary-g-{}", std::process::id()));
    for c in CRATES {
        fs::create_dir_all(dir.join(c)).unwrap();
        for k in 0..30 {
            fs::write(dir.join(c).join(format!("f{k}.rs")), "// nothing\n").unwrap();
        }
    }
    fs::write(
        dir.join("src").join("model.rs"),
        "pub gravity: P::Gravity,\n\
         fn f() { Kind::Gravity; P::gravity_from_f64(g); }\n\
         pub gravity: P::G,\n\
         3 => Kind::TurnGravity,\n\
         fn g_from_f64(g: f64) -> Option<Self::G>;\n",
    )
    .unwrap();
    let found = offences(&dir);
    let _ = fs::remove_dir_all(&dir);
    let lines: Vec<&str> = found
        .iter()
        .map(|f| f.split(": `").next().unwrap_or(""))
        .collect();
    assert!(
        lines
            .iter()
            .all(|l| l.ends_with(":3") || l.ends_with(":4") || l.ends_with(":5")),
        "{found:?}"
    );
    assert_eq!(found.len(), 4, "{found:?}");
}
