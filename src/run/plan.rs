//! `knitfit plan`: what a fit or patch would do, without doing it. Shows the [`Plan`] (effects,
//! force terms, stages with why each runs, what is left out and why, files) and, for a fit, the
//! memory estimate against the limit ([`crate::limits`]). Reads the scene and the leg file's
//! document (to count its triangles); simulates nothing and writes nothing.

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::fit::{memory_check, FitInputs};
use crate::error::Result;
use crate::leg::read_leg_file;
use crate::limits::{MemoryCheck, MemoryEstimate, MemoryLimit};
use crate::plan::{LeftOut, Plan, PlannedStage};
use crate::scene::{Effect, LoadedScene};
use crate::sim::ForceTerms;

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

/// The plan of `knitfit fit` for `loaded`, writing into `out_dir`.
///
/// Errors: the leg file's, as the fit would meet them (unreadable, not glTF, compressed).
pub fn plan_fit(loaded: &LoadedScene, out_dir: &Path) -> Result<PlanOutcome> {
    let scene = &loaded.scene;
    let plan = Plan::fit(scene);
    let leg = FitInputs::of(loaded).leg;
    let triangles = read_leg_file(&leg)?.declared_triangles();
    Ok(PlanOutcome {
        memory: Some(memory_check(scene, &plan, triangles)),
        leg: Some((leg, triangles)),
        files: files(&plan, out_dir),
        scene: loaded.name.clone(),
        plan,
    })
}

/// The plan of `knitfit patch` for `loaded`, writing into `out_dir`.
pub fn plan_patch(loaded: &LoadedScene, out_dir: &Path) -> PlanOutcome {
    let plan = Plan::patch(&loaded.scene);
    PlanOutcome {
        memory: None,
        leg: None,
        files: files(&plan, out_dir),
        scene: loaded.name.clone(),
        plan,
    }
}

fn files(plan: &Plan, out_dir: &Path) -> Vec<PathBuf> {
    plan.file_names()
        .into_iter()
        .map(|name| out_dir.join(name))
        .collect()
}

impl PlanOutcome {
    /// The plan as JSON, for scripts: `command`, `scene`, `leg` (`file`, `declared_triangles`;
    /// null for a patch), `effects`, `forces`, `stages` and `left_out` (`name`, `why`), `files`,
    /// `memory` (`estimate` by part with `total_bytes`, `limit`, `allow_large`, `fits`; null
    /// for a patch).
    pub fn to_json(&self) -> serde_json::Value {
        let p = &self.plan;
        let view = PlanJson {
            command: p.command,
            scene: &self.scene,
            leg: self.leg.as_ref().map(|(file, triangles)| LegJson {
                file: file.display().to_string(),
                declared_triangles: *triangles,
            }),
            effects: &p.effects,
            forces: &p.forces,
            stages: &p.stages,
            left_out: &p.left_out,
            files: self.files.iter().map(|f| f.display().to_string()).collect(),
            memory: self.memory.as_ref().map(|m| MemoryJson {
                estimate: &m.estimate,
                limit: &m.limit,
                allow_large: m.allow_large,
                fits: m.fits(),
            }),
        };
        serde_json::to_value(view).expect("a plan always serialises")
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
            .map(|s| s.stage.to_string().chars().count())
            .chain(p.left_out.iter().map(|s| s.name.chars().count()))
            .max()
            .unwrap_or(0);
        out += "stages, in order:\n";
        for (i, s) in p.stages.iter().enumerate() {
            out += &format!(
                "  {:>2}. {:<width$}  {}\n",
                i + 1,
                s.stage.to_string(),
                s.why
            );
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

/// `knitfit plan --json`.
#[derive(Serialize)]
struct PlanJson<'a> {
    command: &'a str,
    scene: &'a str,
    leg: Option<LegJson>,
    effects: &'a [Effect],
    forces: &'a ForceTerms,
    stages: &'a [PlannedStage],
    left_out: &'a [LeftOut],
    files: Vec<String>,
    memory: Option<MemoryJson<'a>>,
}

#[derive(Serialize)]
struct LegJson {
    file: String,
    declared_triangles: usize,
}

#[derive(Serialize)]
struct MemoryJson<'a> {
    estimate: &'a MemoryEstimate,
    limit: &'a MemoryLimit,
    allow_large: bool,
    fits: bool,
}
