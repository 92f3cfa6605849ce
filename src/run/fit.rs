//! `knitfit fit`: the product's main job (Sakaguchi & Miyata §6.1–6.2). Load the leg, find its
//! axis, build the tube around it, let the springs shrink it onto the leg with sliding contact,
//! measure it, and write the leg with stitch-density attributes, the yarns and the stocking
//! surface.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::Point3;
use serde_json::json;

use super::{Progress, RunPaths, StepProgress};
use crate::base::colour;
use crate::base::{Direction, SurfaceMesh, YarnGeometry, YarnKind};
use crate::error::{Error, Result};
use crate::export;
use crate::export::gltf::GlbNode;
use crate::knit::tube::{build_tube, end_rings, TubeSpec};
use crate::knit::Knit;
use crate::leg::{
    decode_leg, detect_axis, leaves_mesh, read_leg_file, Axis, AxisSource, Collider, Leg,
};
use crate::limits::{peak_memory, MemoryCheck};
use crate::plan::Plan;
use crate::post::fields::{self, KnitFields};
use crate::post::penetration::fix_penetrations;
use crate::post::stitches::{bunched_courses, MAX_BUNCHED_FRACTION};
use crate::render;
use crate::render::density_picture::{self, DensityPictureStyle};
use crate::report::{Metrics, Report, StageClock};
use crate::scene::{Effect, Output, Scene, SolverMethod, RELAXED_LENGTH_FRACTION};
use crate::sim::contact::{ContactCounters, LegContact};
use crate::sim::{
    relax_constrained, relax_multilevel, Constraints, Levels, MultilevelStats, RelaxStats,
};

/// Where the leg comes from and who chose the axis.
#[derive(Clone, Debug)]
pub struct FitInputs {
    /// The leg file.
    pub leg: PathBuf,
    /// Who set `scene.leg.axis` (ignored when it is `None`).
    pub axis_source: AxisSource,
}

/// The result of a fit.
#[derive(Debug)]
pub struct FitOutcome {
    /// The report, as written to `report.json`.
    pub report: Report,
    /// Every file written, report included.
    pub written: Vec<PathBuf>,
}

/// Runs the fit of `scene` and writes its files into `paths.out_dir`.
pub fn run_fit(
    scene: &Scene,
    inputs: &FitInputs,
    paths: &RunPaths,
    progress: &mut dyn Progress,
) -> Result<FitOutcome> {
    let plan = Plan::fit(scene);
    let mut clock = StageClock::default();
    let mut all_inputs = paths.inputs.clone();
    all_inputs.push(inputs.leg.clone());
    let file_names: Vec<&str> = plan
        .files
        .iter()
        .map(|(_, name)| *name)
        .chain(["report.json"])
        .collect();
    export::atomic::prepare_dir(&paths.out_dir, &file_names, &all_inputs)?;

    let SolvedFit {
        leg,
        axis,
        collider,
        spec,
        offset,
        knit,
        solver,
        counters,
        max_penetration_m: max_penetration,
        axial_range_m: axial_range,
        bunched_courses,
        memory,
    } = solve_fit(
        scene,
        &plan,
        inputs,
        &paths.scene_name,
        &mut clock,
        progress,
    )?;
    let radius_m = YarnKind::ALL.map(|k| scene.yarns.get(k).radius_m);
    let (knit_fields, leg_fields) = if plan.has_stage("leg attributes") {
        clock.time("leg attributes", || measure_fields(&knit, &leg, radius_m))
    } else {
        (KnitFields::default(), KnitFields::default())
    };
    let tension = fields::tension(&knit, &plan.forces);

    let mut yarns = knit.yarn_geometry("yarns", [0.0; 3]);
    yarns.point_attributes.insert(
        "tension".into(),
        tension.iter().map(|&t| t as f32).collect(),
    );
    let mut penetration_fix = None;
    if plan.effects.contains(&Effect::PenetrationFix) {
        let (fixed, stats) = clock.time("penetration fix", || {
            fix_penetrations(&yarns, &collider, offset)
        });
        yarns = fixed;
        penetration_fix = Some(stats);
    }
    let leg_mesh = leg_surface(&leg, &leg_fields);
    let mut files = Vec::new();
    // The preview's counters go to the report: they exist only where its structures were built.
    let mut preview = None;
    for &(output, name) in &plan.files {
        let bytes = if output == Output::Preview {
            let (bytes, stats) = clock.time(crate::plan::PREVIEW_STAGE, || {
                render::preview::encode_preview(&leg_mesh, &yarns, scene, name)
            })?;
            preview = Some(stats);
            bytes
        } else {
            clock.time(&format!("encode {name}"), || {
                encode(output, name, scene, &knit, &knit_fields, &yarns, &leg_mesh)
            })?
        };
        files.push((name.to_string(), bytes));
    }

    let density = &leg_fields.stitch_density;
    let covered: Vec<f64> = density.iter().copied().filter(|&d| d > 0.0).collect();
    let metrics = Metrics {
        points: knit.len(),
        steps: solver.steps(),
        residual: solver.residual(),
        max_move: solver.max_move(),
        force_step: solver.force_step(),
        converged: solver.converged(),
        max_penetration_m: Some(max_penetration),
        leg_triangles: Some(leg.triangles.len()),
    };
    let details = json!({
        "leg": {
            "file": leg.path.display().to_string(),
            "units": leg.units.name(),
            "up_axis": leg.up_axis.name(),
            "reoriented_triangles": leg.reoriented_triangles,
            "bounds_m": { "min": leg.bounds().0.coords.as_slice(), "max": leg.bounds().1.coords.as_slice() },
        },
        "axis": axis,
        "tube": {
            "wales": spec.wales,
            "courses": spec.courses,
            "rest_course_spacing_m": spec.relaxed_circumference_m / spec.wales as f64,
            "rest_wale_spacing_m": spec.relaxed_length_m / (spec.courses - 1) as f64,
            "relaxed_length_m": spec.relaxed_length_m,
            "relaxed_circumference_m": spec.relaxed_circumference_m,
            "stiffness_scale": { "course": knit.stiffness_scale[0], "wale": knit.stiffness_scale[1] },
            "axial_range_m": axial_range,
            "bunched_courses": bunched_courses,
        },
        "solver": solver.details(scene),
        "contact": {
            "method": scene.contact.method.name(),
            "offset_m": offset,
            "closest_queries": counters.closest_queries,
            "slides": counters.slides,
            "pushed_out": counters.pushed_out,
            "finished_out": counters.finished_out,
            "settled_out": counters.settled_out,
        },
        "penetration_fix": penetration_fix,
        "preview": preview,
        "memory": {
            "check": memory,
            "peak_resident_bytes": peak_memory(),
        },
        "stitch_density_per_cm2": {
            "leg_vertices_covered": covered.len(),
            "leg_vertices": leg.positions.len(),
            "min": covered.iter().copied().fold(f64::INFINITY, f64::min),
            "max": covered.iter().copied().fold(0.0, f64::max),
        },
    });
    let mut report = Report {
        command: plan.command.to_string(),
        scene: paths.scene_name.clone(),
        effects: plan.effects.iter().map(|e| e.name().to_string()).collect(),
        stages: Vec::new(),
        metrics,
        details,
        outputs: file_names.iter().map(|s| s.to_string()).collect(),
        wall_seconds: 0.0,
    };
    let mut written = clock.time("write files", || {
        export::atomic::write_all(&paths.out_dir, &files, &all_inputs)
    })?;
    report.stages = clock.stages().to_vec();
    report.wall_seconds = clock.wall_seconds();
    written.extend(export::atomic::write_all(
        &paths.out_dir,
        &[("report.json".to_string(), report.to_json())],
        &all_inputs,
    )?);
    Ok(FitOutcome { report, written })
}

/// A fitted knit on its leg, before any post-processing or file: what `fit` goes on to write
/// and what `bench` measures.
pub struct SolvedFit {
    /// The leg, in world space (metres, +Y up).
    pub leg: Leg,
    /// The axis the tube was stretched along.
    pub axis: Axis,
    /// The leg's collider.
    pub collider: Collider,
    /// The tube asked for.
    pub spec: TubeSpec,
    /// Distance kept between yarn centre line and skin, metres.
    pub offset: f64,
    /// The knit at rest on the leg, after the exact contact pass.
    pub knit: Knit,
    /// What the solver did.
    pub solver: SolverRun,
    /// Contact counters over all levels.
    pub counters: ContactCounters,
    /// Deepest yarn point inside the leg against the exact triangles, metres (0 when none is).
    pub max_penetration_m: f64,
    /// Lowest and highest yarn point along the axis, metres from the bottom point.
    pub axial_range_m: [f64; 2],
    /// Courses that came to rest below a course before them (a small fold above a slack ankle;
    /// more than [`MAX_BUNCHED_FRACTION`] of them is refused as bunched).
    pub bunched_courses: usize,
    /// The memory estimate checked before the leg was decoded.
    pub memory: MemoryCheck,
}

/// Loads the leg, finds its axis, builds the collider and fits the tube with the scene's solver,
/// then the exact contact pass and the penetration check: the stages of `plan` up to "check
/// penetration", timed on `clock`.
pub fn solve_fit(
    scene: &Scene,
    plan: &Plan,
    inputs: &FitInputs,
    scene_name: &str,
    clock: &mut StageClock,
    progress: &mut dyn Progress,
) -> Result<SolvedFit> {
    let (leg, memory) = clock.time("load leg", || -> Result<_> {
        let file = read_leg_file(&inputs.leg)?;
        // Refuse a fit too large for memory before the leg is decoded or the knit allocated.
        let memory = MemoryCheck::fit(scene, plan, file.declared_triangles());
        memory.enforce(scene, &inputs.leg.display().to_string())?;
        Ok((
            decode_leg(file, scene.leg.units, scene.leg.up_axis)?,
            memory,
        ))
    })?;
    let axis = clock.time("find axis", || choose_axis(scene, inputs, &leg))?;
    let collider = clock.time("build collider", || {
        Collider::new(&leg, scene.contact.method)
    })?;
    let relaxed_length = relaxed_length(scene, &axis, scene_name)?;
    let spec = TubeSpec {
        wales: scene.tube.wales,
        courses: scene.tube.courses,
        pattern: scene.knit.pattern,
        relaxed_circumference_m: scene.tube.relaxed_circumference_m,
        relaxed_length_m: relaxed_length,
        stitch_m: [scene.knit.course_spacing_m, scene.knit.wale_spacing_m],
    };
    let offset = scene.contact.offset(&scene.yarns);
    let mut levels = TubeLevels {
        spec,
        axis: &axis,
        leg: &leg,
        collider: &collider,
        offset,
        contact: None,
        retired: ContactCounters::default(),
    };
    let (mut knit, solver) = match scene.solver.method {
        SolverMethod::Paper => {
            let mut knit = clock.time("knit tube", || levels.knit(spec.wales, spec.courses));
            progress.begin("fit", scene.solver.max_steps as u64);
            let stats = clock.time("fit", || {
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
            let solved = clock.time("fit", || {
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
    let mut contact = levels
        .contact
        .take()
        .expect("the solver made the fine grid's contact");
    clock.time("exact contact pass", || {
        contact.finish(&mut knit.particles.x, &knit.particles.inv_mass)
    });

    let mut counters = levels.retired;
    counters.add(&contact.counters());
    let (max_penetration_m, axial_range_m) = clock.time("check penetration", || {
        (max_penetration(&knit, &collider), axial_range(&knit, &axis))
    });
    let (bunched, first) = bunched_courses(&knit, &axis.direction());
    if let Some(course) =
        first.filter(|_| bunched as f64 > MAX_BUNCHED_FRACTION * knit.courses as f64)
    {
        return Err(Error::Bunched {
            course,
            bunched,
            courses: knit.courses,
            ratio: scene.yarns.support.stiffness / scene.yarns.nylon.stiffness,
            circumference_m: spec.relaxed_circumference_m,
        });
    }
    Ok(SolvedFit {
        leg,
        axis,
        collider,
        spec,
        offset,
        knit,
        solver,
        counters,
        max_penetration_m,
        axial_range_m,
        bunched_courses: bunched,
        memory,
    })
}

/// Per-point stitch fields of `knit` and their transfer to the leg's vertices.
pub fn measure_fields(knit: &Knit, leg: &Leg, radius_m: [f64; 2]) -> (KnitFields, KnitFields) {
    let per_point = KnitFields::measure(knit, radius_m);
    // Wide enough to span a nylon and a support course whichever way the knit runs, so the
    // alternation of the yarns does not print through as speckle.
    let bandwidth =
        3.0 * mean_spacing(knit, Direction::Course).max(mean_spacing(knit, Direction::Wale));
    let on_leg = per_point.transfer_to_leg(&knit.particles.x, &leg.positions, bandwidth);
    (per_point, on_leg)
}

/// The tube at any grid size, and its contact with the leg: what the solvers knit and constrain.
struct TubeLevels<'a> {
    /// The tube asked for; other levels change only its wales and courses.
    spec: TubeSpec,
    axis: &'a Axis,
    leg: &'a Leg,
    collider: &'a Collider,
    /// Distance kept between yarn centre line and skin, metres.
    offset: f64,
    /// Contact of the level being solved.
    contact: Option<LegContact<'a>>,
    /// Counters of the levels solved before it.
    retired: ContactCounters,
}

impl<'a> Levels for TubeLevels<'a> {
    fn knit(&mut self, wales: usize, courses: usize) -> Knit {
        let spec = TubeSpec {
            wales,
            courses,
            ..self.spec
        };
        build_tube(&spec, self.axis, &self.leg.positions, &self.leg.triangles).knit
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
            self.axis.direction(),
            end_rings(knit),
        ))
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

    /// True when the grid asked for converged.
    pub fn converged(&self) -> bool {
        match self {
            SolverRun::Paper(s) => s.converged,
            SolverRun::Multilevel(s) => s.fine().converged,
        }
    }

    /// The report's `details.solver`.
    pub fn details(&self, scene: &Scene) -> serde_json::Value {
        match self {
            SolverRun::Paper(stats) => json!({
                "method": "paper",
                "tolerance": scene.solver.tolerance,
                "time_step": scene.solver.time_step,
                "time_step_limit": stats.time_step_limit,
                "substeps_per_step": stats.substeps_per_step,
            }),
            SolverRun::Multilevel(stats) => json!({
                "method": "multilevel",
                "tolerance": scene.solver.tolerance,
                "fine_grid_equivalent_iterations": stats.fine_grid_equivalent_iterations(),
                "levels": stats.levels,
            }),
        }
    }
}

/// The axis from the scene (converted from file coordinates) or detected.
fn choose_axis(scene: &Scene, inputs: &FitInputs, leg: &Leg) -> Result<Axis> {
    match &scene.leg.axis {
        Some(given) => {
            let bottom = leg.world_from_file(&Point3::from(given.bottom));
            let top = leg.world_from_file(&Point3::from(given.top));
            Ok(Axis {
                bottom: bottom.coords.into(),
                top: top.coords.into(),
                source: inputs.axis_source,
            })
        }
        None => {
            let axis = detect_axis(leg).ok_or_else(|| Error::Leg {
                path: leg.path.clone(),
                message: "cannot find the leg's axis: the mesh has no area, or open edges all \
                          along it; give leg.axis in the scene or --axis"
                    .into(),
            })?;
            match leaves_mesh(leg, &axis) {
                None => Ok(axis),
                Some(at) => Err(Error::Leg {
                    path: leg.path.clone(),
                    message: format!(
                        "the mesh's principal axis runs outside it ({:.0}% of the way up): the \
                         file holds more than one leg, or a bent one; give the stocking's bottom \
                         and top as leg.axis in the scene or --axis",
                        100.0 * at
                    ),
                }),
            }
        }
    }
}

/// The stocking's relaxed length: given (and shorter than the axis), or a fraction of the axis.
fn relaxed_length(scene: &Scene, axis: &Axis, scene_name: &str) -> Result<f64> {
    let length = axis.length();
    match scene.tube.relaxed_length_m {
        None => Ok(RELAXED_LENGTH_FRACTION * length),
        Some(l) if l < length => Ok(l),
        Some(l) => Err(Error::InvalidScene {
            path: scene_name.to_string(),
            field: "tube.relaxed_length_m".into(),
            message: format!(
                "{l} m is not shorter than the leg axis ({length:.3} m): the stocking would bunch \
                 up instead of being stretched onto the leg; give a shorter length, leave it out \
                 ({RELAXED_LENGTH_FRACTION} × the axis), or place the axis points further apart"
            ),
        }),
    }
}

/// Deepest yarn point inside the leg, metres (0 when none is), from exact closest-point queries.
fn max_penetration(knit: &Knit, collider: &Collider) -> f64 {
    use rayon::prelude::*;
    knit.particles
        .x
        .par_iter()
        .map(|p| (-collider.closest(&Point3::from(*p)).signed_distance).max(0.0))
        .reduce(|| 0.0, f64::max)
}

/// Lowest and highest position of the yarn along the axis, metres from the bottom point.
fn axial_range(knit: &Knit, axis: &Axis) -> [f64; 2] {
    let a = axis.direction();
    knit.particles
        .x
        .iter()
        .fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], p| {
            let s = (p - axis.bottom().coords).dot(&a);
            [lo.min(s), hi.max(s)]
        })
}

/// Mean length of the springs along `direction`, metres.
fn mean_spacing(knit: &Knit, direction: Direction) -> f64 {
    let x = &knit.particles.x;
    let lengths: Vec<f64> = knit
        .springs
        .iter()
        .filter(|s| s.direction == direction)
        .map(|s| (x[s.b.index()] - x[s.a.index()]).norm())
        .collect();
    lengths.iter().sum::<f64>() / lengths.len().max(1) as f64
}

/// Encodes one output file.
fn encode(
    output: Output,
    name: &str,
    scene: &Scene,
    knit: &Knit,
    knit_fields: &KnitFields,
    yarns: &YarnGeometry,
    leg_mesh: &SurfaceMesh,
) -> Result<Vec<u8>> {
    let comments = vec![format!("knitfit {} fit", env!("CARGO_PKG_VERSION"))];
    match (output, name) {
        (Output::Glb, _) => {
            let stocking = stocking_surface(knit, knit_fields, yarns);
            export::gltf::write_nodes_glb(
                &[
                    GlbNode::Surface(leg_mesh),
                    GlbNode::Yarns(yarns),
                    GlbNode::Surface(&stocking),
                ],
                [scene.yarns.nylon.colour, scene.yarns.support.colour],
            )
        }
        (Output::Ply, "leg.ply") => export::ply::write_mesh_ply(leg_mesh, &comments),
        (Output::Ply, _) => export::ply::write_ply(std::slice::from_ref(yarns), &comments),
        // Rendered in its own stage, which reports its counters.
        (Output::Preview, _) => Err(Error::Encode {
            what: name.into(),
            message: "the preview is rendered by its own stage".into(),
        }),
        (Output::Picture, _) => {
            let density: Vec<f64> = leg_mesh
                .point_attributes
                .get("stitch_density")
                .map(|d| d.iter().map(|&v| f64::from(v)).collect())
                .unwrap_or_default();
            let picture = density_picture::draw_density(
                &leg_mesh.positions,
                &leg_mesh.triangles,
                &density,
                &DensityPictureStyle::default(),
            );
            render::encode_png(&picture, name)
        }
    }
}

/// The leg with its fields as attributes (`stitch_density`, `stretch_course`, `stretch_wale`,
/// `coverage`) and the density's heat map as vertex colours.
fn leg_surface(leg: &Leg, fields: &KnitFields) -> SurfaceMesh {
    let positions = leg.positions.iter().map(|p| p.coords.into()).collect();
    let mut mesh = SurfaceMesh::new("leg", positions, leg.triangles.clone());
    let density = &fields.stitch_density;
    if density.len() != leg.positions.len() {
        // No attributes asked for.
        return mesh;
    }
    let covered = density.iter().copied().filter(|&d| d > 0.0);
    let (lo, hi) = covered.fold((f64::INFINITY, 0.0f64), |(lo, hi), d| {
        (lo.min(d), hi.max(d))
    });
    let uncovered = [0.2f32, 0.2, 0.2];
    mesh.colours = Some(
        density
            .iter()
            .map(|&d| {
                if d > 0.0 {
                    colour::heat(if hi > lo { (d - lo) / (hi - lo) } else { 0.5 })
                } else {
                    uncovered
                }
            })
            .collect(),
    );
    for (name, values) in fields.named() {
        mesh.point_attributes
            .insert(name.into(), values.iter().map(|&v| v as f32).collect());
    }
    mesh
}

/// The fitted knit as a triangle surface: the grid triangulated with the seam column repeated
/// so texture coordinates (wale, course) run 0–1 without a jump; per vertex, the yarn point's
/// attributes and its fields (density, stretch, coverage: what a sheer shader on this surface
/// needs). Only the knit's own points are used: `yarns` may hold points the penetration fix
/// inserted after them.
fn stocking_surface(knit: &Knit, knit_fields: &KnitFields, yarns: &YarnGeometry) -> SurfaceMesh {
    let (wales, courses) = (knit.wales, knit.courses);
    let columns = wales + 1;
    let source = |w: usize, c: usize| knit.point(w % wales, c).index();
    let mut positions = Vec::with_capacity(columns * courses);
    let mut texcoords = Vec::with_capacity(columns * courses);
    let point_fields: Vec<(&str, &[f32])> = yarns
        .point_attributes
        .iter()
        .map(|(k, v)| (k.as_str(), &v[..knit.len()]))
        .collect();
    let knit_fields: Vec<(&str, Vec<f32>)> = knit_fields
        .named()
        .into_iter()
        .filter(|(_, v)| v.len() == knit.len())
        .map(|(k, v)| (k, v.iter().map(|&x| x as f32).collect()))
        .collect();
    let sources: Vec<(&str, &[f32])> = point_fields
        .into_iter()
        .chain(knit_fields.iter().map(|(k, v)| (*k, &v[..])))
        .collect();
    let mut attributes: BTreeMap<String, Vec<f32>> = sources
        .iter()
        .map(|(k, _)| (k.to_string(), Vec::new()))
        .collect();
    for c in 0..courses {
        for w in 0..columns {
            let i = source(w, c);
            let p = knit.particles.x[i];
            positions.push([p.x, p.y, p.z]);
            texcoords.push([
                w as f32 / wales as f32,
                1.0 - c as f32 / (courses - 1).max(1) as f32,
            ]);
            for (name, values) in &sources {
                attributes
                    .get_mut(*name)
                    .expect("made above")
                    .push(values[i]);
            }
        }
    }
    let id = |w: usize, c: usize| (c * columns + w) as u32;
    let mut triangles = Vec::with_capacity(2 * wales * courses);
    for c in 0..courses.saturating_sub(1) {
        for w in 0..wales {
            // Counter-clockwise seen from outside: around the axis, then up it.
            triangles.push([id(w, c), id(w + 1, c), id(w + 1, c + 1)]);
            triangles.push([id(w, c), id(w + 1, c + 1), id(w, c + 1)]);
        }
    }
    let mut mesh = SurfaceMesh::new("stocking", positions, triangles);
    // The repeated seam column must share the normal of the column it repeats.
    for c in 0..courses {
        let (first, last) = (id(0, c) as usize, id(wales, c) as usize);
        let n = nalgebra::Vector3::from(mesh.normals[first])
            + nalgebra::Vector3::from(mesh.normals[last]);
        let n = if n.norm() > 0.0 {
            n.normalize()
        } else {
            nalgebra::Vector3::y()
        };
        mesh.normals[first] = n.into();
        mesh.normals[last] = n.into();
    }
    mesh.texcoords = Some(texcoords);
    mesh.point_attributes = attributes;
    mesh
}

/// The directory a scene's relative paths are resolved against.
pub fn scene_dir(scene_path: Option<&Path>) -> PathBuf {
    match scene_path {
        Some(p) => p.parent().map(Path::to_path_buf).unwrap_or_default(),
        None => Path::new(crate::scene::BUNDLED_SCENE_DIR).to_path_buf(),
    }
}
