//! Helpers shared by the integration tests.

use std::path::{Path, PathBuf};
use std::process::Output;

use nalgebra::Point3;
use ply_rs_bw::ply::{DefaultElement, Property};

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

/// The parsed report.json of an output directory.
pub fn report(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("report.json")).unwrap()).unwrap()
}

/// Every bundled sample leg.
pub fn sample_legs() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("samples");
    let mut legs: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "glb"))
        .collect();
    legs.sort();
    assert!(!legs.is_empty());
    legs
}

/// The procedural sample leg: closed, Y-up, at the origin; the tests that edit a leg file or
/// know its triangle count use it.
pub fn procedural_leg() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("samples/procedural_leg.glb")
}

pub fn read_ply(path: &Path) -> ply_rs_bw::ply::Ply<DefaultElement> {
    let mut file = std::fs::File::open(path).unwrap();
    ply_rs_bw::parser::Parser::<DefaultElement>::new()
        .read_ply(&mut file)
        .unwrap()
}

pub fn float(e: &DefaultElement, name: &str) -> f64 {
    match &e[name] {
        Property::Float(v) => *v as f64,
        other => panic!("{name}: {other:?}"),
    }
}

pub fn point(e: &DefaultElement) -> Point3<f64> {
    Point3::new(float(e, "x"), float(e, "y"), float(e, "z"))
}

/// Fits `leg` at `resolution` into a fresh directory and returns (dir, report).
pub fn fit(leg: &Path, resolution: &str, extra: &[&str]) -> (tempfile::TempDir, serde_json::Value) {
    let dir = tempfile::tempdir().unwrap();
    let mut args = vec![
        "fit",
        "--leg",
        leg.to_str().unwrap(),
        "--resolution",
        resolution,
        "-q",
    ];
    args.extend_from_slice(extra);
    let out = knitfit(dir.path(), &args);
    assert!(out.status.success(), "{}: {}", leg.display(), stderr(&out));
    let r = report(&dir.path().join("out"));
    (dir, r)
}

/// Writes an open tube leg as a GLB `dir/name`: `along + 1` rings of `around` vertices, ring
/// `j`'s vertex `i` at `ring_point(j / along, angle)` (angle 0..2π), quads split in two,
/// counter-clockwise seen from outside for a ring that runs counter-clockwise seen from +Y.
pub fn write_tube_leg(
    dir: &Path,
    name: &str,
    around: usize,
    along: usize,
    ring_point: impl Fn(f64, f64) -> [f64; 3],
) -> PathBuf {
    use knitfit::base::SurfaceMesh;
    use knitfit::export::gltf::{write_nodes_glb, GlbNode};
    let mut positions = Vec::new();
    for j in 0..=along {
        for i in 0..around {
            let angle = std::f64::consts::TAU * i as f64 / around as f64;
            positions.push(ring_point(j as f64 / along as f64, angle));
        }
    }
    let mut triangles = Vec::new();
    for j in 0..along {
        for i in 0..around {
            let a = (j * around + i) as u32;
            let b = (j * around + (i + 1) % around) as u32;
            let (c, d) = (b + around as u32, a + around as u32);
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    let mesh = SurfaceMesh::new("leg", positions, triangles);
    let path = dir.join(name);
    std::fs::write(
        &path,
        write_nodes_glb(&[GlbNode::Surface(&mesh)], [[0.5; 3]; 2]).unwrap(),
    )
    .unwrap();
    path
}

/// The names of the stages in a report, in order.
pub fn stage_names(report: &serde_json::Value) -> Vec<String> {
    report["stages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap().to_string())
        .collect()
}

/// Standard base64 with padding, for the data URIs of `.gltf` buffers.
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}
