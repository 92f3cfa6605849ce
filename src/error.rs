//! The one error type of the library. Every variant that comes from user input names the file
//! or flag it came from, and its message says how to fix it.

use std::path::PathBuf;

/// What can go wrong in a knitfit run.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An input file could not be read.
    #[error("{path}: cannot read: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The scene file is not valid JSON, or does not match the scene schema.
    #[error("{path}:{line}:{column}: {message}")]
    SceneSyntax {
        path: String,
        line: usize,
        column: usize,
        message: String,
    },
    /// A scene field (or the flag that overrides it) has a value the run cannot use.
    #[error("{path}: {field}: {message}")]
    InvalidScene {
        path: String,
        field: String,
        message: String,
    },
    /// A settings value the run cannot use, found by a check that needs the leg (its length,
    /// its foot): the field as the scene spells it, and what is wrong. A command reports it
    /// under the scene file, or the flag that set the value ([`crate::scene::LoadedScene::named`]).
    #[error("{}: {}", .0.field, .0.message)]
    Settings(crate::base::settings::Invalid),
    /// The leg file cannot be used: not glTF, no triangles, compressed geometry, bad values, or
    /// implausible units.
    #[error("{path}: {message}")]
    Leg { path: PathBuf, message: String },
    /// The file given to `knitfit render` is missing, not glTF, or lacks the `leg` or `yarns`
    /// node a `knitfit fit` writes; render the `stocking.glb` of a fit.
    #[error("{path}: {message}")]
    RenderInput { path: PathBuf, message: String },
    /// A command-line argument has a value the run cannot use.
    #[error("{flag}: {message}")]
    InvalidArgument { flag: String, message: String },
    /// The run would need more memory than it may use (see `crate::limits`); lower the
    /// resolution, or pass `--allow-large` (`limits.allow_large`) to run anyway.
    #[error(
        "{what} needs about {estimate}, {available} available ({limit_source}); {how_to_override}"
    )]
    TooLarge {
        /// The run, by its size (`a fit of 400×40000 points on leg.glb (…)`).
        what: String,
        /// The estimate, with its unit (`31.2 GiB`).
        estimate: String,
        /// The limit, with its unit.
        available: String,
        /// Where the limit came from (`MemAvailable in /proc/meminfo`).
        limit_source: String,
        /// What to change, and the override.
        how_to_override: String,
    },
    /// The output directory cannot be created or written to.
    #[error("{path}: output directory is not writable: {source}")]
    OutputDir {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The output directory is a file, or lies under one (`file`); give `--out` a directory,
    /// or a path where one can be made.
    #[error("{path}: cannot be the output directory: {file} is a file, not a directory")]
    OutputNotDirectory { path: PathBuf, file: PathBuf },
    /// An output would replace an input file.
    #[error("{path}: refusing to overwrite an input file with an output")]
    WouldOverwriteInput { path: PathBuf },
    /// Writing an output file failed (nothing is left half-written).
    #[error("{path}: cannot write: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The time step is above the explicit stability limit and the scene asked to stop rather
    /// than sub-step.
    #[error(
        "solver.time_step {time_step} is above the explicit stability limit {limit:.4} for the \
         stiffest spring (c1 = {stiffest}); use a time step of at most {limit:.4}, or set \
         solver.on_unstable to \"substep\""
    )]
    TimeStepTooLarge {
        time_step: f64,
        limit: f64,
        stiffest: f64,
    },
    /// The time step is so far above the explicit stability limit that sub-stepping it would
    /// take more than `max_substeps` sub-steps a step (a run that would never end).
    #[error(
        "solver.time_step {} would take more than {max_substeps} sub-steps a step under the \
         explicit stability limit {limit:.3e} for the stiffest spring (c1 = {}); use a time step \
         of at most {most:.3e}",
        crate::base::settings::number(*.time_step),
        crate::base::settings::number(*.stiffest)
    )]
    TooManySubsteps {
        time_step: f64,
        limit: f64,
        stiffest: f64,
        max_substeps: usize,
        most: f64,
    },
    /// The relaxation blew up (energy grew without bound, or a value stopped being finite).
    #[error(
        "relaxation diverged at step {step} ({what}); nothing was written. Lower solver.time_step \
         (now {time_step}, stability limit {limit:.4}) or set solver.on_unstable to \"substep\""
    )]
    Diverged {
        step: usize,
        what: String,
        time_step: f64,
        limit: f64,
    },
    /// The multilevel solver met a value that stopped being finite, or a residual that grew
    /// without bound. Its iteration restarts its momentum whenever motion goes against the
    /// force, so this points at the input (a knit compressed to a point, a leg with NaNs that
    /// slipped through) rather than at a step size.
    #[error(
        "multilevel solver diverged on the {grid} grid at iteration {iteration} ({what}); \
         nothing was written. Check the scene's yarn stiffnesses and tube size, or run the \
         paper's solver (solver.method \"paper\", --solver paper) to compare"
    )]
    SolverDiverged {
        grid: String,
        iteration: usize,
        what: String,
    },
    /// The fit came to rest, but not as a stocking: its courses slid along the leg past each
    /// other and bunched, as a yarn far too tight for the leg does (support yarn much stiffer
    /// than nylon, or a relaxed circumference far below the leg's girth).
    #[error(
        "the fit is not a stocking: {bunched} of its {courses} courses came to rest below courses \
         before them, from course {course} on, {place} (the courses slid down the leg and \
         bunched); nothing was written. The yarn is too tight for this leg: lower yarns.support.stiffness \
         (now {ratio}× nylon's) or raise tube.relaxed_circumference_m (now {circumference_m} m)"
    )]
    Bunched {
        course: usize,
        bunched: usize,
        courses: usize,
        place: String,
        ratio: f64,
        circumference_m: f64,
    },
    /// The solver stopped early because it was going nowhere: its momentum restarted on almost
    /// every iteration and the residual stopped falling (a tube that cannot pass the foot, or is
    /// far too small for the leg). Exit code 3, as for a fit that did not converge, but nothing
    /// is written: the state is no stocking.
    #[error(
        "the fit is going nowhere and was stopped: on the {grid} grid after {iterations} \
         iterations ({seconds:.1} s) the residual stays near {residual:.1e}; {place}; nothing was \
         written. {advice}"
    )]
    Stalled {
        grid: String,
        iterations: usize,
        seconds: f64,
        residual: f64,
        place: String,
        advice: String,
    },
    /// Encoding an output (PNG, glTF) failed.
    #[error("{what}: {message}")]
    Encode { what: String, message: String },
}

impl Error {
    /// Process exit code: 2 for bad input (files, flags, values), 1 for a run that failed, 3
    /// for a fit stopped short of converging.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Read { .. }
            | Error::SceneSyntax { .. }
            | Error::InvalidScene { .. }
            | Error::Settings(_)
            | Error::InvalidArgument { .. }
            | Error::Leg { .. }
            | Error::RenderInput { .. }
            | Error::TooLarge { .. }
            | Error::OutputDir { .. }
            | Error::OutputNotDirectory { .. }
            | Error::WouldOverwriteInput { .. }
            | Error::TimeStepTooLarge { .. }
            | Error::TooManySubsteps { .. } => 2,
            Error::Write { .. }
            | Error::Diverged { .. }
            | Error::SolverDiverged { .. }
            | Error::Bunched { .. }
            | Error::Encode { .. } => 1,
            Error::Stalled { .. } => 3,
        }
    }
}

/// Result with the library's error type.
pub type Result<T> = std::result::Result<T, Error>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_are_one_line_without_runs_of_spaces() {
        let errors = [
            Error::SolverDiverged {
                grid: "38×39".into(),
                iteration: 12,
                what: "a position stopped being finite".into(),
            },
            Error::Diverged {
                step: 3,
                what: "energy grew 1000×".into(),
                time_step: 0.4,
                limit: 0.2,
            },
            Error::Bunched {
                course: 4,
                bunched: 11,
                courses: 100,
                place: "gathered 1–6 cm above the stocking's bottom end".into(),
                ratio: 1000.0,
                circumference_m: 0.2,
            },
            Error::TooManySubsteps {
                time_step: 1e308,
                limit: 0.225,
                stiffest: 10.0,
                max_substeps: 10_000,
                most: 2250.0,
            },
            Error::TimeStepTooLarge {
                time_step: 0.4,
                limit: 0.2,
                stiffest: 10.0,
            },
            Error::Stalled {
                grid: "38×39".into(),
                iterations: 200,
                seconds: 0.1,
                residual: 0.12,
                place: "courses 0–9 of 39 are out of balance".into(),
                advice: "Raise tube.relaxed_circumference_m.".into(),
            },
        ];
        for e in errors {
            let text = e.to_string();
            assert!(!text.contains("  ") && !text.contains('\n'), "{text}");
        }
    }
}
