//! The `knitfit` command line: parse → validated scene → run → exit code. The only place that
//! prints to the user or picks an exit code.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use knitfit::run::{run_patch, Progress, RunPaths};
use knitfit::scene::{check_patch_points, check_stretch_factor, Stretch, StretchAxis};
use knitfit::{Error, Scene};

/// Exit code of a run that finished but did not converge (its files are written and its report
/// says so).
const EXIT_NOT_CONVERGED: u8 = 3;

/// Fits a knitted stocking onto a 3D leg (Sakaguchi & Miyata) and writes files artists' tools
/// read. With no subcommand, runs the main job on the bundled sample scene into `out/`.
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
    /// The paper's flat-patch experiment: hold two edges of a knit patch, pull them apart, relax.
    Patch(PatchArgs),
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
    let args = match cli.command {
        Some(Command::Patch(args)) => args,
        None => PatchArgs {
            out: PathBuf::from("out"),
            ..PatchArgs::default()
        },
    };
    match patch(args, quiet) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("knitfit: error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}

fn patch(args: PatchArgs, quiet: bool) -> Result<ExitCode, Error> {
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
        scene_name: match &args.scene {
            Some(p) => p.display().to_string(),
            None => knitfit::scene::BUNDLED_SCENE_NAME.to_string(),
        },
        inputs: args.scene.iter().cloned().collect(),
        out_dir: args.out.clone(),
    };
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
        println!("wrote to {}/:", args.out.display());
        for path in &outcome.written {
            println!("  {}", path.display());
        }
    }
    if m.converged {
        Ok(ExitCode::SUCCESS)
    } else {
        // A patch squeezed in its plane has no stable flat rest state: the square spring grid
        // has no shear stiffness, so it buckles instead of settling.
        let hint = if scene.patch.stretch.iter().any(|s| s.factor < 1.0) {
            "a patch compressed below its rest size (stretch < 1) buckles and has no flat rest state"
        } else {
            "raise solver.max_steps, or solver.damping if the residual oscillates"
        };
        eprintln!(
            "knitfit: warning: did not converge within solver.max_steps = {} (residual {:.2e}, \
             tolerance {:.0e}); {hint}",
            scene.solver.max_steps, m.residual, scene.solver.tolerance
        );
        Ok(ExitCode::from(EXIT_NOT_CONVERGED))
    }
}

/// Parses `WxH` into `[wales, courses]`.
fn parse_size(text: &str) -> Result<[usize; 2], Error> {
    let bad = |message: String| Error::InvalidArgument {
        flag: "--size".into(),
        message,
    };
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(|| {
        bad(format!(
            "expected WALESxCOURSES such as 10x10, got {text:?}"
        ))
    })?;
    let parse = |s: &str| {
        s.trim().parse::<usize>().map_err(|_| {
            bad(format!(
                "expected WALESxCOURSES such as 10x10, got {text:?}"
            ))
        })
    };
    let size = [parse(w)?, parse(h)?];
    if size[0] < 2 || size[1] < 2 {
        return Err(bad(format!(
            "a patch needs at least 2x2 points (two held edges), got {text}"
        )));
    }
    check_patch_points(size[0], size[1]).map_err(bad)?;
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
