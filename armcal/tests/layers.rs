//! armcal's layers run one way: a check that reads every `crate::…` path in `armcal/src`.
//!
//! Each module (one file; a folder's `mod.rs` is the folder's module) belongs to a layer of
//! [`LAYERS`] (the longest prefix of its path there decides; the same table is drawn in
//! `docs/results/architecture.md`). The check fails on
//! - an import from a module to one of a higher layer (a back edge), and
//! - an import cycle between modules, whatever their layers,
//!
//! each named with the file and line that makes it. Items under `#[cfg(test)]` are not read:
//! a module's unit tests may build their inputs with a higher layer (the fit's tests simulate
//! data), as the integration tests do; the product code may not. `super::` and `self::` paths
//! are not read:
//! a child reaching its parent is how a folder's trait and its implementations are written,
//! and a parent's use of its child is its own business. Comments are skipped (a doc link to a
//! higher layer is a pointer for the reader, not a dependency). `main.rs` is a crate of its
//! own and is not checked.
//!
//! The unit tests at the end run the checker on synthetic trees with a back edge and a cycle,
//! so that it is known to fail when it should.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The layers, lowest first: a module may import from its own layer and those below.
/// Keys are module paths (`fit::calib`) or their prefixes (`fit` for everything under it).
const LAYERS: &[(&str, &[&str])] = &[
    // Numbers, statistics, geometry, random generation, limits of what is read, progress.
    (
        "leaf",
        &["limits", "stats", "geometry", "rng", "progress", "output"],
    ),
    // Measured data and the formats they are read from.
    ("data", &["data", "load"]),
    // The arm model's unknowns and its extended effects (their maths, descriptions, figures).
    ("model", &["params", "kinds", "effects"]),
    // Calibration: the problem, its solver, structure checks and the design they compare
    // with, priors, pruning, finishing, reports.
    ("fit", &["fit"]),
    // What stands on a fit: uncertainty, diagnosis, acceptance, simulation, the data sets.
    (
        "analysis",
        &[
            "uncertainty",
            "diagnose",
            "acceptance",
            "sim",
            "mukca",
            "plausible",
            "eval",
            "accuracy",
        ],
    ),
    // What a person runs: the commands, their HTML reports, the hub's UART.
    ("commands", &["commands", "html", "table_send"]),
];

/// Edges the check tolerates for now, each with why; an entry that no longer occurs fails the
/// check too (so the list only shrinks). Format: `from -> to` as module paths.
const KNOWN: &[(&str, &str)] = &[];

/// A module path (`fit::calib`) from a file under `src` (`fit/calib.rs`, `fit/mod.rs`).
fn module_of(rel: &str) -> String {
    let p = rel.trim_end_matches(".rs");
    let p = p.strip_suffix("/mod").unwrap_or(p);
    if p == "lib" {
        String::new()
    } else {
        p.replace('/', "::")
    }
}

/// The layer (index into `layers`) of `module`: the longest listed prefix.
fn layer_of(layers: &[(&str, &[&str])], module: &str) -> Option<usize> {
    let mut best: Option<(usize, usize)> = None;
    for (i, (_, prefixes)) in layers.iter().enumerate() {
        for p in *prefixes {
            let hit = module == *p || module.starts_with(&format!("{p}::"));
            if hit && best.is_none_or(|(len, _)| p.len() > len) {
                best = Some((p.len(), i));
            }
        }
    }
    best.map(|(_, i)| i)
}

/// The code of a file without its comments (`//` to the end of a line, `/* … */`), string
/// literals kept as they are except that a `//` inside one does not start a comment.
fn strip_comments(src: &str) -> String {
    let b = src.as_bytes();
    let mut out = String::with_capacity(src.len());
    let (mut i, mut in_str) = (0, false);
    while i < b.len() {
        let c = b[i];
        if in_str {
            if c == b'\\' && i + 1 < b.len() {
                out.push_str(&src[i..i + 2]);
                i += 2;
                continue;
            }
            if c == b'"' {
                in_str = false;
            }
        } else if c == b'"' && (i == 0 || b[i - 1] != b'\'') {
            in_str = true;
        } else if c == b'/' && b.get(i + 1) == Some(&b'/') {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
            continue;
        } else if c == b'/' && b.get(i + 1) == Some(&b'*') {
            while i + 1 < b.len() && !(b[i] == b'*' && b[i + 1] == b'/') {
                if b[i] == b'\n' {
                    out.push('\n');
                }
                i += 1;
            }
            i += 2;
            continue;
        }
        let ch = src[i..].chars().next().unwrap_or(' ');
        out.push(ch);
        i += ch.len_utf8();
    }
    out
}

/// `code` with every item under `#[cfg(test)]` blanked (its lines kept, so that line numbers
/// hold): from the attribute to the end of the item, the `;` or the brace that closes its
/// first `{`.
fn without_tests(code: &str) -> String {
    let mut out = code.to_string();
    let mut from = 0;
    while let Some(k) = out[from..].find("#[cfg(test)]") {
        let start = from + k;
        let b = out.as_bytes();
        let (mut i, mut depth) = (start + "#[cfg(test)]".len(), 0usize);
        while i < b.len() {
            match b[i] {
                b'{' => depth += 1,
                b'}' if depth == 1 => break,
                b'}' => depth = depth.saturating_sub(1),
                b';' if depth == 0 => break,
                _ => {}
            }
            i += 1;
        }
        let end = (i + 1).min(out.len());
        // Byte for byte: a character of several bytes (µ, →) becomes as many spaces, so the
        // text keeps its length and every later index stays valid.
        let blank: String = out[start..end]
            .chars()
            .map(|c| match c {
                '\n' => "\n".to_string(),
                c => " ".repeat(c.len_utf8()),
            })
            .collect();
        out.replace_range(start..end, &blank);
        from = end;
    }
    out
}

/// Every path `crate::…` in `code`, use trees expanded (`crate::{a::b, c}` gives `a::b` and
/// `c`), each with its 1-based line.
fn crate_paths(code: &str) -> Vec<(String, usize)> {
    let mut out = Vec::new();
    let b = code.as_bytes();
    let mut from = 0;
    while let Some(k) = code[from..].find("crate::") {
        let at = from + k;
        from = at + "crate::".len();
        let before = at.checked_sub(1).map(|j| b[j]);
        if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == b'_') {
            continue; // `$crate::`, `my_crate::`
        }
        let line = code[..at].matches('\n').count() + 1;
        tree(code, &mut from, String::new(), line, &mut out);
    }
    out
}

/// Reads a use tree at `code[*pos..]` after `prefix`, pushing each leaf path.
fn tree(code: &str, pos: &mut usize, prefix: String, line: usize, out: &mut Vec<(String, usize)>) {
    let b = code.as_bytes();
    let skip_ws = |pos: &mut usize| {
        while *pos < b.len() && b[*pos].is_ascii_whitespace() {
            *pos += 1;
        }
    };
    skip_ws(pos);
    if b.get(*pos) == Some(&b'{') {
        *pos += 1;
        loop {
            skip_ws(pos);
            match b.get(*pos) {
                Some(b'}') => {
                    *pos += 1;
                    return;
                }
                Some(b',') => *pos += 1,
                None => return,
                _ => {
                    let before = *pos;
                    tree(code, pos, prefix.clone(), line, out);
                    if *pos == before {
                        *pos += 1; // something else (`self`, `*`): step over it
                    }
                }
            }
        }
    }
    let start = *pos;
    while *pos < b.len() && (b[*pos].is_ascii_alphanumeric() || b[*pos] == b'_') {
        *pos += 1;
    }
    let ident = &code[start..*pos];
    if ident.is_empty() {
        if !prefix.is_empty() {
            out.push((prefix, line));
        }
        return;
    }
    let path = if prefix.is_empty() {
        ident.to_string()
    } else {
        format!("{prefix}::{ident}")
    };
    if code[*pos..].starts_with("::") {
        *pos += 2;
        tree(code, pos, path, line, out);
    } else if ident != "self" {
        out.push((path, line));
    } else {
        out.push((prefix, line));
    }
}

/// The module a path names or lies in: its longest prefix among `modules`.
fn target<'m>(modules: &'m BTreeSet<String>, path: &str) -> Option<&'m String> {
    let parts: Vec<&str> = path.split("::").collect();
    (1..=parts.len())
        .rev()
        .find_map(|n| modules.get(&parts[..n].join("::")))
}

/// One import of a module by another: where it is written.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Edge {
    from: String,
    to: String,
    file: String,
    line: usize,
}

/// The imports between modules of the tree `files` (path under `src`, contents).
fn edges(files: &[(String, String)]) -> Vec<Edge> {
    let modules: BTreeSet<String> = files.iter().map(|(f, _)| module_of(f)).collect();
    let mut out = BTreeMap::new();
    for (file, src) in files {
        let from = module_of(file);
        for (path, line) in crate_paths(&without_tests(&strip_comments(src))) {
            let Some(to) = target(&modules, &path) else {
                continue; // a re-export of another crate (`tablebuild`) or a macro's path
            };
            if *to != from && !to.is_empty() {
                out.entry((from.clone(), to.clone())).or_insert(Edge {
                    from: from.clone(),
                    to: to.clone(),
                    file: file.clone(),
                    line,
                });
            }
        }
    }
    out.into_values().collect()
}

/// What is wrong with the tree `files` under `layers` (tolerating `known`): one line each.
fn problems(
    files: &[(String, String)],
    layers: &[(&str, &[&str])],
    known: &[(&str, &str)],
) -> Vec<String> {
    let mut out = Vec::new();
    let edges = edges(files);
    let tolerated = |e: &Edge| known.iter().any(|(f, t)| *f == e.from && *t == e.to);
    for (f, _) in files {
        let m = module_of(f);
        if !m.is_empty() && layer_of(layers, &m).is_none() {
            out.push(format!("src/{f}: module `{m}` is in no layer of the table"));
        }
    }
    for e in &edges {
        if tolerated(e) {
            continue;
        }
        if let (Some(a), Some(b)) = (layer_of(layers, &e.from), layer_of(layers, &e.to)) {
            if b > a {
                out.push(format!(
                    "src/{}:{}: back edge: `{}` ({}) imports `{}` ({})",
                    e.file, e.line, e.from, layers[a].0, e.to, layers[b].0
                ));
            }
        }
    }
    for (f, t) in known {
        if !edges.iter().any(|e| e.from == *f && e.to == *t) {
            out.push(format!(
                "known edge `{f} -> {t}` no longer occurs: remove it"
            ));
        }
    }
    let kept: Vec<&Edge> = edges.iter().filter(|e| !tolerated(e)).collect();
    for cycle in cycles(&kept) {
        out.push(format!("import cycle: {}", cycle.join(" -> ")));
    }
    out
}

/// The cycles of the graph `edges`, one per strongly connected component of more than one
/// module, each drawn with the file and line of every step.
fn cycles(edges: &[&Edge]) -> Vec<Vec<String>> {
    let mut next: BTreeMap<&str, Vec<&Edge>> = BTreeMap::new();
    for e in edges {
        next.entry(e.from.as_str()).or_default().push(e);
    }
    let mut found: Vec<Vec<String>> = Vec::new();
    let mut seen_sets: BTreeSet<BTreeSet<String>> = BTreeSet::new();
    // Depth-first from each module for a path back to it (the graph is a few hundred edges).
    for start in next.keys() {
        let mut stack: Vec<(&str, Vec<&Edge>)> = vec![(start, Vec::new())];
        let mut visited: BTreeSet<&str> = BTreeSet::new();
        while let Some((at, path)) = stack.pop() {
            for e in next.get(at).into_iter().flatten() {
                if e.to == *start {
                    let mut p = path.clone();
                    p.push(e);
                    let set: BTreeSet<String> = p.iter().map(|e| e.from.clone()).collect();
                    if seen_sets.insert(set) {
                        found.push(
                            p.iter()
                                .map(|e| format!("{} (src/{}:{})", e.from, e.file, e.line))
                                .chain([start.to_string()])
                                .collect(),
                        );
                    }
                } else if visited.insert(e.to.as_str()) {
                    let mut p = path.clone();
                    p.push(e);
                    stack.push((e.to.as_str(), p));
                }
            }
        }
    }
    found
}

/// Every `.rs` file under `dir` but `main.rs`, with its path relative to `root`.
fn read_tree(root: &Path, dir: &Path, out: &mut Vec<(String, String)>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("a directory entry").path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            read_tree(root, &p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            let rel = p.strip_prefix(root).expect("under src").to_string_lossy();
            let rel = rel.replace('\\', "/");
            if rel != "main.rs" {
                let src = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{rel}: {e}"));
                out.push((rel, src));
            }
        }
    }
}

#[test]
fn armcal_layers_run_one_way_without_cycles() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    read_tree(&root, &root, &mut files);
    assert!(files.len() > 50, "read only {} files", files.len());
    let found = problems(&files, LAYERS, KNOWN);
    assert!(
        found.is_empty(),
        "{} problem(s) in armcal's layers (table in tests/layers.rs and \
         docs/results/architecture.md):\n{}",
        found.len(),
        found.join("\n")
    );
}

#[cfg(test)]
mod checker {
    use super::*;

    const TWO: &[(&str, &[&str])] = &[("low", &["a", "util"]), ("high", &["b"])];

    fn tree_of(files: &[(&str, &str)]) -> Vec<(String, String)> {
        files
            .iter()
            .map(|(f, s)| (f.to_string(), s.to_string()))
            .collect()
    }

    #[test]
    fn a_back_edge_fails_with_its_file_and_line() {
        let files = tree_of(&[
            ("lib.rs", "pub mod a;\npub mod b;\n"),
            ("a/mod.rs", "pub mod x;\n"),
            ("a/x.rs", "\nuse crate::b::Thing;\n"),
            ("b.rs", "use crate::a::x::Other;\npub struct Thing;\n"),
        ]);
        let p = problems(&files, TWO, &[]);
        assert!(
            p.iter()
                .any(|l| l.contains("src/a/x.rs:2: back edge: `a::x` (low) imports `b` (high)")),
            "{p:?}"
        );
        // The other way is allowed.
        let files = tree_of(&[("a.rs", ""), ("b.rs", "use crate::a::Thing;\n")]);
        assert!(problems(&files, TWO, &[]).is_empty());
    }

    #[test]
    fn use_trees_comments_and_strings_are_read_as_the_compiler_would() {
        let src = "use crate::{util::{self, f}, b::{c::D, E}};\n\
                   // use crate::b::Commented;\n\
                   /// [`crate::b`]\n\
                   let s = \"// not a comment\"; let x = crate::b::g();\n";
        let paths: Vec<String> = crate_paths(&strip_comments(src))
            .into_iter()
            .map(|(p, _)| p)
            .collect();
        assert_eq!(paths, ["util", "util::f", "b::c::D", "b::E", "b::g"]);
        let files = tree_of(&[
            ("util.rs", "/// see [`crate::b`]\n// crate::b\nfn f() {}\n"),
            ("b.rs", ""),
        ]);
        assert!(problems(&files, TWO, &[]).is_empty());
        let files = tree_of(&[("util.rs", "fn f() { crate::b::g() }\n"), ("b.rs", "")]);
        assert_eq!(problems(&files, TWO, &[]).len(), 1);
    }

    #[test]
    fn a_cycle_within_a_layer_fails() {
        let files = tree_of(&[
            ("a.rs", "use crate::util::F;\n"),
            ("util.rs", "use crate::a::G;\n"),
        ]);
        let p = problems(&files, TWO, &[]);
        assert_eq!(p.len(), 1, "{p:?}");
        assert!(p[0].starts_with("import cycle: a (src/a.rs:1) -> util (src/util.rs:1) -> a"));
        // Tolerated edges break it; a tolerated edge that is gone fails.
        assert!(problems(&files, TWO, &[("util", "a")]).is_empty());
        let p = problems(&files, TWO, &[("util", "a"), ("a", "b")]);
        assert_eq!(p, ["known edge `a -> b` no longer occurs: remove it"]);
    }

    #[test]
    fn unit_tests_may_use_a_higher_layer_product_code_may_not() {
        let low = "use crate::util::f;\n#[cfg(test)]\nmod tests {\n    use crate::b::g;\n    fn t() { let s = \"}\"; }\n}\n#[cfg(test)]\nuse crate::b::h;\nfn k() { crate::b::late(); }\n";
        let files = tree_of(&[("a.rs", low), ("b.rs", ""), ("util.rs", "")]);
        let p = problems(&files, TWO, &[]);
        assert_eq!(
            p,
            ["src/a.rs:9: back edge: `a` (low) imports `b` (high)"],
            "{}",
            without_tests(low)
        );
    }

    /// A test block with characters of several bytes (µ, →) before a later one: both are
    /// blanked, the text keeps its length, and a product line after them is still found.
    #[test]
    fn test_blocks_with_non_ascii_text_are_blanked() {
        let code = "#[cfg(test)]\nmod t { fn a() { let _ = \"1 µm → 2 µm\"; } }\n#[cfg(test)]\nmod u {}\nfn k() { crate::b::late(); }\n";
        let out = without_tests(code);
        assert_eq!(out.len(), code.len());
        assert!(!out.contains("mod t") && !out.contains("mod u"), "{out}");
        assert!(out.contains("crate::b::late()"), "{out}");
    }

    #[test]
    fn a_module_outside_the_table_fails() {
        let files = tree_of(&[("stray.rs", "")]);
        assert_eq!(
            problems(&files, TWO, &[]),
            ["src/stray.rs: module `stray` is in no layer of the table"]
        );
    }
}
