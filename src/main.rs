//! The `knitfit` command line: parse → the scene with the flags applied → run → summary → exit
//! code. The only place that prints to the user or picks an exit code.

/// `println!` that ends quietly when stdout is closed (`knitfit plan --json | head`) instead of
/// panicking: nothing is left to print to.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// `print!` as [`say!`] for text that ends in its own newline.
macro_rules! say_text {
    ($text:expr) => {{
        use std::io::Write as _;
        let _ = std::io::stdout().write_all($text.as_bytes());
    }};
}

mod cli;

use std::process::ExitCode;

use clap::Parser;

use cli::{
    print_written, Bar, BenchArgs, Cli, Command, FitArgs, PatchArgs, PlanArgs, PlanOf, RenderArgs,
};
use knitfit::export::YarnsWritten;
use knitfit::report::{stocking_extent, SolverDetails};
use knitfit::run::{
    plan_fit, plan_patch, run_bench, run_fit, run_patch, run_render, run_spp_sweep, BenchOptions,
};
use knitfit::scene::Scene;
use knitfit::sim::SolverMethod;
use knitfit::Error;

/// Exit code of a run that finished but did not converge (its files are written and its report
/// says so).
const EXIT_NOT_CONVERGED: u8 = 3;
/// Exit code of a fit that converged but failed a check of a finished fit (yarn left through
/// the skin, density jumping between neighbours): its files are written, its report's
/// `details.checks` says which.
const EXIT_FAILED_CHECKS: u8 = 4;

fn main() -> ExitCode {
    let cli = Cli::parse();
    let quiet = cli.quiet;
    let result = match cli.command {
        Some(Command::Fit(args)) => fit(*args, quiet),
        Some(Command::Patch(args)) => patch(args, quiet),
        Some(Command::Bench(args)) => bench(args, quiet),
        Some(Command::Render(args)) => render(args, quiet),
        Some(Command::Plan(args)) => plan(*args),
        None => fit(FitArgs::default(), quiet),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("knitfit: error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}

fn fit(args: FitArgs, quiet: bool) -> Result<ExitCode, Error> {
    let loaded = args.load()?;
    let outcome = run_fit(&loaded, &args.out_dir(), &mut Bar::new(quiet))?;
    let (scene, report) = (&loaded.scene, &outcome.report);
    let m = &report.metrics;
    if !quiet {
        say!(
            "fit {}x{} on {} ({} triangles): {} steps, residual {:.2e}, max penetration {:.4} mm, \
             {} in {:.2} s",
            report.details.tube.wales,
            report.details.tube.courses,
            loaded.leg_path().display(),
            m.leg_triangles.unwrap_or(0),
            m.steps,
            m.residual,
            m.max_penetration_m.unwrap_or(0.0) * 1000.0,
            converged_word(m.converged),
            report.wall_seconds
        );
        let d = &report.details;
        say!(
            "stocking: {}",
            stocking_extent(
                &d.axis,
                d.leg.landmarks.as_ref(),
                (d.tube.bottom == knitfit::knit::TubeBottom::Toe).then_some(d.tube.centreline_m)
            )
        );
        let k = &d.knit;
        let on_leg = match d.stitch_density_per_cm2.leg_vertices_covered {
            0 => String::new(),
            _ => format!(
                "; on the leg {:.0}–{:.0} stitches/cm², coverage {:.2}–{:.2}, pressure up to {:.1} \
                 mmHg",
                d.stitch_density_per_cm2.min,
                d.stitch_density_per_cm2.max,
                d.coverage.min,
                d.coverage.max,
                d.pressure_mmhg.max
            ),
        };
        let toe_tip = match d.tube.toe_tip_wale_spacing_m {
            Some(rest) => format!(" ({:.1} along over the toe's tip)", rest / k.stitch_m.wale),
            None => String::new(),
        };
        say!(
            "knit: {:.0} needles × {:.0} courses of {}/{} den yarn, each grid cell {:.1} × {:.1} \
             stitches{toe_tip}{on_leg}",
            k.needles,
            k.courses,
            scene.yarns.nylon.denier,
            scene.yarns.support.denier,
            k.stitches_per_cell.course,
            k.stitches_per_cell.wale
        );
        if let Some(real) = &d.yarns.real_stitches {
            let (w, c) = (real.wales, real.courses);
            let written = match d.yarns.written {
                YarnsWritten::Loops => format!("every real stitch as a loop, {w} × {c}"),
                YarnsWritten::Stitches => format!("every real stitch's crossings, {w} × {c}"),
                // The real stitches were laid for the preview only.
                YarnsWritten::Grid => {
                    format!("the fitted grid's (the preview draws every real stitch, {w} × {c})")
                }
            };
            say!(
                "yarns: {written}: {} points, {} segments",
                d.yarns.points,
                d.yarns.segments
            );
        }
        print_written(&args.out_dir(), &outcome.written);
        print_next(&args.out_dir(), &outcome.written);
    }
    // Damping shapes only the paper solver's steps; the multilevel solver has none to tune.
    let advice = match scene.solver.method {
        SolverMethod::Multilevel => {
            "raise solver.max_steps, or loosen solver.tolerance (--tolerance)"
        }
        SolverMethod::Paper => {
            "raise solver.max_steps, or solver.damping if the residual oscillates"
        }
    };
    // The multilevel solver says where the grid had not settled.
    let hint = match &report.details.solver {
        SolverDetails::Multilevel {
            unsettled_at: Some(place),
            ..
        } => format!("{place}; {advice}"),
        _ => advice.to_string(),
    };
    // The pose's relaxation is said where the rest pose's fit settled: else that is the news.
    let rest_unsettled = matches!(
        &report.details.solver,
        SolverDetails::Multilevel {
            unsettled_at: Some(_),
            ..
        }
    );
    let pose_unsettled = report.details.pose.as_ref().filter(|p| !p.converged);
    if let Some(pose) = pose_unsettled.filter(|_| !rest_unsettled) {
        eprintln!(
            "knitfit: warning: the stocking, fitted in the leg's rest pose ({}), had not \
             settled in the pose the file shows after {} iterations (residual {:.1e}, force step {:.1e}, \
             tolerance {:.0e}): \
             the pose folds or stretches the leg further than the carried stocking settles in; \
             its files are written (report.json details.pose)",
            match pose.bend {
                Some(_) => "straightened at the joints its sections show",
                None => "its rig's",
            },
            pose.iterations,
            pose.residual,
            pose.force_step,
            scene.solver.tolerance
        );
        return Ok(ExitCode::from(EXIT_NOT_CONVERGED));
    }
    let failures = report.details.checks.failures();
    if m.converged && !failures.is_empty() {
        eprintln!(
            "knitfit: warning: the fit converged but is not sound: {}; its files are written to \
             show where (report.json details.checks)",
            failures.join("; ")
        );
        return Ok(ExitCode::from(EXIT_FAILED_CHECKS));
    }
    Ok(finish(m.converged, scene, &hint))
}

/// What to open next, from what a fit wrote.
fn print_next(out: &std::path::Path, written: &[std::path::PathBuf]) {
    let wrote = |name: &str| written.iter().any(|p| p.ends_with(name));
    let out = out.display();
    if wrote("stocking.glb") {
        say!(
            "next: open {out}/stocking.glb in Blender (File > Import > glTF 2.0) or any glTF \
             viewer: the leg and the sheer stocking over it (the yarn lines are its second \
             scene, \"knitfit yarns\")"
        );
    }
    if wrote("preview.png") {
        say!("      {out}/preview.png is the yarn-level still");
    } else if wrote("stocking.glb") {
        say!("      knitfit render {out} draws the yarn-level still (preview.png) from it");
    }
}

fn patch(args: PatchArgs, quiet: bool) -> Result<ExitCode, Error> {
    let loaded = args.load()?;
    let outcome = run_patch(&loaded, &args.out_dir(), &mut Bar::new(quiet))?;
    let (scene, report) = (&loaded.scene, &outcome.report);
    let m = &report.metrics;
    if !quiet {
        say!(
            "patch {}x{}: {} relaxation(s), {} steps, residual {:.2e}, {} in {:.2} s",
            scene.patch.size.wales,
            scene.patch.size.courses,
            report.details.patches.len(),
            m.steps,
            m.residual,
            converged_word(m.converged),
            report.wall_seconds
        );
        print_written(&args.out_dir(), &outcome.written);
    }
    // A patch squeezed in its plane has no stable flat rest state: the square spring grid has no
    // shear stiffness, so it buckles instead of settling.
    let hint = if scene.patch.stretch.iter().any(|s| s.factor < 1.0) {
        "a patch compressed below its rest size (stretch < 1) buckles and has no flat rest state"
    } else {
        "raise solver.max_steps, or solver.damping if the residual oscillates"
    };
    Ok(finish(m.converged, scene, hint))
}

/// Prints the plan of a fit or patch; runs nothing.
fn plan(args: PlanArgs) -> Result<ExitCode, Error> {
    if args.of.is_some() && args.fit.given() {
        return Err(Error::InvalidArgument {
            flag: "plan".into(),
            message: "a scene or option before `fit` or `patch` would be ignored; put it after \
                      the subcommand"
                .into(),
        });
    }
    let outcome = match &args.of {
        Some(PlanOf::Patch(patch)) => plan_patch(&patch.load()?, &patch.out_dir()),
        Some(PlanOf::Fit(fit)) => plan_fit(&fit.load()?, &fit.out_dir())?,
        None => plan_fit(&args.fit.load()?, &args.fit.out_dir())?,
    };
    if args.json {
        say!("{:#}", outcome.to_json());
    } else {
        say_text!(outcome.to_text());
    }
    Ok(ExitCode::SUCCESS)
}

fn bench(args: BenchArgs, quiet: bool) -> Result<ExitCode, Error> {
    let options = BenchOptions {
        quick: args.quick,
        out_dir: args.out.clone(),
    };
    let outcome = run_bench(&options, &mut Bar::new(quiet))?;
    if !quiet {
        say_text!(outcome.markdown);
        print_written(&args.out, &outcome.written);
    }
    Ok(ExitCode::SUCCESS)
}

fn render(args: RenderArgs, quiet: bool) -> Result<ExitCode, Error> {
    let loaded = args.load()?;
    let r = &loaded.scene.render;
    if args.spp_sweep {
        let sweep = run_spp_sweep(&loaded.scene, &args.input)?;
        say!(
            "{}×{} {} mode; scene prepared in {:.2} s; reference {} spp in {:.2} s; error over {} \
             leg pixels, RMS in 8-bit sRGB levels",
            r.width,
            r.height,
            r.mode.name(),
            sweep.prepare_seconds,
            sweep.reference_spp,
            sweep.reference_seconds,
            sweep.leg_pixels
        );
        say!(
            "| spp | seconds | RMS error vs {} spp |",
            sweep.reference_spp
        );
        say!("|---|---|---|");
        for row in &sweep.rows {
            say!(
                "| {} | {:.2} | {:.2} |",
                row.spp,
                row.seconds,
                row.rms_error
            );
        }
        return Ok(ExitCode::SUCCESS);
    }
    let outcome = run_render(&loaded, &args.input, args.out.as_deref())?;
    if !quiet {
        say!(
            "rendered {}×{} at {} spp ({} mode) in {:.2} s",
            r.width,
            r.height,
            outcome.report.details.render.spp,
            r.mode.name(),
            outcome.report.wall_seconds
        );
        for path in &outcome.written {
            say!("  {}", path.display());
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn converged_word(converged: bool) -> &'static str {
    if converged {
        "converged"
    } else {
        "NOT converged"
    }
}

/// Exit code for a finished run; warns when it did not converge.
fn finish(converged: bool, scene: &Scene, hint: &str) -> ExitCode {
    if converged {
        return ExitCode::SUCCESS;
    }
    eprintln!(
        "knitfit: warning: did not converge within solver.max_steps = {} (tolerance {:.0e}); \
         {hint}",
        scene.solver.max_steps, scene.solver.tolerance
    );
    ExitCode::from(EXIT_NOT_CONVERGED)
}
