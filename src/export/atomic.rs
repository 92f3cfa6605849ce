//! Atomic output: every file is written under a temporary name in its final directory and renamed
//! into place once complete, so a failed run never leaves a half-written file behind.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Creates `dir` if needed, proves it is writable, and checks that none of the `files` it will
/// receive is one of the `inputs`: all before any work is done, so that a run whose outputs
/// cannot be written fails at once and writes nothing.
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

/// Writes every `(file name, bytes)` into `dir`: all to temporary names first, then all renamed
/// into place. Refuses to replace any of `inputs`. On failure, removes what it wrote. Returns the
/// final paths.
pub fn write_all(
    dir: &Path,
    files: &[(String, Vec<u8>)],
    inputs: &[PathBuf],
) -> Result<Vec<PathBuf>> {
    refuse_inputs(dir, files.iter().map(|(name, _)| name.as_str()), inputs)?;
    let targets: Vec<PathBuf> = files.iter().map(|(name, _)| dir.join(name)).collect();
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

/// True when both paths name the same existing file.
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
}
