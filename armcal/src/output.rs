//! A command's output files: checked before any work, written all or none.
//!
//! A command that writes several files (a calibration file and its table, a diagnosis with
//! its figures) must not leave some of them behind when a later one fails, nor overwrite the
//! data it read. [`check`] refuses, before anything is computed, outputs that name an input
//! or each other (`calibrate -o X.bin`, whose table would go to the same X.bin) and folders
//! that do not exist; [`Staged`] writes every file beside its destination under a temporary
//! name and renames them all at the end, removing the temporaries when dropped before, and
//! refuses at that last moment too any file that would land on an input it was told of (files
//! whose names are only known late: the figures in a `--plots` folder). A private key is
//! staged readable by its owner alone ([`Staged::write_private`]).

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
    /// A file that must be new (a key) exists.
    #[error("{}: exists; a {what} is never overwritten (move it away or name another file)", .path.display())]
    Exists {
        /// The existing file.
        path: PathBuf,
        /// What would have been written.
        what: String,
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

/// Whether two paths name the same file: existing files by identity (device and inode, so a
/// hard link or a symbolic link is caught too), others by their absolute, normalised form.
fn same(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            if x.dev() == y.dev() && x.ino() == y.ino() {
                return true;
            }
        }
    }
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
    inputs: Vec<(PathBuf, String)>,
}

impl Staged {
    /// Nothing staged yet.
    pub fn new() -> Staged {
        Staged::default()
    }

    /// Nothing staged yet; [`Staged::commit`] refuses (writing nothing) any file that would
    /// land on one of `inputs`, (path, what it is) pairs as for [`check`].
    pub fn guarding(inputs: &[(&Path, &str)]) -> Staged {
        let mut s = Staged::new();
        s.inputs = inputs
            .iter()
            .map(|(p, w)| (p.to_path_buf(), w.to_string()))
            .collect();
        s
    }

    /// Stages `bytes` for `dest`, a file that must not exist yet, readable and writable by
    /// its owner alone (mode 0600 on Unix): a private key.
    pub fn write_private(
        &mut self,
        dest: &Path,
        bytes: &[u8],
        what: &str,
    ) -> Result<(), OutputError> {
        self.write_new(dest, bytes, what, 0o600)
    }

    /// Stages `bytes` for `dest`, a file that must not exist yet (a key), created with `mode`
    /// (Unix permissions, before the umask).
    pub fn write_new(
        &mut self,
        dest: &Path,
        bytes: &[u8],
        what: &str,
        mode: u32,
    ) -> Result<(), OutputError> {
        use std::io::Write as _;
        if dest.exists() {
            return Err(OutputError::Exists {
                path: dest.to_path_buf(),
                what: what.to_string(),
            });
        }
        let tmp = self.path_for(dest);
        let mut o = std::fs::OpenOptions::new();
        o.write(true).create_new(true);
        #[cfg(unix)]
        {
            use std::os::unix::fs::OpenOptionsExt;
            o.mode(mode);
        }
        #[cfg(not(unix))]
        let _ = mode;
        let mut f = o.open(&tmp).map_err(io(dest))?;
        f.write_all(bytes).map_err(io(dest))
    }

    /// The temporary path for `dest` (same folder, same extension, hidden name), registered
    /// to be renamed onto `dest` at commit.
    pub(crate) fn path_for(&mut self, dest: &Path) -> PathBuf {
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
    pub(crate) fn create_dir(&mut self, dir: &Path) -> Result<(), OutputError> {
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

    /// Renames every staged file onto its destination and removes what was asked; first
    /// refuses, writing nothing, if a destination is one of the inputs it guards.
    pub fn commit(mut self) -> Result<(), OutputError> {
        for (_, dest) in &self.pending {
            for (inp, their) in &self.inputs {
                if same(dest, inp) {
                    return Err(OutputError::OverwritesInput {
                        path: dest.clone(),
                        what: "output".into(),
                        their: their.clone(),
                    });
                }
            }
        }
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
    fn a_late_output_on_an_input_is_refused_at_commit_and_a_key_is_private() {
        let d = std::env::temp_dir().join(format!("armcal-guard-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        let data = d.join("plot.png");
        std::fs::write(&data, "input").unwrap();
        // A hard link is the same file under another name.
        let link = d.join("link.csv");
        std::fs::hard_link(&data, &link).unwrap();
        let mut s = Staged::guarding(&[(&link, "data")]);
        s.write(&d.join("other.png"), b"fine").unwrap();
        s.write(&data, b"figure").unwrap();
        let e = s.commit().unwrap_err();
        assert!(e.to_string().contains("overwrite the data"), "{e}");
        assert_eq!(std::fs::read(&data).unwrap(), b"input");
        assert!(!d.join("other.png").exists(), "nothing written");

        let key = d.join("k.pem");
        let mut s = Staged::new();
        s.write_private(&key, b"secret", "private key").unwrap();
        s.commit().unwrap();
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&key).unwrap().permissions().mode();
            assert_eq!(mode & 0o777, 0o600, "{mode:o}");
        }
        let e = Staged::new()
            .write_private(&key, b"new", "private key")
            .unwrap_err();
        assert!(e.to_string().contains("never overwritten"), "{e}");
        assert_eq!(std::fs::read(&key).unwrap(), b"secret");
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
