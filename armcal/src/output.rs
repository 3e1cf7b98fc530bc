//! A command's output files: checked before any work, written all or none.
//!
//! A command that writes several files (a calibration file and its table, a diagnosis with
//! its figures) must not leave some of them behind when a later one fails, nor overwrite the
//! data it read. [`check`] refuses, before anything is computed, outputs that name an input
//! or each other (`calibrate -o X.bin`, whose table would go to the same X.bin) and folders
//! that do not exist; [`Staged`] writes every file beside its destination under a temporary
//! name and renames them all at the end, removing the temporaries when dropped before.

use std::path::{Path, PathBuf};

/// Why a command's outputs were refused or could not be written; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// An output names one of the command's inputs.
    #[error("{}: the {what} would overwrite the {their} it is made from; name another file", .path.display())]
    OverwritesInput {
        /// The output's path.
        path: PathBuf,
        /// What the output is.
        what: String,
        /// What the input is.
        their: String,
    },
    /// Two outputs name the same file.
    #[error(
        "{}: the {what} and the {their} would be the same file; name the output another way \
         (the table goes beside the calibration file, with `.bin`)",
        .path.display()
    )]
    SameFile {
        /// The later output's path.
        path: PathBuf,
        /// What the later output is.
        what: String,
        /// What the earlier output is.
        their: String,
    },
    /// An output's folder does not exist.
    #[error("{}: the folder {} does not exist", .path.display(), .dir.display())]
    NoFolder {
        /// The output's path.
        path: PathBuf,
        /// Its missing folder.
        dir: PathBuf,
    },
    /// The file system refused a write, rename, removal or folder.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file or folder concerned.
        path: PathBuf,
        /// The system's reason.
        source: std::io::Error,
    },
}

/// The file system's error on `path`.
fn io(path: &Path) -> impl FnOnce(std::io::Error) -> OutputError + '_ {
    move |source| OutputError::Io {
        path: path.to_path_buf(),
        source,
    }
}

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
pub fn check(outputs: &[(&Path, &str)], inputs: &[(&Path, &str)]) -> Result<(), OutputError> {
    for (i, (out, what)) in outputs.iter().enumerate() {
        for (inp, their) in inputs {
            if same(out, inp) {
                return Err(OutputError::OverwritesInput {
                    path: out.to_path_buf(),
                    what: what.to_string(),
                    their: their.to_string(),
                });
            }
        }
        for (other, their) in &outputs[..i] {
            if same(out, other) {
                return Err(OutputError::SameFile {
                    path: out.to_path_buf(),
                    what: what.to_string(),
                    their: their.to_string(),
                });
            }
        }
        if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
            if !dir.is_dir() {
                return Err(OutputError::NoFolder {
                    path: out.to_path_buf(),
                    dir: dir.to_path_buf(),
                });
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
    pub fn write(&mut self, dest: &Path, bytes: &[u8]) -> Result<(), OutputError> {
        let tmp = self.path_for(dest);
        std::fs::write(&tmp, bytes).map_err(io(dest))
    }

    /// Creates `dir` (and its parents) if needed; a folder created here is removed again if
    /// the files are never committed.
    pub fn create_dir(&mut self, dir: &Path) -> Result<(), OutputError> {
        let mut missing = Vec::new();
        let mut d = Some(dir);
        while let Some(p) = d.filter(|p| !p.as_os_str().is_empty() && !p.exists()) {
            missing.push(p.to_path_buf());
            d = p.parent();
        }
        std::fs::create_dir_all(dir).map_err(io(dir))?;
        self.created_dirs.extend(missing);
        Ok(())
    }

    /// A file to remove at commit (a stale table that would describe another model).
    pub fn remove_at_commit(&mut self, path: &Path) {
        self.remove.push(path.to_path_buf());
    }

    /// Renames every staged file onto its destination and removes what was asked.
    pub fn commit(mut self) -> Result<(), OutputError> {
        let pending = std::mem::take(&mut self.pending);
        for (i, (tmp, dest)) in pending.iter().enumerate() {
            if let Err(e) = std::fs::rename(tmp, dest) {
                self.pending = pending[i..].to_vec();
                return Err(io(dest)(e));
            }
        }
        for p in std::mem::take(&mut self.remove) {
            if p.exists() {
                std::fs::remove_file(&p).map_err(io(&p))?;
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
        assert!(e.to_string().contains("would be the same file"), "{e}");
        let e = check(&[(&data, "calibration file")], &[(&data, "data")]).unwrap_err();
        assert!(e.to_string().contains("overwrite the data"), "{e}");
        let e = check(&[(&d.join("no/such/x.toml"), "calibration file")], &[]).unwrap_err();
        assert!(e.to_string().contains("does not exist"), "{e}");
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
