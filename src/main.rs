//! The `knitfit` command line: parse → validated scene → run → exit code. The only place that
//! prints to the user or picks an exit code.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use knitfit::leg::AxisSource;
use knitfit::run::fit::scene_dir;
use knitfit::run::{
    plan_fit, plan_patch, run_bench, run_fit, run_patch, run_render, run_spp_sweep, BenchOptions,
    FitInputs, PlanOutcome, Progress, RenderInputs, RunPaths,
};
use knitfit::scene::{
    check_axis, check_memory_limit, check_patch_points, check_render_budget, check_render_side,
    check_spp, check_stretch_factor, check_tolerance, check_tube_points, ContactMethod, LegAxis,
    RenderMode, SolverMethod, Stretch, StretchAxis, View,
};
use knitfit::{Error, Scene};

/// Exit code of a run that finished but did not converge (its files are written and its report
/// says so).
const EXIT_NOT_CONVERGED: u8 = 3;

/// Fits a knitted stocking onto a 3D leg (Sakaguchi & Miyata) and writes files artists' tools
/// read. With no subcommand, fits the bundled sample scene into `out/`.
#[derive(Parser, Debug)]
#[command(name = "knitfit", version, about, long_about = None)]
#[command(
    after_help = "Exit codes: 0 done, 1 run failed, 2 bad input, 3 did not converge \
                        (files written, report.json says \"converged\": false)."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// No progress bar and no summary.
    #[arg(short, long, global = true)]
    quiet: bool,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Fit the stocking onto a leg from a glTF file; write stocking.glb, stocking.ply, leg.ply.
    Fit(FitArgs),
    /// The paper's flat-patch experiment: hold two edges of a knit patch, pull them apart, relax.
    Patch(PatchArgs),
    /// What accuracy costs in time: sweep resolution × solver × tolerance on the bundled legs;
    /// write bench.md, bench.csv and bench.png.
    Bench(BenchArgs),
    /// Ray-trace the yarn-level preview of a fit from its stocking.glb (or its directory).
    Render(RenderArgs),
    /// Show what a fit (default) or `plan patch` would run: effects, stages and why each is
    /// there, what is left out, the files, and the fit's memory estimate. Runs nothing and
    /// writes nothing.
    Plan(Box<PlanArgs>),
}

#[derive(clap::Args, Debug)]
struct PlanArgs {
    #[command(subcommand)]
    of: Option<PlanOf>,
    /// The fit to plan, as `knitfit fit` takes it.
    #[command(flatten)]
    fit: FitArgs,
    /// Print the plan as JSON (for scripts).
    #[arg(long, global = true)]
    json: bool,
}

#[derive(Subcommand, Debug)]
enum PlanOf {
    /// The plan of `knitfit fit` (what `knitfit plan` shows without a subcommand).
    Fit(FitArgs),
    /// The plan of `knitfit patch`.
    Patch(PatchArgs),
}

#[derive(clap::Args, Debug, Default)]
struct BenchArgs {
    /// The short sweep (50×50 and 100×100 on the MakeHuman leg): under two minutes.
    #[arg(long)]
    quick: bool,
    /// Output directory (created if missing).
    #[arg(long, default_value = "out/bench")]
    out: PathBuf,
}

#[derive(clap::Args, Debug, Default)]
struct RenderArgs {
    /// A fit's output directory or its stocking.glb.
    input: PathBuf,
    /// Scene file (JSON) for yarn radii, colours and render settings. Default: the bundled
    /// samples/scene.json.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Image width, pixels. Overrides render.width.
    #[arg(long)]
    width: Option<u32>,
    /// Image height, pixels. Overrides render.height.
    #[arg(long)]
    height: Option<u32>,
    /// Camera side: front, side, back or three-quarter. Overrides render.view.
    #[arg(long, value_name = "VIEW")]
    view: Option<String>,
    /// Samples per pixel (stratified). Overrides render.spp.
    #[arg(long)]
    spp: Option<u32>,
    /// yarn (the shaded yarns) or density (stitch density with a colour bar). Overrides
    /// render.mode.
    #[arg(long, value_name = "yarn|density")]
    mode: Option<String>,
    /// Picture to write (.png). Default: preview.png next to the input.
    #[arg(long, value_name = "FILE.png")]
    out: Option<PathBuf>,
    /// Instead of writing a picture, print time and error against a 64-spp reference for 1, 4
    /// and 16 samples per pixel.
    #[arg(long)]
    spp_sweep: bool,
}

#[derive(clap::Args, Debug, Default)]
struct FitArgs {
    /// Scene file (JSON). Default: the bundled samples/scene.json.
    scene: Option<PathBuf>,
    /// Leg file (.glb or .gltf). Overrides leg.file.
    #[arg(long)]
    leg: Option<PathBuf>,
    /// Tube size, WALESxCOURSES (e.g. 150x150). Overrides tube.wales and tube.courses.
    #[arg(long, value_name = "WxC")]
    resolution: Option<String>,
    /// Bottom and top of the stocking on the leg's axis, in the leg file's coordinates:
    /// BX,BY,BZ,TX,TY,TZ. Overrides leg.axis.
    #[arg(long, value_name = "BX,BY,BZ,TX,TY,TZ", allow_hyphen_values = true)]
    axis: Option<String>,
    /// Contact queries: bvh (fast) or brute (the paper's all-triangles test). Overrides
    /// contact.method.
    #[arg(long, value_name = "bvh|brute")]
    contact: Option<String>,
    /// Solver: multilevel (fast, the default) or paper (the paper's explicit steps, the
    /// reference). Overrides solver.method.
    #[arg(long, value_name = "multilevel|paper")]
    solver: Option<String>,
    /// Convergence tolerance on the relative residual and the largest move. Overrides
    /// solver.tolerance.
    #[arg(long, value_name = "TOL")]
    tolerance: Option<f64>,
    /// Memory the fit may use, GiB; a fit estimated to need more is refused before it starts.
    /// Overrides limits.memory_gib (default: what the system has available).
    #[arg(long, value_name = "GIB")]
    memory_limit: Option<f64>,
    /// Run even when the memory estimate is over the limit. Sets limits.allow_large.
    #[arg(long)]
    allow_large: bool,
    /// Output directory (created if missing).
    #[arg(long, default_value = "out")]
    out: PathBuf,
}

impl FitArgs {
    /// True when a scene or any option other than `--out` was given (every field is named, so
    /// a new option cannot be forgotten here).
    fn given(&self) -> bool {
        let FitArgs {
            scene,
            leg,
            resolution,
            axis,
            contact,
            solver,
            tolerance,
            memory_limit,
            allow_large,
            out: _,
        } = self;
        scene.is_some()
            || leg.is_some()
            || resolution.is_some()
            || axis.is_some()
            || contact.is_some()
            || solver.is_some()
            || tolerance.is_some()
            || memory_limit.is_some()
            || *allow_large
    }
}

#[derive(clap::Args, Debug, Default)]
struct PatchArgs {
    /// Scene file (JSON). Default: the bundled samples/scene.json.
    scene: Option<PathBuf>,
    /// Patch size in points, WALESxCOURSES (e.g. 10x10). Overrides patch.size.
    #[arg(long, value_name = "WxH")]
    size: Option<String>,
    /// A stretch to run, course=S or wale=S (S = held-edge distance / rest distance). Repeat for
    /// both directions side by side. Overrides patch.stretch.
    #[arg(long, value_name = "AXIS=S")]
    stretch: Vec<String>,
    /// Output directory (created if missing).
    #[arg(long, default_value = "out")]
    out: PathBuf,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let quiet = cli.quiet;
    let result = match cli.command {
        Some(Command::Patch(args)) => patch(args, quiet),
        Some(Command::Fit(args)) => fit(args, quiet),
        Some(Command::Bench(args)) => bench(args, quiet),
        Some(Command::Render(args)) => render(args, quiet),
        Some(Command::Plan(args)) => plan(*args),
        None => fit(
            FitArgs {
                out: PathBuf::from("out"),
                ..FitArgs::default()
            },
            quiet,
        ),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("knitfit: error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}

fn patch(args: PatchArgs, quiet: bool) -> Result<ExitCode, Error> {
    let (scene, paths) = patch_request(&args)?;
    let mut bar = Bar::new(quiet);
    let outcome = run_patch(&scene, &paths, &mut bar)?;
    let m = &outcome.report.metrics;
    if !quiet {
        println!(
            "patch {}x{}: {} relaxation(s), {} steps, residual {:.2e}, {} in {:.2} s",
            scene.patch.size[0],
            scene.patch.size[1],
            scene.patch.stretch.len(),
            m.steps,
            m.residual,
            if m.converged {
                "converged"
            } else {
                "NOT converged"
            },
            outcome.report.wall_seconds
        );
        print_written(&args.out, &outcome.written);
    }
    // A patch squeezed in its plane has no stable flat rest state: the square spring grid has no
    // shear stiffness, so it buckles instead of settling.
    let hint = if scene.patch.stretch.iter().any(|s| s.factor < 1.0) {
        "a patch compressed below its rest size (stretch < 1) buckles and has no flat rest state"
    } else {
        "raise solver.max_steps, or solver.damping if the residual oscillates"
    };
    Ok(finish(m.converged, &scene, hint))
}

/// The scene of a patch, its flags applied, and where it reads and writes.
fn patch_request(args: &PatchArgs) -> Result<(Scene, RunPaths), Error> {
    let mut scene = Scene::load(args.scene.as_deref())?;
    if let Some(size) = &args.size {
        scene.patch.size = parse_size(size)?;
    }
    if !args.stretch.is_empty() {
        scene.patch.stretch = args
            .stretch
            .iter()
            .map(|s| parse_stretch(s))
            .collect::<Result<_, _>>()?;
    }
    let paths = RunPaths {
        scene_name: scene_name(&args.scene),
        inputs: args.scene.iter().cloned().collect(),
        out_dir: args.out.clone(),
    };
    Ok((scene, paths))
}

fn fit(args: FitArgs, quiet: bool) -> Result<ExitCode, Error> {
    let (scene, inputs, paths) = fit_request(&args)?;
    let mut bar = Bar::new(quiet);
    let outcome = run_fit(&scene, &inputs, &paths, &mut bar)?;
    let m = &outcome.report.metrics;
    if !quiet {
        println!(
            "fit {}x{} on {} ({} triangles): {} steps, residual {:.2e}, max penetration {:.4} mm, \
             {} in {:.2} s",
            scene.tube.wales,
            scene.tube.courses,
            inputs.leg.display(),
            m.leg_triangles.unwrap_or(0),
            m.steps,
            m.residual,
            m.max_penetration_m.unwrap_or(0.0) * 1000.0,
            if m.converged {
                "converged"
            } else {
                "NOT converged"
            },
            outcome.report.wall_seconds
        );
        print_written(&args.out, &outcome.written);
    }
    Ok(finish(
        m.converged,
        &scene,
        "raise solver.max_steps, or solver.damping if the residual oscillates",
    ))
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
    let outcome: PlanOutcome = match &args.of {
        Some(PlanOf::Patch(patch)) => {
            let (scene, paths) = patch_request(patch)?;
            plan_patch(&scene, &paths)
        }
        Some(PlanOf::Fit(fit)) => {
            let (scene, inputs, paths) = fit_request(fit)?;
            plan_fit(&scene, &inputs, &paths)?
        }
        None => {
            let (scene, inputs, paths) = fit_request(&args.fit)?;
            plan_fit(&scene, &inputs, &paths)?
        }
    };
    if args.json {
        println!("{:#}", outcome.to_json());
    } else {
        print!("{}", outcome.to_text());
    }
    Ok(ExitCode::SUCCESS)
}

/// The scene of a fit, its flags applied, its leg, and where it reads and writes.
fn fit_request(args: &FitArgs) -> Result<(Scene, FitInputs, RunPaths), Error> {
    let mut scene = Scene::load(args.scene.as_deref())?;
    if let Some(text) = &args.resolution {
        let [w, c] = parse_grid("--resolution", text, 3, 2)?;
        check_tube_points(w, c).map_err(|message| Error::InvalidArgument {
            flag: "--resolution".into(),
            message,
        })?;
        scene.tube.wales = w;
        scene.tube.courses = c;
    }
    let mut axis_source = AxisSource::Scene;
    if let Some(text) = &args.axis {
        scene.leg.axis = Some(parse_axis(text)?);
        axis_source = AxisSource::CommandLine;
    }
    if let Some(method) = &args.contact {
        scene.contact.method = match method.as_str() {
            "bvh" => ContactMethod::Bvh,
            "brute" => ContactMethod::Brute,
            other => {
                return Err(Error::InvalidArgument {
                    flag: "--contact".into(),
                    message: format!("must be bvh or brute, got {other:?}"),
                })
            }
        };
    }
    if let Some(method) = &args.solver {
        scene.solver.method = match method.as_str() {
            "multilevel" => SolverMethod::Multilevel,
            "paper" => SolverMethod::Paper,
            other => {
                return Err(Error::InvalidArgument {
                    flag: "--solver".into(),
                    message: format!("must be multilevel or paper, got {other:?}"),
                })
            }
        };
    }
    if let Some(tolerance) = args.tolerance {
        check_tolerance(tolerance).map_err(|message| Error::InvalidArgument {
            flag: "--tolerance".into(),
            message,
        })?;
        scene.solver.tolerance = tolerance;
    }
    if let Some(gib) = args.memory_limit {
        check_memory_limit(gib).map_err(|message| Error::InvalidArgument {
            flag: "--memory-limit".into(),
            message,
        })?;
        scene.limits.memory_gib = Some(gib);
    }
    if args.allow_large {
        scene.limits.allow_large = true;
    }
    let leg = match &args.leg {
        Some(path) => path.clone(),
        None => scene_dir(args.scene.as_deref()).join(&scene.leg.file),
    };
    let paths = RunPaths {
        scene_name: scene_name(&args.scene),
        inputs: args.scene.iter().cloned().collect(),
        out_dir: args.out.clone(),
    };
    Ok((scene, FitInputs { leg, axis_source }, paths))
}

fn bench(args: BenchArgs, quiet: bool) -> Result<ExitCode, Error> {
    let options = BenchOptions {
        quick: args.quick,
        out_dir: args.out.clone(),
    };
    let mut bar = Bar::new(quiet);
    let outcome = run_bench(&options, &mut bar)?;
    if !quiet {
        print!("{}", outcome.markdown);
        print_written(&args.out, &outcome.written);
    }
    Ok(ExitCode::SUCCESS)
}

fn render(args: RenderArgs, quiet: bool) -> Result<ExitCode, Error> {
    let mut scene = Scene::load(args.scene.as_deref())?;
    let bad = |flag: &str, message: String| Error::InvalidArgument {
        flag: flag.into(),
        message,
    };
    if let Some(w) = args.width {
        check_render_side(w).map_err(|m| bad("--width", m))?;
        scene.render.width = w;
    }
    if let Some(h) = args.height {
        check_render_side(h).map_err(|m| bad("--height", m))?;
        scene.render.height = h;
    }
    if let Some(spp) = args.spp {
        check_spp(spp).map_err(|m| bad("--spp", m))?;
        scene.render.spp = spp;
    }
    if let Some(view) = &args.view {
        scene.render.view = View::parse(view).ok_or_else(|| {
            bad(
                "--view",
                format!("must be front, side, back or three-quarter, got {view:?}"),
            )
        })?;
        // A view asked for on the command line wins over the scene's fixed camera.
        scene.render.camera = None;
    }
    if let Some(mode) = &args.mode {
        scene.render.mode = match mode.as_str() {
            "yarn" => RenderMode::Yarn,
            "density" => RenderMode::Density,
            other => {
                return Err(bad(
                    "--mode",
                    format!("must be yarn or density, got {other:?}"),
                ))
            }
        };
    }
    // The sweep's reference takes 64 samples per pixel whatever --spp says.
    let r = &scene.render;
    let spp = if args.spp_sweep { 64 } else { r.spp };
    check_render_budget(r.width, r.height, spp).map_err(|m| bad("--width/--height/--spp", m))?;
    if args.spp_sweep {
        let sweep = run_spp_sweep(&scene, &args.input)?;
        println!(
            "{}×{} {} mode; scene prepared in {:.2} s; reference {} spp in {:.2} s; error over {} \
             leg pixels, RMS in 8-bit sRGB levels",
            scene.render.width,
            scene.render.height,
            scene.render.mode.name(),
            sweep.prepare_seconds,
            sweep.reference_spp,
            sweep.reference_seconds,
            sweep.leg_pixels
        );
        println!(
            "| spp | seconds | RMS error vs {} spp |",
            sweep.reference_spp
        );
        println!("|---|---|---|");
        for row in &sweep.rows {
            println!(
                "| {} | {:.2} | {:.2} |",
                row.spp, row.seconds, row.rms_error
            );
        }
        return Ok(ExitCode::SUCCESS);
    }
    let inputs = RenderInputs {
        input: args.input.clone(),
        out: args.out.clone(),
        scene_name: scene_name(&args.scene),
        inputs: args.scene.iter().cloned().collect(),
    };
    let outcome = run_render(&scene, &inputs)?;
    if !quiet {
        let r = &scene.render;
        println!(
            "rendered {}×{} at {} spp ({} mode) in {:.2} s",
            r.width,
            r.height,
            outcome.report.details["render"]["spp"],
            r.mode.name(),
            outcome.report.wall_seconds
        );
        for path in &outcome.written {
            println!("  {}", path.display());
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn scene_name(scene: &Option<PathBuf>) -> String {
    match scene {
        Some(p) => p.display().to_string(),
        None => knitfit::scene::BUNDLED_SCENE_NAME.to_string(),
    }
}

fn print_written(out: &std::path::Path, written: &[PathBuf]) {
    println!("wrote to {}/:", out.display());
    for path in written {
        println!("  {}", path.display());
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

/// Parses `BX,BY,BZ,TX,TY,TZ`.
fn parse_axis(text: &str) -> Result<LegAxis, Error> {
    let bad = |message: String| Error::InvalidArgument {
        flag: "--axis".into(),
        message,
    };
    let numbers: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| {
            bad(format!(
                "expected six numbers BX,BY,BZ,TX,TY,TZ, got {text:?}"
            ))
        })?;
    let [bx, by, bz, tx, ty, tz] = numbers[..] else {
        return Err(bad(format!(
            "expected six numbers BX,BY,BZ,TX,TY,TZ, got {}",
            numbers.len()
        )));
    };
    let axis = LegAxis {
        bottom: [bx, by, bz],
        top: [tx, ty, tz],
    };
    check_axis(&axis).map_err(bad)?;
    Ok(axis)
}

/// Parses `AxB` into two counts of at least `min_a` and `min_b`.
fn parse_grid(flag: &str, text: &str, min_a: usize, min_b: usize) -> Result<[usize; 2], Error> {
    let bad = |message: String| Error::InvalidArgument {
        flag: flag.into(),
        message,
    };
    let example = || format!("expected two counts such as 150x150, got {text:?}");
    let (a, b) = text.split_once(['x', 'X']).ok_or_else(|| bad(example()))?;
    let parse = |s: &str| s.trim().parse::<usize>().map_err(|_| bad(example()));
    let size = [parse(a)?, parse(b)?];
    if size[0] < min_a || size[1] < min_b {
        return Err(bad(format!(
            "needs at least {min_a}x{min_b} points, got {text}"
        )));
    }
    Ok(size)
}

/// Parses `WxH` into `[wales, courses]` of a patch.
fn parse_size(text: &str) -> Result<[usize; 2], Error> {
    let size = parse_grid("--size", text, 2, 2)?;
    check_patch_points(size[0], size[1]).map_err(|message| Error::InvalidArgument {
        flag: "--size".into(),
        message,
    })?;
    Ok(size)
}

/// Parses `course=S` or `wale=S`.
fn parse_stretch(text: &str) -> Result<Stretch, Error> {
    let bad = |message: String| Error::InvalidArgument {
        flag: "--stretch".into(),
        message,
    };
    let (axis, factor) = text
        .split_once('=')
        .ok_or_else(|| bad(format!("expected course=S or wale=S, got {text:?}")))?;
    let axis = match axis.trim() {
        "course" => StretchAxis::Course,
        "wale" => StretchAxis::Wale,
        other => return Err(bad(format!("axis must be course or wale, got {other:?}"))),
    };
    let factor: f64 = factor
        .trim()
        .parse()
        .map_err(|_| bad(format!("stretch factor must be a number, got {factor:?}")))?;
    check_stretch_factor(factor).map_err(bad)?;
    Ok(Stretch { axis, factor })
}

/// A progress bar on stderr, shown only on a terminal and without `-q`.
struct Bar {
    visible: bool,
    bar: Option<ProgressBar>,
}

impl Bar {
    fn new(quiet: bool) -> Bar {
        Bar {
            visible: !quiet && std::io::stderr().is_terminal(),
            bar: None,
        }
    }
}

impl Progress for Bar {
    fn begin(&mut self, stage: &str, total: u64) {
        if !self.visible {
            return;
        }
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
        bar.set_style(
            ProgressStyle::with_template("{prefix:>20} [{elapsed_precise}] {pos} steps {msg}")
                .expect("static template"),
        );
        bar.set_prefix(stage.to_string());
        self.bar = Some(bar);
    }

    fn advance(&mut self, position: u64, residual: f64) {
        if let Some(bar) = &self.bar {
            bar.set_position(position);
            if position.is_multiple_of(16) {
                bar.set_message(format!("residual {residual:.2e}"));
            }
        }
    }

    fn end(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}
