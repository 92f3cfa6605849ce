//! From a scene to the work a run will do: the effects that run, the force terms they switch on,
//! the ordered [`Stage`]s with the reason for each, what is left out and why, and the files.
//! The run executes exactly these stages (its clock records each against the plan) and the
//! report lists them, so nothing runs that the scene did not ask for.

use serde::Serialize;

use crate::base::{GridSize, YarnKind};
use crate::export::{Output, YarnsWritten};
use crate::fit::{
    FitSettings, LoadSettings, PlaceSettings, ProductSettings, RealStitches, SolveSettings,
};
use crate::knit::tube::TOE_TIP_CELL_M;
use crate::knit::{TubeBottom, TubeTop};
use crate::leg::AxisSource;
use crate::limits::FitMemory;
use crate::preview::RenderMode;
use crate::scene::{Effect, LoadedScene, Scene, LEG_AXIS};
use crate::sim::multilevel::{grid_sizes_down_to, COARSEST, STOCKING_COARSEST};
use crate::sim::stall::YarnStiffness;
use crate::sim::{ForceTerms, SolverMethod};
use crate::stage::{File, FitFile, PatchFile, Stage};

/// Where `tube.bottom` puts the stocking's start, in words.
pub fn tube_bottom_words(bottom: Option<TubeBottom>) -> String {
    match bottom {
        None => "the toe where the leg has a foot, else the ankle (tube.bottom)".into(),
        Some(TubeBottom::Ankle) => "the ankle (tube.bottom)".into(),
        Some(TubeBottom::Toe) => "the toe (tube.bottom)".into(),
    }
}

/// Where `tube.top` puts the stocking's end, in words.
pub fn tube_top_words(top: TubeTop) -> String {
    match top {
        TubeTop::BelowCrotchM(d) => {
            format!(
                "{:.0} cm below the crotch, or inside the cut (tube.top)",
                d * 100.0
            )
        }
        TubeTop::Fraction(f) => format!("{:.0}% of the leg's height (tube.top)", f * 100.0),
    }
}

/// The files a fit can encode, in the order it writes them, with the output that asks for
/// each: the one table from output kind to file (the writers are `fit::products`'s).
pub const FIT_FILES: [(Output, FitFile); 4] = [
    (Output::Glb, FitFile::StockingGlb),
    (Output::Ply, FitFile::StockingPly),
    (Output::Ply, FitFile::LegPly),
    (Output::Picture, FitFile::DensityPicture),
];

/// The files the patch experiment can encode, as [`FIT_FILES`].
pub const PATCH_FILES: [(Output, PatchFile); 3] = [
    (Output::Ply, PatchFile::Ply),
    (Output::Glb, PatchFile::Glb),
    (Output::Picture, PatchFile::Picture),
];

/// The preview's file name in a fit's output directory.
pub const PREVIEW_FILE: &str = "preview.png";
/// The report's file name.
pub const REPORT_FILE: &str = "report.json";

/// The files a fit of `scene` encodes, in order.
pub fn fit_files(scene: &Scene) -> Vec<FitFile> {
    FIT_FILES
        .iter()
        .filter(|(output, _)| scene.wants(*output))
        .map(|&(_, file)| file)
        .collect()
}

/// The files the patch experiment of `scene` encodes, in order.
pub fn patch_files(scene: &Scene) -> Vec<PatchFile> {
    PATCH_FILES
        .iter()
        .filter(|(output, _)| scene.wants(*output))
        .map(|&(_, file)| file)
        .collect()
}

/// One stage a run will execute, and why.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PlannedStage {
    /// The stage.
    #[serde(rename = "name")]
    pub stage: Stage,
    /// What in the scene or command asks for it.
    pub why: String,
}

/// Something a scene could ask for that will not run, and why not.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct LeftOut {
    /// What is left out (`render preview`, `effect contact`).
    pub name: String,
    /// Why.
    pub why: String,
}

/// A file a run will write besides its report.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlannedFile {
    /// Its name in the output directory.
    pub name: String,
    /// The output of the scene that asks for it.
    pub output: Output,
}

/// The work of one run.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// Command name (`patch`).
    pub command: &'static str,
    /// Effects that run, in the scene's order, without duplicates.
    pub effects: Vec<Effect>,
    /// Force terms and coefficients the solver uses.
    pub forces: ForceTerms,
    /// Stages in execution order.
    pub stages: Vec<PlannedStage>,
    /// Stages and effects that will not run although a scene could ask for them.
    pub left_out: Vec<LeftOut>,
    /// Files to write besides the report, in order.
    pub files: Vec<PlannedFile>,
    /// The report's file name.
    pub report: String,
}

impl Plan {
    /// Takes `stage` out of the plan: one the leg file rules out once it is read (`knitfit
    /// plan` reads it; the fit's own plan keeps the stage, which then does not run).
    pub fn without(&mut self, stage: Stage) {
        self.stages.retain(|s| s.stage != stage);
    }

    /// True when the plan has this stage.
    pub fn has(&self, stage: Stage) -> bool {
        self.stages.iter().any(|s| s.stage == stage)
    }

    /// Every file the run writes, its report last.
    pub fn file_names(&self) -> Vec<&str> {
        self.files
            .iter()
            .map(|f| f.name.as_str())
            .chain([self.report.as_str()])
            .collect()
    }

    fn add(&mut self, stage: Stage, why: impl Into<String>) {
        self.stages.push(PlannedStage {
            stage,
            why: why.into(),
        });
    }

    fn leave_out(&mut self, name: impl Into<String>, why: impl Into<String>) {
        self.left_out.push(LeftOut {
            name: name.into(),
            why: why.into(),
        });
    }

    fn new(command: &'static str, forces: ForceTerms, effects: Vec<Effect>) -> Plan {
        Plan {
            command,
            forces,
            effects,
            stages: Vec::new(),
            left_out: Vec::new(),
            files: Vec::new(),
            report: REPORT_FILE.to_string(),
        }
    }
}

impl Plan {
    /// The plan of `knitfit patch` for `scene`: for each stretch, build a patch and relax it;
    /// then measure stitches and encode the asked-for files.
    pub fn patch(scene: &Scene) -> Plan {
        // A flat patch has no leg to touch or cut through.
        let without_leg = [Effect::Contact, Effect::PenetrationFix];
        let mut effects = dedup(&scene.effects);
        let dropped: Vec<Effect> = effects
            .iter()
            .copied()
            .filter(|e| without_leg.contains(e))
            .collect();
        effects.retain(|e| !without_leg.contains(e));
        let mut plan = Plan::new("patch", force_terms(scene, &effects), effects);
        for effect in dropped {
            plan.leave_out(
                format!("effect {}", effect.name()),
                "a flat patch has no leg",
            );
        }
        plan.leave_out(Stage::LoadLeg.to_string(), "a flat patch has no leg");
        let terms = match plan.forces.connection_factor {
            Some(c2) => format!("spring force (eq. 1) + yarn connection (eq. 2, c2 = {c2})"),
            None => "spring force (eq. 1) only".to_string(),
        };
        for &stretch in &scene.patch.stretch {
            plan.add(
                Stage::KnitPatch(stretch),
                format!("patch.stretch asks for {stretch}"),
            );
            plan.add(Stage::RelaxPatch(stretch), terms.clone());
        }
        plan.add(
            Stage::MeasureStitches,
            "report.json: stitch shapes per stretch",
        );
        for (output, file) in PATCH_FILES {
            if scene.wants(output) {
                plan.add(
                    Stage::Encode(File::Patch(file)),
                    format!("outputs lists \"{}\"", output.name()),
                );
                plan.files.push(PlannedFile {
                    name: file.name().to_string(),
                    output,
                });
            }
        }
        if scene.wants(Output::Preview) {
            plan.leave_out(
                Stage::RenderPreview.to_string(),
                "a flat patch has no leg to preview",
            );
        }
        plan.add(Stage::WriteFiles, "every run writes report.json");
        plan
    }
}

impl Plan {
    /// The plan of `knitfit fit` for `scene`: load the leg, find its axis, build the collider and
    /// the tube, fit with contact, measure, and encode the asked-for files.
    pub fn fit(scene: &Scene) -> Plan {
        let mut effects = dedup(&scene.effects);
        // Contact is what a fit is; it runs whether or not the scene lists it.
        if !effects.contains(&Effect::Contact) {
            effects.push(Effect::Contact);
        }
        // The penetration fix reroutes the yarn polylines of the files: without a file that holds
        // them, there is nothing for it to do.
        let yarn_preview = scene.wants(Output::Preview) && scene.render.mode == RenderMode::Yarn;
        // The preview draws the real loops unmended: a loop dipping into the skin by a few
        // micrometres is hidden where it dips, as in the file it would be mended.
        let polylines = scene.wants(Output::Glb) || scene.wants(Output::Ply);
        let skip_fix = !polylines && effects.contains(&Effect::PenetrationFix);
        if skip_fix {
            effects.retain(|&e| e != Effect::PenetrationFix);
        }
        let mut plan = Plan::new("fit", force_terms(scene, &effects), effects);
        if skip_fix {
            plan.leave_out(
                Stage::PenetrationFix.to_string(),
                "effects lists \"penetration_fix\", but no file holds a yarn polyline (glb or \
                 ply)",
            );
        }
        plan.add(
            Stage::LoadLeg,
            "the leg file (leg.file, or --leg): its declared triangles and the tube are checked \
             against the memory limit before anything is decoded",
        );
        match scene.leg.axis {
            Some(_) => plan.add(
                Stage::FindAxis,
                "leg.axis is given: convert it to world space and check the leg goes around it",
            ),
            None => {
                plan.add(
                    Stage::FindLandmarks,
                    format!(
                        "leg.axis is absent: find the {} leg (leg.side), its sole, toe, ankle, \
                         knee and thigh top from girth profiles",
                        scene.leg.side.name()
                    ),
                );
                plan.add(
                    Stage::FindAxis,
                    format!(
                        "place the axis from {} to {}",
                        tube_bottom_words(scene.tube.bottom),
                        tube_top_words(scene.tube.top)
                    ),
                );
            }
        }
        plan.add(
            Stage::BuildCollider,
            format!("contact ({} queries)", scene.contact.method.name()),
        );
        let wales = scene.tube.wales;
        // Courses left out are known once the leg's length is (Fabric::grid_courses).
        let grid = match scene.tube.courses {
            Some(courses) => format!("{wales}×{courses}"),
            None => format!("{wales} wales × the courses for cells as many stitches long as wide"),
        };
        let terms = match plan.forces.connection_factor {
            Some(c2) => format!("spring force + yarn connection (c2 = {c2}) + sliding contact"),
            None => "spring force + sliding contact".to_string(),
        };
        match scene.solver.method {
            SolverMethod::Paper => {
                plan.add(Stage::KnitTube, format!("tube {grid}"));
                plan.add(
                    Stage::Fit,
                    format!("{terms}; solver.method \"paper\": explicit damped steps"),
                );
            }
            SolverMethod::Multilevel => {
                // The grid a stocking ends on, graded at the toe's tip (docs/decisions/0073).
                let graded = format!(
                    "; its last grid graded to {:.0} mm cells over the toe's tip where even \
                     ones are longer",
                    1e3 * TOE_TIP_CELL_M
                );
                let grids = match scene.tube.courses {
                    // Courses left out: known, and so the levels, once the leg's length is.
                    None => format!(
                        "up to {grid}: an open tube on grids halving down to {COARSEST} a side; \
                         a stocking to the toe on the real stitch count's levels with no more \
                         wales than it, else from its coarsest level if that is the coarser \
                         grid, else on grids halving down to {STOCKING_COARSEST} a side{graded}"
                    ),
                    Some(courses) => {
                        let chain = |coarsest: usize| -> String {
                            let sizes = grid_sizes_down_to(GridSize::new(wales, courses), coarsest);
                            let grids: Vec<String> = sizes.iter().map(|g| g.to_string()).collect();
                            grids.join(" → ")
                        };
                        // A stocking to the toe coarsens less (its heel and toe need rings a
                        // few centimetres apart) and follows the real stitch count's levels,
                        // whose courses the leg's length decides; without tube.bottom the leg
                        // decides, so name both.
                        let stocking = format!(
                            "on the real stitch count's levels with no more wales than {grid}, \
                             whatever their courses, then {grid}; where it has none, from its \
                             coarsest level if that is the coarser grid, else on grids {}{graded}",
                            chain(STOCKING_COARSEST)
                        );
                        let tube = format!("on grids {}", chain(COARSEST));
                        match scene.tube.bottom {
                            Some(TubeBottom::Ankle) => tube,
                            Some(TubeBottom::Toe) => stocking,
                            None if tube == stocking => tube,
                            None => format!("{tube} (to the toe: {stocking})"),
                        }
                    }
                };
                plan.add(
                    Stage::Fit,
                    format!(
                        "{terms}; solver.method \"multilevel\": tubes knitted and relaxed \
                         coarse to fine {grids}"
                    ),
                );
            }
        }
        plan.add(
            Stage::ExactContactPass,
            "contact: move out any point a cached tangent plane let dip below the offset",
        );
        plan.add(
            Stage::CheckPenetration,
            "report.json: max_penetration_m against the exact triangles",
        );
        // A given axis is in the pose's coordinates: such a leg is fitted as the file shows it.
        if scene.leg.axis.is_none() {
            plan.add(
                Stage::Pose,
                "where the leg is posed, by the file's skin or bent where its sections show the \
                 joints: the stocking is fitted in the rest pose (the rig's, or the leg \
                 straightened), carried into the pose and relaxed there",
            );
        }
        let density_preview =
            scene.wants(Output::Preview) && scene.render.mode == RenderMode::Density;
        let leg_files = scene.wants(Output::Glb) || scene.wants(Output::Ply);
        if leg_files || scene.wants(Output::Picture) || density_preview {
            plan.add(
                Stage::LegAttributes,
                "stitch density, stretch, coverage, tension and pressure per leg vertex, for the leg in the files \
                 and the density pictures",
            );
        } else {
            plan.leave_out(
                Stage::LegAttributes.to_string(),
                "no output holds the leg (glb, ply, picture or a density preview)",
            );
        }
        let written = scene.yarns_written();
        let for_files = match written {
            YarnsWritten::Grid => None,
            YarnsWritten::Stitches => Some("outputs lists \"stitches\""),
            YarnsWritten::Loops => Some("outputs lists \"loops\""),
        };
        let for_preview = yarn_preview.then_some("the yarn preview draws every real stitch");
        if let Some(why) = for_files.or(for_preview) {
            plan.add(
                Stage::LayStitches,
                format!(
                    "{why}: the knit at its real count ({} needles around, a course per {} m), \
                     placed in the fitted grid and laid on the skin",
                    scene.fabric().needles.round(),
                    scene.knit.wale_spacing_m
                ),
            );
        }
        let loops_for_files = (written == YarnsWritten::Loops).then_some("outputs lists \"loops\"");
        if let Some(why) = loops_for_files.or(for_preview) {
            plan.add(
                Stage::KnitLoops,
                format!("{why}: every real stitch as a loop polyline (Choi & Lo 2003)"),
            );
        }
        if plan.effects.contains(&Effect::PenetrationFix) {
            plan.add(
                Stage::PenetrationFix,
                "effect penetration_fix, for the yarn polylines written",
            );
        }
        if scene.wants(Output::Glb) {
            plan.add(
                Stage::StockingSurface,
                "outputs lists \"glb\": the knit as a sheer surface, lifted clear of the skin so \
                 that viewers tell the two apart",
            );
        }
        for (output, file) in FIT_FILES {
            if !scene.wants(output) {
                continue;
            }
            plan.add(
                Stage::Encode(File::Fit(file)),
                format!("outputs lists \"{}\"", output.name()),
            );
            plan.files.push(PlannedFile {
                name: file.name().to_string(),
                output,
            });
        }
        if scene.wants(Output::Preview) {
            plan.add(
                Stage::RenderPreview,
                preview_reason(scene, "outputs lists \"preview\""),
            );
            plan.files.push(PlannedFile {
                name: PREVIEW_FILE.to_string(),
                output: Output::Preview,
            });
        } else {
            plan.leave_out(
                Stage::RenderPreview.to_string(),
                "outputs does not list \"preview\": no BVH, yarn grid or camera is built",
            );
        }
        plan.add(Stage::WriteFiles, "every run writes report.json");
        plan
    }
}

impl Plan {
    /// The plan of `knitfit render`: read a fit's `stocking.glb` (`input`), ray-trace and encode
    /// the preview as `picture` with its report `report` beside it. No solver, no forces.
    pub fn render(scene: &Scene, input: &str, picture: &str, report: &str) -> Plan {
        let no_forces = ForceTerms {
            stiffness: [0.0; 3],
            connection_factor: None,
        };
        let mut plan = Plan::new("render", no_forces, Vec::new());
        plan.report = report.to_string();
        plan.add(Stage::ReadStocking, format!("the leg and yarns of {input}"));
        plan.add(
            Stage::RenderPreview,
            preview_reason(scene, "knitfit render"),
        );
        plan.files.push(PlannedFile {
            name: picture.to_string(),
            output: Output::Preview,
        });
        plan.add(Stage::WriteFiles, "the picture and its report");
        plan
    }
}

/// Why the preview is rendered (`asked_by`), and how.
fn preview_reason(scene: &Scene, asked_by: &str) -> String {
    let r = &scene.render;
    let camera = if r.camera.is_some() {
        "scene camera".to_string()
    } else {
        format!("{} view", r.view.name())
    };
    format!(
        "{asked_by}: {} mode, {}×{}, {} spp, {camera}",
        r.mode.name(),
        r.width,
        r.height,
        r.spp
    )
}

impl Plan {
    /// What each stage of this plan's fit of `loaded` is given: the parts of the scene each
    /// stage owns, the force terms, the outputs the memory estimate counts, and the products
    /// the plan's stages make.
    pub fn fit_settings(&self, loaded: &LoadedScene) -> FitSettings {
        let scene = &loaded.scene;
        let axis_source = match loaded.set_by(LEG_AXIS) {
            Some(_) => AxisSource::CommandLine,
            None => AxisSource::Scene,
        };
        let real_stitches = match (self.has(Stage::LayStitches), self.has(Stage::KnitLoops)) {
            (false, _) => RealStitches::None,
            (true, false) => RealStitches::Crossings,
            (true, true) => RealStitches::Loops,
        };
        let picture = Stage::Encode(File::Fit(FitFile::DensityPicture));
        let render = &scene.render;
        FitSettings {
            load: LoadSettings {
                units: scene.leg.units,
                up: scene.leg.up_axis,
            },
            place: PlaceSettings {
                axis: scene.leg.axis.map(|axis| (axis, axis_source)),
                side: scene.leg.side,
            },
            tube: scene.tube.clone(),
            fabric: scene.fabric(),
            pattern: scene.knit.pattern,
            memory: FitMemory {
                limits: scene.limits.clone(),
                outputs: self.files.iter().map(|file| file.output).collect(),
                preview_pixels: u64::from(render.width) * u64::from(render.height),
            },
            solve: SolveSettings {
                solver: scene.solver.clone(),
                forces: self.forces,
                contact: scene.contact.method,
                offset_m: scene.contact.offset(&scene.yarns),
                yarn_stiffness: YarnStiffness {
                    nylon: scene.yarns.nylon.stiffness,
                    support: scene.yarns.support.stiffness,
                },
            },
            measure: self.has(Stage::LegAttributes),
            products: Some(ProductSettings {
                yarns_written: scene.yarns_written(),
                real_stitches,
                penetration_fix: self.has(Stage::PenetrationFix),
                stocking_surface: self.has(Stage::StockingSurface),
                // The pictures are seen from the character's front where a view draws it.
                pictured: self.has(picture)
                    || self.has(Stage::RenderPreview) && render.camera.is_none(),
                colours: scene.yarns.each(|yarn| yarn.colour),
            }),
        }
    }
}

/// The force terms the effects switch on.
fn force_terms(scene: &Scene, effects: &[Effect]) -> ForceTerms {
    let nylon = scene.yarns.nylon.stiffness;
    let stiffness = if effects.contains(&Effect::AlternatingYarns) {
        YarnKind::ALL.map(|k| scene.yarns.get(k).stiffness)
    } else {
        [nylon; 3]
    };
    ForceTerms {
        stiffness,
        connection_factor: effects
            .contains(&Effect::YarnConnection)
            .then_some(scene.knit.connection_factor),
    }
}

fn dedup(effects: &[Effect]) -> Vec<Effect> {
    let mut out: Vec<Effect> = Vec::new();
    for &e in effects {
        if !out.contains(&e) {
            out.push(e);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(plan: &Plan) -> Vec<String> {
        plan.stages.iter().map(|s| s.stage.to_string()).collect()
    }

    #[test]
    fn connection_off_removes_the_connection_term() {
        let mut scene = Scene::load(None).unwrap();
        scene.effects = vec![Effect::AlternatingYarns];
        let plan = Plan::patch(&scene);
        assert_eq!(plan.forces.connection_factor, None);
        assert!(plan.stages.iter().any(|s| s.why.contains("eq. 1) only")));
    }

    #[test]
    fn without_alternating_yarns_every_spring_is_nylon_stiff() {
        let mut scene = Scene::load(None).unwrap();
        scene.effects = vec![];
        assert_eq!(Plan::patch(&scene).forces.stiffness, [1.0; 3]);
    }

    #[test]
    fn the_penetration_fix_runs_only_for_written_polylines() {
        let mut scene = Scene::load(None).unwrap();
        scene.effects = vec![Effect::PenetrationFix];
        let fit = Plan::fit(&scene);
        assert!(fit.effects.contains(&Effect::PenetrationFix));
        assert!(fit.has(Stage::PenetrationFix));
        scene.outputs = vec![Output::Picture];
        let fit = Plan::fit(&scene);
        assert!(!fit.effects.contains(&Effect::PenetrationFix));
        assert!(!fit.has(Stage::PenetrationFix));
        assert!(!Plan::patch(&scene)
            .effects
            .contains(&Effect::PenetrationFix));
    }

    #[test]
    fn the_multilevel_fit_knits_each_grid_inside_the_fit_stage() {
        let fit_why = |scene: &Scene| {
            let fit = Plan::fit(scene);
            let stage = fit.stages.iter().find(|s| s.stage == Stage::Fit).unwrap();
            stage.why.clone()
        };
        let mut scene = Scene::load(None).unwrap();
        assert!(!Plan::fit(&scene).has(Stage::KnitTube));
        // The bundled scene leaves the courses to the stitch: known once the leg's length is.
        assert_eq!(scene.tube.courses, None);
        let why = fit_why(&scene);
        assert!(
            why.contains(
                "up to 150 wales × the courses for cells as many stitches long as wide: an open \
                 tube on grids halving down to 24 a side; a stocking to the toe on the real \
                 stitch count's levels"
            ),
            "{why}"
        );
        scene.tube.courses = Some(150);
        let why = fit_why(&scene);
        assert!(why.contains("38×39 → 75×76 → 150×150"), "{why}");
        // A stocking to the toe follows the real stitch count's levels with no more wales than
        // it, or its coarsest, or halves its own down to 48 a side, and the plan says so.
        scene.tube.bottom = Some(TubeBottom::Toe);
        let why = fit_why(&scene);
        assert!(
            why.ends_with(
                "on the real stitch count's levels with no more wales than 150×150, whatever \
                 their courses, then 150×150; where it has none, from its coarsest level if \
                 that is the coarser grid, else on grids 75×76 → 150×150; its last grid graded \
                 to 2 mm cells over the toe's tip where even ones are longer"
            ),
            "{why}"
        );
        let (wales, courses) = (scene.tube.wales, scene.tube.courses);
        (scene.tube.wales, scene.tube.courses) = (100, Some(100));
        let why = fit_why(&scene);
        assert!(
            why.contains("the coarser grid, else on grids 50×51 → 100×100; its last grid graded"),
            "{why}"
        );
        (scene.tube.wales, scene.tube.courses) = (wales, courses);
        scene.tube.bottom = Some(TubeBottom::Ankle);
        let why = fit_why(&scene);
        assert!(why.ends_with("on grids 38×39 → 75×76 → 150×150"), "{why}");
        scene.solver.method = SolverMethod::Paper;
        let fit = Plan::fit(&scene);
        assert!(fit.has(Stage::KnitTube));
    }

    #[test]
    fn the_preview_is_rendered_only_when_outputs_list_it() {
        let mut scene = Scene::load(None).unwrap();
        scene.outputs = vec![Output::Glb, Output::Picture];
        let plan = Plan::fit(&scene);
        assert!(!plan.has(Stage::RenderPreview));
        assert!(!plan.files.iter().any(|f| f.output == Output::Preview));
        scene.outputs.push(Output::Preview);
        let plan = Plan::fit(&scene);
        let stage = plan
            .stages
            .iter()
            .find(|s| s.stage == Stage::RenderPreview)
            .unwrap();
        assert!(
            stage.why.contains("outputs lists \"preview\""),
            "{}",
            stage.why
        );
        assert!(stage.why.contains("yarn mode"), "{}", stage.why);
        assert_eq!(plan.files.last().unwrap().name, PREVIEW_FILE);
    }

    #[test]
    fn a_yarn_preview_alone_draws_real_loops_without_the_fix_or_leg_attributes() {
        let mut scene = Scene::load(None).unwrap();
        scene.outputs = vec![Output::Preview];
        let plan = Plan::fit(&scene);
        assert!(plan.has(Stage::LayStitches) && plan.has(Stage::KnitLoops));
        assert!(!plan.has(Stage::PenetrationFix), "no yarn file to mend");
        assert!(!plan.has(Stage::LegAttributes));
        scene.render.mode = RenderMode::Density;
        let plan = Plan::fit(&scene);
        assert!(!plan.has(Stage::PenetrationFix) && !plan.has(Stage::LayStitches));
        assert!(
            plan.has(Stage::LegAttributes),
            "the density mode colours by them"
        );
    }

    #[test]
    fn only_asked_for_files_are_encoded() {
        let mut scene = Scene::load(None).unwrap();
        scene.outputs = vec![Output::Glb];
        let plan = Plan::patch(&scene);
        let names = names(&plan);
        assert!(names.contains(&"encode patch.glb".to_string()));
        assert!(!names.iter().any(|n| n.contains("ply") || n.contains("png")));
        assert_eq!(plan.file_names(), ["patch.glb", "report.json"]);
    }

    #[test]
    fn every_file_table_entry_is_encoded_in_its_own_stage_in_table_order() {
        let scene = Scene::load(None).unwrap();
        let plan = Plan::fit(&scene);
        let encoded: Vec<String> = plan
            .stages
            .iter()
            .filter_map(|s| match s.stage {
                Stage::Encode(file) => Some(file.name().to_string()),
                _ => None,
            })
            .collect();
        // The preview is rendered in a stage of its own, not encoded.
        let files: Vec<String> = plan
            .files
            .iter()
            .map(|f| f.name.clone())
            .filter(|name| name != "preview.png")
            .collect();
        assert!(plan.has(Stage::RenderPreview));
        assert_eq!(encoded, files);
        assert_eq!(
            fit_files(&scene)
                .iter()
                .map(|f| f.name())
                .collect::<Vec<_>>(),
            files
        );
    }
}
