//! Running the `knitfit` binary and reading what it wrote: its exit, its streams, its output
//! directory and its report.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Output;
use std::sync::{Mutex, OnceLock};

use knitfit::report::{CommandDetails, FitDetails, PatchDetails, RenderDetails, Report};
use serde::de::DeserializeOwned;
use serde_json::{json, Value};

use super::files::exact_json;

/// Runs the knitfit binary with `args` in directory `cwd`.
pub fn knitfit(cwd: &Path, args: &[&str]) -> Output {
    knitfit_env(cwd, args, &[])
}

/// Runs the knitfit binary with extra environment variables.
pub fn knitfit_env(cwd: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_knitfit"));
    cmd.current_dir(cwd).args(args);
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("the knitfit binary runs")
}

/// Writes `text` to `dir/name` and returns the path.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Standard error as text.
pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Standard output as text.
pub fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Sorted file names in `dir` (empty when it does not exist).
pub fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

/// The report `file` (a run's `report.json`, or `render`'s `preview.report.json`), read as the
/// report of the command whose details are `D`: every field typed, none unknown
/// (`deny_unknown_fields`), so a renamed or added field fails here rather than passing as
/// `null`; every number exactly as written ([`exact_json`]).
pub fn read_report_file<D: DeserializeOwned + CommandDetails>(file: &Path) -> Report<D> {
    let text = std::fs::read_to_string(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    serde_json::from_value(exact_json(&text)).unwrap_or_else(|e| panic!("{}: {e}", file.display()))
}

/// The `report.json` of the fit whose output directory is `dir`.
pub fn read_fit_report(dir: &Path) -> Report<FitDetails> {
    read_report_file(&dir.join("report.json"))
}

/// The `report.json` of the patch experiment whose output directory is `dir`.
pub fn read_patch_report(dir: &Path) -> Report<PatchDetails> {
    read_report_file(&dir.join("report.json"))
}

/// The `preview.report.json` that `knitfit render` wrote into the fit directory `dir`.
pub fn read_render_report(dir: &Path) -> Report<RenderDetails> {
    read_report_file(&dir.join("preview.report.json"))
}

/// The flags of a fit that ends at the ankle (an open tube), for tests about the open tube's
/// axis or at grids too coarse for a stocking to the toe.
pub const OPEN_TUBE: &[&str] = &["--bottom", "ankle"];

/// The files [`fit`] writes unless a test names its own, with `--outputs` or a scene file: the
/// stocking and leg files.
/// The pictures (the preview and the real stitches it draws, `density.png`) are most of a
/// coarse fit's time and are checked by the tests about them, which ask for them.
const FILES: &[&str] = &["--outputs", "ply,glb"];

/// Fits `leg` at `resolution` into a fresh directory and returns (dir, report).
pub fn fit(
    leg: &Path,
    resolution: &str,
    extra: &[&str],
) -> (tempfile::TempDir, Report<FitDetails>) {
    let dir = tempfile::tempdir().unwrap();
    let r = fit_in(dir.path(), leg, resolution, extra);
    (dir, r)
}

/// Fits `leg` at `resolution` into `dir/out` and returns the report.
fn fit_in(dir: &Path, leg: &Path, resolution: &str, extra: &[&str]) -> Report<FitDetails> {
    let mut args = vec![
        "fit",
        "--leg",
        leg.to_str().unwrap(),
        "--resolution",
        resolution,
        "-q",
    ];
    args.extend_from_slice(extra);
    let names_outputs = |arg: &&str| *arg == "--outputs" || arg.ends_with(".json");
    if !extra.iter().any(names_outputs) {
        args.extend_from_slice(FILES);
    }
    let out = knitfit(dir, &args);
    assert!(out.status.success(), "{}: {}", leg.display(), stderr(&out));
    read_fit_report(&dir.join("out"))
}

/// [`fit`], run once per test binary for each distinct call and read by every test that makes
/// it: the open tube on each sample at 60×60 is read by five tests. Its directory must only be
/// read. Statics are never dropped, so it is made in cargo's scratch folder for tests
/// (`target/tmp`), not the system's.
pub fn shared_fit(
    leg: &Path,
    resolution: &str,
    extra: &[&str],
) -> (&'static tempfile::TempDir, &'static Report<FitDetails>) {
    type Fitted = OnceLock<(tempfile::TempDir, Report<FitDetails>)>;
    static FITS: OnceLock<Mutex<HashMap<String, &'static Fitted>>> = OnceLock::new();
    let call = format!("{} {resolution} {}", leg.display(), extra.join(" "));
    // The map's lock is held only to find the call's cell: different calls fit side by side,
    // and a test making a call already under way waits for it.
    let fitted: &'static Fitted = FITS
        .get_or_init(Default::default)
        .lock()
        .unwrap()
        .entry(call)
        .or_insert_with(|| Box::leak(Box::default()));
    let (dir, report) = fitted.get_or_init(|| {
        let dir = tempfile::tempdir_in(env!("CARGO_TARGET_TMPDIR")).unwrap();
        let report = fit_in(dir.path(), leg, resolution, extra);
        (dir, report)
    });
    (dir, report)
}

/// The names of the stages in a report, in order.
pub fn stage_names<D>(report: &Report<D>) -> Vec<String> {
    report.stages.iter().map(|s| s.name.to_string()).collect()
}

/// Runs `knitfit fit` on a scene in a fresh directory: `scene` is the scene file's JSON (the leg
/// path in it may be absolute), written as `dir/scene.json`; outputs go to `dir/out`.
pub fn run_scene(scene: &Value, resolution: &str, extra: &[&str]) -> (tempfile::TempDir, Output) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.json"), scene.to_string()).unwrap();
    let mut args = vec!["fit", "scene.json", "--resolution", resolution, "-q"];
    args.extend_from_slice(extra);
    let out = knitfit(dir.path(), &args);
    (dir, out)
}

/// A scene fitting `leg` (absolute path), with `leg_extra` merged into its `leg` object and
/// `top` merged at the top level; writes only the PLYs (they hold every figure checked).
pub fn scene_for(leg: &Path, leg_extra: Value, top: Value) -> Value {
    let mut scene = json!({
        "leg": { "file": leg.to_str().unwrap() },
        "outputs": ["ply"],
    });
    merge(&mut scene["leg"], leg_extra);
    merge(&mut scene, top);
    scene
}

/// Merges `from` into `into`, objects key by key, anything else replacing what was there.
pub fn merge(into: &mut Value, from: Value) {
    if let Value::Object(from) = from {
        for (k, v) in from {
            match (into.get_mut(&k), v) {
                (Some(slot @ Value::Object(_)), v @ Value::Object(_)) => merge(slot, v),
                (_, v) => into[&k] = v,
            }
        }
    }
}

/// Runs the knitfit binary with `args` in `cwd`, killed if it has not ended within `limit`:
/// `None` then, the output otherwise.
pub fn knitfit_within(cwd: &Path, args: &[&str], limit: std::time::Duration) -> Option<Output> {
    use std::io::Read;
    use std::process::Stdio;
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_knitfit"))
        .current_dir(cwd)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the knitfit binary runs");
    // Drained on threads, so a chatty child cannot block on a full pipe while it is timed.
    let drain = |pipe: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            if let Some(mut pipe) = pipe {
                pipe.read_to_end(&mut bytes).ok();
            }
            bytes
        })
    };
    let stdout = drain(
        child
            .stdout
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let stderr = drain(
        child
            .stderr
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let start = std::time::Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("waiting on knitfit") {
            break Some(status);
        }
        if start.elapsed() > limit {
            child.kill().ok();
            child.wait().ok();
            break None;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    };
    let (stdout, stderr) = (stdout.join().unwrap(), stderr.join().unwrap());
    status.map(|status| Output {
        status,
        stdout,
        stderr,
    })
}
