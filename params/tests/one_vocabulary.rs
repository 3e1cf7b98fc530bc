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
];

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
                if line.contains(s) {
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
