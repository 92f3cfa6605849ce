//! `report.json`: what ran, how long each stage took, how accurate the result is, and which
//! files were written. Every command writes one.

use std::time::Instant;

use serde::Serialize;

/// Wall time of one stage.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StageTime {
    /// Stage name, as in the plan.
    pub name: String,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// Accuracy and size of a run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Metrics {
    /// Mass points simulated (summed over all relaxations of the run).
    pub points: usize,
    /// Solver steps (summed over all relaxations).
    pub steps: usize,
    /// Worst final relative residual over the relaxations.
    pub residual: f64,
    /// Worst final largest move per step (iteration), relative to the shortest rest length.
    pub max_move: f64,
    /// Multilevel fit only: the final force step (largest move the unbalanced force alone would
    /// make in one iteration, over the shortest rest length), which with the residual decides
    /// convergence there.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub force_step: Option<f64>,
    /// True when every relaxation converged below the tolerance.
    pub converged: bool,
    /// Fit only: deepest yarn point inside the leg after the fit, measured against the exact
    /// triangles, metres (0 when none is inside).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_penetration_m: Option<f64>,
    /// Fit only: triangles of the leg mesh.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub leg_triangles: Option<usize>,
}

/// The report of one run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// The command that ran (`patch`).
    pub command: String,
    /// The scene file (or the bundled one).
    pub scene: String,
    /// Effects that ran, by scene name.
    pub effects: Vec<String>,
    /// Stages in the order they ran.
    pub stages: Vec<StageTime>,
    /// Accuracy and size.
    pub metrics: Metrics,
    /// Command-specific details (e.g. per-stretch results of `patch`).
    pub details: serde_json::Value,
    /// Files written, by name, including `report.json`.
    pub outputs: Vec<String>,
    /// Wall-clock seconds of the whole run.
    pub wall_seconds: f64,
}

impl Report {
    /// Pretty JSON, newline-terminated.
    pub fn to_json(&self) -> Vec<u8> {
        let mut bytes = serde_json::to_vec_pretty(self).expect("a report always serialises");
        bytes.push(b'\n');
        bytes
    }
}

/// Times stages as they run.
#[derive(Debug)]
pub struct StageClock {
    started: Instant,
    stages: Vec<StageTime>,
}

impl Default for StageClock {
    fn default() -> Self {
        StageClock {
            started: Instant::now(),
            stages: Vec::new(),
        }
    }
}

impl StageClock {
    /// Runs `f` as stage `name` and records its wall time.
    pub fn time<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = f();
        self.stages.push(StageTime {
            name: name.to_string(),
            seconds: start.elapsed().as_secs_f64(),
        });
        out
    }

    /// The stages recorded so far.
    pub fn stages(&self) -> &[StageTime] {
        &self.stages
    }

    /// Seconds since the clock started.
    pub fn wall_seconds(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }
}
