//! `knitfit patch`: the paper's flat-patch experiment (§5, Fig. 8/9). For each requested stretch
//! a fresh patch is built, its two held edges pulled apart, and the rest relaxed; the relaxed
//! patches are measured, drawn side by side and written.

use std::path::Path;

use super::{Outcome, Progress, Run};
use crate::base::YarnGeometry;
use crate::draw::patch_picture::{self, Panel, PictureStyle};
use crate::error::Result;
use crate::export;
use crate::knit::patch::{build_patch, PatchSpec};
use crate::knit::{Knit, Stretch, StretchAxis};
use crate::plan::{patch_files, Plan};
use crate::post::{measure_stitches, StitchStats};
use crate::report::{Metrics, PatchDetails, PatchRun};
use crate::scene::{LoadedScene, Scene};
use crate::sim::{relax, RelaxStats};
use crate::stage::StepProgress;
use crate::stage::{File, PatchFile, Stage};

/// One relaxed patch.
struct Relaxed {
    stretch: Stretch,
    knit: Knit,
    stats: RelaxStats,
    stitches: Option<StitchStats>,
}

/// Runs the patch experiment of `loaded` and writes its files into `out_dir`.
///
/// Nothing is written unless every stage succeeds. A run that reaches the step limit without
/// converging still writes its files; its report says `"converged": false`.
pub fn run_patch(
    loaded: &LoadedScene,
    out_dir: &Path,
    progress: &mut dyn Progress,
) -> Result<Outcome<PatchDetails>> {
    let scene = &loaded.scene;
    scene.check_for_patch().map_err(|e| loaded.refusal(e))?;
    let plan = Plan::patch(scene);
    let mut run = Run::new(&plan, out_dir, loaded.inputs());
    run.prepare()?;

    let spec = PatchSpec {
        grid: scene.patch.size,
        pattern: scene.knit.pattern,
        course_spacing_m: scene.knit.course_spacing_m,
        wale_spacing_m: scene.knit.wale_spacing_m,
    };
    let mut runs = Vec::new();
    for &stretch in &scene.patch.stretch {
        let mut knit = run.stage(Stage::KnitPatch(stretch), || build_patch(&spec, stretch));
        let stage = Stage::RelaxPatch(stretch);
        progress.begin(&stage.to_string(), scene.solver.max_steps as u64);
        let stats = run.stage(stage, || {
            relax(
                &mut knit,
                &plan.forces,
                &scene.solver,
                &mut StepProgress(progress),
            )
        });
        progress.end();
        runs.push(Relaxed {
            stretch,
            knit,
            stats: stats?,
            stitches: None,
        });
    }
    run.stage(Stage::MeasureStitches, || {
        for r in &mut runs {
            r.stitches = measure_stitches(&r.knit);
        }
    });

    let geometries = side_by_side(&runs);
    for file in patch_files(scene) {
        run.encode(Stage::Encode(File::Patch(file)), file.name(), || {
            encode(file, scene, &runs, &geometries)
        })?;
    }
    run.finish(&loaded.name, metrics(&runs), details(scene, &runs))
}

/// Encodes one of the patch experiment's files.
fn encode(
    file: PatchFile,
    scene: &Scene,
    runs: &[Relaxed],
    geometries: &[YarnGeometry],
) -> Result<Vec<u8>> {
    let yarns = &scene.yarns;
    match file {
        PatchFile::Ply => export::ply::write_ply(geometries, &ply_comments(scene)),
        PatchFile::Glb => export::gltf::write_glb(geometries, yarns.each(|y| y.colour)),
        PatchFile::Picture => {
            let held: Vec<Vec<bool>> = runs
                .iter()
                .map(|r| {
                    r.knit
                        .particles
                        .inv_mass
                        .iter()
                        .map(|&m| m == 0.0)
                        .collect()
                })
                .collect();
            let panels: Vec<Panel> = geometries
                .iter()
                .zip(&held)
                .map(|(geometry, held)| Panel { geometry, held })
                .collect();
            let style = PictureStyle {
                yarn_radius_m: yarns.each(|y| y.radius_m()),
                yarn_colour: yarns.each(|y| y.colour),
                ..PictureStyle::default()
            };
            crate::draw::encode_png(&patch_picture::draw_patches(&panels, &style), file.name())
        }
    }
}

/// The relaxed patches as yarn geometry, laid side by side along x with a gap of a quarter
/// patch width, in the order the stretches were given.
fn side_by_side(runs: &[Relaxed]) -> Vec<YarnGeometry> {
    let mut offset_x = 0.0;
    let mut out = Vec::new();
    for (i, run) in runs.iter().enumerate() {
        let xs = run.knit.particles.x.iter().map(|p| p.x);
        let (min, max) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
        let width = max - min;
        if i > 0 {
            offset_x += width / 2.0;
        }
        out.push(
            run.knit
                .yarn_geometry(&format!("patch {}", run.stretch), [offset_x, 0.0, 0.0]),
        );
        offset_x += width / 2.0 + width / 4.0;
    }
    out
}

fn ply_comments(scene: &Scene) -> Vec<String> {
    vec![
        format!("knitfit {} patch experiment", env!("CARGO_PKG_VERSION")),
        format!(
            "pattern {:?}, {}x{} points",
            scene.knit.pattern, scene.patch.size.wales, scene.patch.size.courses
        ),
    ]
}

fn metrics(runs: &[Relaxed]) -> Metrics {
    Metrics {
        points: runs.iter().map(|r| r.knit.len()).sum(),
        steps: runs.iter().map(|r| r.stats.steps).sum(),
        residual: runs.iter().map(|r| r.stats.residual).fold(0.0, f64::max),
        max_move: runs.iter().map(|r| r.stats.max_move).fold(0.0, f64::max),
        force_step: None,
        converged: runs.iter().all(|r| r.stats.converged),
        max_penetration_m: None,
        leg_triangles: None,
    }
}

/// Per-stretch results, and the anisotropy when the same factor was applied along both axes.
fn details(scene: &Scene, runs: &[Relaxed]) -> PatchDetails {
    PatchDetails {
        size: scene.patch.size,
        pattern: scene.knit.pattern,
        patches: runs
            .iter()
            .map(|r| PatchRun {
                stretch: r.stretch,
                points: r.knit.len(),
                relaxation: r.stats,
                stitches: r.stitches.clone(),
            })
            .collect(),
        anisotropy: anisotropy(scene, runs),
    }
}

/// Anisotropy (see [`crate::post::anisotropy`]) when a square patch was stretched by the same
/// factor along both axes.
fn anisotropy(scene: &Scene, runs: &[Relaxed]) -> Option<f64> {
    let find = |axis| runs.iter().find(|r| r.stretch.axis == axis);
    let (c, w) = (find(StretchAxis::Course)?, find(StretchAxis::Wale)?);
    if c.stretch.factor != w.stretch.factor || scene.patch.size.wales != scene.patch.size.courses {
        return None;
    }
    Some(crate::post::anisotropy(
        c.stitches.as_ref()?,
        w.stitches.as_ref()?,
    ))
}
