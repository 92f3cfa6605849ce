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
/// Errors: [`Error::WouldOverwriteInput`] for an output that is an input (same file once
/// canonicalized, so links count), [`Error::OutputDir`] when the directory cannot be created or
/// written to.
pub fn prepare_dir(dir: &Path, files: &[&str], inputs: &[PathBuf]) -> Result<()> {
    let fail = |source| Error::OutputDir {
        path: dir.to_path_buf(),
        source,
    };
    refuse_inputs(dir, files.iter().copied(), inputs)?;
    std::fs::create_dir_all(dir).map_err(fail)?;
    let probe = dir.join(format!(".knitfit-probe-{}", std::process::id()));
    std::fs::File::create(&probe).map_err(fail)?;
    std::fs::remove_file(&probe).map_err(fail)?;
    Ok(())
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
        prepare_dir(&out, &["a.txt", "b.txt"], &[]).unwrap();
        let files = vec![
            ("a.txt".to_string(), b"A".to_vec()),
            ("b.txt".to_string(), b"B".to_vec()),
        ];
        let written = write_all(&out, &files, &[]).unwrap();
        assert_eq!(written, vec![out.join("a.txt"), out.join("b.txt")]);
        assert_eq!(names(&out), ["a.txt", "b.txt"]);
        assert_eq!(std::fs::read(out.join("b.txt")).unwrap(), b"B");
    }

    #[test]
    fn directory_under_a_file_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("f"), "x").unwrap();
        let err = prepare_dir(&dir.path().join("f/out"), &[], &[]).unwrap_err();
        assert!(matches!(err, Error::OutputDir { .. }), "{err}");
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
