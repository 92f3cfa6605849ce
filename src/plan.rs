//! From a scene to the work a run will do: the effects that run, the force terms they switch on,
//! and the ordered stages, each with the reason it is there. Nothing outside the plan runs, and
//! the report lists the stages that did.

use crate::knit::YarnKind;
use crate::scene::{Effect, Output, Scene};
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
    /// Files to write besides `report.json`, in order.
    pub files: Vec<(Output, &'static str)>,
}

impl Plan {
    /// The plan of `knitfit patch` for `scene`: for each stretch, build a patch and relax it;
    /// then measure stitches and encode the asked-for files.
    pub fn patch(scene: &Scene) -> Plan {
        let effects = dedup(&scene.effects);
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
        add("write files".into(), "every run writes report.json".into());
        Plan {
            command: "patch",
            effects,
            forces,
            stages,
            files,
        }
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
    fn only_asked_for_files_are_encoded() {
        let mut scene = Scene::load(None).unwrap();
        scene.outputs = vec![Output::Glb];
        let plan = Plan::patch(&scene);
        let names: Vec<_> = plan.stages.iter().map(|s| s.name.as_str()).collect();
        assert!(names.contains(&"encode patch.glb"));
        assert!(!names.iter().any(|n| n.contains("ply") || n.contains("png")));
    }
}
