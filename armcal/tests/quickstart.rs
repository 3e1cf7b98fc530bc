//! The README's metrologist quick start, run verbatim: the fenced block after the marker
//! `<!-- quickstart:` is read from `README.md`, and each of its lines is run by `sh` in a
//! fresh folder that holds the project's `data/` (a link), with the `armcal` under test first
//! on the PATH. A line that fails fails the test, naming the line and what it printed; so the
//! quick start cannot drift from what the tool does.

use std::path::Path;
use std::process::Command;

/// The lines of the README's quick start block (comments and blank lines left out).
fn quickstart_lines(readme: &str) -> Vec<String> {
    let after = readme
        .split_once("<!-- quickstart:")
        .expect("README.md has no `<!-- quickstart:` marker")
        .1;
    let block = after
        .split_once("```sh\n")
        .expect("no ```sh block after the quick start marker")
        .1
        .split_once("```")
        .expect("the quick start block is not closed")
        .0;
    block
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(str::to_string)
        .collect()
}

#[test]
fn the_readme_quick_start_runs_verbatim() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let lines = quickstart_lines(&readme);
    assert!(
        lines.len() >= 5 && lines.iter().all(|l| l.starts_with("armcal ")),
        "the quick start is armcal commands: {lines:?}"
    );
    for step in ["simulate", "calibrate", "diagnose", "check", "--report"] {
        assert!(lines.iter().any(|l| l.contains(step)), "no `{step}` step");
    }
    let dir = std::env::temp_dir().join(format!("armcal-quickstart-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::os::unix::fs::symlink(root.join("data").canonicalize().unwrap(), dir.join("data"))
        .unwrap();
    let bin = Path::new(env!("CARGO_BIN_EXE_armcal")).parent().unwrap();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    for line in &lines {
        let o = Command::new("sh")
            .args(["-c", line])
            .current_dir(&dir)
            .env("PATH", &path)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "README quick start line failed ({}):\n{line}\n{}{}",
            o.status,
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
    }
    // What the steps say they write is there.
    for f in [
        "points.csv",
        "acceptance.csv",
        "my-arm.toml",
        "my-arm.bin",
        "my-arm-extended.toml",
        "acceptance.html",
    ] {
        assert!(dir.join(f).is_file(), "{f} not written");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
