//! `knitfit bench`: what accuracy costs in time, measured. For each bundled leg, resolution,
//! solver and tolerance, fit the bundled scene and record the wall time, iterations, final
//! residual and largest move, the true maximum penetration, the peak memory, and the accuracy:
//! how far the result is from a reference fit of the same leg and resolution relaxed to a
//! tight tolerance, as the relative L2 difference of the leg's stitch density
//! (`_STITCH_DENSITY`) and the RMS distance between corresponding yarn points.
//!
//! The reference is the multilevel solver at [`REFERENCE_TOLERANCE`]; both solvers reach the
//! same rest state (a test checks it), so it serves both. Cases run one after another in one
//! process; the peak memory of each is the process's peak resident set since the case began
//! (Linux `/proc/self/clear_refs`), `None` where the system does not tell.
//!
//! After the sweep, [`stocking`] times `knitfit fit` end to end, every file written, for a
//! stocking to the toe: bench.md's section "Whole stocking (to the toe)".

pub mod stocking;
mod table;

use std::path::{Path, PathBuf};

use super::{NoProgress, Progress};
use crate::base::GridSize;
use crate::draw::bench_plot::{self, Curve};
use crate::error::Result;
use crate::export;
use crate::fit::{self, FitSettings, SolvedFit};
use crate::knit::TubeBottom;
use crate::limits::{peak_memory, reset_peak_memory};
use crate::plan::Plan;
use crate::report::StageClock;
use crate::scene::{LoadedScene, Scene, BUNDLED_SCENE_DIR, BUNDLED_SCENE_NAME};
use crate::sim::SolverMethod;
use crate::stage::Stage;
use stocking::StockingRow;
use table::{mib, CSV_HEADER};

/// Tolerance of the reference fits: a hundred times tighter than the tightest swept.
pub const REFERENCE_TOLERANCE: f64 = 1e-6;

/// What to sweep.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    /// The short sweep (two small resolutions, one leg, and the whole stocking at 150 around):
    /// under two minutes on two cores.
    pub quick: bool,
    /// Where `bench.md`, `bench.csv` and `bench.png` go.
    pub out_dir: PathBuf,
}

/// One fit of the sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchCase {
    /// Leg file name in `samples/`.
    pub leg: &'static str,
    /// Tube size.
    pub grid: GridSize,
    /// Solver.
    pub solver: SolverMethod,
    /// Convergence tolerance.
    pub tolerance: f64,
}

impl BenchCase {
    /// The leg and grid as two table cells: `makehuman_leg | 50×50`.
    fn leg_and_grid(&self) -> String {
        let leg = self.leg.trim_end_matches(".glb");
        format!("{leg} | {}", self.grid)
    }
}

/// What one case measured.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchRow {
    /// The case.
    pub case: BenchCase,
    /// Seconds of the solve (the fit and the exact contact pass).
    pub seconds: f64,
    /// Steps (paper) or iterations over all levels (multilevel).
    pub iterations: usize,
    /// Final relative residual.
    pub residual: f64,
    /// Final largest move per step over the shortest rest length.
    pub max_move: f64,
    /// Whether it converged within `solver.max_steps`.
    pub converged: bool,
    /// Deepest yarn point inside the leg, metres.
    pub max_penetration_m: f64,
    /// Peak resident memory during the case, bytes.
    pub peak_memory_bytes: Option<u64>,
    /// ‖density − reference‖₂ / ‖reference‖₂ over the leg's vertices (`None` without a
    /// reference).
    pub density_error: Option<f64>,
    /// RMS distance to the reference's yarn points, metres.
    pub rms_distance_m: Option<f64>,
}

/// A case that was not run, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct SkippedCase {
    /// The case.
    pub case: BenchCase,
    /// Why it was not run.
    pub why: String,
}

/// The sweep's results and the files that hold them.
#[derive(Debug)]
pub struct BenchOutcome {
    /// Measured cases, in sweep order.
    pub rows: Vec<BenchRow>,
    /// Cases left out.
    pub skipped: Vec<SkippedCase>,
    /// The reference fits, one per leg and grid, in sweep order.
    pub references: Vec<ReferenceRun>,
    /// The whole stockings to the toe, every file written.
    pub stockings: Vec<StockingRow>,
    /// `bench.md` as written.
    pub markdown: String,
    /// Files written.
    pub written: Vec<PathBuf>,
}

/// The sweep `options` ask for: per leg, resolutions × solvers × tolerances, and what is left
/// out (the paper's solver beyond the size where it takes minutes).
pub fn bench_cases(options: &BenchOptions) -> (Vec<BenchCase>, Vec<SkippedCase>) {
    let tolerances = [1e-2, 1e-3, 1e-4];
    let sweeps: &[(&'static str, &[(usize, usize)])] = if options.quick {
        &[("makehuman_leg.glb", &[(50, 50), (100, 100)])]
    } else {
        &[
            (
                "makehuman_leg.glb",
                &[(50, 50), (100, 100), (150, 150), (300, 300), (400, 1600)],
            ),
            ("procedural_leg.glb", &[(50, 50), (150, 150)]),
            // A leg as users export it: with its foot, the stocking placed on its landmarks.
            ("makehuman_leg_foot.glb", &[(50, 50), (150, 150)]),
        ]
    };
    let mut cases = Vec::new();
    let mut skipped = Vec::new();
    for &(leg, sizes) in sweeps {
        for &(wales, courses) in sizes {
            for solver in [SolverMethod::Paper, SolverMethod::Multilevel] {
                for &tolerance in &tolerances {
                    let grid = GridSize::new(wales, courses);
                    let real_count = grid.points() > 300 * 300;
                    let case = BenchCase {
                        leg,
                        grid,
                        solver,
                        tolerance,
                    };
                    if solver == SolverMethod::Paper && real_count {
                        skipped.push(SkippedCase {
                            case,
                            why: "the paper's solver needs hours at this size (its steps grow \
                                  with the square of the resolution); compare at 300×300"
                                .into(),
                        });
                    } else {
                        cases.push(case);
                    }
                }
            }
        }
    }
    (cases, skipped)
}

/// Runs the sweep and the whole stockings, writes `bench.md`, `bench.csv` and `bench.png` into
/// `options.out_dir`.
pub fn run_bench(options: &BenchOptions, progress: &mut dyn Progress) -> Result<BenchOutcome> {
    let files = ["bench.md", "bench.csv", "bench.png"];
    let prepared = export::atomic::prepare_dir(&options.out_dir, &files, &[])?;
    let (cases, skipped) = bench_cases(options);
    let stocking_cases = stocking::stocking_cases(options.quick);
    progress.begin("bench", (cases.len() + stocking_cases.len()) as u64);
    let (rows, references) = sweep(&cases, progress)?;
    let stockings = stocking::measure_stockings(&stocking_cases, progress, cases.len() as u64)?;
    progress.end();
    let mut markdown = markdown(&rows, &skipped, &references, options.quick);
    markdown.push_str(&stocking::markdown(&stockings));
    let png = bench_plot::draw(&curves(&rows), "bench.png")?;
    let csv = csv(&rows) + &stocking::csv_rows(&stockings);
    let written = export::atomic::write_all(
        &options.out_dir,
        &[
            ("bench.md".to_string(), markdown.clone().into_bytes()),
            ("bench.csv".to_string(), csv.into_bytes()),
            ("bench.png".to_string(), png),
        ],
        &[],
    )?;
    prepared.keep();
    Ok(BenchOutcome {
        rows,
        skipped,
        references,
        stockings,
        markdown,
        written,
    })
}

/// Fits every case and its leg and grid's reference; advances `progress` once per case.
fn sweep(
    cases: &[BenchCase],
    progress: &mut dyn Progress,
) -> Result<(Vec<BenchRow>, Vec<ReferenceRun>)> {
    let base = Scene::load(None)?;
    let mut rows = Vec::new();
    let mut reference: Option<(BenchCase, Reference)> = None;
    let mut references = Vec::new();
    for (n, case) in cases.iter().enumerate() {
        let same_grid = |r: &BenchCase| (r.leg, r.grid) == (case.leg, case.grid);
        if !reference.as_ref().is_some_and(|(r, _)| same_grid(r)) {
            let ref_case = BenchCase {
                solver: SolverMethod::Multilevel,
                tolerance: REFERENCE_TOLERANCE,
                ..case.clone()
            };
            let (fit, seconds, _) = fit_case(&base, &ref_case)?;
            references.push(ReferenceRun {
                case: ref_case.clone(),
                seconds,
                iterations: fit.solver.steps(),
                residual: fit.solver.residual(),
                converged: fit.solver.converged(),
            });
            reference = Some((ref_case, Reference::of(&fit, &base)));
        }
        let (fit, seconds, peak_memory_bytes) = fit_case(&base, case)?;
        let (density_error, rms_distance_m) = match &reference {
            Some((r, reference)) if same_grid(r) => {
                let (d, x) = reference.compare(&fit, &base);
                (Some(d), Some(x))
            }
            _ => (None, None),
        };
        rows.push(BenchRow {
            case: case.clone(),
            seconds,
            iterations: fit.solver.steps(),
            residual: fit.solver.residual(),
            max_move: fit.solver.max_move(),
            converged: fit.solver.converged(),
            max_penetration_m: fit.max_penetration_m,
            peak_memory_bytes,
            density_error,
            rms_distance_m,
        });
        progress.advance(n as u64 + 1, fit.solver.residual());
    }
    Ok((rows, references))
}

/// Fits one case with the bundled scene; returns the fit, the solve's seconds and the peak
/// memory.
fn fit_case(base: &Scene, case: &BenchCase) -> Result<(SolvedFit, f64, Option<u64>)> {
    let mut scene = base.clone();
    scene.tube.wales = case.grid.wales;
    scene.tube.courses = Some(case.grid.courses);
    // The sweep compares solvers on the open tube, on every leg alike (the whole stocking has
    // its own section).
    scene.tube.bottom = Some(TubeBottom::Ankle);
    scene.solver.method = case.solver;
    scene.solver.tolerance = case.tolerance;
    let plan = Plan::fit(&scene);
    let loaded = LoadedScene {
        scene,
        name: BUNDLED_SCENE_NAME.into(),
        path: None,
        overrides: Vec::new(),
    };
    // The solve alone: the fields are measured after the case's peak memory is read.
    let settings = FitSettings {
        measure: false,
        products: None,
        ..plan.fit_settings(&loaded)
    };
    reset_peak_memory();
    let mut clock = StageClock::new(&plan);
    let leg = Path::new(BUNDLED_SCENE_DIR).join(case.leg);
    let (leg, _) = fit::load(&leg, &settings, &mut clock)?;
    let fitted =
        fit::fit(leg, &settings, &mut clock, &mut NoProgress).map_err(|e| loaded.named(e))?;
    let seconds = clock.seconds_in(&[Stage::Fit, Stage::ExactContactPass]);
    Ok((fitted.solved, seconds, peak_memory()))
}

/// How a reference fit went: a case measured against a reference that did not converge is
/// measured against an approximation, and `bench.md` says so.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceRun {
    /// The reference's leg, grid and tolerance ([`REFERENCE_TOLERANCE`], multilevel).
    pub case: BenchCase,
    /// Seconds of its solve.
    pub seconds: f64,
    /// Iterations over all levels.
    pub iterations: usize,
    /// Final relative residual.
    pub residual: f64,
    /// Whether it reached [`REFERENCE_TOLERANCE`] within `solver.max_steps`.
    pub converged: bool,
}

/// What a case is compared with.
struct Reference {
    density: Vec<f64>,
    positions: Vec<crate::base::Vec3>,
}

impl Reference {
    fn of(fit: &SolvedFit, scene: &Scene) -> Reference {
        Reference {
            density: leg_density(fit, scene),
            positions: fit.knit.particles.x.clone(),
        }
    }

    /// Relative L2 density difference and RMS point distance of `fit` from this reference.
    fn compare(&self, fit: &SolvedFit, scene: &Scene) -> (f64, f64) {
        let density = leg_density(fit, scene);
        let (mut diff_sq, mut ref_sq) = (0.0, 0.0);
        for (d, r) in density.iter().zip(&self.density) {
            diff_sq += (d - r) * (d - r);
            ref_sq += r * r;
        }
        let density_error = if ref_sq > 0.0 {
            (diff_sq / ref_sq).sqrt()
        } else {
            0.0
        };
        let x = &fit.knit.particles.x;
        let sum_sq: f64 = x
            .iter()
            .zip(&self.positions)
            .map(|(a, b)| (a - b).norm_squared())
            .sum();
        (density_error, (sum_sq / x.len().max(1) as f64).sqrt())
    }
}

/// The stitch density on the leg's vertices, stitches per cm².
fn leg_density(fit: &SolvedFit, scene: &Scene) -> Vec<f64> {
    let terms = Plan::fit(scene).forces;
    fit::measure::fields(fit, &scene.fabric(), &terms)
        .on_leg
        .stitch_density
}

/// One curve per leg, solver and resolution: error against time over the tolerances.
fn curves(rows: &[BenchRow]) -> Vec<Curve> {
    let mut curves: Vec<Curve> = Vec::new();
    for row in rows {
        let c = &row.case;
        let label = format!(
            "{} {}x{} {}",
            c.solver.name(),
            c.grid.wales,
            c.grid.courses,
            c.leg.trim_end_matches(".glb").trim_end_matches("_leg")
        );
        let Some(error) = row.density_error else {
            continue;
        };
        let point = (row.seconds, error);
        match curves.iter_mut().find(|k| k.label == label) {
            Some(k) => k.points.push(point),
            None => curves.push(Curve {
                label,
                paper: c.solver == SolverMethod::Paper,
                points: vec![point],
            }),
        }
    }
    curves
}

/// The machine the bench ran on, in words.
pub fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|info| {
            info.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    format!(
        "{cpu}, {} threads (rayon), {} build",
        rayon::current_num_threads(),
        if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        }
    )
}

/// `bench.md`: the table, what was left out, and how to read it.
fn markdown(
    rows: &[BenchRow],
    skipped: &[SkippedCase],
    references: &[ReferenceRun],
    quick: bool,
) -> String {
    let mut md = String::new();
    md.push_str(&format!(
        "# knitfit bench{}\n\nMachine: {}. Scene: the bundled one; reference per leg and \
         resolution: multilevel at tolerance {REFERENCE_TOLERANCE:.0e}. Time: the solve (fit and \
         exact contact pass). Density error: ‖ρ − ρ_ref‖₂ / ‖ρ_ref‖₂ over the leg's vertices; \
         distance: RMS over yarn points.\n\n",
        if quick { " --quick" } else { "" },
        machine()
    ));
    md.push_str(
        "| leg | grid | points | solver | tol | time s | iterations | residual | max move | \
         converged | max penetration mm | peak MiB | density error | RMS distance mm |\n",
    );
    md.push_str("|---|---|---:|---|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|\n");
    for r in rows {
        let c = &r.case;
        md.push_str(&format!(
            "| {} | {} | {} | {:.0e} | {:.2} | {} | {:.1e} | {:.1e} | {} | {:.4} | {} | \
             {} | {} |\n",
            c.leg_and_grid(),
            c.grid.points(),
            c.solver.name(),
            c.tolerance,
            r.seconds,
            r.iterations,
            r.residual,
            r.max_move,
            if r.converged { "yes" } else { "no" },
            r.max_penetration_m * 1000.0,
            mib(r.peak_memory_bytes),
            r.density_error.map_or("n/a".into(), |e| format!("{e:.2e}")),
            r.rms_distance_m
                .map_or("n/a".into(), |d| format!("{:.4}", d * 1000.0)),
        ));
    }
    let speedups = speedups(rows);
    if !speedups.is_empty() {
        md.push_str("\nSpeed-up of multilevel over paper at the same leg, grid and tolerance:\n\n");
        md.push_str("| leg | grid | tol | paper s | multilevel s | ratio |\n");
        md.push_str("|---|---|---:|---:|---:|---:|\n");
        for (c, paper, fast) in speedups {
            md.push_str(&format!(
                "| {} | {:.0e} | {:.2} | {:.2} | {:.0}× |\n",
                c.leg_and_grid(),
                c.tolerance,
                paper,
                fast,
                paper / fast.max(1e-9)
            ));
        }
    }
    let matched = same_accuracy(rows);
    if !matched.is_empty() {
        md.push_str(
            "\nAt the same accuracy: for each paper run, the fastest multilevel run on the same leg \
             and grid whose density error is no larger:\n\n",
        );
        md.push_str("| leg | grid | paper tol | paper s | density error | multilevel tol | multilevel s | density error | ratio |\n");
        md.push_str("|---|---|---:|---:|---:|---:|---:|---:|---:|\n");
        for (paper, fast) in matched {
            let c = &paper.case;
            md.push_str(&format!(
                "| {} | {:.0e} | {:.2} | {:.2e} | {:.0e} | {:.2} | {:.2e} | {:.0}× |\n",
                c.leg_and_grid(),
                c.tolerance,
                paper.seconds,
                paper.density_error.unwrap_or(f64::NAN),
                fast.case.tolerance,
                fast.seconds,
                fast.density_error.unwrap_or(f64::NAN),
                paper.seconds / fast.seconds.max(1e-9)
            ));
        }
    }
    if !references.is_empty() {
        md.push_str("\nThe references (multilevel at ");
        md.push_str(&format!("{REFERENCE_TOLERANCE:.0e}):\n\n"));
        md.push_str("| leg | grid | time s | iterations | residual | converged |\n");
        md.push_str("|---|---|---:|---:|---:|---|\n");
        for r in references {
            let c = &r.case;
            md.push_str(&format!(
                "| {} | {:.2} | {} | {:.1e} | {} |\n",
                c.leg_and_grid(),
                r.seconds,
                r.iterations,
                r.residual,
                if r.converged { "yes" } else { "no" },
            ));
        }
    }
    if !skipped.is_empty() {
        md.push_str("\nNot run:\n\n");
        for s in skipped {
            let c = &s.case;
            md.push_str(&format!(
                "- {} {}×{} {} tol {:.0e}: {}\n",
                c.leg.trim_end_matches(".glb"),
                c.grid.wales,
                c.grid.courses,
                c.solver.name(),
                c.tolerance,
                s.why
            ));
        }
    }
    md
}

/// Pairs of (paper, multilevel) seconds for the same leg, grid and tolerance.
fn speedups(rows: &[BenchRow]) -> Vec<(BenchCase, f64, f64)> {
    rows.iter()
        .filter(|r| r.case.solver == SolverMethod::Paper)
        .filter_map(|paper| {
            rows.iter()
                .find(|r| {
                    r.case
                        == BenchCase {
                            solver: SolverMethod::Multilevel,
                            ..paper.case.clone()
                        }
                })
                .map(|fast| (paper.case.clone(), paper.seconds, fast.seconds))
        })
        .collect()
}

/// For each paper row, the fastest multilevel row of the same leg and grid that is at least as
/// accurate (density error no larger), if any.
fn same_accuracy(rows: &[BenchRow]) -> Vec<(&BenchRow, &BenchRow)> {
    rows.iter()
        .filter(|r| r.case.solver == SolverMethod::Paper)
        .filter_map(|paper| {
            rows.iter()
                .filter(|r| {
                    r.case.solver == SolverMethod::Multilevel
                        && (r.case.leg, r.case.grid) == (paper.case.leg, paper.case.grid)
                        && r.density_error
                            .zip(paper.density_error)
                            .is_some_and(|(a, b)| a <= b)
                })
                .min_by(|a, b| a.seconds.total_cmp(&b.seconds))
                .map(|fast| (paper, fast))
        })
        .collect()
}

/// `bench.csv`'s header and the sweep's lines, one per case, SI units.
fn csv(rows: &[BenchRow]) -> String {
    let mut out = String::from(CSV_HEADER);
    for r in rows {
        let c = &r.case;
        out.push_str(&format!(
            "{},{},{},{},{},{:e},{:.6},{},{:e},{:e},{},{:e},{},{},{},{},,,\n",
            c.leg,
            c.grid.wales,
            c.grid.courses,
            c.grid.points(),
            c.solver.name(),
            c.tolerance,
            r.seconds,
            r.iterations,
            r.residual,
            r.max_move,
            r.converged,
            r.max_penetration_m,
            r.peak_memory_bytes.map_or(String::new(), |b| b.to_string()),
            r.density_error.map_or(String::new(), |e| format!("{e:e}")),
            r.rms_distance_m.map_or(String::new(), |d| format!("{d:e}")),
            TubeBottom::Ankle.name(),
        ));
    }
    out
}
