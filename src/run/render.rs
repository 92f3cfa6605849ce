//! `knitfit render`: the yarn-level preview of a finished fit, read back from its
//! `stocking.glb` (paper §7–8). Writes the picture (default `preview.png` next to the input) and
//! a small report beside it (`preview.report.json`, so the fit's own `report.json` is never
//! replaced). `spp_sweep` instead measures what anti-aliasing costs: the same picture at 1, 4
//! and 16 samples per pixel, timed, against a 64-sample reference; it writes nothing.

use std::path::{Path, PathBuf};
use std::time::Instant;

use nalgebra::Point3;

use super::{Outcome, Run};
use crate::base::{Stance, SurfaceMesh};
use crate::error::{Error, Result};
use crate::export::gltf::read::read_stocking_glb;
use crate::leg::landmarks::stance_of;
use crate::plan::Plan;
use crate::preview::{render_prepared, PreparedScene, PreviewInput};
use crate::report::{Metrics, RenderDetails};
use crate::scene::{LoadedScene, Scene};
use crate::stage::Stage;

/// Samples per pixel of the sweep's reference.
const REFERENCE_SPP: u32 = 64;

/// One row of the accuracy/time sweep.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SweepRow {
    /// Samples per pixel.
    pub spp: u32,
    /// Wall-clock seconds of the render (scene preparation excluded).
    pub seconds: f64,
    /// RMS difference from the reference over the pixels that show the leg, in 8-bit sRGB
    /// levels (0–255), all three channels.
    pub rms_error: f64,
}

/// The accuracy/time sweep's result.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Sweep {
    /// Seconds to read the GLB and build the BVH and yarn grid (shared by every row).
    pub prepare_seconds: f64,
    /// Samples per pixel of the reference.
    pub reference_spp: u32,
    /// Seconds of the reference render.
    pub reference_seconds: f64,
    /// Pixels the error is measured over.
    pub leg_pixels: usize,
    /// One row per sample count.
    pub rows: Vec<SweepRow>,
}

/// The GLB an input names: the file itself, or `stocking.glb` in a directory.
pub fn glb_path(input: &Path) -> PathBuf {
    if input.is_dir() {
        input.join("stocking.glb")
    } else {
        input.to_path_buf()
    }
}

/// Renders the preview of `input` (a fit's directory or its `stocking.glb`) as the scene's
/// `render` asks and writes it to `out` (default: `preview.png` next to the input), with its
/// report beside it.
pub fn run_render(
    loaded: &LoadedScene,
    input: &Path,
    out: Option<&Path>,
) -> Result<Outcome<RenderDetails>> {
    let scene = &loaded.scene;
    let glb = glb_path(input);
    let out = match out {
        Some(path) => path.to_path_buf(),
        None => glb
            .parent()
            .map(|p| p.join("preview.png"))
            .unwrap_or_else(|| PathBuf::from("preview.png")),
    };
    let (dir, name) = split_output(&out)?;
    let report_name = format!(
        "{}.report.json",
        Path::new(&name)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "preview".into())
    );
    let plan = Plan::render(scene, &glb.display().to_string(), &name, &report_name);
    let mut all_inputs = loaded.inputs();
    all_inputs.push(glb.clone());
    let mut run = Run::new(&plan, &dir, all_inputs);
    // Read first: a bad input must fail before any directory is made.
    let stocking = run.stage(Stage::ReadStocking, || read_stocking_glb(&glb))?;
    run.prepare()?;
    let (bytes, stats) = run.stage(Stage::RenderPreview, || -> Result<_> {
        let stance = stance(&stocking.leg, scene);
        let input = PreviewInput::new(&stocking.leg, &stocking.yarns, &scene.yarns, stance);
        let prepared = PreparedScene::new(input, &name)?;
        let preview = render_prepared(&prepared, &scene.render);
        let bytes = crate::draw::encode_png(&preview.image, &name)?;
        Ok((bytes, preview.stats))
    })?;
    run.keep(&name, bytes);
    let metrics = Metrics {
        points: stocking.yarns.positions.len(),
        steps: 0,
        residual: 0.0,
        max_move: 0.0,
        force_step: None,
        converged: true,
        max_penetration_m: None,
        leg_triangles: Some(stocking.leg.triangles.len()),
    };
    let details = RenderDetails {
        input: glb.display().to_string(),
        yarn_covered_fraction: if stats.leg_samples > 0 {
            stats.yarn_samples as f64 / stats.leg_samples as f64
        } else {
            0.0
        },
        render: stats,
    };
    run.finish(&loaded.name, metrics, details)
}

/// How the character in a fit's `leg` stands, for a camera framed from its front; the default
/// where the scene places the camera itself (the stance would go unused).
fn stance(leg: &SurfaceMesh, scene: &Scene) -> Stance {
    if scene.render.camera.is_some() {
        return Stance::default();
    }
    let positions: Vec<Point3<f64>> = leg.positions.iter().map(|&p| Point3::from(p)).collect();
    stance_of(&positions, &leg.triangles)
}

/// Renders the input at 1, 4 and 16 samples per pixel and at a 64-sample reference, timing
/// each, and measures each against the reference. Writes nothing.
///
/// Errors: [`Error::InvalidArgument`] when the reference's samples are over the render budget.
pub fn run_spp_sweep(scene: &Scene, input: &Path) -> Result<Sweep> {
    scene
        .render
        .check_budget(REFERENCE_SPP)
        .map_err(|e| Error::InvalidArgument {
            flag: "--spp-sweep".into(),
            message: e.message,
        })?;
    let glb = glb_path(input);
    let start = Instant::now();
    let stocking = read_stocking_glb(&glb)?;
    let prepared = PreparedScene::new(
        PreviewInput::new(
            &stocking.leg,
            &stocking.yarns,
            &scene.yarns,
            stance(&stocking.leg, scene),
        ),
        "preview",
    )?;
    let prepare_seconds = start.elapsed().as_secs_f64();
    let timed = |spp: u32| {
        let mut settings = scene.render.clone();
        settings.spp = spp;
        let start = Instant::now();
        let preview = render_prepared(&prepared, &settings);
        (preview, start.elapsed().as_secs_f64())
    };
    let (reference, reference_seconds) = timed(REFERENCE_SPP);
    let leg: Vec<bool> = reference.buffers.leg.iter().map(|&f| f > 0.0).collect();
    let leg_pixels = leg.iter().filter(|&&b| b).count();
    let mut rows = Vec::new();
    for spp in [1, 4, 16] {
        let (preview, seconds) = timed(spp);
        let mut sum = 0.0;
        for (i, (a, b)) in preview
            .image
            .pixels()
            .zip(reference.image.pixels())
            .enumerate()
        {
            if leg[i] {
                for c in 0..3 {
                    let d = f64::from(a.0[c]) - f64::from(b.0[c]);
                    sum += d * d;
                }
            }
        }
        let rms_error = (sum / (3 * leg_pixels.max(1)) as f64).sqrt();
        rows.push(SweepRow {
            spp,
            seconds,
            rms_error,
        });
    }
    Ok(Sweep {
        prepare_seconds,
        reference_spp: REFERENCE_SPP,
        reference_seconds,
        leg_pixels,
        rows,
    })
}

/// The directory and file name of an output picture; it must be a `.png`.
fn split_output(out: &Path) -> Result<(PathBuf, String)> {
    let bad = |message: String| Error::InvalidArgument {
        flag: "--out".into(),
        message,
    };
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| bad(format!("{} has no file name", out.display())))?;
    let is_png = Path::new(&name)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !is_png {
        return Err(bad(format!("must name a .png file, got {}", out.display())));
    }
    let dir = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    Ok((dir, name))
}
