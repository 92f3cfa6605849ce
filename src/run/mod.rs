//! One function per command, stringing the stages of its [`crate::plan::Plan`] together:
//! load → knit → solve → post-process → export. The library prints nothing; long stages report
//! to a [`Progress`] the caller supplies (the CLI draws a progress bar with it).

pub mod bench;
pub mod fit;
pub mod patch;
pub mod plan;
pub mod render;

use std::path::PathBuf;

pub use bench::{run_bench, BenchOptions, BenchOutcome};
pub use fit::{run_fit, FitInputs, FitOutcome};
pub use patch::{run_patch, PatchOutcome};
pub use plan::{plan_fit, plan_patch, PlanOutcome};
pub use render::{run_render, run_spp_sweep, RenderInputs, RenderOutcome};

/// Receives progress of long stages.
pub trait Progress {
    /// A stage of up to `total` steps begins.
    fn begin(&mut self, stage: &str, total: u64);
    /// The current stage reached `position` with the given residual.
    fn advance(&mut self, position: u64, residual: f64);
    /// The current stage ended.
    fn end(&mut self);
}

/// Progress that goes nowhere (tests, `-q`).
pub struct NoProgress;

impl Progress for NoProgress {
    fn begin(&mut self, _stage: &str, _total: u64) {}
    fn advance(&mut self, _position: u64, _residual: f64) {}
    fn end(&mut self) {}
}

/// Feeds solver steps to a [`Progress`].
struct StepProgress<'a>(&'a mut dyn Progress);

impl crate::sim::RelaxObserver for StepProgress<'_> {
    fn on_step(&mut self, step: usize, residual: f64) {
        self.0.advance(step as u64, residual);
    }
}

/// Where a run reads from and writes to.
#[derive(Clone, Debug)]
pub struct RunPaths {
    /// How the scene is named in messages and the report.
    pub scene_name: String,
    /// Input files, never to be overwritten by an output.
    pub inputs: Vec<PathBuf>,
    /// Output directory (created if missing).
    pub out_dir: PathBuf,
}
