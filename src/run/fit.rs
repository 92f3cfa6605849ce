//! `knitfit fit`: the product's main job (Sakaguchi & Miyata §6.1–6.2). Load the leg, find its
//! axis, build the tube around it, let the springs shrink it onto the leg with sliding contact,
//! measure it, and write the leg with stitch-density attributes, the yarns and the stocking
//! surface.

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use nalgebra::{Point3, Vector3};

use super::{Outcome, Progress, Run, StepProgress};
use crate::base::settings::number;
use crate::base::{Material, Stance, SurfaceMesh, YarnGeometry, YarnKind};
use crate::draw;
use crate::draw::density_map::{self, DensityPictureStyle};
use crate::error::{Error, Result};
use crate::export;
use crate::export::gltf::GlbNode;
use crate::export::{Output, YarnsWritten};
use crate::knit::path::{path_to_toe, TubePath};
use crate::knit::settings::{check_grid_size, MAX_TUBE_POINTS};
use crate::knit::tube::{
    build_stocking, build_tube, end_rings, heel_pocket_half_length_m, part_at,
    toe_graded_intervals, tube_axis, Centreline, CourseSpacing, TubeSpec,
};
use crate::knit::Fabric;
use crate::knit::{Knit, TubeBottom, TubeHeel, RELAXED_LENGTH_FRACTION};
use crate::leg::landmarks::stance_of;
use crate::leg::{
    decode_leg, find_landmarks, leaves_mesh, read_leg_file, Axis, AxisSource, Collider, Landmarks,
    Leg, SkinCurvature,
};
use crate::limits::{peak_memory, FitSize, MemoryCheck};
use crate::plan::{fit_files, File, FitFile, Plan, Stage, PREVIEW_FILE};
use crate::post::fields::{self, measure_fields, KnitFields};
use crate::post::lattice::{lay_on_skin, lay_stitches, LaidStitches};
use crate::post::loops::{loops, SAMPLES_PER_LOOP};
use crate::post::penetration::{fix_penetrations, PenetrationStats};
use crate::post::regions::{regions, stretch_by_region};
use crate::post::stitches::{
    bunched_courses, slack, slack_details, SlackDetails, MAX_BUNCHED_FRACTION,
};
use crate::post::surfaces::{
    leg_surface, lift_clear_of, stocking_surface, STOCKING_CLEARANCE_M, STOCKING_LIFT_M,
};
use crate::preview::{PreviewInput, PreviewStats};
use crate::report::{
    Bounds, ContactDetails, DensityRange, FieldRange, FitDetails, KnitDetails, LandmarkDetails,
    LegDetails, MemoryDetails, Metrics, PerDirection, SolverDetails, StageClock,
    StockingSurfaceDetails, ToeBoxDetails, TubeDetails, YarnValues, YarnsDetails,
};
use crate::scene::{LoadedScene, Scene, LEG_AXIS};
use crate::sim::accelerated::OutOfBalance;
use crate::sim::contact::{ContactCounters, LegContact};
use crate::sim::multilevel::{
    grid_sizes_down_to, grid_sizes_following, largest_level, COARSEST, STOCKING_COARSEST,
};
use crate::sim::{
    relax_constrained, relax_multilevel, Constraints, ForceTerms, LevelStats, Levels,
    MultilevelStats, RelaxStats, SolverMethod,
};

/// Where the leg comes from and who chose the axis.
#[derive(Clone, Debug)]
pub struct FitInputs {
    /// The leg file.
    pub leg: PathBuf,
    /// Who set `scene.leg.axis` (ignored when it is `None`).
    pub axis_source: AxisSource,
}

impl FitInputs {
    /// The leg and axis source of a loaded scene: `leg.file` (or `--leg`), and `--axis` when
    /// that flag set the axis.
    pub fn of(scene: &LoadedScene) -> FitInputs {
        FitInputs {
            leg: scene.leg_path(),
            axis_source: match scene.set_by(LEG_AXIS) {
                Some(_) => AxisSource::CommandLine,
                None => AxisSource::Scene,
            },
        }
    }
}

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
    let inputs = FitInputs::of(loaded);
    let mut all_inputs = loaded.inputs();
    all_inputs.push(inputs.leg.clone());
    let mut run = Run::new(&plan, out_dir, all_inputs);
    run.prepare()?;

    let fit = solve_fit(
        scene,
        &plan,
        &inputs,
        &loaded.name,
        &mut run.clock,
        progress,
    )?;
    let fabric = scene.fabric();
    let (knit_fields, leg_fields) = if plan.has(Stage::LegAttributes) {
        run.stage(Stage::LegAttributes, || fit.fields(&fabric, &plan.forces))
    } else {
        (KnitFields::default(), KnitFields::default())
    };
    let slack = slack(&fit.knit);
    // The real stitches, for the yarn files (`stitches`, `loops`) or the preview, which draws
    // every stitch as a loop so that its sheerness comes out of the knit's structure.
    let real = match plan.has(Stage::LayStitches) {
        true => Some(run.stage(Stage::LayStitches, || real_stitches(loaded, &plan, &fit))?),
        false => None,
    };
    let laid = real.as_ref().map(|(_, stats)| *stats);
    let real_loops = match (&real, plan.has(Stage::KnitLoops)) {
        (Some((real, _)), true) => Some(run.stage(Stage::KnitLoops, || loops(real, &fabric))),
        _ => None,
    };
    // The yarns the files hold: the grid's, or the real stitches' (as crossings, or as loops
    // laid on the skin: a loop bulges past its stitch's corners). Loops made only for the
    // preview are drawn as they are: a loop dipping a few micrometres into the skin is hidden
    // where it dips.
    let (mut yarns, preview_loops) = match (scene.yarns_written(), &real, real_loops) {
        (YarnsWritten::Stitches, Some((real, _)), loops) => {
            (knit_yarns(real, &fabric, &plan.forces), loops)
        }
        (YarnsWritten::Loops, _, Some(mut loops)) => {
            lay_on_skin(&mut loops.positions, &fit.collider, fit.offset);
            (loops, None)
        }
        (_, _, loops) => (knit_yarns(&fit.knit, &fabric, &plan.forces), loops),
    };
    let slack = slack_details(&fit.knit, &slack, &fit.centreline, |s| {
        fit.path
            .as_ref()
            .map(|path| format!("{:?}", part_at(path, s)).to_lowercase())
    });
    let mut penetration_fix = None;
    if plan.has(Stage::PenetrationFix) {
        let (fixed, stats) = run.stage(Stage::PenetrationFix, || {
            fix_penetrations(&yarns, &fit.collider, fit.offset)
        });
        yarns = fixed;
        penetration_fix = Some(stats);
    }
    let stocking = plan.has(Stage::StockingSurface).then(|| {
        run.stage(Stage::StockingSurface, || {
            // The fitted grid's surface: it reads the grid's yarn attributes.
            let grid_yarns = match scene.yarns_written() {
                YarnsWritten::Grid => None,
                _ => Some(knit_yarns(&fit.knit, &fabric, &plan.forces)),
            };
            let grid = grid_yarns.as_ref().unwrap_or(&yarns);
            let mut surface = stocking_surface(&fit.knit, &knit_fields, grid);
            let dipping = lift_clear_of(&mut surface, &fit.collider);
            (surface, dipping)
        })
    });
    // The pictures are seen from the character's front: its stance, where one is drawn from it
    // (a leg placed by a given axis has no landmarks yet; they are found for this).
    let pictured = plan.has(Stage::Encode(File::Fit(FitFile::DensityPicture)))
        || plan.has(Stage::RenderPreview) && scene.render.camera.is_none();
    let stance = match (&fit.landmarks, pictured) {
        (_, false) => Stance::default(),
        (Some(landmarks), true) => landmarks.stance(),
        (None, true) => stance_of(&fit.leg.positions, &fit.leg.triangles),
    };
    let products = FitProducts {
        scene,
        stance,
        yarns: &yarns,
        leg_mesh: leg_surface(&fit.leg, &leg_fields),
        leg_material: fit.leg.material.clone().unwrap_or_else(Material::skin),
        stocking: stocking.as_ref().map(|(surface, _)| surface),
    };
    for file in fit_files(scene) {
        run.encode(Stage::Encode(File::Fit(file)), file.name(), || {
            products.encode(file)
        })?;
    }
    // The preview's counters go to the report: they exist only where its structures were built.
    let mut preview = None;
    if plan.has(Stage::RenderPreview) {
        let (bytes, stats) = run.stage(Stage::RenderPreview, || {
            // The real loops (those of the files where they hold loops); a density preview
            // draws no yarn.
            let drawn = preview_loops.as_ref().unwrap_or(&yarns);
            let input = PreviewInput::new(&products.leg_mesh, drawn, &scene.yarns, stance);
            crate::preview::encode_preview(input, &scene.render, PREVIEW_FILE)
        })?;
        run.keep(PREVIEW_FILE, bytes);
        preview = Some(stats);
    }
    let metrics = Metrics {
        points: fit.knit.len(),
        steps: fit.solver.steps(),
        residual: fit.solver.residual(),
        max_move: fit.solver.max_move(),
        force_step: fit.solver.force_step(),
        converged: fit.solver.converged(),
        max_penetration_m: Some(fit.max_penetration_m),
        leg_triangles: Some(fit.leg.triangles.len()),
    };
    let yarns = YarnsDetails {
        written: scene.yarns_written(),
        points: yarns.positions.len(),
        segments: yarns.segments.len(),
        real_stitches: laid,
    };
    let stocking_surface = stocking.map(|(_, dipping)| StockingSurfaceDetails {
        lift_m: STOCKING_LIFT_M,
        clearance_m: STOCKING_CLEARANCE_M,
        triangles_dipping: dipping,
    });
    let details = FitDetails {
        stocking_surface,
        ..fit_details(
            scene,
            &fit,
            &leg_fields,
            slack,
            penetration_fix,
            preview,
            yarns,
        )
    };
    run.finish(&loaded.name, metrics, details)
}

/// A knit's points and springs as yarns, with each point's `tension` (N/m around) and `slack`.
fn knit_yarns(knit: &Knit, fabric: &Fabric, forces: &ForceTerms) -> YarnGeometry {
    let stretch = fields::stretch(knit);
    let [tension, _] = fields::tension(knit, fabric, forces, &stretch);
    let mut yarns = knit.yarn_geometry("yarns", [0.0; 3]);
    let as_f32 = |v: &[f64]| v.iter().map(|&x| x as f32).collect();
    yarns
        .point_attributes
        .insert("tension".into(), as_f32(&tension));
    yarns
        .point_attributes
        .insert("slack".into(), as_f32(&slack(knit)));
    yarns
}

/// The knit at the real stitch count, built like the fitted grid (path, toe seam, heel pocket)
/// and laid in it on the skin ([`lay_stitches`]).
fn real_stitches(
    loaded: &LoadedScene,
    plan: &Plan,
    fit: &SolvedFit,
) -> Result<(Knit, LaidStitches)> {
    let scene = &loaded.scene;
    let [wales, courses] = scene.fabric().real_count(fit.spec.relaxed_length_m);
    let loops = plan.has(Stage::KnitLoops);
    // Point ids are 32-bit, and drawn as loops each stitch is `SAMPLES_PER_LOOP` points: a bound
    // on the count, not on memory, so `allow_large` does not lift it.
    let (most, what) = match loops {
        true => (
            MAX_TUBE_POINTS / SAMPLES_PER_LOOP,
            "stitches that 32-bit indices can number drawn as loops (\"loops\", \"preview\")",
        ),
        false => (MAX_TUBE_POINTS, "points a knit's 32-bit indices can number"),
    };
    if wales.checked_mul(courses).is_none_or(|n| n > most) {
        return Err(Error::InvalidScene {
            path: loaded.name.clone(),
            field: "knit".into(),
            message: format!(
                "the real stitches of this stocking, {wales}×{courses}, are over the {most} \
                 {what}; ask for fewer knit.needles or a larger stitch (knit.course_spacing_m, \
                 knit.wale_spacing_m)"
            ),
        });
    }
    // The stocking's length, and so the real count, is known only now: checked as a fit of
    // that size would be (an upper bound: no solver runs on it).
    let outputs: Vec<_> = plan.files.iter().map(|file| file.output).collect();
    let size = FitSize {
        tube: [wales, courses],
        loops,
        ..fit_size(scene, &outputs, fit.leg.triangles.len())
    };
    MemoryCheck::fit(&size, &scene.limits)
        .enforce_real_stitches(&fit.leg.path.display().to_string())?;
    let spec = TubeSpec {
        wales,
        courses,
        ..fit.spec
    };
    let mut real = match &fit.path {
        Some(path) => build_stocking(&spec, path, scene.tube.heel, CourseSpacing::Even),
        None => build_tube(&spec, &fit.axis, &fit.leg.positions, &fit.leg.triangles),
    };
    let lock_axis = match &fit.path {
        Some(path) => path.stations[0].t,
        None => fit.axis.direction(),
    };
    let laid = lay_stitches(&fit.knit, &mut real, &fit.collider, fit.offset, lock_axis);
    Ok((real, laid))
}

/// The report's details of a finished fit.
fn fit_details(
    scene: &Scene,
    fit: &SolvedFit,
    leg_fields: &KnitFields,
    slack: SlackDetails,
    penetration_fix: Option<PenetrationStats>,
    preview: Option<PreviewStats>,
    yarns: YarnsDetails,
) -> FitDetails {
    let (leg, spec, knit) = (&fit.leg, &fit.spec, &fit.knit);
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
    let fabric = scene.fabric();
    // The grid's own rests: a graded grid's welt is a little longer than an even one's.
    let [around, along] = fabric.stitches_per_cell(knit.grid_rest_m());
    let (min, max) = leg.bounds();
    FitDetails {
        leg: LegDetails {
            file: leg.path.display().to_string(),
            units: leg.units,
            up_axis: leg.up_axis,
            up_axis_found: leg.up_axis_found,
            reoriented_triangles: leg.reoriented_triangles,
            cleaned: leg.cleaned,
            bounds_m: Bounds {
                min: min.coords.into(),
                max: max.coords.into(),
            },
            landmarks: fit.landmarks.as_ref().map(|l| LandmarkDetails::of(l, leg)),
        },
        axis: fit.axis,
        tube: TubeDetails {
            wales: spec.wales,
            courses: spec.courses,
            rest_course_spacing_m: knit.grid_rest_m()[0],
            rest_wale_spacing_m: knit.grid_rest_m()[1],
            toe_tip_wale_spacing_m: knit
                .is_graded()
                .then(|| knit.course_interval(knit.courses - 2)),
            relaxed_length_m: spec.relaxed_length_m,
            relaxed_circumference_m: spec.relaxed_circumference_m,
            stiffness_scale: PerDirection {
                course: knit.stiffness_scale[0],
                wale: knit.stiffness_scale[1],
            },
            centreline_m: fit.centreline.length(),
            bottom: if fit.knit.has_toe_seam() {
                TubeBottom::Toe
            } else {
                TubeBottom::Ankle
            },
            heel: if fit.knit.short_rows().is_some() {
                TubeHeel::Pocket
            } else {
                TubeHeel::None
            },
            axial_range_m: fit.axial_range_m,
            bunched_courses: fit.bunched_courses,
            slack,
            // Only where the fit's contact saw the toes boxed.
            toe_box: (fit.path.as_ref())
                .filter(|_| fit.toe_box.is_some())
                .and_then(|path| path.toe_box_rim())
                .map(|(centre, towards_toe, length_m)| ToeBoxDetails {
                    rim_centre_m: centre.coords.into(),
                    towards_toe: towards_toe.into(),
                    length_m,
                }),
        },
        solver: fit.solver.details(scene, fit.unsettled_at.clone()),
        contact: ContactDetails {
            method: scene.contact.method,
            offset_m: fit.offset,
            counters: fit.counters,
        },
        penetration_fix,
        preview,
        memory: MemoryDetails {
            check: fit.memory.clone(),
            peak_resident_bytes: peak_memory(),
        },
        yarns,
        stocking_surface: None,
        stretch_by_region: match &fit.landmarks {
            Some(landmarks) => {
                let regions = regions(knit, &fit.centreline, fit.path.as_ref(), landmarks);
                let (course, wale) = fields::stretch(knit);
                let shares = knit.point_fabric_shares();
                stretch_by_region(&regions, &course, &wale, shares.as_deref())
            }
            None => Vec::new(),
        },
        knit: KnitDetails {
            needles: fabric.needles,
            courses: spec.relaxed_length_m / fabric.stitch_m[1],
            stitch_m: PerDirection {
                course: fabric.stitch_m[0],
                wale: fabric.stitch_m[1],
            },
            yarn_diameter_um: YarnValues {
                nylon: 1e6 * fabric.yarn_diameter_m[YarnKind::Nylon.index() as usize],
                support: 1e6 * fabric.yarn_diameter_m[YarnKind::Support.index() as usize],
            },
            loop_stiffness_n_per_m: fabric.loop_stiffness_n_per_m,
            stitches_per_cell: PerDirection {
                course: around,
                wale: along,
            },
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

/// A fitted knit on its leg, before any post-processing or file: what `fit` goes on to write
/// and what `bench` measures.
pub struct SolvedFit {
    /// The leg, in world space (metres, +Y up).
    pub leg: Leg,
    /// The leg's landmarks, where the axis was placed on them.
    pub landmarks: Option<Landmarks>,
    /// The axis the tube was stretched along (a stocking to the toe: its leg part).
    pub axis: Axis,
    /// The path of a stocking to the toe, down the leg, around the heel and along the foot.
    pub path: Option<TubePath>,
    /// The stocking's centreline, from course 0 to the last course.
    pub centreline: Centreline,
    /// The leg's collider.
    pub collider: Collider,
    /// The toes boxed (`TubePath::box_the_toes`), where the path has toes: the surface the fit's
    /// contact saw there, the fabric bridging the gaps between toes.
    pub toe_box: Option<Collider>,
    /// The tube asked for.
    pub spec: TubeSpec,
    /// Distance kept between yarn centre line and skin, metres.
    pub offset: f64,
    /// The knit at rest on the leg, after the exact contact pass.
    pub knit: Knit,
    /// What the solver did.
    pub solver: SolverRun,
    /// Where the grid asked for had not settled when the solver ran out of steps, in words:
    /// the courses, their place and whether the residual was within the tolerance (multilevel
    /// only); `None` when it converged.
    pub unsettled_at: Option<String>,
    /// Contact counters over all levels.
    pub counters: ContactCounters,
    /// Deepest yarn point inside the leg against the exact triangles, metres (0 when none is).
    pub max_penetration_m: f64,
    /// Nearest and furthest yarn along the centreline, metres from its start.
    pub axial_range_m: [f64; 2],
    /// Courses that came to rest below a course before them (a small fold above a slack ankle;
    /// more than [`MAX_BUNCHED_FRACTION`] of them is refused as bunched).
    pub bunched_courses: usize,
    /// The memory estimate checked before the leg was decoded.
    pub memory: MemoryCheck,
}

/// Loads the leg, finds its axis, builds the collider and fits the tube with the scene's solver,
/// then the exact contact pass and the penetration check: the stages of `plan` up to
/// [`Stage::CheckPenetration`], timed on `clock`.
pub fn solve_fit(
    scene: &Scene,
    plan: &Plan,
    inputs: &FitInputs,
    scene_name: &str,
    clock: &mut StageClock,
    progress: &mut dyn Progress,
) -> Result<SolvedFit> {
    let (leg, mut memory) = clock.time(Stage::LoadLeg, || -> Result<_> {
        let file = read_leg_file(&inputs.leg)?;
        // Refuse a fit too large for memory before the leg is decoded or the knit allocated.
        let memory = memory_check(scene, plan, file.declared_triangles());
        memory.enforce(&inputs.leg.display().to_string())?;
        Ok((
            decode_leg(file, scene.leg.units, scene.leg.up_axis)?,
            memory,
        ))
    })?;
    let Placement {
        landmarks,
        axis,
        path,
    } = place_axis(scene, inputs, &leg, clock)?;
    let centreline = match &path {
        Some(path) => Centreline::of_path(path),
        None => Centreline::straight(&axis),
    };
    let (collider, boxed_toes) = clock.time(Stage::BuildCollider, || -> Result<_> {
        let collider = Collider::new(&leg, scene.contact.method)?;
        // The fit's contact sees the toes boxed (TubePath::box_the_toes).
        let boxed = path
            .as_ref()
            .and_then(|path| path.box_the_toes(&leg.positions, &leg.triangles));
        let boxed_toes = match boxed {
            Some((positions, triangles)) => {
                let mut boxed = leg.clone();
                (boxed.positions, boxed.triangles) = (positions, triangles);
                Some(Collider::new(&boxed, scene.contact.method)?)
            }
            None => None,
        };
        Ok((collider, boxed_toes))
    })?;
    let relaxed_length = relaxed_length(scene, centreline.length(), scene_name)?;
    let fabric = scene.fabric();
    let spec = tube_spec(
        scene,
        plan,
        &leg,
        path.is_some(),
        relaxed_length,
        scene_name,
        &mut memory,
    )?;
    check_heel_pocket(scene, &spec, path.is_some(), scene_name)?;
    let offset = scene.contact.offset(&scene.yarns);
    let mut levels = TubeLevels {
        spec,
        path: path.as_ref(),
        heel: scene.tube.heel,
        centreline: &centreline,
        lock_axis: match &path {
            Some(path) => path.stations[0].t,
            None => axis.direction(),
        },
        axis: &axis,
        leg: &leg,
        collider: boxed_toes.as_ref().unwrap_or(&collider),
        offset,
        support_ratio: scene.yarns.support.stiffness / scene.yarns.nylon.stiffness,
        real_count: fabric.real_count(relaxed_length),
        contact: None,
        retired: ContactCounters::default(),
    };
    let (mut knit, solver) = match scene.solver.method {
        SolverMethod::Paper => {
            let mut knit = clock.time(Stage::KnitTube, || {
                levels.knit(spec.wales, spec.courses, true)
            });
            progress.begin("fit", scene.solver.max_steps as u64);
            let stats = clock.time(Stage::Fit, || {
                let contact = levels.constraints(&knit);
                relax_constrained(
                    &mut knit,
                    &plan.forces,
                    &scene.solver,
                    contact,
                    &mut StepProgress(progress),
                )
            });
            progress.end();
            (knit, SolverRun::Paper(stats?))
        }
        SolverMethod::Multilevel => {
            progress.begin("fit", scene.solver.max_steps as u64);
            let solved = clock.time(Stage::Fit, || {
                relax_multilevel(
                    &mut levels,
                    spec.wales,
                    spec.courses,
                    &plan.forces,
                    scene.solver.tolerance,
                    scene.solver.max_steps,
                    &mut StepProgress(progress),
                )
            });
            progress.end();
            let (knit, stats) = solved?;
            (knit, SolverRun::Multilevel(stats))
        }
    };
    if let Some(level) = solver.stalled() {
        // A stocking stopped while bunched is refused as that: it says more.
        let ratio = levels.support_ratio;
        refuse_bunched(&knit, &centreline, spec.relaxed_circumference_m, ratio)?;
        return Err(stalled(
            scene,
            &leg,
            &axis,
            &centreline,
            landmarks.as_ref(),
            level,
            &course_places(&knit, level.courses),
        ));
    }
    // A fit that ran out of steps is written, and says where it had not settled.
    let unsettled_at = solver.unsettled().map(|(level, unsettled)| {
        let named = landmarks_or_found(scene, &leg, landmarks.as_ref());
        let at = Whereabouts::of(
            &axis,
            &centreline,
            named.as_deref(),
            &course_places(&knit, level.courses),
            unsettled,
        );
        unsettled_words(&at, unsettled, level, scene.solver.tolerance)
    });
    let mut contact = levels
        .contact
        .take()
        .expect("the solver made the fine grid's contact");
    clock.time(Stage::ExactContactPass, || {
        contact.finish_on(&collider, &mut knit.particles.x, &knit.particles.inv_mass)
    });

    let mut counters = levels.retired;
    counters.add(&contact.counters());
    let ((max_penetration_m, touching), axial_range_m) =
        clock.time(Stage::CheckPenetration, || {
            (
                skin_contact(&knit, &collider),
                axial_range(&knit, &centreline),
            )
        });
    if touching < MIN_TOUCHING_FRACTION {
        return Err(Error::Leg {
            path: leg.path.clone(),
            message: format!(
                "the fitted stocking is not on the leg: only {:.0}% of its points came to rest \
                 on the skin (a fit touches it nearly everywhere); the axis ({}) misses the leg or \
                 the stocking is far too wide for it",
                100.0 * touching,
                match axis.source {
                    AxisSource::CommandLine => "--axis",
                    AxisSource::Scene => "leg.axis",
                    AxisSource::Landmarks => "placed on the landmarks",
                }
            ),
        });
    }
    let bunched = refuse_bunched(
        &knit,
        &centreline,
        spec.relaxed_circumference_m,
        levels.support_ratio,
    )?;
    Ok(SolvedFit {
        leg,
        landmarks,
        axis,
        path,
        centreline,
        collider,
        toe_box: boxed_toes,
        spec,
        offset,
        knit,
        solver,
        unsettled_at,
        counters,
        max_penetration_m,
        axial_range_m,
        bunched_courses: bunched,
        memory,
    })
}

/// How many of `knit`'s courses came to rest below a course before them; refused as
impl SolvedFit {
    /// The surface the fitted fabric rests on: the skin, with the toes boxed where it has toes.
    pub fn rested_on(&self) -> &Collider {
        self.toe_box.as_ref().unwrap_or(&self.collider)
    }

    /// The fitted knit's fields, per point and on the leg's vertices ([`measure_fields`]), as
    /// the real stocking `fabric` with the stiffness of `terms`, pressing on the skin it rests on.
    pub fn fields(&self, fabric: &Fabric, terms: &ForceTerms) -> (KnitFields, KnitFields) {
        let skin = SkinCurvature::of(self.rested_on(), fields::MEASURE_SPAN_M);
        measure_fields(&self.knit, &self.leg, &skin, self.offset, fabric, terms)
    }
}

/// [`Error::Bunched`] above [`MAX_BUNCHED_FRACTION`] of them.
fn refuse_bunched(
    knit: &Knit,
    centreline: &Centreline,
    circumference_m: f64,
    support_ratio: f64,
) -> Result<usize> {
    let (bunched, first) = bunched_courses(knit, centreline);
    match first.filter(|_| bunched as f64 > MAX_BUNCHED_FRACTION * knit.courses as f64) {
        Some(course) => Err(Error::Bunched {
            course,
            bunched,
            courses: knit.courses,
            place: {
                // Where the courses from the first out of order on came to rest.
                let along: Vec<f64> = (course..knit.courses)
                    .map(|c| centreline.course_along(knit, c))
                    .collect();
                let lo = along.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = along.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                format!(
                    "gathered {:.0}–{:.0} cm along the stocking from its {} end",
                    100.0 * lo.max(0.0),
                    100.0 * hi.max(0.0),
                    if knit.has_toe_seam() { "top" } else { "bottom" }
                )
            },
            ratio: support_ratio,
            circumference_m,
        }),
        None => Ok(bunched),
    }
}

/// Finds the leg's landmarks when the scene gives no axis, and places the stocking's axis: the
/// [`Stage::FindLandmarks`] and [`Stage::FindAxis`] of a fit, timed on `clock`. `knitfit plan`
/// runs the same, so a plan shows what the fit will dress or refuses what it will refuse.
///
/// Errors: [`Error::Leg`] when the landmarks cannot be found, the axis cannot be placed on them,
/// or the leg does not go around the axis.
pub fn place_axis(
    scene: &Scene,
    inputs: &FitInputs,
    leg: &Leg,
    clock: &mut StageClock,
) -> Result<Placement> {
    let landmarks = match scene.leg.axis {
        Some(_) => None,
        None => Some(clock.time(Stage::FindLandmarks, || {
            find_landmarks(&leg.positions, &leg.triangles, leg.up, scene.leg.side).map_err(
                |message| Error::Leg {
                    path: leg.path.clone(),
                    message: format!("cannot find the leg's landmarks: {message}"),
                },
            )
        })?),
    };
    let (axis, path) = clock.time(Stage::FindAxis, || -> Result<_> {
        let axis = choose_axis(scene, inputs, leg, &landmarks)?;
        let path = match (scene.tube.bottom, &landmarks) {
            (Some(TubeBottom::Ankle), _) => None,
            (Some(TubeBottom::Toe), None) => {
                return Err(Error::Leg {
                    path: leg.path.clone(),
                    message: "tube.bottom is \"toe\", but leg.axis gives a straight tube; set \
                              tube.bottom to \"ankle\", or leave leg.axis out so the stocking \
                              follows the leg's landmarks"
                        .into(),
                })
            }
            // Absent: to the toe where the leg has a foot.
            (None, None) => None,
            (None, Some(l)) if l.foot.is_none() => None,
            (_, Some(l)) => Some(stocking_path(scene, leg, l)?),
        };
        Ok((axis, path))
    })?;
    Ok(Placement {
        landmarks,
        axis,
        path,
    })
}

/// Where a fit's stocking goes: the landmarks it was placed on, its axis, and, for a stocking
/// to the toe, its path over the foot.
pub struct Placement {
    /// The leg's landmarks (none where the scene gives the axis).
    pub landmarks: Option<Landmarks>,
    /// The stocking's axis (to the toe: its leg part, from the ankle up).
    pub axis: Axis,
    /// The path of a stocking to the toe.
    pub path: Option<TubePath>,
}

/// The tube the scene asks for on a stocking `relaxed_length` long, its courses given or, where
/// the scene leaves them out, the stitch's ([`Fabric::grid_courses`]), checked as a given grid is
/// before the leg is read: its size, its memory (which replaces `memory`, the estimate made
/// before), and for a stocking to the toe its coarseness.
fn tube_spec(
    scene: &Scene,
    plan: &Plan,
    leg: &Leg,
    to_toe: bool,
    relaxed_length: f64,
    scene_name: &str,
    memory: &mut MemoryCheck,
) -> Result<TubeSpec> {
    let fabric = scene.fabric();
    let wales = scene.tube.wales;
    let spec = TubeSpec {
        wales,
        courses: scene
            .tube
            .courses
            .unwrap_or_else(|| fabric.grid_courses(wales, relaxed_length)),
        pattern: scene.knit.pattern,
        relaxed_circumference_m: fabric.relaxed_circumference_m(),
        relaxed_length_m: relaxed_length,
        stitch_m: fabric.stitch_m,
    };
    if scene.tube.courses.is_none() {
        let refuse = |message: String| Error::InvalidScene {
            path: scene_name.to_string(),
            field: "tube.courses".into(),
            message: format!(
                "left out, it follows the stitch: {message}; give tube.courses (--resolution \
                 WxC)"
            ),
        };
        check_grid_size(wales, spec.courses).map_err(refuse)?;
        if let Some(why) = to_toe
            .then(|| too_coarse_a_stocking(wales, spec.courses))
            .flatten()
        {
            return Err(refuse(why));
        }
    }
    // A stocking with fewer courses than the stitch's is relaxed first on the real count's
    // level with its wales, which has more points (`grid_sizes_following`).
    let solved_on = to_toe
        .then(|| {
            let real = fabric.real_count(relaxed_length);
            largest_level(&grid_sizes_following(
                real,
                wales,
                spec.courses,
                STOCKING_COARSEST,
            ))
        })
        .filter(|&[w, c]| w.saturating_mul(c) > wales * spec.courses);
    if let Some([w, c]) = solved_on {
        check_grid_size(w, c).map_err(|message| Error::InvalidScene {
            path: scene_name.to_string(),
            field: "tube".into(),
            message: format!("relaxed first on the real stitch count's {w}×{c} level: {message}"),
        })?;
    }
    // Courses left out, or a larger level, are known only now: the estimate made before the
    // leg was read is replaced.
    if scene.tube.courses.is_none() || solved_on.is_some() {
        let outputs: Vec<_> = plan.files.iter().map(|file| file.output).collect();
        let size = FitSize {
            tube: [wales, spec.courses],
            solved_on,
            ..fit_size(scene, &outputs, leg.triangles.len())
        };
        *memory = MemoryCheck::fit(&size, &scene.limits);
        memory.enforce(&leg.path.display().to_string())?;
    }
    Ok(spec)
}

/// Fewest wales or courses a stocking to the toe is fitted on: below it the rings are
/// centimetres apart over the heel and the toe. Its coarse levels may go to
/// [`STOCKING_COARSEST`], as they only start the next level.
const SMALLEST_STOCKING: usize = 60;

/// Why a stocking to the toe may not be fitted on a `wales × courses` grid, if it may not.
fn too_coarse_a_stocking(wales: usize, courses: usize) -> Option<String> {
    (wales.min(courses) < SMALLEST_STOCKING).then(|| {
        format!(
            "at {wales}×{courses} the rings would be centimetres apart over the heel and the \
             toe, where such a coarse fit chatters instead of settling; give at least \
             {SMALLEST_STOCKING}×{SMALLEST_STOCKING} (--resolution, tube.wales and \
             tube.courses)"
        )
    })
}

/// The path of a stocking to the toe on `landmarks`, its top where `tube.top` puts it.
fn stocking_path(scene: &Scene, leg: &Leg, landmarks: &Landmarks) -> Result<TubePath> {
    let fail = |message: String| Error::Leg {
        path: leg.path.clone(),
        message: format!(
            "cannot take the stocking to the toe: {message}; or set tube.bottom to \"ankle\" \
             (--bottom ankle) for a stocking that ends there"
        ),
    };
    // Courses left out are checked once the stocking's length gives them (`tube_spec`).
    let courses = scene.tube.courses.unwrap_or(SMALLEST_STOCKING);
    if let Some(why) = too_coarse_a_stocking(scene.tube.wales, courses) {
        return Err(fail(why));
    }
    let axis = tube_axis(landmarks, TubeBottom::Toe, scene.tube.top).map_err(fail)?;
    let top_s = axis.top().coords.dot(&Vector3::from(landmarks.up));
    path_to_toe(landmarks, top_s, &leg.positions, &leg.triangles).map_err(fail)
}

/// Courses per wale the memory estimate takes where the scene leaves the courses out, before
/// the stocking's length is known: 1.6–2.0 on the samples' stockings to the toe.
const COURSES_PER_WALE_ESTIMATE: usize = 2;

/// The fit's memory check: its tube, leg and files against the scene's limits.
pub fn memory_check(scene: &Scene, plan: &Plan, leg_triangles: usize) -> MemoryCheck {
    let outputs: Vec<_> = plan.files.iter().map(|file| file.output).collect();
    MemoryCheck::fit(&fit_size(scene, &outputs, leg_triangles), &scene.limits)
}

/// The size of `scene`'s fit for the memory estimate, writing `outputs`.
fn fit_size<'a>(scene: &Scene, outputs: &'a [Output], leg_triangles: usize) -> FitSize<'a> {
    FitSize {
        // Courses left out follow the stitch (Fabric::grid_courses): up to twice the wales on
        // the samples' stockings to the toe, fewer on a leg alone; checked again once known
        // (`tube_spec`).
        tube: [
            scene.tube.wales,
            scene
                .tube
                .courses
                .unwrap_or(COURSES_PER_WALE_ESTIMATE * scene.tube.wales),
        ],
        leg_triangles,
        outputs,
        preview_pixels: u64::from(scene.render.width) * u64::from(scene.render.height),
        // Loops are drawn for the real stitches, checked once their count is known.
        loops: false,
        // A larger level than the grid is known once the stocking's length is (`tube_spec`).
        solved_on: None,
    }
}

/// The tube at any grid size, and its contact with the leg: what the solvers knit and constrain.
struct TubeLevels<'a> {
    /// The tube asked for; other levels change only its wales and courses.
    spec: TubeSpec,
    /// A stocking to the toe's path (else an open tube along `axis`).
    path: Option<&'a TubePath>,
    heel: TubeHeel,
    centreline: &'a Centreline,
    /// The direction the held ring(s) may not move along.
    lock_axis: Vector3<f64>,
    axis: &'a Axis,
    leg: &'a Leg,
    collider: &'a Collider,
    /// Distance kept between yarn centre line and skin, metres.
    offset: f64,
    /// Support yarn's stiffness over nylon's, for the bunched refusal.
    support_ratio: f64,
    /// The real stitch count (wales, courses), whose levels a stocking's grids follow.
    real_count: [usize; 2],
    /// Contact of the level being solved.
    contact: Option<LegContact<'a>>,
    /// Counters of the levels solved before it.
    retired: ContactCounters,
}

impl<'a> Levels for TubeLevels<'a> {
    fn knit(&mut self, wales: usize, courses: usize, finest: bool) -> Knit {
        let spec = TubeSpec {
            wales,
            courses,
            ..self.spec
        };
        match self.path {
            // The grid the fit ends on resolves the toe's tip; the levels it starts from
            // follow the real stitches' even courses (docs/decisions/0073).
            Some(path) => {
                let spacing = match finest {
                    true => CourseSpacing::FinerAtTheToe,
                    false => CourseSpacing::Even,
                };
                build_stocking(&spec, path, self.heel, spacing)
            }
            None => build_tube(&spec, self.axis, &self.leg.positions, &self.leg.triangles),
        }
    }

    fn constraints(&mut self, knit: &Knit) -> &mut dyn Constraints {
        if let Some(done) = self.contact.take() {
            self.retired.add(&done.counters());
        }
        let rest_spacing = self.spec.relaxed_circumference_m / knit.wales as f64;
        let query_radius = (10.0 * rest_spacing).max(0.005);
        self.contact.insert(LegContact::new(
            self.collider,
            self.offset,
            query_radius,
            self.lock_axis,
            end_rings(knit),
        ))
    }

    fn grid_sizes(&self, wales: usize, courses: usize) -> Vec<(usize, usize)> {
        // A heel and a toe need rings a few centimetres apart at most, and a foot rests where
        // its coarse levels leave it: a grid starts where the real count does, where it can.
        let Some(_) = self.path else {
            return grid_sizes_down_to(wales, courses, COARSEST);
        };
        let mut sizes = grid_sizes_following(self.real_count, wales, courses, STOCKING_COARSEST);
        // A grid graded at the toe's tip that is also one of the real count's levels (courses
        // following the stitch) solves that level, even, first: so it starts where the real
        // count's level rests, as an N×N grid does from the level with its wales.
        let [real_wales, real_courses] = self.real_count;
        let chain = grid_sizes_down_to(real_wales, real_courses, STOCKING_COARSEST);
        let spec = TubeSpec {
            wales,
            courses,
            ..self.spec
        };
        if chain.contains(&(wales, courses)) && toe_graded_intervals(&spec).is_some() {
            sizes.insert(sizes.len() - 1, (wales, courses));
        }
        sizes
    }

    fn accept(&mut self, knit: &Knit) -> Result<()> {
        refuse_bunched(
            knit,
            self.centreline,
            self.spec.relaxed_circumference_m,
            self.support_ratio,
        )
        .map(|_| ())
    }
}

/// What the fit's solver did.
pub enum SolverRun {
    /// The paper's explicit solver.
    Paper(RelaxStats),
    /// The multilevel solver.
    Multilevel(MultilevelStats),
}

impl SolverRun {
    /// Steps (paper) or iterations over all levels (multilevel).
    pub fn steps(&self) -> usize {
        match self {
            SolverRun::Paper(s) => s.steps,
            SolverRun::Multilevel(s) => s.total_iterations(),
        }
    }

    /// Final relative residual on the grid asked for.
    pub fn residual(&self) -> f64 {
        match self {
            SolverRun::Paper(s) => s.residual,
            SolverRun::Multilevel(s) => s.fine().residual,
        }
    }

    /// Final largest move per step on the grid asked for, over the shortest rest length.
    pub fn max_move(&self) -> f64 {
        match self {
            SolverRun::Paper(s) => s.max_move,
            SolverRun::Multilevel(s) => s.fine().max_move,
        }
    }

    /// Multilevel only: the final force step on the grid asked for.
    pub fn force_step(&self) -> Option<f64> {
        match self {
            SolverRun::Paper(_) => None,
            SolverRun::Multilevel(s) => Some(s.fine().force_step),
        }
    }

    /// The level that stopped as futile, if one did (multilevel only).
    pub fn stalled(&self) -> Option<&LevelStats> {
        match self {
            SolverRun::Paper(_) => None,
            SolverRun::Multilevel(s) => s.levels.last().filter(|l| l.stall.is_some()),
        }
    }

    /// The grid asked for, and where it had not settled when it ran out of steps (multilevel
    /// only).
    pub fn unsettled(&self) -> Option<(&LevelStats, &OutOfBalance)> {
        match self {
            SolverRun::Paper(_) => None,
            SolverRun::Multilevel(s) => {
                let fine = s.fine();
                fine.unsettled.as_ref().map(|at| (fine, at))
            }
        }
    }

    /// True when the grid asked for converged.
    pub fn converged(&self) -> bool {
        match self {
            SolverRun::Paper(s) => s.converged,
            SolverRun::Multilevel(s) => s.fine().converged,
        }
    }

    /// The report's `details.solver`.
    pub fn details(&self, scene: &Scene, unsettled_at: Option<String>) -> SolverDetails {
        match self {
            SolverRun::Paper(stats) => SolverDetails::Paper {
                tolerance: scene.solver.tolerance,
                time_step: scene.solver.time_step,
                time_step_limit: stats.time_step_limit,
                substeps_per_step: stats.substeps_per_step,
            },
            SolverRun::Multilevel(stats) => SolverDetails::Multilevel {
                tolerance: scene.solver.tolerance,
                fine_grid_equivalent_iterations: stats.fine_grid_equivalent_iterations(),
                levels: stats.levels.clone(),
                unsettled_at,
            },
        }
    }
}

/// The axis from the scene (converted from file coordinates), or placed on the landmarks by
/// `tube.bottom` and `tube.top`; refused where the leg does not go around it.
fn choose_axis(
    scene: &Scene,
    inputs: &FitInputs,
    leg: &Leg,
    landmarks: &Option<Landmarks>,
) -> Result<Axis> {
    let fail = |message: String| Error::Leg {
        path: leg.path.clone(),
        message,
    };
    let axis = match (&scene.leg.axis, landmarks) {
        (Some(given), _) => {
            let bottom = leg.world_from_file(&Point3::from(given.bottom));
            let top = leg.world_from_file(&Point3::from(given.top));
            Axis {
                bottom: bottom.coords.into(),
                top: top.coords.into(),
                source: inputs.axis_source,
            }
        }
        (None, Some(landmarks)) => {
            let bottom = scene.tube.bottom.unwrap_or(TubeBottom::Ankle);
            tube_axis(landmarks, bottom, scene.tube.top).map_err(fail)?
        }
        (None, None) => unreachable!("landmarks are found whenever no axis is given"),
    };
    if let Some(at) = leaves_mesh(leg, &axis) {
        let given = match axis.source {
            AxisSource::CommandLine => "--axis",
            AxisSource::Scene => "leg.axis",
            AxisSource::Landmarks => "the axis placed on the landmarks",
        };
        return Err(fail(format!(
            "{given} runs outside the leg {:.0}% of the way from its bottom end to its top: it \
             misses the leg, or runs between two legs; check its coordinates (file units, {} up)",
            100.0 * at,
            leg.up_axis.name()
        )));
    }
    Ok(axis)
}

/// Below this many points around, a grid's rings are polygons coarse enough to catch on a knee
/// (a heavy knee is about 40 cm around: 1.6 cm a side at 24).
const COARSE_GRID_WALES: usize = 40;

/// Where a level of `courses` courses has each along its fabric: the knit's relaxed places
/// where it is that level (a graded grid's courses crowd over the toe's tip), else evenly.
fn course_places(knit: &Knit, courses: usize) -> Vec<f64> {
    match knit.courses == courses && knit.is_graded() {
        true => knit.course_places(),
        false => (0..courses).map(|c| c as f64).collect(),
    }
}

/// Where on the stocking a level's courses stopped out of balance, in words.
struct Whereabouts {
    /// The courses, and how far along the stocking they lie: "courses 140–148 of 150 (70–75 cm
    /// down the stocking from its top)".
    courses: String,
    /// The worst point's height and nearest landmark (", worst 2 cm above the sole, at the
    /// foot"); empty without landmarks.
    worst: String,
    /// True for a stocking to the toe (knitted from its welt down: course 0 is its top).
    to_the_toe: bool,
    /// True where the worst point is nearest the foot, or no landmark names it.
    at_foot: bool,
}

impl Whereabouts {
    fn of(
        axis: &Axis,
        centreline: &Centreline,
        landmarks: Option<&Landmarks>,
        places: &[f64],
        at: &OutOfBalance,
    ) -> Whereabouts {
        let courses = places.len();
        let total = places.last().copied().filter(|&p| p > 0.0).unwrap_or(1.0);
        let place = |c: usize| places.get(c).copied().unwrap_or(total);
        let [from, to] = at.courses.map(|c| place(c) / total * centreline.length());
        let to_the_toe = centreline.length() > axis.length() + 1e-9;
        let [first, last] = at.courses;
        let along = format!(
            "{} of {courses} ({:.0}–{:.0} cm {})",
            if first == last {
                format!("course {first}")
            } else {
                format!("courses {first}–{last}")
            },
            100.0 * from,
            100.0 * to,
            if to_the_toe {
                "down the stocking from its top"
            } else {
                "up the stocking from its bottom end"
            }
        );
        let Some(l) = landmarks else {
            return Whereabouts {
                courses: along,
                worst: String::new(),
                to_the_toe,
                at_foot: true,
            };
        };
        let worst = Point3::from(at.worst_point);
        let up = Vector3::from(l.up);
        let height = worst.coords.dot(&up) - l.sole_s();
        let named = [
            ("the foot", l.sole_s()),
            ("the ankle", l.ankle.s),
            ("the knee", l.knee.s),
            ("the top of the thigh", l.thigh_top.s),
        ];
        let (name, _) = named
            .iter()
            .min_by(|a, b| {
                let d = |s: f64| (worst.coords.dot(&up) - s).abs();
                d(a.1).total_cmp(&d(b.1))
            })
            .expect("four landmarks");
        Whereabouts {
            courses: along,
            worst: format!(
                ", worst {:.0} cm above the sole, at {name}",
                (100.0 * height).max(0.0)
            ),
            to_the_toe,
            at_foot: *name == "the foot",
        }
    }
}

/// `landmarks`, or where a given axis left the fit none, the leg's own: what names a place.
fn landmarks_or_found<'a>(
    scene: &Scene,
    leg: &Leg,
    landmarks: Option<&'a Landmarks>,
) -> Option<Cow<'a, Landmarks>> {
    match landmarks {
        Some(l) => Some(Cow::Borrowed(l)),
        None => find_landmarks(&leg.positions, &leg.triangles, leg.up, scene.leg.side)
            .ok()
            .map(Cow::Owned),
    }
}

/// Where a `level` that ran out of steps had not settled, in words, `at` the place of
/// `unsettled`: the courses whose force step was above the `tolerance`, and whether the residual
/// was within it (only those courses had not settled); or the grid as a whole, where no point
/// was above it and only the residual was.
fn unsettled_words(
    at: &Whereabouts,
    unsettled: &OutOfBalance,
    level: &LevelStats,
    tolerance: f64,
) -> String {
    if unsettled.worst_force_step <= tolerance {
        return format!(
            "no course stood out: the residual over the whole grid, {:.1e}, was above the \
             tolerance",
            level.residual
        );
    }
    let residual = match level.residual < tolerance {
        true => format!(
            "; the residual, {:.1e}, was within the tolerance, their largest force step, {:.1e}, \
             was not",
            level.residual, unsettled.worst_force_step
        ),
        false => String::new(),
    };
    format!("{} had not settled{}{residual}", at.courses, at.worst)
}

/// The error of a fit stopped as futile on `level`: where along the stocking its courses are out
/// of balance, near which landmark, and what to change.
fn stalled(
    scene: &Scene,
    leg: &Leg,
    axis: &Axis,
    centreline: &Centreline,
    landmarks: Option<&Landmarks>,
    level: &LevelStats,
    places: &[f64],
) -> Error {
    let stall = level.stall.expect("a stalled level says where");
    let named = landmarks_or_found(scene, leg, landmarks);
    let landmarks = named.as_deref();
    let at = Whereabouts::of(axis, centreline, landmarks, places, &stall);
    let place = format!("{} are out of balance{}", at.courses, at.worst);
    let (to_the_toe, at_foot) = (at.to_the_toe, at.at_foot);
    let circumference = scene.fabric().relaxed_circumference_m();
    let advice = match (landmarks, axis.source) {
        (Some(l), _) if circumference < 0.5 * l.ankle.girth_m => format!(
            "The stocking is far too small for this leg: relaxed {circumference} m around, \
             against an ankle of {:.3} m; raise tube.relaxed_circumference_m.",
            l.ankle.girth_m
        ),
        (Some(_), _) if to_the_toe && at_foot => {
            "The foot of the stocking cannot settle on this foot (look for debris or a broken \
             surface there): end the stocking at the ankle (--bottom ankle), or try another grid \
             (--resolution)."
                .to_string()
        }
        (_, AxisSource::CommandLine | AxisSource::Scene) if at_foot => {
            let flag = if axis.source == AxisSource::CommandLine {
                "--axis"
            } else {
                "leg.axis"
            };
            let ankle = landmarks.map_or(String::new(), |l| {
                let at = leg.file_from_world(&Point3::from(l.ankle.centre));
                format!(
                    " (here about {:.3}, {:.3}, {:.3} in the file)",
                    at.x, at.y, at.z
                )
            });
            format!(
                "Check {flag}: a straight stocking cannot be pulled over a foot, so its bottom \
                 belongs at the ankle{ankle}; leave {flag} out and knitfit places the stocking on \
                 the leg's landmarks."
            )
        }
        (_, AxisSource::CommandLine | AxisSource::Scene) => format!(
            "Check {}: the stocking cannot settle around it here; leave it out and knitfit \
             places the stocking on the leg's landmarks.",
            if axis.source == AxisSource::CommandLine {
                "--axis"
            } else {
                "leg.axis"
            }
        ),
        _ if scene.yarns.support.stiffness >= 100.0 * scene.yarns.nylon.stiffness => format!(
            "The support yarn ({}× nylon's) barely stretches: lower yarns.support.stiffness, or \
             raise tube.relaxed_circumference_m (now {circumference} m).",
            scene.yarns.support.stiffness / scene.yarns.nylon.stiffness
        ),
        _ if level.wales < COARSE_GRID_WALES => format!(
            "The {}×{} grid is coarse for this leg: its rings are polygons whose corners catch \
             on it; give a finer grid (--resolution, tube.wales and tube.courses).",
            level.wales, level.courses
        ),
        _ => "The leg is too thin or bent here for the stocking: end it lower (tube.top), or \
              raise tube.relaxed_circumference_m."
            .into(),
    };
    Error::Stalled {
        grid: format!("{}×{}", level.wales, level.courses),
        iterations: level.iterations,
        seconds: level.seconds,
        residual: level.residual,
        place,
        advice,
    }
}

/// The stocking's relaxed length: given (and shorter than the axis), or a fraction of the axis.
fn relaxed_length(scene: &Scene, length: f64, scene_name: &str) -> Result<f64> {
    match scene.tube.relaxed_length_m {
        None => Ok(RELAXED_LENGTH_FRACTION * length),
        Some(l) if l < length => Ok(l),
        Some(l) => Err(Error::InvalidScene {
            path: scene_name.to_string(),
            field: "tube.relaxed_length_m".into(),
            message: format!(
                "{l} m is not shorter than the stocking's centreline ({length:.3} m): the \
                 stocking would bunch up instead of being stretched onto the leg; give a shorter \
                 length, leave it out ({RELAXED_LENGTH_FRACTION} × the centreline), or place the \
                 axis points further apart"
            ),
        }),
    }
}

/// Refuses a heel pocket longer than the relaxed stocking it is knitted into: its rows on the
/// grid are its length over the grid's course spacing, so such a pocket has more rows than the
/// stocking has courses, without bound (a relaxed length of 1e-9 m aborted allocating them).
fn check_heel_pocket(scene: &Scene, spec: &TubeSpec, to_toe: bool, scene_name: &str) -> Result<()> {
    let (half, length) = (heel_pocket_half_length_m(spec), spec.relaxed_length_m);
    if scene.tube.heel != TubeHeel::Pocket || !to_toe || half <= length {
        return Ok(());
    }
    // Millimetres as millimetres; a length far below them as the number it is.
    let length = match length >= 1e-3 {
        true => format!("{length:.3}"),
        false => number(length),
    };
    Err(Error::InvalidScene {
        path: scene_name.to_string(),
        field: "tube.heel".into(),
        message: format!(
            "the heel pocket would be {half:.3} m of fabric each way ({:.0} stitches around / \
             6 courses of {} m), longer than the relaxed stocking ({length} m): ask for fewer \
             stitches around (knit.needles) or a shorter knit.wale_spacing_m, or give a longer \
             tube.relaxed_length_m",
            spec.relaxed_circumference_m / spec.stitch_m[0],
            number(spec.stitch_m[1]),
        ),
    })
}

/// A fit whose yarn rests on the skin at fewer than this fraction of its points is no stocking
/// on this leg: a tight fit touches nearly everywhere, and even one far wider than the leg
/// (support yarn 1000× nylon's relaxed at the thigh's girth) rests on a fifth of its points.
pub const MIN_TOUCHING_FRACTION: f64 = 0.1;
/// A point within this distance of the skin rests on it, metres.
const TOUCHING_M: f64 = 0.002;

/// From exact closest-point queries: the deepest yarn point inside the leg, metres (0 when none
/// is), and the fraction of points within [`TOUCHING_M`] of the skin.
fn skin_contact(knit: &Knit, collider: &Collider) -> (f64, f64) {
    use rayon::prelude::*;
    let (deepest, touching) = knit
        .particles
        .x
        .par_iter()
        .map(|p| {
            let d = collider.closest(&Point3::from(*p)).signed_distance;
            ((-d).max(0.0), usize::from(d <= TOUCHING_M))
        })
        .reduce(|| (0.0, 0), |a, b| (a.0.max(b.0), a.1 + b.1));
    (deepest, touching as f64 / knit.len().max(1) as f64)
}

/// Lowest and highest of `points` along the axis, metres from the bottom point.
/// Nearest and furthest yarn along `centreline`, metres from its start: every grid point's
/// place along an open tube's straight axis; along a stocking to the toe's bent line, its
/// courses' (the mean of each).
fn axial_range(knit: &Knit, centreline: &Centreline) -> [f64; 2] {
    let range = |values: &mut dyn Iterator<Item = f64>| {
        values.fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], s| {
            [lo.min(s), hi.max(s)]
        })
    };
    if knit.has_toe_seam() {
        range(&mut (0..knit.courses).map(|c| centreline.course_along(knit, c)))
    } else {
        let grid = &knit.particles.x[..knit.grid_len()];
        range(&mut grid.iter().map(|p| centreline.along(p)))
    }
}

/// What a fit's files are encoded from.
struct FitProducts<'a> {
    scene: &'a Scene,
    /// How the character stands: what the density picture's views are taken from.
    stance: Stance,
    yarns: &'a YarnGeometry,
    leg_mesh: SurfaceMesh,
    /// The leg's look in `stocking.glb`: its file's material, or skin.
    leg_material: Material,
    /// The stocking surface, lifted ([`Stage::StockingSurface`]; with `glb` only).
    stocking: Option<&'a SurfaceMesh>,
}

impl FitProducts<'_> {
    /// Encodes `file`.
    fn encode(&self, file: FitFile) -> Result<Vec<u8>> {
        let comments = || vec![format!("knitfit {} fit", env!("CARGO_PKG_VERSION"))];
        match file {
            FitFile::StockingGlb => {
                let Some(stocking) = self.stocking else {
                    // The plan builds it wherever it encodes stocking.glb.
                    return Err(Error::Encode {
                        what: "glTF".into(),
                        message: "stocking.glb has no stocking surface to hold".into(),
                    });
                };
                let yarns = &self.scene.yarns;
                // The yarn lines in a scene of their own: drawn in the default one they would
                // sit on top of the sheer stocking (docs/decisions/0056).
                export::gltf::write_scenes_glb(
                    &[
                        (
                            "knitfit",
                            &[
                                GlbNode::Opaque {
                                    mesh: &self.leg_mesh,
                                    material: &self.leg_material,
                                },
                                // Sheer in the nylon's colour: its coverage is the vertex
                                // colours' alpha (docs/decisions/0052).
                                GlbNode::Sheer {
                                    mesh: stocking,
                                    colour: yarns.nylon.colour,
                                },
                            ],
                        ),
                        // Named apart from its node: three.js renames a node that shares a name.
                        ("knitfit yarns", &[GlbNode::Yarns(self.yarns)]),
                    ],
                    yarns.each(|y| y.colour),
                )
            }
            FitFile::StockingPly => {
                export::ply::write_ply(std::slice::from_ref(self.yarns), &comments())
            }
            FitFile::LegPly => export::ply::write_mesh_ply(&self.leg_mesh, &comments()),
            FitFile::DensityPicture => {
                let density: Vec<f64> = self
                    .leg_mesh
                    .point_attributes
                    .get("stitch_density")
                    .map(|d| d.iter().map(|&v| f64::from(v)).collect())
                    .unwrap_or_default();
                let picture = density_map::draw_density(
                    &self.leg_mesh.positions,
                    &self.leg_mesh.triangles,
                    &density,
                    &self.stance,
                    &DensityPictureStyle::default(),
                );
                draw::encode_png(&picture, file.name())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stocking_to_the_toe_stopped_at_the_foot_counts_from_its_top_and_offers_the_ankle() {
        let scene = Scene::load(None).unwrap();
        let leg_path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("samples")
            .join("lowpoly_leg.glb");
        let leg = decode_leg(
            read_leg_file(&leg_path).unwrap(),
            scene.leg.units,
            scene.leg.up_axis,
        )
        .unwrap();
        let inputs = FitInputs {
            leg: leg_path,
            axis_source: AxisSource::Scene,
        };
        let plan = Plan::fit(&scene);
        let placed = place_axis(&scene, &inputs, &leg, &mut StageClock::new(&plan)).unwrap();
        let path = placed
            .path
            .as_ref()
            .expect("a leg with a foot gets a path to the toe");
        let centreline = Centreline::of_path(path);
        let tip = placed.landmarks.as_ref().unwrap().foot.unwrap().toe_tip;
        let level = LevelStats {
            wales: 150,
            courses: 150,
            iterations: 1700,
            polish_iterations: 0,
            restarts: 1500,
            stall_restarts: 0,
            start_residual: 1.5,
            residual: 2.7e-3,
            force_step: 0.1,
            max_move: 0.1,
            converged: false,
            stall: Some(OutOfBalance {
                courses: [140, 148],
                worst_point: tip,
                worst_force_step: 0.1,
            }),
            unsettled: None,
            seconds: 1.0,
        };
        let message = stalled(
            &scene,
            &leg,
            &placed.axis,
            &centreline,
            placed.landmarks.as_ref(),
            &level,
            &(0..level.courses).map(|c| c as f64).collect::<Vec<_>>(),
        )
        .to_string();
        for expected in [
            "going nowhere",
            "courses 140–148 of 150",
            "down the stocking from its top",
            "at the foot",
            "--bottom ankle",
        ] {
            assert!(
                message.contains(expected),
                "expected {expected:?} in {message}"
            );
        }
        assert_eq!(message.lines().count(), 1, "{message}");
    }

    #[test]
    fn a_graded_grids_courses_are_placed_along_its_fabric_in_words() {
        // Courses crowding towards the end: the last three lie in the last 10 cm of a metre,
        // not the last 29 as their index would say.
        let axis = Axis {
            bottom: [0.0, 0.0, 0.0],
            top: [0.0, 1.0, 0.0],
            source: AxisSource::Scene,
        };
        let places = [0.0, 0.2, 0.4, 0.6, 0.8, 0.9, 0.95, 1.0];
        let at = OutOfBalance {
            courses: [5, 7],
            worst_point: [0.0, 0.9, 0.0],
            worst_force_step: 0.1,
        };
        let words = Whereabouts::of(&axis, &Centreline::straight(&axis), None, &places, &at);
        assert_eq!(
            words.courses,
            "courses 5–7 of 8 (90–100 cm up the stocking from its bottom end)"
        );
    }

    #[test]
    fn a_grid_out_of_steps_says_which_courses_had_not_settled_and_whether_the_residual_did() {
        let at = Whereabouts {
            courses: "courses 297–299 of 300 (73–74 cm down the stocking from its top)".into(),
            worst: ", worst 1 cm above the sole, at the foot".into(),
            to_the_toe: true,
            at_foot: true,
        };
        let unsettled = OutOfBalance {
            courses: [297, 299],
            worst_point: [0.0; 3],
            worst_force_step: 1.5e-3,
        };
        let level = |residual: f64| LevelStats {
            wales: 300,
            courses: 300,
            iterations: 15_000,
            polish_iterations: 0,
            restarts: 30,
            stall_restarts: 0,
            start_residual: 0.2,
            residual,
            force_step: 1.5e-3,
            max_move: 0.01,
            converged: false,
            stall: None,
            unsettled: Some(unsettled),
            seconds: 20.0,
        };
        let corner = unsettled_words(&at, &unsettled, &level(3.8e-5), 1e-4);
        assert_eq!(
            corner,
            "courses 297–299 of 300 (73–74 cm down the stocking from its top) had not settled, \
             worst 1 cm above the sole, at the foot; the residual, 3.8e-5, was within the \
             tolerance, their largest force step, 1.5e-3, was not"
        );
        let both = unsettled_words(&at, &unsettled, &level(2e-4), 1e-4);
        assert!(both.ends_with("at the foot"), "{both}");
        // No point above the tolerance: the grid as a whole, not the worst point's course.
        let calm = OutOfBalance {
            worst_force_step: 5e-5,
            ..unsettled
        };
        let whole = unsettled_words(&at, &calm, &level(2e-4), 1e-4);
        assert!(
            whole.starts_with("no course stood out") && !whole.contains("297"),
            "{whole}"
        );
    }
}
