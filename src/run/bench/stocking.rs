//! The bench's whole stocking: `knitfit fit` end to end, every file written, for a stocking to
//! the toe on the MakeHuman leg with its foot ([`STOCKING_LEG`]). The sweep times the solve
//! alone; this times what a user waits for: the fit and everything after it (the leg's
//! attributes, the penetration fix, encoding `stocking.glb`, `stocking.ply`, `leg.ply`,
//! `density.png` and `preview.png`, writing them and `report.json`).
//!
//! Each case is [`run_fit`] itself, on the bundled scene with `tube.bottom: "toe"`, the case's
//! grid and heel and every output, into a scratch directory removed afterwards. Its figures come
//! from the run's report (per-stage seconds, iterations, residual, penetration) and from the
//! `stocking.glb` it wrote, read back: the reach is the distance from the landmarks' toe tip to
//! the nearest yarn point. A fit the solver stops (stalled, bunched, diverged) is measured too:
//! its row says how long it ran and why it stopped.

use std::path::{Path, PathBuf};
use std::time::Instant;

use nalgebra::Point3;

use crate::base::GridSize;
use crate::error::{Error, Result};
use crate::export::gltf::read_stocking_glb;
use crate::export::Output;
use crate::knit::{TubeBottom, TubeHeel};
use crate::limits::{peak_memory, reset_peak_memory};
use crate::report::{FitDetails, Report};
use crate::run::{run_fit, NoProgress, Progress};
use crate::scene::{LoadedScene, Scene, BUNDLED_SCENE_NAME};
use crate::sim::SolverMethod;
use crate::stage::{FitFile, Stage};

use super::table::mib;

/// The leg the whole stocking is fitted to, in `samples/`: the MakeHuman leg with its foot.
pub const STOCKING_LEG: &str = "makehuman_leg_foot.glb";

/// The real stitch count: a sheer stocking has about 400 wales around and 1000–1600 courses
/// along. 1000 keeps the bench's whole run near ten seconds on two cores (400×1600 fits too,
/// in about twice the time).
const REAL_COUNT: StockingCase = StockingCase {
    grid: GridSize::new(400, 1000),
    heel: TubeHeel::None,
};

/// One whole stocking.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StockingCase {
    /// Points around by courses, welt to toe.
    pub grid: GridSize,
    /// The heel.
    pub heel: TubeHeel,
}

/// What one whole run measured.
#[derive(Clone, Debug, PartialEq)]
pub struct StockingRow {
    /// The case.
    pub case: StockingCase,
    /// The scene's solver.
    pub solver: SolverMethod,
    /// The scene's tolerance.
    pub tolerance: f64,
    /// Seconds of the whole run, scene to `report.json` (to the refusal, for a stopped fit).
    pub seconds: f64,
    /// Peak resident memory during the run, bytes.
    pub peak_memory_bytes: Option<u64>,
    /// The fit's figures, or why the solver stopped it.
    pub result: StockingResult,
}

/// How a whole run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum StockingResult {
    /// Every file written.
    Fitted(StockingFit),
    /// The solver stopped the fit, and nothing was written: its message.
    Stopped(String),
}

/// The figures of a whole run that wrote its files.
#[derive(Clone, Debug, PartialEq)]
pub struct StockingFit {
    /// Points of the knit (short rows included).
    pub points: usize,
    /// Seconds of the fit stage.
    pub fit_seconds: f64,
    /// Seconds of the solve as the sweep times it: the fit and the exact contact pass.
    pub solve_seconds: f64,
    /// Seconds of the preview.
    pub preview_seconds: f64,
    /// Iterations over all levels.
    pub iterations: usize,
    /// Final relative residual.
    pub residual: f64,
    /// Final largest move per iteration over the shortest rest length.
    pub max_move: f64,
    /// Whether it converged within `solver.max_steps`.
    pub converged: bool,
    /// Deepest yarn point inside the leg, metres.
    pub max_penetration_m: f64,
    /// Distance from the landmarks' toe tip to the nearest yarn point, metres (`None` where no
    /// toe tip was found).
    pub reach_m: Option<f64>,
}

/// The whole stockings to measure: 150 around with and without a heel pocket; the full bench
/// adds the real stitch count.
pub fn stocking_cases(quick: bool) -> Vec<StockingCase> {
    let mut cases: Vec<StockingCase> = [TubeHeel::None, TubeHeel::Pocket]
        .map(|heel| StockingCase {
            grid: GridSize::new(150, 150),
            heel,
        })
        .to_vec();
    if !quick {
        cases.push(REAL_COUNT);
    }
    cases
}

/// Runs every case in a scratch directory; advances `progress` from `done` on, one per case.
pub fn measure_stockings(
    cases: &[StockingCase],
    progress: &mut dyn Progress,
    done: u64,
) -> Result<Vec<StockingRow>> {
    let scratch = Scratch::new();
    let mut rows = Vec::new();
    for (n, case) in cases.iter().enumerate() {
        let row = measure_stocking(case, &scratch.0)?;
        let residual = match &row.result {
            StockingResult::Fitted(fit) => fit.residual,
            StockingResult::Stopped(_) => f64::NAN,
        };
        progress.advance(done + n as u64 + 1, residual);
        rows.push(row);
    }
    Ok(rows)
}

/// Runs `knitfit fit` on `case` into a directory under `scratch` and measures it.
pub fn measure_stocking(case: &StockingCase, scratch: &Path) -> Result<StockingRow> {
    let loaded = stocking_scene(case)?;
    let out_dir = scratch.join(format!(
        "{}x{}-{}",
        case.grid.wales,
        case.grid.courses,
        case.heel.name()
    ));
    reset_peak_memory();
    let started = Instant::now();
    let run = run_fit(&loaded, &out_dir, &mut NoProgress);
    let seconds = started.elapsed().as_secs_f64();
    let peak_memory_bytes = peak_memory();
    let result = match run {
        Ok(outcome) => StockingResult::Fitted(figures(&outcome.report, &out_dir)?),
        Err(error) => StockingResult::Stopped(stopped(error)?),
    };
    Ok(StockingRow {
        case: *case,
        solver: loaded.scene.solver.method,
        tolerance: loaded.scene.solver.tolerance,
        seconds,
        peak_memory_bytes,
        result,
    })
}

/// The bundled scene on [`STOCKING_LEG`], to the toe, with `case`'s grid and heel and every
/// output.
fn stocking_scene(case: &StockingCase) -> Result<LoadedScene> {
    let mut scene = Scene::load(None)?;
    scene.leg.file = STOCKING_LEG.into();
    scene.tube.bottom = Some(TubeBottom::Toe);
    scene.tube.heel = case.heel;
    scene.tube.wales = case.grid.wales;
    scene.tube.courses = Some(case.grid.courses);
    scene.outputs = vec![Output::Ply, Output::Glb, Output::Picture, Output::Preview];
    Ok(LoadedScene {
        scene,
        name: BUNDLED_SCENE_NAME.into(),
        path: None,
        overrides: Vec::new(),
    })
}

/// The figures of a finished run: its report's, and the reach of the `stocking.glb` it wrote
/// into `out_dir`.
fn figures(report: &Report<FitDetails>, out_dir: &Path) -> Result<StockingFit> {
    let seconds = |stages: &[Stage]| -> f64 {
        let ran = report.stages.iter().filter(|r| stages.contains(&r.name));
        ran.map(|r| r.seconds).sum()
    };
    let m = &report.metrics;
    Ok(StockingFit {
        points: m.points,
        fit_seconds: seconds(&[Stage::Fit]),
        solve_seconds: seconds(&[Stage::Fit, Stage::ExactContactPass]),
        preview_seconds: seconds(&[Stage::RenderPreview]),
        iterations: m.steps,
        residual: m.residual,
        max_move: m.max_move,
        converged: m.converged,
        max_penetration_m: m.max_penetration_m.unwrap_or(0.0),
        reach_m: reach_m(&report.details, out_dir)?,
    })
}

/// Distance from the toe tip in `details` to the nearest yarn point of the `stocking.glb` in
/// `out_dir`, metres; `None` where the landmarks found no toe.
fn reach_m(details: &FitDetails, out_dir: &Path) -> Result<Option<f64>> {
    let landmarks = details.leg.landmarks.as_ref();
    let Some(tip) = landmarks.and_then(|l| l.toe_tip.as_ref()) else {
        return Ok(None);
    };
    let tip = Point3::from(tip.m);
    let stocking = read_stocking_glb(&out_dir.join(FitFile::StockingGlb.name()))?;
    let nearest = stocking
        .yarns
        .positions
        .iter()
        .map(|&p| (Point3::from(p) - tip).norm())
        .fold(f64::INFINITY, f64::min);
    Ok(Some(nearest))
}

/// The message of a fit the solver stopped; any other error is returned as it is.
fn stopped(error: Error) -> Result<String> {
    match error {
        Error::Stalled { .. }
        | Error::Bunched { .. }
        | Error::SolverDiverged { .. }
        | Error::Diverged { .. } => Ok(error.to_string()),
        other => Err(other),
    }
}

/// A directory of the bench's own under the system's temporary one, removed with what it holds
/// when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new() -> Scratch {
        let name = format!("knitfit-bench-{}", std::process::id());
        Scratch(std::env::temp_dir().join(name))
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        // Nothing there is wanted afterwards; a directory that cannot be removed is left.
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// `bench.md`'s section for the whole stockings: the table, then why any fit stopped.
pub fn markdown(rows: &[StockingRow]) -> String {
    let mut md = String::from("\n## Whole stocking (to the toe)\n\n");
    md.push_str(&format!(
        "`knitfit fit` end to end on {}, to the toe: the bundled scene with tube.bottom \"toe\", \
         the heel named, and every output (stocking.glb, stocking.ply, leg.ply, density.png, \
         preview.png). Whole run: from the scene to report.json written; fit: the fit stage \
         alone; preview: its rendering. Reach: from the landmarks' toe tip to the nearest yarn \
         point of stocking.glb.\n\n",
        STOCKING_LEG.trim_end_matches(".glb")
    ));
    md.push_str(
        "| grid | heel | points | whole run s | fit s | preview s | iterations | residual | \
         converged | max penetration mm | reach mm | peak MiB |\n",
    );
    md.push_str("|---|---|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|\n");
    for row in rows {
        md.push_str(&table_row(row));
    }
    for row in rows {
        if let StockingResult::Stopped(why) = &row.result {
            let c = &row.case;
            let line = format!("\n{}, heel {}, stopped: {why}\n", c.grid, c.heel.name());
            md.push_str(&line);
        }
    }
    md
}

/// One row of the markdown table.
fn table_row(row: &StockingRow) -> String {
    let c = &row.case;
    let (grid, heel) = (c.grid, c.heel.name());
    let mib = mib(row.peak_memory_bytes);
    match &row.result {
        StockingResult::Fitted(f) => format!(
            "| {grid} | {heel} | {} | {:.2} | {:.2} | {:.2} | {} | {:.1e} | {} | {:.4} | {} | \
             {mib} |\n",
            f.points,
            row.seconds,
            f.fit_seconds,
            f.preview_seconds,
            f.iterations,
            f.residual,
            if f.converged { "yes" } else { "no" },
            f.max_penetration_m * 1000.0,
            f.reach_m
                .map_or("n/a".into(), |r| format!("{:.1}", r * 1000.0)),
        ),
        StockingResult::Stopped(_) => format!(
            "| {grid} | {heel} | {} | {:.2} | — | — | — | — | stopped (below) | — | — | {mib} |\n",
            c.grid.points(),
            row.seconds,
        ),
    }
}

/// `bench.csv`'s lines for the whole stockings, in its columns: `seconds` is the solve as the
/// sweep times it, `whole_seconds` the whole run; a stopped fit has `converged` false and no
/// figures.
pub fn csv_rows(rows: &[StockingRow]) -> String {
    rows.iter().map(csv_row).collect()
}

fn csv_row(row: &StockingRow) -> String {
    let c = &row.case;
    let fitted = match &row.result {
        StockingResult::Fitted(f) => Some(f),
        StockingResult::Stopped(_) => None,
    };
    let figure = |get: &dyn Fn(&StockingFit) -> String| fitted.map_or(String::new(), get);
    let fields = [
        STOCKING_LEG.to_string(),
        c.grid.wales.to_string(),
        c.grid.courses.to_string(),
        fitted.map_or(c.grid.points(), |f| f.points).to_string(),
        row.solver.name().to_string(),
        format!("{:e}", row.tolerance),
        figure(&|f| format!("{:.6}", f.solve_seconds)),
        figure(&|f| f.iterations.to_string()),
        figure(&|f| format!("{:e}", f.residual)),
        figure(&|f| format!("{:e}", f.max_move)),
        fitted.is_some_and(|f| f.converged).to_string(),
        figure(&|f| format!("{:e}", f.max_penetration_m)),
        row.peak_memory_bytes
            .map_or(String::new(), |b| b.to_string()),
        // No reference: the density error and the distance are the sweep's.
        String::new(),
        String::new(),
        TubeBottom::Toe.name().to_string(),
        c.heel.name().to_string(),
        format!("{:.6}", row.seconds),
        figure(&|f| f.reach_m.map_or(String::new(), |r| format!("{r:e}"))),
    ];
    fields.join(",") + "\n"
}

#[cfg(test)]
mod tests {
    use super::super::table::CSV_HEADER;
    use super::*;

    fn row(result: StockingResult) -> StockingRow {
        StockingRow {
            case: REAL_COUNT,
            solver: SolverMethod::Multilevel,
            tolerance: 1e-3,
            seconds: 53.0,
            peak_memory_bytes: Some(1 << 27),
            result,
        }
    }

    fn fitted() -> StockingFit {
        StockingFit {
            points: 400_000,
            fit_seconds: 40.0,
            solve_seconds: 40.5,
            preview_seconds: 3.0,
            iterations: 2000,
            residual: 9e-4,
            max_move: 1e-3,
            converged: true,
            max_penetration_m: 0.0,
            reach_m: Some(0.002),
        }
    }

    #[test]
    fn the_quick_bench_measures_150_around_with_and_without_a_heel_pocket_only() {
        let quick = stocking_cases(true);
        assert!(quick.iter().all(|c| c.grid == GridSize::new(150, 150)));
        let heels: Vec<_> = quick.iter().map(|c| c.heel).collect();
        assert_eq!(heels, [TubeHeel::None, TubeHeel::Pocket]);
        let full = stocking_cases(false);
        assert_eq!(full[..2], quick[..]);
        assert_eq!(full[2..], [REAL_COUNT]);
    }

    #[test]
    fn every_whole_stocking_csv_line_has_the_headers_columns() {
        let columns = CSV_HEADER.trim_end().split(',').count();
        let stopped = StockingResult::Stopped("the fit is going nowhere".into());
        let lines = csv_rows(&[row(StockingResult::Fitted(fitted())), row(stopped)]);
        assert_eq!(lines.lines().count(), 2);
        for line in lines.lines() {
            assert_eq!(line.split(',').count(), columns, "{line}");
            assert!(
                line.starts_with("makehuman_leg_foot.glb,400,1000,"),
                "{line}"
            );
        }
    }

    #[test]
    fn a_stopped_fit_is_a_row_whose_message_follows_the_table() {
        let why = "the fit is going nowhere and was stopped: on the 400×1000 grid";
        let md = markdown(&[row(StockingResult::Stopped(why.into()))]);
        assert!(md.contains("## Whole stocking (to the toe)"), "{md}");
        assert!(md.contains("| 400×1000 | none | 400000 | 53.00 |"), "{md}");
        assert!(
            md.contains(&format!("400×1000, heel none, stopped: {why}")),
            "{md}"
        );
    }

    #[test]
    fn a_whole_run_writes_every_file_reaches_the_toe_and_leaves_no_scratch_behind() {
        let case = StockingCase {
            grid: GridSize::new(60, 60),
            heel: TubeHeel::None,
        };
        let rows = measure_stockings(&[case], &mut NoProgress, 0).unwrap();
        let StockingResult::Fitted(fit) = &rows[0].result else {
            panic!("stopped: {:?}", rows[0].result);
        };
        assert!(fit.converged && fit.max_penetration_m == 0.0);
        assert!(fit.preview_seconds > 0.0 && fit.fit_seconds < rows[0].seconds);
        let reach = fit.reach_m.expect("the foot's toe tip");
        assert!(
            reach < 0.01,
            "the toe tip is {:.1} mm from the yarn",
            reach * 1e3
        );
        assert!(!Scratch::new().0.exists());
    }
}
