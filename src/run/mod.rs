//! The commands: each builds its [`Plan`], runs its stages in one shared frame (`Run`: the
//! output directory checked first, stages timed, files encoded in memory, written atomically,
//! then the report) and returns what it wrote. Data flows one way, scene → load → knit → solve
//! → post-process → encode → write → report; the library prints nothing (long stages report to
//! a [`Progress`] the caller supplies, which the CLI draws as a progress bar).

pub mod bench;
pub mod fit;
pub mod patch;
pub mod plan;
pub mod render;

use std::path::{Path, PathBuf};

use serde::Serialize;

pub use bench::{run_bench, BenchOptions, BenchOutcome};
pub use fit::run_fit;
pub use patch::run_patch;
pub use plan::{plan_fit, plan_patch, PlanOutcome};
pub use render::{run_render, run_spp_sweep, Sweep};

use crate::error::Result;
use crate::export::atomic;
use crate::plan::Plan;
use crate::report::{Metrics, Report, StageClock};
use crate::stage::Stage;
pub use crate::stage::{NoProgress, Progress};

/// What a command wrote: its report (as written) and every file, the report last.
#[derive(Debug)]
pub struct Outcome<D> {
    /// The report, as written.
    pub report: Report<D>,
    /// Every file written, in order.
    pub written: Vec<PathBuf>,
}

/// The frame every command runs in: the plan's stages timed as they run, the output directory
/// checked before the work starts, the files encoded in memory and written together at the end
/// (each to a temporary name, then renamed; never over an input), then the report. A run that
/// fails at any stage writes nothing, and removes the output directory again if it made it.
pub(crate) struct Run<'p> {
    plan: &'p Plan,
    out_dir: PathBuf,
    /// The checked output directory, once [`Run::prepare`] has run: dropped with the run, it
    /// removes the directories it created unless the run finished.
    prepared: Option<atomic::PreparedDir>,
    inputs: Vec<PathBuf>,
    /// The stages' times, against the plan.
    pub clock: StageClock,
    files: Vec<(String, Vec<u8>)>,
}

impl<'p> Run<'p> {
    /// A run of `plan` writing into `out_dir`, never over one of `inputs`; its clock starts now.
    pub fn new(plan: &'p Plan, out_dir: &Path, inputs: Vec<PathBuf>) -> Run<'p> {
        Run {
            plan,
            out_dir: out_dir.to_path_buf(),
            prepared: None,
            inputs,
            clock: StageClock::new(plan),
            files: Vec::new(),
        }
    }

    /// Checks the output directory can take the plan's files (creating it if needed) before any
    /// work is done, so a run that could not write fails at once. A directory created here is
    /// removed again if the run fails before [`Run::finish`] has written into it.
    pub fn prepare(&mut self) -> Result<()> {
        self.prepared = Some(atomic::prepare_dir(
            &self.out_dir,
            &self.plan.file_names(),
            &self.inputs,
        )?);
        Ok(())
    }

    /// Runs `work` as `stage`, timed.
    pub fn stage<T>(&mut self, stage: Stage, work: impl FnOnce() -> T) -> T {
        self.clock.time(stage, work)
    }

    /// Runs `work` as `stage` and keeps the bytes it makes as the file `name`.
    pub fn encode(
        &mut self,
        stage: Stage,
        name: &str,
        work: impl FnOnce() -> Result<Vec<u8>>,
    ) -> Result<()> {
        let bytes = self.clock.time(stage, work)?;
        self.keep(name, bytes);
        Ok(())
    }

    /// Keeps `bytes` as the file `name`, to be written with the others.
    pub fn keep(&mut self, name: &str, bytes: Vec<u8>) {
        self.files.push((name.to_string(), bytes));
    }

    /// Writes the files (stage [`Stage::WriteFiles`]), then the report of the scene `scene`
    /// with these `metrics` and `details`.
    pub fn finish<D: Serialize>(
        mut self,
        scene: &str,
        metrics: Metrics,
        details: D,
    ) -> Result<Outcome<D>> {
        let files = std::mem::take(&mut self.files);
        let mut written = self.clock.time(Stage::WriteFiles, || {
            atomic::write_all(&self.out_dir, &files, &self.inputs)
        })?;
        let report = Report {
            command: self.plan.command,
            scene: scene.to_string(),
            effects: self.plan.effects.clone(),
            stages: self.clock.records().to_vec(),
            metrics,
            details,
            outputs: self
                .plan
                .file_names()
                .iter()
                .map(|s| s.to_string())
                .collect(),
            wall_seconds: self.clock.wall_seconds(),
        };
        written.extend(atomic::write_all(
            &self.out_dir,
            &[(self.plan.report.clone(), report.to_json())],
            &self.inputs,
        )?);
        if let Some(prepared) = self.prepared.take() {
            prepared.keep();
        }
        Ok(Outcome { report, written })
    }
}
