//! Where the commands write: never over one of their own inputs, never half a file.
//!
//! Why: `tcomp fit --data d.csv --out d.csv` used to turn the measurement into a blob, and a failed
//! run could leave a truncated file behind. So every command that writes checks its outputs against
//! its inputs (by canonical path, so `./d.csv`, `d.csv` and a symbolic link are the same file) before
//! it reads anything, writes each file to a temporary name in the same directory and renames it over
//! the target only at the very end. A directory output (`demo`) is built in a hidden staging
//! directory inside the target and its files are renamed into place once everything succeeded.

use anyhow::{Context, bail};
use std::path::{Path, PathBuf};

/// `path` made absolute with symbolic links resolved; for a file that does not exist yet, its
/// directory's canonical path joined with its name. `None` when not even the directory exists.
fn canonical(path: &Path) -> Option<PathBuf> {
    if let Ok(c) = path.canonicalize() {
        return Some(c);
    }
    let name = path.file_name()?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    dir.canonicalize().ok().map(|d| d.join(name))
}

/// Fails when any of `outputs` is the same file as one of `inputs` (each named by its option, e.g.
/// `("--data", path)`), naming both.
pub fn refuse_overwriting_inputs(
    option: &str,
    outputs: &[PathBuf],
    inputs: &[(&str, &Path)],
) -> anyhow::Result<()> {
    for out in outputs {
        let Some(o) = canonical(out) else { continue };
        for (flag, input) in inputs {
            if canonical(input).is_some_and(|i| i == o) {
                bail!(
                    "{option} {} is the input given by {flag} {}: writing it would destroy that input; choose another output",
                    out.display(),
                    input.display()
                );
            }
        }
    }
    Ok(())
}

/// Checks, before any work, that `out` can be a file written by renaming over it: not a directory,
/// and its directory exists.
pub fn check_file_output(option: &str, out: &Path) -> anyhow::Result<()> {
    if out.is_dir() {
        bail!(
            "{option} {} is a directory; give a file name",
            out.display()
        );
    }
    if out.file_name().is_none() {
        bail!("{option} {} does not name a file", out.display());
    }
    let dir = match out.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        bail!(
            "{option} {}: the directory {} does not exist",
            out.display(),
            dir.display()
        );
    }
    Ok(())
}

/// A hidden staging directory inside an output directory: a command writes its files there, then
/// [`Staging::commit`] renames each into the output directory. Dropped without a commit, it removes
/// itself (and the output directory too, when it created it and nothing else is in it).
pub struct Staging {
    out: PathBuf,
    dir: PathBuf,
    created_out: bool,
}

impl Staging {
    /// Creates the staging directory inside `out` (creating `out` if needed).
    pub fn new(option: &str, out: &Path) -> anyhow::Result<Self> {
        if out.exists() && !out.is_dir() {
            bail!("{option} {} exists and is not a directory", out.display());
        }
        let created_out = !out.exists();
        std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
        let dir = out.join(format!(".tcomp-staging.{}", std::process::id()));
        let staging = Self {
            out: out.to_path_buf(),
            dir,
            created_out,
        };
        std::fs::create_dir(&staging.dir)
            .with_context(|| format!("creating {}", staging.dir.display()))?;
        Ok(staging)
    }

    /// Where the command writes its files.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Renames every file of the staging directory into the output directory (each rename is
    /// atomic: a reader sees the old file or the new one) and removes the staging directory.
    pub fn commit(self) -> anyhow::Result<Vec<PathBuf>> {
        let mut moved = Vec::new();
        let entries = std::fs::read_dir(&self.dir)
            .with_context(|| format!("reading {}", self.dir.display()))?;
        for entry in entries {
            let entry = entry.with_context(|| format!("reading {}", self.dir.display()))?;
            let to = self.out.join(entry.file_name());
            std::fs::rename(entry.path(), &to)
                .with_context(|| format!("moving {} into place", to.display()))?;
            moved.push(to);
        }
        moved.sort();
        Ok(moved)
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
        if self.created_out && !self.dir.exists() {
            // Only succeeds when empty, i.e. when the run failed before anything was moved.
            let _ = std::fs::remove_dir(&self.out);
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn the_same_file_by_another_name_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let data = dir.path().join("d.csv");
        std::fs::write(&data, "t\n1\n").unwrap();
        let other = dir.path().join("sub/../d.csv");
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        let e = refuse_overwriting_inputs("--out", &[other], &[("--data", &data)]).unwrap_err();
        assert!(e.to_string().contains("--data"), "{e}");
        let fresh = dir.path().join("m.tcm");
        assert!(refuse_overwriting_inputs("--out", &[fresh], &[("--data", &data)]).is_ok());
    }

    #[test]
    fn staging_moves_files_or_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        let s = Staging::new("--out", &out).unwrap();
        std::fs::write(s.path().join("a.txt"), "a").unwrap();
        let moved = s.commit().unwrap();
        assert_eq!(moved, vec![out.join("a.txt")]);
        assert_eq!(std::fs::read_dir(&out).unwrap().count(), 1);

        let fresh = dir.path().join("fresh");
        let s = Staging::new("--out", &fresh).unwrap();
        std::fs::write(s.path().join("b.txt"), "b").unwrap();
        drop(s);
        assert!(!fresh.exists());
    }
}
