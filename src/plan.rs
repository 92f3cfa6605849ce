//! From a scene to the work a run will do: the effects that run, the force terms they switch on,
//! and the ordered stages, each with the reason it is there. Nothing outside the plan runs, and
//! the report lists the stages that did.

use crate::base::YarnKind;
use crate::scene::{Effect, Output, RenderMode, Scene, SolverMethod};
use crate::sim::multilevel::grid_sizes;
use crate::sim::ForceTerms;

/// One stage a run will execute, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlannedStage {
    /// Stage name, as in the report (`relax course=1.5`).
    pub name: String,
    /// What in the scene or command asks for it.
    pub why: String,
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
    /// Stages and effects that will not run although a scene could ask for them, each with
    /// why not (`why`).
    pub left_out: Vec<PlannedStage>,
    /// Files to write besides `report.json`, in order.
    pub files: Vec<(Output, &'static str)>,
}

impl Plan {
    /// The plan of `knitfit patch` for `scene`: for each stretch, build a patch and relax it;
    /// then measure stitches and encode the asked-for files.
    pub fn patch(scene: &Scene) -> Plan {
        // A flat patch has no leg to touch or cut through.
        let mut effects = dedup(&scene.effects);
        let mut left_out = Vec::new();
        for effect in [Effect::Contact, Effect::PenetrationFix] {
            if effects.contains(&effect) {
                left_out.push(PlannedStage {
                    name: format!("effect {}", effect.name()),
                    why: "a flat patch has no leg".into(),
                });
            }
        }
        left_out.push(PlannedStage {
            name: "load leg".into(),
            why: "a flat patch has no leg".into(),
        });
        effects.retain(|&e| e != Effect::Contact && e != Effect::PenetrationFix);
        let forces = force_terms(scene, &effects);
        let mut stages = Vec::new();
        let mut add = |name: String, why: String| stages.push(PlannedStage { name, why });
        for stretch in &scene.patch.stretch {
            add(
                format!("knit {stretch}"),
                format!("patch.stretch asks for {stretch}"),
            );
            let terms = match forces.connection_factor {
                Some(c2) => format!("spring force (eq. 1) + yarn connection (eq. 2, c2 = {c2})"),
                None => "spring force (eq. 1) only".to_string(),
            };
            add(format!("relax {stretch}"), terms);
        }
        add(
            "measure stitches".into(),
            "report.json: stitch shapes per stretch".into(),
        );
        let mut files = Vec::new();
        for (output, file) in [
            (Output::Ply, "patch.ply"),
            (Output::Glb, "patch.glb"),
            (Output::Picture, "patch.png"),
        ] {
            if scene.wants(output) {
                add(
                    format!("encode {file}"),
                    format!("outputs lists \"{}\"", output_name(output)),
                );
                files.push((output, file));
            }
        }
        if scene.wants(Output::Preview) {
            left_out.push(PlannedStage {
                name: PREVIEW_STAGE.into(),
                why: "a flat patch has no leg to preview".into(),
            });
        }
        add("write files".into(), "every run writes report.json".into());
        Plan {
            command: "patch",
            effects,
            forces,
            stages,
            left_out,
            files,
        }
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
        // The penetration fix reroutes yarn polylines: without a file (or a yarn picture) that
        // shows them, there is nothing for it to do.
        let yarn_preview = scene.wants(Output::Preview) && scene.render.mode == RenderMode::Yarn;
        let polylines = scene.wants(Output::Glb) || scene.wants(Output::Ply) || yarn_preview;
        let mut left_out = Vec::new();
        if !polylines && effects.contains(&Effect::PenetrationFix) {
            effects.retain(|&e| e != Effect::PenetrationFix);
            left_out.push(PlannedStage {
                name: "penetration fix".into(),
                why: "effects lists \"penetration_fix\", but no output draws a yarn polyline \
                      (glb, ply or a yarn preview)"
                    .into(),
            });
        }
        let forces = force_terms(scene, &effects);
        let mut stages = Vec::new();
        let mut add = |name: &str, why: String| {
            stages.push(PlannedStage {
                name: name.to_string(),
                why,
            })
        };
        add(
            "load leg",
            "the leg file (leg.file, or --leg): its declared triangles and the tube are checked \
             against the memory limit before anything is decoded"
                .into(),
        );
        add(
            "find axis",
            match scene.leg.axis {
                Some(_) => "leg.axis is given: convert it to world space".into(),
                None => "leg.axis is absent: detect the principal axis".into(),
            },
        );
        add(
            "build collider",
            format!("contact ({} queries)", scene.contact.method.name()),
        );
        let (wales, courses) = (scene.tube.wales, scene.tube.courses);
        let terms = match forces.connection_factor {
            Some(c2) => format!("spring force + yarn connection (c2 = {c2}) + sliding contact"),
            None => "spring force + sliding contact".to_string(),
        };
        match scene.solver.method {
            SolverMethod::Paper => {
                add("knit tube", format!("tube {wales}×{courses}"));
                add(
                    "fit",
                    format!("{terms}; solver.method \"paper\": explicit damped steps"),
                );
            }
            SolverMethod::Multilevel => {
                let grids: Vec<String> = grid_sizes(wales, courses)
                    .iter()
                    .map(|(w, c)| format!("{w}×{c}"))
                    .collect();
                add(
                    "fit",
                    format!(
                        "{terms}; solver.method \"multilevel\": tubes knitted and relaxed \
                         coarse to fine on grids {}",
                        grids.join(" → ")
                    ),
                );
            }
        }
        add(
            "exact contact pass",
            "contact: move out any point a cached tangent plane let dip below the offset".into(),
        );
        add(
            "check penetration",
            "report.json: max_penetration_m against the exact triangles".into(),
        );
        let mut files = Vec::new();
        let density_preview =
            scene.wants(Output::Preview) && scene.render.mode == RenderMode::Density;
        let leg_files = scene.wants(Output::Glb) || scene.wants(Output::Ply);
        if leg_files || scene.wants(Output::Picture) || density_preview {
            add(
                "leg attributes",
                "stitch density, stretch and coverage per leg vertex, for the leg in the \
                 files and the density pictures"
                    .into(),
            );
        } else {
            left_out.push(PlannedStage {
                name: "leg attributes".into(),
                why: "no output holds the leg (glb, ply, picture or a density preview)".into(),
            });
        }
        if effects.contains(&Effect::PenetrationFix) {
            add(
                "penetration fix",
                "effect penetration_fix, for the yarn polylines written".into(),
            );
        }
        for (output, file) in [
            (Output::Glb, "stocking.glb"),
            (Output::Ply, "stocking.ply"),
            (Output::Ply, "leg.ply"),
            (Output::Picture, "density.png"),
            (Output::Preview, "preview.png"),
        ] {
            if !scene.wants(output) {
                if output == Output::Preview {
                    left_out.push(PlannedStage {
                        name: PREVIEW_STAGE.into(),
                        why: "outputs does not list \"preview\": no BVH, yarn grid or camera \
                              is built"
                            .into(),
                    });
                }
                continue;
            }
            if output == Output::Preview {
                add(PREVIEW_STAGE, preview_reason(scene));
            } else {
                add(
                    &format!("encode {file}"),
                    format!("outputs lists \"{}\"", output_name(output)),
                );
            }
            files.push((output, file));
        }
        add("write files", "every run writes report.json".into());
        Plan {
            command: "fit",
            effects,
            forces,
            stages,
            left_out,
            files,
        }
    }
}

/// The stage that ray-traces and encodes `preview.png`.
pub const PREVIEW_STAGE: &str = "render preview";

/// Why the preview is rendered, and how.
fn preview_reason(scene: &Scene) -> String {
    let r = &scene.render;
    let camera = if r.camera.is_some() {
        "scene camera".to_string()
    } else {
        format!("{} view", r.view.name())
    };
    format!(
        "outputs lists \"preview\": {} mode, {}×{}, {} spp, {camera}",
        r.mode.name(),
        r.width,
        r.height,
        r.spp
    )
}

impl Plan {
    /// The plan of `knitfit render`: read a fit's `stocking.glb`, ray-trace and encode the
    /// preview, write it. No solver, no forces.
    pub fn render(scene: &Scene, input: &str) -> Plan {
        let stages = vec![
            PlannedStage {
                name: "read stocking.glb".into(),
                why: format!("the leg and yarns of {input}"),
            },
            PlannedStage {
                name: PREVIEW_STAGE.into(),
                why: preview_reason(scene).replacen(
                    "outputs lists \"preview\"",
                    "knitfit render",
                    1,
                ),
            },
            PlannedStage {
                name: "write files".into(),
                why: "the picture and report.json".into(),
            },
        ];
        Plan {
            command: "render",
            effects: Vec::new(),
            forces: ForceTerms {
                stiffness: [0.0; 2],
                connection_factor: None,
            },
            stages,
            left_out: Vec::new(),
            files: vec![(Output::Preview, "preview.png")],
        }
    }
}

impl Plan {
    /// True when the plan has a stage of this name.
    pub fn has_stage(&self, name: &str) -> bool {
        self.stages.iter().any(|s| s.name == name)
    }
}

/// The force terms the effects switch on.
fn force_terms(scene: &Scene, effects: &[Effect]) -> ForceTerms {
    let nylon = scene.yarns.nylon.stiffness;
    let stiffness = if effects.contains(&Effect::AlternatingYarns) {
        YarnKind::ALL.map(|k| scene.yarns.get(k).stiffness)
    } else {
        [nylon, nylon]
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

/// Name of an output as written in scene files.
pub fn output_name(output: Output) -> &'static str {
    match output {
        Output::Ply => "ply",
        Output::Glb => "glb",
        Output::Picture => "picture",
        Output::Preview => "preview",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        assert_eq!(Plan::patch(&scene).forces.stiffness, [1.0, 1.0]);
    }

    #[test]
    fn the_penetration_fix_runs_only_for_written_polylines() {
        let mut scene = Scene::load(None).unwrap();
        scene.effects = vec![Effect::PenetrationFix];
        let stage_names =
            |plan: &Plan| -> Vec<String> { plan.stages.iter().map(|s| s.name.clone()).collect() };
        let fit = Plan::fit(&scene);
        assert!(fit.effects.contains(&Effect::PenetrationFix));
        assert!(stage_names(&fit).contains(&"penetration fix".to_string()));
        scene.outputs = vec![Output::Picture];
        let fit = Plan::fit(&scene);
        assert!(!fit.effects.contains(&Effect::PenetrationFix));
        assert!(!stage_names(&fit).contains(&"penetration fix".to_string()));
        assert!(!Plan::patch(&scene)
            .effects
            .contains(&Effect::PenetrationFix));
    }

    #[test]
    fn the_multilevel_fit_knits_each_grid_inside_the_fit_stage() {
        let mut scene = Scene::load(None).unwrap();
        let fit = Plan::fit(&scene);
        assert!(!fit.has_stage("knit tube"));
        let why = &fit.stages.iter().find(|s| s.name == "fit").unwrap().why;
        assert!(why.contains("38×39 → 75×76 → 150×150"), "{why}");
        scene.solver.method = SolverMethod::Paper;
        let fit = Plan::fit(&scene);
        assert!(fit.has_stage("knit tube"));
    }

    #[test]
    fn the_preview_is_rendered_only_when_outputs_list_it() {
        let mut scene = Scene::load(None).unwrap();
        scene.outputs = vec![Output::Glb, Output::Picture];
        let plan = Plan::fit(&scene);
        assert!(!plan.has_stage(PREVIEW_STAGE));
        assert!(!plan.files.iter().any(|(o, _)| *o == Output::Preview));
        scene.outputs.push(Output::Preview);
        let plan = Plan::fit(&scene);
        let stage = plan
            .stages
            .iter()
            .find(|s| s.name == PREVIEW_STAGE)
            .unwrap();
        assert!(
            stage.why.contains("outputs lists \"preview\""),
            "{}",
            stage.why
        );
        assert!(stage.why.contains("yarn mode"), "{}", stage.why);
        assert_eq!(plan.files.last(), Some(&(Output::Preview, "preview.png")));
    }

    #[test]
    fn a_yarn_preview_alone_still_gets_the_penetration_fix_but_no_leg_attributes() {
        let mut scene = Scene::load(None).unwrap();
        scene.outputs = vec![Output::Preview];
        let plan = Plan::fit(&scene);
        assert!(
            plan.has_stage("penetration fix"),
            "yarns drawn must follow the skin"
        );
        assert!(!plan.has_stage("leg attributes"));
        scene.render.mode = RenderMode::Density;
        let plan = Plan::fit(&scene);
        assert!(!plan.has_stage("penetration fix"));
        assert!(
            plan.has_stage("leg attributes"),
            "the density mode colours by them"
        );
    }

    #[test]
    fn only_asked_for_files_are_encoded() {
        let mut scene = Scene::load(None).unwrap();
        scene.outputs = vec![Output::Glb];
        let plan = Plan::patch(&scene);
        let names: Vec<_> = plan.stages.iter().map(|s| s.name.as_str()).collect();
        assert!(names.contains(&"encode patch.glb"));
        assert!(!names.iter().any(|n| n.contains("ply") || n.contains("png")));
    }
}
