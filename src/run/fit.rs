//! `knitfit fit`: the product's main job. Follows the fit's plan through the fit library's
//! stages ([`crate::fit`]: load, place, size, solve, measure, products), timed on the run's
//! clock, then encodes the files, renders the preview and writes the report.

use std::path::Path;

use super::{Outcome, Progress, Run};
use crate::base::YarnKind;
use crate::error::Result;
use crate::fit::{self, measure, FitSettings, Fitted, SolverRun};
use crate::knit::{TubeBottom, TubeHeel};
use crate::limits::{peak_memory, MemoryCheck};
use crate::plan::{fit_files, Plan, PREVIEW_FILE};
use crate::post::surfaces::{STOCKING_CLEARANCE_M, STOCKING_LIFT_M};
use crate::preview::PreviewStats;
use crate::report::{
    Bounds, ContactDetails, DensityRange, FieldRange, FitDetails, KnitDetails, LandmarkDetails,
    LegDetails, MemoryDetails, Metrics, SolverDetails, StockingSurfaceDetails, ToeBoxDetails,
    TubeDetails, YarnValues, YarnsDetails,
};
use crate::scene::LoadedScene;
use crate::sim::SolverSettings;
use crate::stage::{File, Stage};

/// Runs the fit of `loaded` and writes its files into `out_dir`.
///
/// Nothing is written unless every stage succeeds. A fit that reaches the step limit without
/// converging still writes its files; its report says `"converged": false`.
pub fn run_fit(
    loaded: &LoadedScene,
    out_dir: &Path,
    progress: &mut dyn Progress,
) -> Result<Outcome<FitDetails>> {
    let scene = &loaded.scene;
    let plan = Plan::fit(scene);
    let settings = plan.fit_settings(loaded);
    let leg_path = loaded.leg_path();
    let mut inputs = loaded.inputs();
    inputs.push(leg_path.clone());
    let mut run = Run::new(&plan, out_dir, inputs);
    run.prepare()?;

    let (leg, memory) = fit::load(&leg_path, &settings, &mut run.clock)?;
    let fitted = fit::fit(leg, &settings, &mut run.clock, progress).map_err(|e| loaded.named(e))?;
    let solved = &fitted.solved;
    let products = (fitted.products.as_ref()).expect("a fit's plan makes its products");
    for file in fit_files(scene) {
        run.encode(Stage::Encode(File::Fit(file)), file.name(), || {
            products.encode(file)
        })?;
    }
    // The preview's counters go to the report: they exist only where its structures were built.
    let mut preview = None;
    if plan.has(Stage::RenderPreview) {
        let (bytes, stats) = run.stage(Stage::RenderPreview, || {
            products.render_preview(&scene.yarns, &scene.render, PREVIEW_FILE)
        })?;
        run.keep(PREVIEW_FILE, bytes);
        preview = Some(stats);
    }
    let metrics = Metrics {
        points: solved.knit.len(),
        steps: solved.solver.steps(),
        residual: solved.solver.residual(),
        max_move: solved.solver.max_move(),
        force_step: solved.solver.force_step(),
        // A posed leg's stocking is done when it settled in the pose too.
        converged: solved.solver.converged() && fitted.pose.as_ref().is_none_or(|p| p.converged),
        max_penetration_m: Some(solved.max_penetration_m),
        leg_triangles: Some(solved.leg.triangles.len()),
    };
    let yarns = YarnsDetails {
        written: scene.yarns_written(),
        points: products.yarns.positions.len(),
        segments: products.yarns.segments.len(),
        real_stitches: products.laid,
    };
    let details = details(
        &fitted,
        &settings,
        solved.memory.clone().unwrap_or(memory),
        preview,
        yarns,
    );
    run.finish(&loaded.name, metrics, details)
}

/// The report's details of `fitted` with `settings`, `memory` the fit's memory check.
fn details(
    fitted: &Fitted,
    settings: &FitSettings,
    memory: MemoryCheck,
    preview: Option<PreviewStats>,
    yarns: YarnsDetails,
) -> FitDetails {
    let (fit, leg_fields) = (&fitted.solved, &fitted.fields.on_leg);
    let (leg, spec, knit, placement) = (&fit.leg, &fit.spec, &fit.knit, &fit.placement);
    let products = fitted.products.as_ref();
    let covered: Vec<f64> = leg_fields
        .stitch_density
        .iter()
        .copied()
        .filter(|&d| d > 0.0)
        .collect();
    let on_covered = |field: &[f64]| -> Vec<f64> {
        field
            .iter()
            .zip(&leg_fields.stitch_density)
            .filter(|(_, &d)| d > 0.0)
            .map(|(&v, _)| v)
            .collect()
    };
    let fabric = &settings.fabric;
    let (min, max) = leg.bounds();
    FitDetails {
        leg: LegDetails {
            file: leg.path.display().to_string(),
            units: leg.units,
            up_axis: leg.up_axis,
            up_axis_from: leg.up_from,
            reoriented_triangles: leg.reoriented_triangles,
            cleaned: leg.cleaned,
            bounds_m: Bounds {
                min: min.coords.into(),
                max: max.coords.into(),
            },
            landmarks: (placement.landmarks.as_ref())
                .map(|l| LandmarkDetails::of(l, fit.placed_on())),
        },
        axis: placement.axis,
        tube: TubeDetails {
            wales: spec.grid.wales,
            courses: spec.grid.courses,
            rest_course_spacing_m: knit.grid_rest_m().course,
            rest_wale_spacing_m: knit.grid_rest_m().wale,
            toe_tip_wale_spacing_m: knit
                .is_graded()
                .then(|| knit.course_interval(knit.courses - 2)),
            relaxed_length_m: spec.relaxed_length_m,
            relaxed_circumference_m: spec.relaxed_circumference_m,
            stiffness_scale: knit.stiffness_scale,
            centreline_m: placement.centreline.length(),
            bottom: if knit.has_toe_seam() {
                TubeBottom::Toe
            } else {
                TubeBottom::Ankle
            },
            heel: if knit.short_rows().is_some() {
                TubeHeel::Pocket
            } else {
                TubeHeel::None
            },
            axial_range_m: fit.axial_range_m,
            bunched_courses: fit.bunched_courses,
            slack: measure::slack_of(fit),
            // Only where the fit's contact saw the toes boxed.
            toe_box: (placement.path.as_ref())
                .filter(|_| fit.toe_box.is_some())
                .and_then(|path| path.toe_box_rim())
                .map(|(centre, towards_toe, length_m)| ToeBoxDetails {
                    rim_centre_m: centre.coords.into(),
                    towards_toe: towards_toe.into(),
                    length_m,
                }),
        },
        solver: solver_details(
            &fit.solver,
            &settings.solve.solver,
            fit.unsettled_at.clone(),
        ),
        contact: ContactDetails {
            method: settings.solve.contact,
            offset_m: fit.offset,
            counters: fit.counters,
        },
        penetration_fix: products.and_then(|p| p.penetration_fix),
        pose: fitted.pose.clone(),
        preview,
        memory: MemoryDetails {
            check: memory,
            peak_resident_bytes: peak_memory(),
        },
        yarns,
        stocking_surface: (products.and_then(|p| p.stocking.as_ref())).map(|(_, dipping)| {
            StockingSurfaceDetails {
                lift_m: STOCKING_LIFT_M,
                clearance_m: STOCKING_CLEARANCE_M,
                triangles_dipping: *dipping,
            }
        }),
        checks: fitted.checks.clone(),
        stretch_by_region: measure::stretch_by_part(fit),
        knit: KnitDetails {
            needles: fabric.needles,
            courses: spec.relaxed_length_m / fabric.stitch_m.wale,
            stitch_m: fabric.stitch_m,
            yarn_diameter_um: YarnValues {
                nylon: 1e6 * fabric.yarn_diameter_m[YarnKind::Nylon.index() as usize],
                support: 1e6 * fabric.yarn_diameter_m[YarnKind::Support.index() as usize],
            },
            loop_stiffness_n_per_m: fabric.loop_stiffness_n_per_m,
            // The grid's own rests: a graded grid's welt is a little longer than an even one's.
            stitches_per_cell: fabric.stitches_per_cell(knit.grid_rest_m()),
        },
        coverage: FieldRange::of(&on_covered(&leg_fields.coverage)),
        pressure_mmhg: FieldRange::of(&on_covered(&leg_fields.pressure)),
        stitch_density_per_cm2: DensityRange {
            leg_vertices_covered: covered.len(),
            leg_vertices: leg.positions.len(),
            min: covered.iter().copied().fold(f64::INFINITY, f64::min),
            max: covered.iter().copied().fold(0.0, f64::max),
        },
    }
}

/// The report's `details.solver` of `run`, a run with `settings`.
fn solver_details(
    run: &SolverRun,
    settings: &SolverSettings,
    unsettled_at: Option<String>,
) -> SolverDetails {
    match run {
        SolverRun::Paper(stats) => SolverDetails::Paper {
            tolerance: settings.tolerance,
            time_step: settings.time_step,
            time_step_limit: stats.time_step_limit,
            substeps_per_step: stats.substeps_per_step,
        },
        SolverRun::Multilevel(stats) => SolverDetails::Multilevel {
            tolerance: settings.tolerance,
            fine_grid_equivalent_iterations: stats.fine_grid_equivalent_iterations(),
            levels: stats.levels.clone(),
            unsettled_at,
        },
    }
}
