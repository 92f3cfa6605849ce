//! `knitfit patch`: the paper's flat-patch experiment (§5, Fig. 8/9). For each requested stretch
//! a fresh patch is built, its two held edges pulled apart, and the rest relaxed; the relaxed
//! patches are measured, drawn side by side and written.

use std::path::PathBuf;

use serde_json::json;

use super::{Progress, RunPaths, StepProgress};
use crate::base::YarnGeometry;
use crate::error::Result;
use crate::export;
use crate::knit::patch::{build_patch, PatchSpec};
use crate::knit::Knit;
use crate::plan::Plan;
use crate::post::{measure_stitches, StitchStats};
use crate::render::patch_picture::{self, Panel, PictureStyle};
use crate::report::{Metrics, Report, StageClock};
use crate::scene::{Output, Scene, Stretch, StretchAxis};
use crate::sim::{relax, RelaxStats};

/// The result of a patch run.
#[derive(Debug)]
pub struct PatchOutcome {
    /// The report, as written to `report.json`.
    pub report: Report,
    /// Every file written, report included.
    pub written: Vec<PathBuf>,
}

/// One relaxed patch.
struct Relaxed {
    stretch: Stretch,
    knit: Knit,
    stats: RelaxStats,
    stitches: Option<StitchStats>,
}

/// Runs the patch experiment of `scene` and writes its files into `paths.out_dir`.
///
/// Nothing is written unless every stage succeeds. A run that reaches the step limit without
/// converging still writes its files; its report says `"converged": false`.
pub fn run_patch(
    scene: &Scene,
    paths: &RunPaths,
    progress: &mut dyn Progress,
) -> Result<PatchOutcome> {
    let plan = Plan::patch(scene);
    let mut clock = StageClock::default();
    let file_names: Vec<&str> = plan
        .files
        .iter()
        .map(|(_, name)| *name)
        .chain(["report.json"])
        .collect();
    export::atomic::prepare_dir(&paths.out_dir, &file_names, &paths.inputs)?;

    let spec = PatchSpec {
        wales: scene.patch.size[0],
        courses: scene.patch.size[1],
        pattern: scene.knit.pattern,
        course_spacing_m: scene.knit.course_spacing_m,
        wale_spacing_m: scene.knit.wale_spacing_m,
    };
    let mut runs = Vec::new();
    for &stretch in &scene.patch.stretch {
        let mut knit = clock.time(&format!("knit {stretch}"), || build_patch(&spec, stretch));
        let stage = format!("relax {stretch}");
        progress.begin(&stage, scene.solver.max_steps as u64);
        let stats = clock.time(&stage, || {
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
    clock.time("measure stitches", || {
        for run in &mut runs {
            run.stitches = measure_stitches(&run.knit);
        }
    });

    let geometries = side_by_side(&runs);
    let mut files = Vec::new();
    for &(output, name) in &plan.files {
        let bytes = clock.time(&format!("encode {name}"), || match output {
            Output::Ply => export::ply::write_ply(&geometries, &ply_comments(scene)),
            Output::Glb => export::gltf::write_glb(
                &geometries,
                [scene.yarns.nylon.colour, scene.yarns.support.colour],
            ),
            Output::Picture => {
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
                    yarn_radius_m: [scene.yarns.nylon.radius_m, scene.yarns.support.radius_m],
                    yarn_colour: [scene.yarns.nylon.colour, scene.yarns.support.colour],
                    ..PictureStyle::default()
                };
                crate::render::encode_png(&patch_picture::draw_patches(&panels, &style), name)
            }
            // `Plan::patch` never lists it: a flat patch has no leg to render on.
            Output::Preview => Err(crate::error::Error::Encode {
                what: name.into(),
                message: "a patch has no leg to preview".into(),
            }),
        })?;
        files.push((name.to_string(), bytes));
    }

    let mut report = Report {
        command: plan.command.to_string(),
        scene: paths.scene_name.clone(),
        effects: plan.effects.iter().map(|e| e.name().to_string()).collect(),
        stages: Vec::new(),
        metrics: metrics(&runs),
        details: details(scene, &runs),
        outputs: files
            .iter()
            .map(|(name, _)| name.clone())
            .chain(["report.json".to_string()])
            .collect(),
        wall_seconds: 0.0,
    };
    let mut written = clock.time("write files", || {
        export::atomic::write_all(&paths.out_dir, &files, &paths.inputs)
    })?;
    report.stages = clock.stages().to_vec();
    report.wall_seconds = clock.wall_seconds();
    written.extend(export::atomic::write_all(
        &paths.out_dir,
        &[("report.json".to_string(), report.to_json())],
        &paths.inputs,
    )?);
    Ok(PatchOutcome { report, written })
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
            scene.knit.pattern, scene.patch.size[0], scene.patch.size[1]
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
fn details(scene: &Scene, runs: &[Relaxed]) -> serde_json::Value {
    let patches: Vec<_> = runs
        .iter()
        .map(|r| {
            json!({
                "stretch": { "axis": r.stretch.axis.name(), "factor": r.stretch.factor },
                "points": r.knit.len(),
                "steps": r.stats.steps,
                "substeps_per_step": r.stats.substeps_per_step,
                "time_step_limit": r.stats.time_step_limit,
                "residual": r.stats.residual,
                "max_move": r.stats.max_move,
                "converged": r.stats.converged,
                "stitches": r.stitches,
            })
        })
        .collect();
    let mut details = json!({
        "size": scene.patch.size,
        "pattern": scene.knit.pattern,
        "patches": patches,
    });
    if let Some(a) = anisotropy(scene, runs) {
        details["anisotropy"] = json!(a);
    }
    details
}

/// Anisotropy (see [`crate::post::anisotropy`]) when a square patch was stretched by the same
/// factor along both axes.
fn anisotropy(scene: &Scene, runs: &[Relaxed]) -> Option<f64> {
    let find = |axis| runs.iter().find(|r| r.stretch.axis == axis);
    let (c, w) = (find(StretchAxis::Course)?, find(StretchAxis::Wale)?);
    if c.stretch.factor != w.stretch.factor || scene.patch.size[0] != scene.patch.size[1] {
        return None;
    }
    Some(crate::post::anisotropy(
        c.stitches.as_ref()?,
        w.stitches.as_ref()?,
    ))
}
