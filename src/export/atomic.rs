//! Atomic output: every file is written under a temporary name in its final directory and renamed
//! into place once complete, so a failed run never leaves a half-written file behind.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Creates `dir` if needed, proves it is writable (creates and removes a probe file), and checks
/// that none of the `files` (names in `dir`) it will receive is one of the `inputs`: all before
/// any work is done, so that a run whose outputs cannot be written fails at once and writes
/// nothing.
///
/// The directories this call creates (`dir` and any missing parents) are removed again when the
/// returned [`PreparedDir`] is dropped before [`PreparedDir::keep`], as far as they are still
/// empty: a run that fails leaves no directory of its own making behind, and one that existed
/// before is left as it was.
///
/// Errors: [`Error::WouldOverwriteInput`] for an output that is an input (same file once
/// canonicalized, so links count), [`Error::OutputNotDirectory`] when `dir` or one of its
/// parents is a file, [`Error::OutputDir`] when the directory cannot be created or written to.
pub fn prepare_dir(dir: &Path, files: &[&str], inputs: &[PathBuf]) -> Result<PreparedDir> {
    let fail = |source| Error::OutputDir {
        path: dir.to_path_buf(),
        source,
    };
    refuse_inputs(dir, files.iter().copied(), inputs)?;
    if let Some(file) = dir
        .ancestors()
        .filter(|p| !p.as_os_str().is_empty())
        .find_map(|p| std::fs::metadata(p).ok().map(|m| (p, m)))
        .filter(|(_, m)| !m.is_dir())
        .map(|(p, _)| p)
    {
        return Err(Error::OutputNotDirectory {
            path: dir.to_path_buf(),
            file: file.to_path_buf(),
        });
    }
    let prepared = PreparedDir {
        created: create_dirs(dir).map_err(fail)?,
    };
    let probe = dir.join(format!(".knitfit-probe-{}", std::process::id()));
    std::fs::File::create(&probe).map_err(fail)?;
    std::fs::remove_file(&probe).map_err(fail)?;
    Ok(prepared)
}

/// An output directory [`prepare_dir`] checked, and the directories it created for it.
#[must_use = "dropping it removes the directories it created"]
#[derive(Debug)]
pub struct PreparedDir {
    /// The directories created, outermost first.
    created: Vec<PathBuf>,
}

impl PreparedDir {
    /// Keeps the directories created: the run they were made for has written into them.
    pub fn keep(mut self) {
        self.created.clear();
    }
}

impl Drop for PreparedDir {
    /// Removes the directories created, innermost first, each only if empty (`remove_dir`
    /// refuses one that is not, so nothing anyone wrote is ever removed).
    fn drop(&mut self) {
        for dir in self.created.iter().rev() {
            if std::fs::remove_dir(dir).is_err() {
                break;
            }
        }
    }
}

/// Creates `dir` and its missing parents, as `create_dir_all` does, and returns the ones this
/// call made, outermost first (one that another process makes meanwhile is not counted). On
/// failure, removes those it made.
fn create_dirs(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let missing: Vec<&Path> = dir
        .ancestors()
        .filter(|p| !p.as_os_str().is_empty())
        .take_while(|p| {
            matches!(std::fs::symlink_metadata(p), Err(e) if e.kind() == std::io::ErrorKind::NotFound)
        })
        .collect();
    let mut created = PreparedDir {
        created: Vec::new(),
    };
    for p in missing.into_iter().rev() {
        match std::fs::create_dir(p) {
            Ok(()) => created.created.push(p.to_path_buf()),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && p.is_dir() => {}
            // Dropping `created` removes what was made so far.
            Err(e) => return Err(e),
        }
    }
    Ok(std::mem::take(&mut created.created))
}

/// Writes every `(file name, bytes)` into `dir` (which must exist, see [`prepare_dir`]) and
/// returns the final paths, in order.
///
/// Every file is first written to a temporary name in `dir` (`.NAME.tmp-PID`); only once all are
/// written are they renamed into place, so no file is ever half-written. Refuses, before writing
/// anything, to replace any of `inputs` ([`Error::WouldOverwriteInput`]). On failure returns
/// [`Error::Write`] naming the file and removes every temporary file it made; if a rename fails,
/// the files renamed before it stay in place, each complete. A name must be a plain file name
/// (no directory part).
pub fn write_all(
    dir: &Path,
    files: &[(String, Vec<u8>)],
    inputs: &[PathBuf],
) -> Result<Vec<PathBuf>> {
    refuse_inputs(dir, files.iter().map(|(name, _)| name.as_str()), inputs)?;
    let targets: Vec<PathBuf> = files.iter().map(|(name, _)| dir.join(name)).collect();
    for ((name, _), target) in files.iter().zip(&targets) {
        if Path::new(name).file_name() != Some(name.as_ref()) {
            return Err(Error::Write {
                path: target.clone(),
                source: std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    "not a plain file name",
                ),
            });
        }
    }
    let mut temps: Vec<PathBuf> = Vec::new();
    let cleanup = |temps: &[PathBuf]| {
        for t in temps {
            let _ = std::fs::remove_file(t);
        }
    };
    for ((name, bytes), target) in files.iter().zip(&targets) {
        let temp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
        let written = std::fs::File::create(&temp).and_then(|mut f| f.write_all(bytes));
        temps.push(temp);
        if let Err(source) = written {
            cleanup(&temps);
            return Err(Error::Write {
                path: target.clone(),
                source,
            });
        }
    }
    for (i, (temp, target)) in temps.iter().zip(&targets).enumerate() {
        if let Err(source) = std::fs::rename(temp, target) {
            cleanup(&temps[i..]);
            return Err(Error::Write {
                path: target.clone(),
                source,
            });
        }
    }
    Ok(targets)
}

/// Fails if any `dir/name` is one of the `inputs`.
fn refuse_inputs<'a>(
    dir: &Path,
    names: impl Iterator<Item = &'a str>,
    inputs: &[PathBuf],
) -> Result<()> {
    for name in names {
        let target = dir.join(name);
        if inputs.iter().any(|input| same_file(input, &target)) {
            return Err(Error::WouldOverwriteInput { path: target });
        }
    }
    Ok(())
}

/// True when both paths name the same existing file (after resolving links and `..`).
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn writes_every_file_and_leaves_no_temporaries() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("new/sub");
        let prepared = prepare_dir(&out, &["a.txt", "b.txt"], &[]).unwrap();
        let files = vec![
            ("a.txt".to_string(), b"A".to_vec()),
            ("b.txt".to_string(), b"B".to_vec()),
        ];
        let written = write_all(&out, &files, &[]).unwrap();
        prepared.keep();
        assert_eq!(written, vec![out.join("a.txt"), out.join("b.txt")]);
        assert_eq!(names(&out), ["a.txt", "b.txt"]);
        assert_eq!(std::fs::read(out.join("b.txt")).unwrap(), b"B");
    }

    #[test]
    fn directory_under_a_file_is_refused_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("f");
        std::fs::write(&file, "x").unwrap();
        let err = prepare_dir(&file.join("out"), &[], &[]).unwrap_err();
        assert!(
            matches!(&err, Error::OutputNotDirectory { file: f, .. } if *f == file),
            "{err}"
        );
    }

    #[test]
    fn a_file_named_as_the_directory_is_refused_and_left_alone() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("f");
        std::fs::write(&file, "x").unwrap();
        let err = prepare_dir(&file, &["a.txt"], &[]).unwrap_err();
        assert!(matches!(err, Error::OutputNotDirectory { .. }), "{err}");
        assert!(
            err.to_string().contains("is a file, not a directory"),
            "{err}"
        );
        assert_eq!(std::fs::read(&file).unwrap(), b"x");
    }

    #[test]
    fn directories_it_created_are_removed_unless_kept() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("new/sub/out");
        drop(prepare_dir(&out, &["a.txt"], &[]).unwrap());
        assert!(names(dir.path()).is_empty(), "{:?}", names(dir.path()));
        prepare_dir(&out, &["a.txt"], &[]).unwrap().keep();
        assert!(out.is_dir());
    }

    #[test]
    fn a_directory_that_existed_is_left_as_it_was() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("old");
        std::fs::create_dir(&out).unwrap();
        drop(prepare_dir(&out.join("new"), &["a.txt"], &[]).unwrap());
        assert_eq!(names(dir.path()), ["old"]);
        assert!(names(&out).is_empty());
        drop(prepare_dir(&out, &["a.txt"], &[]).unwrap());
        assert!(out.is_dir());
    }

    #[test]
    fn a_created_directory_that_is_no_longer_empty_stays() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("new/out");
        let prepared = prepare_dir(&out, &["a.txt"], &[]).unwrap();
        std::fs::write(out.join("a.txt"), "A").unwrap();
        drop(prepared);
        assert_eq!(names(&out), ["a.txt"]);
    }

    #[test]
    fn never_overwrites_an_input() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("patch.ply");
        std::fs::write(&input, "input").unwrap();
        let files = vec![("patch.ply".to_string(), b"output".to_vec())];
        let err = write_all(dir.path(), &files, std::slice::from_ref(&input)).unwrap_err();
        assert!(matches!(err, Error::WouldOverwriteInput { .. }), "{err}");
        assert_eq!(std::fs::read(&input).unwrap(), b"input");
        assert_eq!(names(dir.path()), ["patch.ply"]);
    }

    #[test]
    fn failed_write_removes_its_temporaries() {
        let dir = tempfile::tempdir().unwrap();
        // A directory where the second temporary file should go makes its creation fail.
        let blocker = format!(".b.txt.tmp-{}", std::process::id());
        std::fs::create_dir(dir.path().join(&blocker)).unwrap();
        let files = vec![
            ("a.txt".to_string(), b"A".to_vec()),
            ("b.txt".to_string(), b"B".to_vec()),
        ];
        let err = write_all(dir.path(), &files, &[]).unwrap_err();
        assert!(
            matches!(&err, Error::Write { path, .. } if path.ends_with("b.txt")),
            "{err}"
        );
        assert_eq!(
            names(dir.path()),
            [blocker],
            "nothing written, nothing left"
        );
    }

    #[test]
    fn failed_rename_removes_its_temporaries() {
        let dir = tempfile::tempdir().unwrap();
        // A non-empty directory at the target makes the rename fail.
        std::fs::create_dir_all(dir.path().join("b.txt/keep")).unwrap();
        let files = vec![
            ("a.txt".to_string(), b"A".to_vec()),
            ("b.txt".to_string(), b"B".to_vec()),
        ];
        let err = write_all(dir.path(), &files, &[]).unwrap_err();
        assert!(matches!(err, Error::Write { .. }), "{err}");
        assert_eq!(names(dir.path()), ["a.txt", "b.txt"]);
        assert_eq!(std::fs::read(dir.path().join("a.txt")).unwrap(), b"A");
    }

    #[test]
    fn name_with_a_directory_part_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let files = vec![("../escape.txt".to_string(), b"x".to_vec())];
        let err = write_all(dir.path(), &files, &[]).unwrap_err();
        assert!(matches!(err, Error::Write { .. }), "{err}");
        assert!(names(dir.path()).is_empty());
    }

    #[test]
    fn prepare_dir_refuses_an_input_before_creating_anything() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("leg.glb");
        std::fs::write(&input, "leg").unwrap();
        let err = prepare_dir(dir.path(), &["leg.glb"], std::slice::from_ref(&input)).unwrap_err();
        assert!(matches!(err, Error::WouldOverwriteInput { .. }), "{err}");
        assert_eq!(names(dir.path()), ["leg.glb"]);
    }

    #[cfg(unix)]
    #[test]
    fn a_link_to_an_input_counts_as_the_input() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("leg.glb");
        std::fs::write(&input, "leg").unwrap();
        let out = dir.path().join("out");
        std::fs::create_dir(&out).unwrap();
        std::os::unix::fs::symlink(&input, out.join("stocking.glb")).unwrap();
        let files = vec![("stocking.glb".to_string(), b"x".to_vec())];
        let err = write_all(&out, &files, std::slice::from_ref(&input)).unwrap_err();
        assert!(matches!(err, Error::WouldOverwriteInput { .. }), "{err}");
        assert_eq!(std::fs::read(&input).unwrap(), b"leg");
    }
}
