//! The command line's arguments (clap) and the progress bar. A flag that sets a scene field
//! becomes an [`Override`] of that field: the scene applies the flags and validates once, so a
//! flag's value meets the same checks as the field's and a refusal names the flag.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::json;

use knitfit::base::GridSize;
use knitfit::run::Progress;
use knitfit::scene::{LoadedScene, Override, LEG_AXIS, LEG_FILE};
use knitfit::Error;

/// Fits a knitted stocking onto a 3D leg (Sakaguchi & Miyata) and writes files artists' tools
/// read. With no subcommand, fits the bundled sample scene into `out/`.
#[derive(Parser, Debug)]
#[command(name = "knitfit", version, about, long_about = None)]
#[command(
    after_help = "Exit codes: 0 done, 1 run failed, 2 bad input, 3 did not converge \
                        (at the step limit: files written, report.json says \"converged\": \
                        false; stopped early as going nowhere: nothing written), 4 converged \
                        but failed a check (yarn through the skin, density jumping between \
                        neighbours: files written, report.json details.checks says which)."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// No progress bar and no summary.
    #[arg(short, long, global = true)]
    pub quiet: bool,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Fit the stocking onto a leg from a glTF or PLY file; write stocking.glb, stocking.ply,
    /// leg.ply.
    Fit(Box<FitArgs>),
    /// The paper's flat-patch experiment: hold two edges of a knit patch, pull them apart, relax.
    Patch(PatchArgs),
    /// What accuracy costs in time: sweep resolution × solver × tolerance on the bundled legs,
    /// then time whole fits of a stocking to the toe; write bench.md, bench.csv and bench.png.
    Bench(BenchArgs),
    /// Ray-trace the yarn-level preview of a fit from its stocking.glb (or its directory).
    Render(RenderArgs),
    /// Show what a fit (default) or `plan patch` would run: effects, stages and why each is
    /// there, what is left out, the files, and the fit's memory estimate. Runs nothing and
    /// writes nothing.
    Plan(Box<PlanArgs>),
}

#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    #[command(subcommand)]
    pub of: Option<PlanOf>,
    /// The fit to plan, as `knitfit fit` takes it.
    #[command(flatten)]
    pub fit: FitArgs,
    /// Print the plan as JSON (for scripts).
    #[arg(long, global = true)]
    pub json: bool,
}

#[derive(Subcommand, Debug)]
pub enum PlanOf {
    /// The plan of `knitfit fit` (what `knitfit plan` shows without a subcommand).
    Fit(Box<FitArgs>),
    /// The plan of `knitfit patch`.
    Patch(PatchArgs),
}

#[derive(clap::Args, Debug, Default)]
pub struct BenchArgs {
    /// The short sweep (50×50 and 100×100 on the MakeHuman leg, the whole stocking at 150×150):
    /// under two minutes.
    #[arg(long)]
    pub quick: bool,
    /// Output directory (created if missing).
    #[arg(long, default_value = "out/bench")]
    pub out: PathBuf,
}

#[derive(clap::Args, Debug, Default)]
pub struct RenderArgs {
    /// A fit's output directory or its stocking.glb.
    pub input: PathBuf,
    /// Scene file (JSON) for yarn radii, colours and render settings. Default: the bundled
    /// samples/scene.json.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Image width, pixels. Overrides render.width.
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height, pixels. Overrides render.height.
    #[arg(long)]
    pub height: Option<u32>,
    /// Camera side: front, side, back or three-quarter. Overrides render.view (and the
    /// scene's fixed camera).
    #[arg(long, value_name = "VIEW")]
    pub view: Option<String>,
    /// Samples per pixel (stratified). Overrides render.spp.
    #[arg(long)]
    pub spp: Option<u32>,
    /// yarn (the shaded yarns) or density (stitch density with a colour bar). Overrides
    /// render.mode.
    #[arg(long, value_name = "yarn|density")]
    pub mode: Option<String>,
    /// Picture to write (.png). Default: preview.png next to the input.
    #[arg(long, value_name = "FILE.png")]
    pub out: Option<PathBuf>,
    /// Instead of writing a picture, print time and error against a 64-spp reference for 1, 4
    /// and 16 samples per pixel.
    #[arg(long)]
    pub spp_sweep: bool,
}

#[derive(clap::Args, Debug, Default)]
pub struct FitArgs {
    /// Scene file (JSON). Default: the bundled samples/scene.json.
    pub scene: Option<PathBuf>,
    /// Leg file (.glb, .gltf or .ply). Overrides leg.file.
    #[arg(long)]
    pub leg: Option<PathBuf>,
    /// Tube size: WALES (e.g. 150; the courses follow the stitch, each cell as many stitches
    /// long as wide) or WALESxCOURSES (e.g. 150x150). Overrides tube.wales and tube.courses.
    #[arg(long, value_name = "W or WxC")]
    pub resolution: Option<String>,
    /// Bottom and top of the stocking on the leg's axis, in the leg file's coordinates:
    /// BX,BY,BZ,TX,TY,TZ. Overrides leg.axis.
    #[arg(long, value_name = "BX,BY,BZ,TX,TY,TZ", allow_hyphen_values = true)]
    pub axis: Option<String>,
    /// Units of the leg file's coordinates: m, dm, cm, mm or in. Overrides leg.units.
    #[arg(long, value_name = "m|dm|cm|mm|in")]
    pub units: Option<String>,
    /// Which file axis points up: auto (found from the anatomy), +y, -y, +z, -z, +x or -x.
    /// Overrides leg.up_axis.
    #[arg(long, value_name = "AXIS", allow_hyphen_values = true)]
    pub up_axis: Option<String>,
    /// Which leg to dress where the file holds both: the character's own left or right.
    /// Overrides leg.side.
    #[arg(long, value_name = "left|right")]
    pub side: Option<String>,
    /// Where the stocking ends at the bottom: toe (over the foot, closed by a toe seam) or
    /// ankle (open). Overrides tube.bottom.
    #[arg(long, value_name = "toe|ankle")]
    pub bottom: Option<String>,
    /// The heel of a stocking to the toe: none (heel-less) or pocket (short rows). Overrides
    /// tube.heel.
    #[arg(long, value_name = "none|pocket")]
    pub heel: Option<String>,
    /// Contact queries: bvh (fast) or brute (the paper's all-triangles test). Overrides
    /// contact.method.
    #[arg(long, value_name = "bvh|brute")]
    pub contact: Option<String>,
    /// Solver: multilevel (fast, the default) or paper (the paper's explicit steps, the
    /// reference). Overrides solver.method.
    #[arg(long, value_name = "multilevel|paper")]
    pub solver: Option<String>,
    /// Convergence tolerance on the relative residual and the largest move per step (paper)
    /// or force step (multilevel). Overrides solver.tolerance.
    #[arg(long, value_name = "TOL")]
    pub tolerance: Option<f64>,
    /// Memory the fit may use, GiB; a fit estimated to need more is refused before it starts.
    /// Overrides limits.memory_gib (default: what the system has available).
    #[arg(long, value_name = "GIB")]
    pub memory_limit: Option<f64>,
    /// Run even when the memory estimate is over the limit. Sets limits.allow_large.
    #[arg(long)]
    pub allow_large: bool,
    /// Files to write besides report.json, comma-separated: ply, glb, picture, preview,
    /// stitches, loops (e.g. ply,glb: no pictures, the fastest run). Overrides outputs.
    #[arg(long, value_name = "LIST")]
    pub outputs: Option<String>,
    /// Output directory, created if missing (default: out).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

/// Where a fit or patch writes when `--out` is not given.
const DEFAULT_OUT: &str = "out";

impl FitArgs {
    /// The output directory: `--out`, else `out`.
    pub fn out_dir(&self) -> PathBuf {
        self.out
            .clone()
            .unwrap_or_else(|| PathBuf::from(DEFAULT_OUT))
    }

    /// True when a scene or any option was given (every field is named, so a new option cannot
    /// be forgotten here).
    pub fn given(&self) -> bool {
        let FitArgs {
            scene,
            leg,
            resolution,
            axis,
            units,
            up_axis,
            side,
            bottom,
            heel,
            contact,
            solver,
            tolerance,
            memory_limit,
            allow_large,
            outputs,
            out,
        } = self;
        scene.is_some()
            || leg.is_some()
            || resolution.is_some()
            || axis.is_some()
            || units.is_some()
            || up_axis.is_some()
            || side.is_some()
            || bottom.is_some()
            || heel.is_some()
            || contact.is_some()
            || solver.is_some()
            || tolerance.is_some()
            || memory_limit.is_some()
            || *allow_large
            || outputs.is_some()
            || out.is_some()
    }

    /// The scene file with these flags applied.
    pub fn load(&self) -> Result<LoadedScene, Error> {
        let mut set = Vec::new();
        if let Some(path) = &self.leg {
            // A scene file holds the leg's path as text; a path that is not text cannot go there.
            let path = path.to_str().ok_or_else(|| Error::InvalidArgument {
                flag: "--leg".into(),
                message: format!("{} is not valid UTF-8; rename the file", path.display()),
            })?;
            set.push(Override::new("--leg", LEG_FILE, path));
        }
        if let Some(text) = &self.resolution {
            // Wales alone leave the courses to the stitch (`null`: tube.courses left out).
            let (wales, courses) = match text.trim().parse::<usize>() {
                Ok(wales) => (wales, serde_json::Value::Null),
                Err(_) => {
                    let GridSize { wales, courses } =
                        parse_grid("--resolution", text).map_err(|_| Error::InvalidArgument {
                            flag: "--resolution".into(),
                            message: format!(
                                "expected wales such as 150, or wales and courses such as \
                                 150x150, got {text:?}"
                            ),
                        })?;
                    (wales, courses.into())
                }
            };
            set.push(
                Override::new("--resolution", "tube.wales", wales).and("tube.courses", courses),
            );
        }
        if let Some(text) = &self.axis {
            let [bx, by, bz, tx, ty, tz] = parse_axis(text)?;
            let axis = json!({ "bottom": [bx, by, bz], "top": [tx, ty, tz] });
            set.push(Override::new("--axis", LEG_AXIS, axis));
        }
        for (flag, field, value) in [
            ("--units", "leg.units", &self.units),
            ("--up-axis", "leg.up_axis", &self.up_axis),
            ("--side", "leg.side", &self.side),
            ("--bottom", "tube.bottom", &self.bottom),
            ("--heel", "tube.heel", &self.heel),
        ] {
            if let Some(value) = value {
                set.push(Override::new(flag, field, value.as_str()));
            }
        }
        if let Some(method) = &self.contact {
            set.push(Override::new(
                "--contact",
                "contact.method",
                method.as_str(),
            ));
        }
        if let Some(method) = &self.solver {
            set.push(Override::new("--solver", "solver.method", method.as_str()));
        }
        if let Some(tolerance) = self.tolerance {
            let tolerance = finite("--tolerance", tolerance)?;
            set.push(Override::new("--tolerance", "solver.tolerance", tolerance));
        }
        if let Some(gib) = self.memory_limit {
            let gib = finite("--memory-limit", gib)?;
            set.push(Override::new("--memory-limit", "limits.memory_gib", gib));
        }
        if self.allow_large {
            set.push(Override::new("--allow-large", "limits.allow_large", true));
        }
        if let Some(list) = &self.outputs {
            // The names are checked where the scene's `outputs` are: an unknown one is refused
            // naming this flag.
            let names: Vec<&str> = list
                .split(',')
                .map(str::trim)
                .filter(|name| !name.is_empty())
                .collect();
            set.push(Override::new("--outputs", "outputs", json!(names)));
        }
        LoadedScene::load(self.scene.as_deref(), set)
    }
}

#[derive(clap::Args, Debug, Default)]
pub struct PatchArgs {
    /// Scene file (JSON). Default: the bundled samples/scene.json.
    pub scene: Option<PathBuf>,
    /// Patch size in points, WALESxCOURSES (e.g. 10x10). Overrides patch.size.
    #[arg(long, value_name = "WxH")]
    pub size: Option<String>,
    /// A stretch to run, course=S or wale=S (S = held-edge distance / rest distance). Repeat for
    /// both directions side by side. Overrides patch.stretch.
    #[arg(long, value_name = "AXIS=S")]
    pub stretch: Vec<String>,
    /// Output directory, created if missing (default: out).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

impl PatchArgs {
    /// The output directory: `--out`, else `out`.
    pub fn out_dir(&self) -> PathBuf {
        self.out
            .clone()
            .unwrap_or_else(|| PathBuf::from(DEFAULT_OUT))
    }

    /// The scene file with these flags applied.
    pub fn load(&self) -> Result<LoadedScene, Error> {
        let mut set = Vec::new();
        if let Some(text) = &self.size {
            let size = parse_grid("--size", text)?;
            set.push(Override::new("--size", "patch.size", json!(size)));
        }
        if !self.stretch.is_empty() {
            let stretches = self
                .stretch
                .iter()
                .map(|text| parse_stretch(text))
                .collect::<Result<Vec<_>, _>>()?;
            set.push(Override::new("--stretch", "patch.stretch", stretches));
        }
        LoadedScene::load(self.scene.as_deref(), set)
    }
}

impl RenderArgs {
    /// The scene file with these flags applied.
    pub fn load(&self) -> Result<LoadedScene, Error> {
        let mut set = Vec::new();
        if let Some(width) = self.width {
            set.push(Override::new("--width", "render.width", width));
        }
        if let Some(height) = self.height {
            set.push(Override::new("--height", "render.height", height));
        }
        if let Some(spp) = self.spp {
            set.push(Override::new("--spp", "render.spp", spp));
        }
        if let Some(view) = &self.view {
            // A view asked for on the command line wins over the scene's fixed camera.
            set.push(
                Override::new("--view", "render.view", view.as_str())
                    .and("render.camera", serde_json::Value::Null),
            );
        }
        if let Some(mode) = &self.mode {
            set.push(Override::new("--mode", "render.mode", mode.as_str()));
        }
        LoadedScene::load(self.scene.as_deref(), set)
    }
}

/// Parses `AxB` into a grid (the scene checks its range).
fn parse_grid(flag: &str, text: &str) -> Result<GridSize, Error> {
    let bad = || Error::InvalidArgument {
        flag: flag.into(),
        message: format!("expected two counts such as 150x150, got {text:?}"),
    };
    let (a, b) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let parse = |s: &str| s.trim().parse::<usize>().map_err(|_| bad());
    Ok(GridSize::new(parse(a)?, parse(b)?))
}

/// Parses `BX,BY,BZ,TX,TY,TZ` (the scene checks the points).
fn parse_axis(text: &str) -> Result<[f64; 6], Error> {
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
    if !numbers.iter().all(|c| c.is_finite()) {
        return Err(bad("coordinates must be finite numbers".into()));
    }
    numbers.try_into().map_err(|numbers: Vec<f64>| {
        bad(format!(
            "expected six numbers BX,BY,BZ,TX,TY,TZ, got {}",
            numbers.len()
        ))
    })
}

/// `value`, refused unless finite: a scene file cannot hold NaN or infinity, so neither may a
/// flag that sets a scene field.
fn finite(flag: &str, value: f64) -> Result<f64, Error> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::InvalidArgument {
            flag: flag.into(),
            message: format!("must be a finite number, got {value}"),
        })
    }
}

/// Parses `course=S` or `wale=S` into the scene's form of a stretch (the scene checks the axis
/// name and the factor).
fn parse_stretch(text: &str) -> Result<serde_json::Value, Error> {
    let bad = |message: String| Error::InvalidArgument {
        flag: "--stretch".into(),
        message,
    };
    let (axis, factor) = text
        .split_once('=')
        .ok_or_else(|| bad(format!("expected course=S or wale=S, got {text:?}")))?;
    let factor: f64 = factor
        .trim()
        .parse()
        .map_err(|_| bad(format!("stretch factor must be a number, got {factor:?}")))?;
    let factor = finite("--stretch", factor)?;
    Ok(json!({ "axis": axis.trim(), "factor": factor }))
}

/// A progress bar on stderr, shown only on a terminal and without `-q`.
pub struct Bar {
    visible: bool,
    bar: Option<ProgressBar>,
}

impl Bar {
    pub fn new(quiet: bool) -> Bar {
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

/// Prints where a run's files went.
pub fn print_written(out: &Path, written: &[PathBuf]) {
    say!("wrote to {}/:", out.display());
    for path in written {
        say!("  {}", path.display());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use knitfit::leg::{ContactMethod, Side, Units, UpAxis, UpChoice};
    use knitfit::preview::{RenderMode, View};
    use knitfit::sim::SolverMethod;

    fn parse(args: &[&str]) -> Command {
        let all = [&["knitfit"][..], args].concat();
        Cli::try_parse_from(all).unwrap().command.unwrap()
    }

    #[test]
    fn every_fit_flag_sets_its_scene_field() {
        let Command::Fit(args) = parse(&[
            "fit",
            "--leg",
            "legs/my leg.glb",
            "--resolution",
            "30x20",
            "--axis",
            "0,0.1,0,0,0.9,-0.1",
            "--units",
            "cm",
            "--up-axis",
            "-z",
            "--side",
            "right",
            "--contact",
            "brute",
            "--solver",
            "paper",
            "--tolerance",
            "0.01",
            "--memory-limit",
            "2.5",
            "--allow-large",
            "--out",
            "there",
        ]) else {
            panic!("not a fit")
        };
        let loaded = args.load().unwrap();
        let s = &loaded.scene;
        assert_eq!(loaded.leg_path(), PathBuf::from("legs/my leg.glb"));
        assert_eq!((s.tube.wales, s.tube.courses), (30, Some(20)));
        let axis = s.leg.axis.unwrap();
        assert_eq!((axis.bottom, axis.top), ([0.0, 0.1, 0.0], [0.0, 0.9, -0.1]));
        assert_eq!(loaded.set_by(LEG_AXIS), Some("--axis"));
        assert_eq!(s.leg.units, Units::Centimetres);
        assert_eq!(s.leg.up_axis, UpChoice::Axis(UpAxis::NegZ));
        assert_eq!(s.leg.side, Side::Right);
        assert_eq!(s.contact.method, ContactMethod::Brute);
        assert_eq!(s.solver.method, SolverMethod::Paper);
        assert_eq!(s.solver.tolerance, 0.01);
        assert_eq!(s.limits.memory_gib, Some(2.5));
        assert!(s.limits.allow_large);
        assert_eq!(args.out_dir(), PathBuf::from("there"));
        assert!(args.given());
        assert!(!FitArgs::default().given());
        assert_eq!(FitArgs::default().out_dir(), PathBuf::from("out"));
    }

    #[test]
    fn every_patch_and_render_flag_sets_its_scene_field() {
        let Command::Patch(args) = parse(&[
            "patch",
            "--size",
            "8x6",
            "--stretch",
            "course=2",
            "--stretch",
            "wale=1.25",
        ]) else {
            panic!("not a patch")
        };
        let s = args.load().unwrap().scene;
        assert_eq!(s.patch.size, GridSize::new(8, 6));
        let stretches: Vec<String> = s.patch.stretch.iter().map(|s| s.to_string()).collect();
        assert_eq!(stretches, ["course=2", "wale=1.25"]);

        let Command::Render(args) = parse(&[
            "render", "out", "--width", "320", "--height", "200", "--spp", "9", "--view", "side",
            "--mode", "density",
        ]) else {
            panic!("not a render")
        };
        let r = args.load().unwrap().scene.render;
        assert_eq!((r.width, r.height, r.spp), (320, 200, 9));
        assert_eq!((r.view, r.mode), (View::Side, RenderMode::Density));
        assert!(r.camera.is_none());
    }

    #[test]
    fn a_flag_value_the_scene_refuses_is_refused_under_the_flag() {
        for (args, expect) in [
            (
                &["fit", "--resolution", "2x2"][..],
                "--resolution: needs at least 3 wales",
            ),
            (
                &["fit", "--resolution", "2by2"][..],
                "--resolution: expected wales such as 150, or wales and courses",
            ),
            (
                &["fit", "--resolution", "2"][..],
                "--resolution: needs at least 3 wales",
            ),
            (
                &["fit", "--axis", "1,2,3"][..],
                "--axis: expected six numbers",
            ),
            (
                &["fit", "--tolerance", "NaN"][..],
                "--tolerance: must be a finite number",
            ),
            (
                &["fit", "--solver", "fast"][..],
                "--solver: unknown variant `fast`",
            ),
            (
                &["fit", "--units", "km"][..],
                "--units: unknown variant `km`, expected one of `m`, `dm`, `cm`, `mm`, `in`",
            ),
            (
                &["fit", "--up-axis", "up"][..],
                "--up-axis: unknown up axis \"up\": expected \"auto\", \"+y\"",
            ),
            (
                &["fit", "--up-axis", "y"][..],
                "--up-axis: unknown up axis \"y\"",
            ),
            (
                &["fit", "--side", "middle"][..],
                "--side: unknown variant `middle`, expected `left` or `right`",
            ),
            (
                &["patch", "--stretch", "course"][..],
                "--stretch: expected course=S",
            ),
        ] {
            let err = match parse(args) {
                Command::Fit(a) => a.load().unwrap_err(),
                Command::Patch(a) => a.load().unwrap_err(),
                _ => unreachable!("only fits and patches listed"),
            };
            assert!(err.to_string().starts_with(expect), "{args:?}: {err}");
        }
    }

    #[test]
    fn the_leg_flags_take_every_name_the_scene_does() {
        for up in ["auto", "+y", "-y", "+z", "-z", "+x", "-x"] {
            for form in [vec!["--up-axis", up], vec![&format!("--up-axis={up}")[..]]] {
                let args = [&["fit"][..], &form].concat();
                let Command::Fit(fit) = parse(&args) else {
                    panic!("not a fit")
                };
                assert_eq!(fit.load().unwrap().scene.leg.up_axis.name(), up, "{args:?}");
            }
        }
        for units in ["m", "dm", "cm", "mm", "in"] {
            let Command::Fit(fit) = parse(&["fit", "--units", units]) else {
                panic!("not a fit")
            };
            assert_eq!(fit.load().unwrap().scene.leg.units.name(), units);
        }
        // `plan` takes the fit's flags, before or after `fit`.
        for args in [
            &["plan", "--side", "right"][..],
            &["plan", "fit", "--side", "right"],
        ] {
            let Command::Plan(plan) = parse(args) else {
                panic!("not a plan")
            };
            let fit = match &plan.of {
                Some(PlanOf::Fit(fit)) => fit,
                _ => &plan.fit,
            };
            assert_eq!(fit.load().unwrap().scene.leg.side, Side::Right, "{args:?}");
        }
    }

    #[cfg(unix)]
    #[test]
    fn a_leg_path_that_is_not_text_is_refused_by_name() {
        use std::os::unix::ffi::OsStrExt;
        let args = FitArgs {
            leg: Some(PathBuf::from(std::ffi::OsStr::from_bytes(b"leg\xff.glb"))),
            ..FitArgs::default()
        };
        let err = args.load().unwrap_err().to_string();
        assert!(err.starts_with("--leg: leg"), "{err}");
        assert!(err.contains("not valid UTF-8"), "{err}");
    }
}
