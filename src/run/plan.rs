//! `knitfit plan`: what a fit or patch would do, without doing it. Shows the [`Plan`] (effects,
//! force terms, stages with why each runs, what is left out and why, files) and, for a fit, the
//! memory estimate against the limit ([`crate::limits`]). Reads the scene and the leg file's
//! document (to count its triangles); simulates nothing and writes nothing.

use std::path::PathBuf;

use serde_json::json;

use super::fit::FitInputs;
use super::RunPaths;
use crate::error::Result;
use crate::leg::read_leg_file;
use crate::limits::MemoryCheck;
use crate::plan::{Plan, PlannedStage};
use crate::scene::Scene;

/// What `knitfit plan` shows.
#[derive(Clone, Debug)]
pub struct PlanOutcome {
    /// The plan the run would follow.
    pub plan: Plan,
    /// How the scene is named.
    pub scene: String,
    /// Fit only: the leg file and the triangles it declares.
    pub leg: Option<(PathBuf, usize)>,
    /// Fit only: the memory estimate against the limit.
    pub memory: Option<MemoryCheck>,
    /// The files the run would write, report included, in its output directory.
    pub files: Vec<PathBuf>,
}

/// The plan of `knitfit fit` for `scene` on `inputs.leg`.
///
/// Errors: the leg file's, as the fit would meet them (unreadable, not glTF, compressed).
pub fn plan_fit(scene: &Scene, inputs: &FitInputs, paths: &RunPaths) -> Result<PlanOutcome> {
    let plan = Plan::fit(scene);
    let triangles = read_leg_file(&inputs.leg)?.declared_triangles();
    Ok(PlanOutcome {
        memory: Some(MemoryCheck::fit(scene, &plan, triangles)),
        leg: Some((inputs.leg.clone(), triangles)),
        files: files(&plan, paths),
        scene: paths.scene_name.clone(),
        plan,
    })
}

/// The plan of `knitfit patch` for `scene`.
pub fn plan_patch(scene: &Scene, paths: &RunPaths) -> PlanOutcome {
    let plan = Plan::patch(scene);
    PlanOutcome {
        memory: None,
        leg: None,
        files: files(&plan, paths),
        scene: paths.scene_name.clone(),
        plan,
    }
}

fn files(plan: &Plan, paths: &RunPaths) -> Vec<PathBuf> {
    plan.files
        .iter()
        .map(|(_, name)| *name)
        .chain(["report.json"])
        .map(|name| paths.out_dir.join(name))
        .collect()
}

impl PlanOutcome {
    /// The plan as JSON, for scripts: `command`, `scene`, `leg` (`file`, `declared_triangles`;
    /// null for a patch), `effects`, `forces`, `stages` and `left_out` (`name`, `why`), `files`,
    /// `memory` (`estimate` by part with `total_bytes`, `limit`, `allow_large`, `fits`; null
    /// for a patch).
    pub fn to_json(&self) -> serde_json::Value {
        let stages = |list: &[PlannedStage]| -> Vec<serde_json::Value> {
            list.iter()
                .map(|s| json!({ "name": s.name, "why": s.why }))
                .collect()
        };
        let p = &self.plan;
        json!({
            "command": p.command,
            "scene": self.scene,
            "leg": self.leg.as_ref().map(|(file, triangles)| json!({
                "file": file.display().to_string(),
                "declared_triangles": triangles,
            })),
            "effects": p.effects.iter().map(|e| e.name()).collect::<Vec<_>>(),
            "forces": {
                "stiffness": p.forces.stiffness,
                "connection_factor": p.forces.connection_factor,
            },
            "stages": stages(&p.stages),
            "left_out": stages(&p.left_out),
            "files": self.files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>(),
            "memory": self.memory.as_ref().map(|m| json!({
                "estimate": m.estimate,
                "limit": m.limit,
                "allow_large": m.allow_large,
                "fits": m.fits(),
            })),
        })
    }

    /// The plan as text for a person: a header, then one line per stage with why it runs.
    pub fn to_text(&self) -> String {
        let p = &self.plan;
        let mut out = format!("knitfit {}: scene {}", p.command, self.scene);
        if let Some((file, triangles)) = &self.leg {
            out += &format!(", leg {} ({triangles} triangles)", file.display());
        }
        out += "\n";
        let effects: Vec<&str> = p.effects.iter().map(|e| e.name()).collect();
        out += &format!(
            "effects: {}\n",
            if effects.is_empty() {
                "none".to_string()
            } else {
                effects.join(", ")
            }
        );
        let [nylon, support] = p.forces.stiffness;
        out += &format!("forces: springs (eq. 1, c1 = {nylon} nylon, {support} support)");
        if let Some(c2) = p.forces.connection_factor {
            out += &format!(" + yarn connection (eq. 2, c2 = {c2})");
        }
        out += "\n";
        let width = p
            .stages
            .iter()
            .chain(&p.left_out)
            .map(|s| s.name.chars().count())
            .max()
            .unwrap_or(0);
        out += "stages, in order:\n";
        for (i, s) in p.stages.iter().enumerate() {
            out += &format!("  {:>2}. {:<width$}  {}\n", i + 1, s.name, s.why);
        }
        if !p.left_out.is_empty() {
            out += "left out:\n";
            for s in &p.left_out {
                out += &format!("      {:<width$}  {}\n", s.name, s.why);
            }
        }
        let files: Vec<String> = self.files.iter().map(|f| f.display().to_string()).collect();
        out += &format!("files: {}\n", files.join(", "));
        if let Some(memory) = &self.memory {
            out += &format!("memory: {}\n", memory.summary());
        }
        out
    }
}
