//! docs/GUIDE.md shows what knitfit prints, and these tests run the same commands and hold the
//! guide's samples to their output.
//!
//! A sample is a fenced block right after a marker comment that names its command:
//!
//! - `<!-- sample: ARGS -->`: the block is all that `knitfit ARGS` prints (standard output, then
//!   standard error);
//! - `<!-- sample, its last lines: ARGS -->`: the block is the last lines of it;
//! - `<!-- sample, a line each: ARGS | ARGS | … -->`: each line of the block is all that one
//!   command prints, in order;
//! - `<!-- sample file: PATH -->`: the block is that file's JSON (compared as parsed JSON).
//!
//! The rule: every line of a sample must be the line knitfit printed, character for character,
//! except where the sample writes `…`, which stands for any text. The guide writes `…` only for
//! what differs from run to run or machine to machine: seconds, the directory the samples are
//! in, and the memory available with where that figure came from. So a changed message, a
//! renamed field, a new or lost line, or a figure the binary no longer prints (a step count, a
//! memory estimate, a landmark) fails; a different timing does not.
//!
//! The commands run in a fresh directory, where the guide's `bad1.json` holds
//! `{"solver": {"step": 0.1}}`; an argument `samples/…` is the repository's sample. The bundled
//! fit is the costly one (a few seconds in release); the rest are plans and refusals.

use std::path::{Path, PathBuf};

use crate::support::{knitfit, stderr, stdout, write};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// How a sample's block relates to its commands' output.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Shape {
    Whole,
    LastLines,
    LineEach,
}

/// A sample of the guide: its line in GUIDE.md, its commands, how it is compared, its block.
#[derive(Debug)]
struct Sample {
    line: usize,
    commands: Vec<String>,
    shape: Shape,
    block: Vec<String>,
}

/// The fenced block that starts on `lines[at]` (its opening fence), without the fences.
fn block_at(lines: &[&str], at: usize, marker_line: usize) -> Vec<String> {
    assert!(
        lines.get(at).is_some_and(|l| l.starts_with("```")),
        "docs/GUIDE.md:{marker_line}: a sample marker not followed by a fenced block"
    );
    lines[at + 1..]
        .iter()
        .take_while(|l| !l.starts_with("```"))
        .map(|l| l.to_string())
        .collect()
}

/// The guide's samples of output (`<!-- sample…: … -->`) and of files (`<!-- sample file: … -->`).
fn samples(guide: &str) -> (Vec<Sample>, Vec<(usize, String, String)>) {
    let lines: Vec<&str> = guide.lines().collect();
    let (mut outputs, mut files) = (Vec::new(), Vec::new());
    for (i, line) in lines.iter().enumerate() {
        let Some(marker) = line
            .strip_prefix("<!-- sample")
            .and_then(|m| m.strip_suffix(" -->"))
        else {
            continue;
        };
        let block = block_at(&lines, i + 1, i + 1);
        if let Some(path) = marker.strip_prefix(" file: ") {
            files.push((i + 1, path.to_string(), block.join("\n")));
            continue;
        }
        let (shape, commands) = if let Some(c) = marker.strip_prefix(": ") {
            (Shape::Whole, c)
        } else if let Some(c) = marker.strip_prefix(", its last lines: ") {
            (Shape::LastLines, c)
        } else if let Some(c) = marker.strip_prefix(", a line each: ") {
            (Shape::LineEach, c)
        } else {
            panic!("docs/GUIDE.md:{}: unknown sample marker {line}", i + 1)
        };
        outputs.push(Sample {
            line: i + 1,
            commands: commands.split(" | ").map(str::to_string).collect(),
            shape,
            block,
        });
    }
    (outputs, files)
}

/// Whether `actual` is `sample` with each `…` standing for any text.
fn matches(sample: &str, actual: &str) -> bool {
    let parts: Vec<&str> = sample.split('…').collect();
    if parts.len() == 1 {
        return sample == actual;
    }
    let (first, last) = (parts[0], parts[parts.len() - 1]);
    if !actual.starts_with(first) || actual.len() < first.len() + last.len() {
        return false;
    }
    let mut rest = &actual[first.len()..];
    for part in &parts[1..parts.len() - 1] {
        match rest.find(part) {
            Some(at) => rest = &rest[at + part.len()..],
            None => return false,
        }
    }
    rest.ends_with(last)
}

/// Runs `command` (`knitfit ARGS`) in `dir` and returns all it printed, standard output first.
fn run(dir: &Path, command: &str) -> String {
    let args: Vec<String> = command
        .strip_prefix("knitfit")
        .unwrap_or_else(|| panic!("a sample's command starts `knitfit`: {command}"))
        .split_whitespace()
        .map(|a| {
            if a.starts_with("samples/") {
                root().join(a).to_string_lossy().into_owned()
            } else {
                a.to_string()
            }
        })
        .collect();
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = knitfit(dir, &args);
    format!("{}{}", stdout(&out), stderr(&out))
}

#[test]
fn the_guides_sample_output_is_what_knitfit_prints() {
    let guide = std::fs::read_to_string(root().join("docs/GUIDE.md")).unwrap();
    let (samples, _) = samples(&guide);
    // The first run, the plans of the bundled leg and the whole body, the refusals.
    assert!(
        samples.len() >= 5,
        "docs/GUIDE.md has {} sample markers",
        samples.len()
    );
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "bad1.json", r#"{"solver": {"step": 0.1}}"#);
    for sample in &samples {
        let printed: Vec<String> = match sample.shape {
            Shape::LineEach => sample
                .commands
                .iter()
                .map(|c| run(dir.path(), c).trim_end().to_string())
                .collect(),
            _ => {
                assert_eq!(sample.commands.len(), 1, "docs/GUIDE.md:{}", sample.line);
                let all = run(dir.path(), &sample.commands[0]);
                let lines: Vec<String> = all.lines().map(str::to_string).collect();
                if sample.shape == Shape::LastLines {
                    let skip = lines.len().saturating_sub(sample.block.len());
                    lines[skip..].to_vec()
                } else {
                    lines
                }
            }
        };
        let context = || {
            format!(
                "docs/GUIDE.md:{}: the sample of `{}` is not what it prints; it printed:\n{}",
                sample.line,
                sample.commands.join(" | "),
                printed.join("\n")
            )
        };
        assert_eq!(sample.block.len(), printed.len(), "{}", context());
        for (want, got) in sample.block.iter().zip(&printed) {
            assert!(
                matches(want, got),
                "{}\n\nfirst line that differs:\n  guide:   {want}\n  printed: {got}",
                context()
            );
        }
    }
}

#[test]
fn the_guides_bundled_scene_is_samples_scene_json() {
    let guide = std::fs::read_to_string(root().join("docs/GUIDE.md")).unwrap();
    let (_, files) = samples(&guide);
    assert!(!files.is_empty(), "docs/GUIDE.md shows no file as a sample");
    for (line, path, block) in files {
        let shown: serde_json::Value = serde_json::from_str(&block)
            .unwrap_or_else(|e| panic!("docs/GUIDE.md:{line}: not JSON: {e}"));
        let file: serde_json::Value =
            serde_json::from_slice(&std::fs::read(root().join(&path)).unwrap()).unwrap();
        assert_eq!(shown, file, "docs/GUIDE.md:{line} shows {path} otherwise");
    }
}

#[test]
fn an_ellipsis_in_a_sample_stands_for_any_text_and_nothing_else_does() {
    assert!(matches("converged in … s", "converged in 5.86 s"));
    assert!(matches(
        "… GiB available (…): fits",
        "20.3 GiB available (MemAvailable in /proc/meminfo): fits"
    ));
    assert!(matches("leg …/samples/a.glb", "leg /work/x/samples/a.glb"));
    assert!(!matches("converged in … s", "did not converge in 5.86 s"));
    assert!(!matches("704 steps", "705 steps"));
    assert!(!matches("a…b…c", "a-c-b"));
    assert!(!matches("ab…ba", "aba"));
}
