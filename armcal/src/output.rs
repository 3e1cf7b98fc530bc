//! A command's output files: checked before any work, written all or none.
//!
//! A command that writes several files (a calibration file and its table, a diagnosis with
//! its figures) must not leave some of them behind when a later one fails, nor overwrite the
//! data it read. [`check`] refuses, before anything is computed, outputs that name an input
//! or each other (`calibrate -o X.bin`, whose table would go to the same X.bin) and folders
//! that do not exist; [`Staged`] writes every file beside its destination under a temporary
//! name and renames them all at the end, removing the temporaries when dropped before.

use std::path::{Path, PathBuf};

/// Whether two paths name the same file (existing files by identity, others by their
/// absolute, normalised form).
fn same(a: &Path, b: &Path) -> bool {
    let norm = |p: &Path| -> PathBuf {
        if let Ok(c) = p.canonicalize() {
            return c;
        }
        let abs = std::env::current_dir()
            .map(|d| d.join(p))
            .unwrap_or_else(|_| p.to_path_buf());
        match (
            abs.parent().and_then(|d| d.canonicalize().ok()),
            abs.file_name(),
        ) {
            (Some(d), Some(f)) => d.join(f),
            _ => abs,
        }
    };
    norm(a) == norm(b)
}

/// Refuses outputs that would overwrite an input or another output, or whose folder does
/// not exist. `outputs` are (path, what it is) pairs, `inputs` likewise.
pub fn check(outputs: &[(&Path, &str)], inputs: &[(&Path, &str)]) -> Result<(), String> {
    for (i, (out, what)) in outputs.iter().enumerate() {
        for (inp, their) in inputs {
            if same(out, inp) {
                return Err(format!(
                    "{}: the {what} would overwrite the {their} it is made from; name another file",
                    out.display()
                ));
            }
        }
        for (other, their) in &outputs[..i] {
            if same(out, other) {
                return Err(format!(
                    "{}: the {what} and the {their} would be the same file; name the output \
                     another way (the table goes beside the calibration file, with `.bin`)",
                    out.display()
                ));
            }
        }
        if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
            if !dir.is_dir() {
                return Err(format!(
                    "{}: the folder {} does not exist",
                    out.display(),
                    dir.display()
                ));
            }
        }
    }
    Ok(())
}

/// Files written under temporary names, renamed into place by [`Staged::commit`].
#[derive(Debug, Default)]
pub struct Staged {
    pending: Vec<(PathBuf, PathBuf)>,
    remove: Vec<PathBuf>,
    created_dirs: Vec<PathBuf>,
}

impl Staged {
    /// Nothing staged yet.
    pub fn new() -> Staged {
        Staged::default()
    }

    /// The temporary path for `dest` (same folder, same extension, hidden name), registered
    /// to be renamed onto `dest` at commit.
    pub fn path_for(&mut self, dest: &Path) -> PathBuf {
        let name = dest
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let ext = dest
            .extension()
            .map(|e| format!(".{}", e.to_string_lossy()))
            .unwrap_or_default();
        let tmp = dest.with_file_name(format!(
            ".{name}.armcal-{}-{}{ext}",
            std::process::id(),
            self.pending.len()
        ));
        self.pending.push((tmp.clone(), dest.to_path_buf()));
        tmp
    }

    /// Stages `bytes` for `dest`.
    pub fn write(&mut self, dest: &Path, bytes: &[u8]) -> Result<(), String> {
        let tmp = self.path_for(dest);
        std::fs::write(&tmp, bytes).map_err(|e| format!("{}: {e}", dest.display()))
    }

    /// Creates `dir` (and its parents) if needed; a folder created here is removed again if
    /// the files are never committed.
    pub fn create_dir(&mut self, dir: &Path) -> Result<(), String> {
        let mut missing = Vec::new();
        let mut d = Some(dir);
        while let Some(p) = d.filter(|p| !p.as_os_str().is_empty() && !p.exists()) {
            missing.push(p.to_path_buf());
            d = p.parent();
        }
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        self.created_dirs.extend(missing);
        Ok(())
    }

    /// A file to remove at commit (a stale table that would describe another model).
    pub fn remove_at_commit(&mut self, path: &Path) {
        self.remove.push(path.to_path_buf());
    }

    /// Renames every staged file onto its destination and removes what was asked.
    pub fn commit(mut self) -> Result<(), String> {
        let pending = std::mem::take(&mut self.pending);
        for (i, (tmp, dest)) in pending.iter().enumerate() {
            if let Err(e) = std::fs::rename(tmp, dest) {
                self.pending = pending[i..].to_vec();
                return Err(format!("{}: {e}", dest.display()));
            }
        }
        for p in std::mem::take(&mut self.remove) {
            if p.exists() {
                std::fs::remove_file(&p).map_err(|e| format!("{}: {e}", p.display()))?;
            }
        }
        self.created_dirs.clear();
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        for (tmp, _) in &self.pending {
            let _ = std::fs::remove_file(tmp);
        }
        // Innermost first; only folders left empty.
        for d in &self.created_dirs {
            let _ = std::fs::remove_dir(d);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_overwriting_an_input_or_itself() {
        let d = std::env::temp_dir().join(format!("armcal-output-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let data = d.join("data.csv");
        std::fs::write(&data, "x").unwrap();
        let bin = d.join("x.bin");
        let e = check(
            &[
                (&bin, "calibration file"),
                (&bin.with_extension("bin"), "table"),
            ],
            &[(&data, "data")],
        )
        .unwrap_err();
        assert!(e.contains("would be the same file"), "{e}");
        let e = check(&[(&data, "calibration file")], &[(&data, "data")]).unwrap_err();
        assert!(e.contains("overwrite the data"), "{e}");
        let e = check(&[(&d.join("no/such/x.toml"), "calibration file")], &[]).unwrap_err();
        assert!(e.contains("does not exist"), "{e}");
        assert!(check(
            &[(&d.join("x.toml"), "calibration file")],
            &[(&data, "data")]
        )
        .is_ok());
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn nothing_is_left_unless_committed() {
        let d = std::env::temp_dir().join(format!("armcal-staged-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        {
            let mut s = Staged::new();
            s.create_dir(&d.join("plots")).unwrap();
            s.write(&d.join("plots/a.png"), b"a").unwrap();
            s.write(&d.join("b.toml"), b"b").unwrap();
        }
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0, "all removed");
        let mut s = Staged::new();
        s.write(&d.join("b.toml"), b"b").unwrap();
        s.commit().unwrap();
        assert_eq!(std::fs::read(d.join("b.toml")).unwrap(), b"b");
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
        let _ = std::fs::remove_dir_all(&d);
    }
}
