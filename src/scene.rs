//! The scene file: what to knit, with which yarns, how to solve, which effects to simulate and
//! which files to write.
//!
//! JSON, read with serde. Unknown fields are errors (a typo must not be silently ignored); every
//! field has a default, so `{}` is a complete scene. Each field's doc gives its unit and default.
//! [`Scene::validate`] checks values after parsing and names the offending field.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::base::YarnKind;
use crate::error::{Error, Result};
use crate::knit::Pattern;

/// The scene bundled with the binary (`samples/scene.json`), used when no scene file is given.
pub const BUNDLED_SCENE: &str = include_str!("../samples/scene.json");
/// How the bundled scene is named in messages and reports.
pub const BUNDLED_SCENE_NAME: &str = "samples/scene.json (bundled)";
/// Where the bundled scene's relative paths (its leg) are found: the crate's `samples/`.
pub const BUNDLED_SCENE_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/samples");

/// A whole scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct Scene {
    /// Knit structure: pattern, rest spacing, connection factor.
    pub knit: KnitSettings,
    /// Yarn materials.
    pub yarns: Yarns,
    /// Relaxation solver settings.
    pub solver: SolverSettings,
    /// Physical effects to simulate (default: `["yarn_connection", "alternating_yarns"]`). The
    /// spring force of eq. (1) always runs; everything else runs only when listed here.
    #[serde(default = "default_effects")]
    pub effects: Vec<Effect>,
    /// Files to write besides `report.json`, which is always written
    /// (default: `["ply", "glb", "picture"]`).
    #[serde(default = "default_outputs")]
    pub outputs: Vec<Output>,
    /// The flat-patch experiment (`knitfit patch`).
    pub patch: PatchSettings,
    /// The leg to fit onto (`knitfit fit`).
    pub leg: LegSettings,
    /// The stocking tube (`knitfit fit`).
    pub tube: TubeSettings,
    /// Contact between yarn and leg (`knitfit fit`).
    pub contact: ContactSettings,
    /// The yarn-level preview still (`preview.png` of `knitfit fit`, and `knitfit render`).
    pub render: RenderSettings,
    /// How much memory a fit may use (`knitfit fit`; see [`crate::limits`]).
    pub limits: Limits,
}

/// The memory a fit may use. A fit whose estimate is over it is refused before the leg is
/// decoded or the knit allocated ([`crate::limits`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct Limits {
    /// Memory the fit may use, GiB; absent means what the system has available (`MemAvailable`
    /// in `/proc/meminfo`, or the cgroup's limit when lower), or
    /// [`crate::limits::FALLBACK_LIMIT_GIB`] where neither can be read (default: absent).
    /// `--memory-limit` overrides it.
    pub memory_gib: Option<f64>,
    /// Run the fit even when its estimate is over the limit: the check is skipped
    /// (default: false). `--allow-large` sets it.
    pub allow_large: bool,
}

/// Length units a leg file can be in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Units {
    /// Metres (glTF's unit; default).
    #[default]
    #[serde(rename = "m")]
    Metres,
    /// Decimetres (the MakeHuman base mesh).
    #[serde(rename = "dm")]
    Decimetres,
    /// Centimetres.
    #[serde(rename = "cm")]
    Centimetres,
    /// Millimetres.
    #[serde(rename = "mm")]
    Millimetres,
    /// Inches.
    #[serde(rename = "in")]
    Inches,
}

impl Units {
    /// Metres per unit.
    pub fn metres(self) -> f64 {
        match self {
            Units::Metres => 1.0,
            Units::Decimetres => 0.1,
            Units::Centimetres => 0.01,
            Units::Millimetres => 0.001,
            Units::Inches => 0.0254,
        }
    }

    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Units::Metres => "m",
            Units::Decimetres => "dm",
            Units::Centimetres => "cm",
            Units::Millimetres => "mm",
            Units::Inches => "in",
        }
    }
}

/// Which file axis points up.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum UpAxis {
    /// +Y, glTF's convention (default).
    #[default]
    #[serde(rename = "+y")]
    PosY,
    /// −Y.
    #[serde(rename = "-y")]
    NegY,
    /// +Z (Blender's and many CAD tools' convention).
    #[serde(rename = "+z")]
    PosZ,
    /// −Z.
    #[serde(rename = "-z")]
    NegZ,
    /// +X.
    #[serde(rename = "+x")]
    PosX,
    /// −X.
    #[serde(rename = "-x")]
    NegX,
}

impl UpAxis {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            UpAxis::PosY => "+y",
            UpAxis::NegY => "-y",
            UpAxis::PosZ => "+z",
            UpAxis::NegZ => "-z",
            UpAxis::PosX => "+x",
            UpAxis::NegX => "-x",
        }
    }
}

/// Two points on the leg's long axis, in the leg file's coordinates and units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LegAxis {
    /// Bottom of the stocking (near the ankle).
    pub bottom: [f64; 3],
    /// Top of the stocking (upper thigh).
    pub top: [f64; 3],
}

/// The leg to fit onto.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LegSettings {
    /// glTF file (`.glb` or `.gltf`), relative to the scene file (default:
    /// `"procedural_leg.glb"`, next to the bundled scene).
    pub file: String,
    /// Units of the file's coordinates (default: `"m"`, as glTF specifies).
    pub units: Units,
    /// Which file axis points up (default: `"+y"`, as glTF specifies).
    pub up_axis: UpAxis,
    /// Bottom and top of the stocking on the leg's long axis, in file coordinates; detected from
    /// the mesh when absent (default: absent).
    pub axis: Option<LegAxis>,
}

impl Default for LegSettings {
    fn default() -> Self {
        LegSettings {
            file: "procedural_leg.glb".into(),
            units: Units::Metres,
            up_axis: UpAxis::PosY,
            axis: None,
        }
    }
}

/// The stocking tube before fitting (paper §6.1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TubeSettings {
    /// Points around the tube (wales) (default: 150, the paper's smaller fit).
    pub wales: usize,
    /// Rings along the tube (courses) (default: 150).
    pub courses: usize,
    /// Circumference of the stocking lying relaxed, metres (default: 0.20, a typical sheer
    /// stocking's leg measured flat and doubled).
    pub relaxed_circumference_m: f64,
    /// Length of the relaxed stocking between the two axis points, metres; must be shorter than
    /// the axis, since a stocking is worn stretched along the leg. Absent means
    /// [`RELAXED_LENGTH_FRACTION`] of the axis length (default: absent).
    pub relaxed_length_m: Option<f64>,
}

/// A stocking's relaxed length as a fraction of the leg length it covers, when the scene does
/// not give one: sheer stockings are worn stretched by about 1.4× along the leg.
pub const RELAXED_LENGTH_FRACTION: f64 = 0.7;

impl Default for TubeSettings {
    fn default() -> Self {
        TubeSettings {
            wales: 150,
            courses: 150,
            relaxed_circumference_m: 0.20,
            relaxed_length_m: None,
        }
    }
}

/// How yarn/leg contact is found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ContactMethod {
    /// Bounding-volume hierarchy (parry) queries (default).
    #[default]
    Bvh,
    /// The paper's test of every point against every triangle: a slow reference.
    Brute,
}

impl ContactMethod {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            ContactMethod::Bvh => "bvh",
            ContactMethod::Brute => "brute",
        }
    }
}

/// Contact between yarn and leg (paper §6.2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ContactSettings {
    /// How contact is found (default: `"bvh"`).
    pub method: ContactMethod,
    /// Distance kept between yarn centre line and skin, metres; absent means the nylon yarn
    /// radius (default: absent).
    pub offset_m: Option<f64>,
}

impl Default for ContactSettings {
    fn default() -> Self {
        ContactSettings {
            method: ContactMethod::Bvh,
            offset_m: None,
        }
    }
}

impl ContactSettings {
    /// The contact offset in metres.
    pub fn offset(&self, yarns: &Yarns) -> f64 {
        self.offset_m.unwrap_or(yarns.nylon.radius_m)
    }
}

/// Knit structure.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct KnitSettings {
    /// `"plain"` (one nylon yarn) or `"alternating"` (nylon and support yarn in alternate courses,
    /// the paper's 交編). Default: `"alternating"`.
    pub pattern: Pattern,
    /// Rest length of a course spring: the distance between neighbouring wales along a course,
    /// in metres (default: 0.0005, i.e. 20 wales per cm, typical of a sheer stocking).
    pub course_spacing_m: f64,
    /// Rest length of a wale spring: the distance between neighbouring courses along a wale,
    /// in metres (default: 0.00074). With `course_spacing_m` it sets the fabric's stitch shape,
    /// which a fit keeps at any grid size (`Knit::with_stitch_shape`): 0.5 × 0.74 mm is the
    /// fabric the bundled 150×150 fits have always had. A square stitch (0.5 × 0.5 mm) is
    /// stiffer around than along, and on the MakeHuman leg its slack ankle crumples (density
    /// 1,495 stitches/cm² at 300×300 where the rest of the leg has under 100).
    pub wale_spacing_m: f64,
    /// Connection factor c2 of eq. (2), dimensionless (default: 0.2, the paper's value). Used only
    /// when `effects` lists `yarn_connection`.
    pub connection_factor: f64,
}

impl Default for KnitSettings {
    fn default() -> Self {
        KnitSettings {
            pattern: Pattern::Alternating,
            course_spacing_m: 0.0005,
            wale_spacing_m: 0.00074,
            connection_factor: 0.2,
        }
    }
}

/// The two yarn materials.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Yarns {
    /// Nylon yarn (default: c1 = 1, radius 0.03 mm). The only yarn of a plain pattern.
    pub nylon: Yarn,
    /// Support yarn (default: c1 = 10, radius 0.04 mm). Used by the alternating pattern.
    pub support: Yarn,
}

impl Default for Yarns {
    fn default() -> Self {
        Yarns {
            nylon: Yarn {
                stiffness: 1.0,
                radius_m: 0.00003,
                colour: [0.16, 0.11, 0.09],
            },
            support: Yarn {
                stiffness: 10.0,
                radius_m: 0.00004,
                colour: [0.08, 0.07, 0.10],
            },
        }
    }
}

impl Yarns {
    /// The material of a yarn kind.
    pub fn get(&self, kind: YarnKind) -> &Yarn {
        match kind {
            YarnKind::Nylon => &self.nylon,
            YarnKind::Support => &self.support,
        }
    }
}

/// One yarn material.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Yarn {
    /// Spring stiffness c1 of eq. (1), per solver time unit squared for a unit mass point
    /// (force per metre of extension per unit mass). The paper uses 1 for nylon, 10 for support.
    pub stiffness: f64,
    /// Yarn radius, metres. Used for drawing and, later, contact offset and coverage.
    pub radius_m: f64,
    /// Linear-RGB base colour, each channel 0–1.
    #[serde(default = "default_colour")]
    pub colour: [f64; 3],
}

fn default_colour() -> [f64; 3] {
    [0.15, 0.1, 0.1]
}

/// What the solver does when the time step is above the explicit stability limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum OnUnstable {
    /// Split each step into equal sub-steps below the limit (default).
    #[default]
    Substep,
    /// Stop with an error naming the limit.
    Error,
    /// Run at the given step anyway; the divergence watchdog stops the run if it blows up. For
    /// experiments that show why the limit matters.
    Ignore,
}

/// Which solver relaxes a fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum SolverMethod {
    /// Coarse-to-fine grids with an accelerated (momentum with restart) iteration on each
    /// (`sim::multilevel`; default). The same rest state as `paper`, in a small fraction of the
    /// time; `time_step`, `damping` and `on_unstable` do not apply to it.
    #[default]
    Multilevel,
    /// The paper's explicit damped steps (§5) on the full grid: the reference.
    Paper,
}

impl SolverMethod {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            SolverMethod::Multilevel => "multilevel",
            SolverMethod::Paper => "paper",
        }
    }
}

/// Relaxation solver settings. `knitfit patch` always runs the paper's explicit solver, since it
/// reproduces the paper's experiment; `knitfit fit` runs `method`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverSettings {
    /// Which solver relaxes a fit (default: `"multilevel"`).
    pub method: SolverMethod,
    /// Time step t, in solver time units (default: 0.1, the paper's value).
    pub time_step: f64,
    /// Velocity damper: velocities decay as `exp(-damping · t)` each step; per solver time unit
    /// (default: 1.0, close to the fastest settling of the paper's 10×10 patch; see README).
    pub damping: f64,
    /// Convergence tolerance on the relative residual (RMS net force on free points over RMS
    /// spring-force magnitude) and on the largest move per step relative to the shortest rest
    /// length (default: 0.001).
    pub tolerance: f64,
    /// Step limit (for `multilevel`, iterations per grid level); a run that reaches it is
    /// reported as not converged (default: 100000).
    pub max_steps: usize,
    /// What to do when `time_step` is above the explicit stability limit (default: `"substep"`).
    pub on_unstable: OnUnstable,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            method: SolverMethod::Multilevel,
            time_step: 0.1,
            damping: 1.0,
            tolerance: 1e-3,
            max_steps: 100_000,
            on_unstable: OnUnstable::Substep,
        }
    }
}

/// A physical effect a scene can ask for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    /// The connection force of eq. (2): tension drawn along the course yarn.
    YarnConnection,
    /// Nylon and support yarn have their own stiffness. Without it, every spring uses the nylon
    /// yarn's stiffness even where the pattern lays support yarn (an ablation of the paper).
    AlternatingYarns,
    /// Yarn slides on the leg and never enters it (paper §6.2). Always on for a fit.
    Contact,
    /// After a fit, yarn segments that cut through the leg are rerouted over the skin (paper
    /// §6.3). Runs only when a yarn polyline is written (`glb` or `ply`).
    PenetrationFix,
}

impl Effect {
    /// Name as written in scene files and reports.
    pub fn name(self) -> &'static str {
        match self {
            Effect::YarnConnection => "yarn_connection",
            Effect::AlternatingYarns => "alternating_yarns",
            Effect::Contact => "contact",
            Effect::PenetrationFix => "penetration_fix",
        }
    }
}

fn default_effects() -> Vec<Effect> {
    vec![Effect::YarnConnection, Effect::AlternatingYarns]
}

/// A file a run can write (besides `report.json`, which every run writes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Output {
    /// PLY: yarn points with an edge element (`patch.ply`; `stocking.ply` and `leg.ply` for a
    /// fit).
    Ply,
    /// Binary glTF (`patch.glb`; `stocking.glb` for a fit).
    Glb,
    /// PNG picture: the relaxed stitches (`patch.png`), or for a fit the leg coloured by
    /// stitch density, front and side, with a colour bar (`density.png`).
    Picture,
    /// PNG: the ray-traced yarn-level still of the fitted stocking on the leg (`preview.png`,
    /// `knitfit fit` only; settings in `render`).
    Preview,
}

fn default_outputs() -> Vec<Output> {
    vec![Output::Ply, Output::Glb, Output::Picture]
}

/// Direction a patch is stretched in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StretchAxis {
    /// Along the course: the two end wales are held and pulled apart.
    Course,
    /// Along the wale: the first and last courses are held and pulled apart.
    Wale,
}

impl StretchAxis {
    /// Name as in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            StretchAxis::Course => "course",
            StretchAxis::Wale => "wale",
        }
    }
}

/// One stretch of the patch experiment.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stretch {
    /// Which pair of edges is held and pulled apart.
    pub axis: StretchAxis,
    /// Held-edge distance over rest distance, dimensionless (1 = unstretched).
    pub factor: f64,
}

impl std::fmt::Display for Stretch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}={}", self.axis.name(), self.factor)
    }
}

/// The flat-patch experiment (paper §5, Fig. 8/9).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PatchSettings {
    /// Patch size as `[wales, courses]`, points (default: `[10, 10]`, the paper's patch).
    pub size: [usize; 2],
    /// Stretches to run, each on a fresh patch; drawn side by side (default: course ×1.5 and
    /// wale ×1.5, the paper's Fig. 9).
    pub stretch: Vec<Stretch>,
}

impl Default for PatchSettings {
    fn default() -> Self {
        PatchSettings {
            size: [10, 10],
            stretch: vec![
                Stretch {
                    axis: StretchAxis::Course,
                    factor: 1.5,
                },
                Stretch {
                    axis: StretchAxis::Wale,
                    factor: 1.5,
                },
            ],
        }
    }
}

/// Which side the auto-framed camera looks at the leg from. glTF's character faces +Z with +Y
/// up (as in `density.png`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum View {
    /// From +Z towards −Z (default).
    #[default]
    Front,
    /// From +X towards −X (the outer side of a left leg).
    Side,
    /// From −Z towards +Z.
    Back,
    /// From +X+Z, halfway between front and side.
    #[serde(rename = "three-quarter", alias = "three_quarter")]
    ThreeQuarter,
}

impl View {
    /// Every view, in the order the command line lists them.
    pub const ALL: [View; 4] = [View::Front, View::Side, View::Back, View::ThreeQuarter];

    /// Name as in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            View::Front => "front",
            View::Side => "side",
            View::Back => "back",
            View::ThreeQuarter => "three-quarter",
        }
    }

    /// Parses a name as written by [`View::name`].
    pub fn parse(text: &str) -> Option<View> {
        View::ALL.into_iter().find(|v| v.name() == text)
    }
}

/// What a preview pixel shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum RenderMode {
    /// The yarns as cylinders over the skin, shaded (paper §7–8, Fig. 17) (default).
    #[default]
    Yarn,
    /// The leg coloured by stitch density, with a colour bar (paper Fig. 18).
    Density,
}

impl RenderMode {
    /// Name as in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            RenderMode::Yarn => "yarn",
            RenderMode::Density => "density",
        }
    }
}

/// A camera given by the scene instead of the auto-framed one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSettings {
    /// Eye position, metres, world space (the leg's frame after units and up axis: +Y up).
    pub position: [f64; 3],
    /// The point looked at, metres, world space.
    pub target: [f64; 3],
    /// Vertical field of view, degrees (default: 25).
    #[serde(default = "default_fov_deg")]
    pub fov_deg: f64,
}

fn default_fov_deg() -> f64 {
    25.0
}

/// The yarn-level preview (`preview.png`, `knitfit render`). Colours are linear RGB, 0–1.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RenderSettings {
    /// Image width, pixels (default: 768; 16 to 8192).
    pub width: u32,
    /// Image height, pixels (default: 768; 16 to 8192).
    pub height: u32,
    /// Side the auto-framed camera looks from (default: `"front"`); ignored with `camera`.
    pub view: View,
    /// Samples per pixel, stratified on a grid of ⌈√spp⌉ columns and as many rows as needed,
    /// so a non-square count is rounded up to fill the grid (default: 16; 1 to 1024).
    pub spp: u32,
    /// What the pixels show (default: `"yarn"`).
    pub mode: RenderMode,
    /// A fixed camera; absent means auto-framed on the leg from `view` (default: absent).
    pub camera: Option<CameraSettings>,
    /// Skin albedo (default: `[0.52, 0.31, 0.22]`, a warm light skin tone).
    pub skin_colour: [f64; 3],
    /// Background (default: `[0.78, 0.78, 0.80]`, a light grey).
    pub background: [f64; 3],
    /// Direction towards the key light in the camera's frame (right, up, towards the viewer),
    /// any length (default: `[-0.45, 0.55, 0.70]`: from the upper left, in front).
    pub light_direction: [f64; 3],
    /// Radiance of the key light (default: 1.1).
    pub light_intensity: f64,
    /// Ambient (environment) light, as a fraction of the key light (default: 0.35).
    pub ambient: f64,
    /// Strength of the yarn's anisotropic highlight (Kajiya–Kay), 0 = none (default: 0.5).
    pub yarn_sheen: f64,
    /// Exponent of the highlight: higher is narrower (default: 48).
    pub yarn_sheen_exponent: f64,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 768,
            height: 768,
            view: View::Front,
            spp: 16,
            mode: RenderMode::Yarn,
            camera: None,
            skin_colour: [0.52, 0.31, 0.22],
            background: [0.78, 0.78, 0.80],
            light_direction: [-0.45, 0.55, 0.70],
            light_intensity: 1.1,
            ambient: 0.35,
            yarn_sheen: 0.5,
            yarn_sheen_exponent: 48.0,
        }
    }
}

/// Smallest and largest image side accepted, pixels.
pub const RENDER_SIDE_PX: (u32, u32) = (16, 8192);
/// Largest samples per pixel accepted.
pub const MAX_SPP: u32 = 1024;

/// Checks an image side (`--width`, `render.width`).
pub fn check_render_side(px: u32) -> std::result::Result<(), String> {
    let (lo, hi) = RENDER_SIDE_PX;
    if (lo..=hi).contains(&px) {
        Ok(())
    } else {
        Err(format!("must be {lo} to {hi} pixels, got {px}"))
    }
}

/// Most pixels and most samples one preview may take: beyond them a render needs gigabytes
/// of buffers or hours.
pub const MAX_RENDER_PIXELS: u64 = 4096 * 4096;
/// See [`MAX_RENDER_PIXELS`].
pub const MAX_RENDER_SAMPLES: u64 = 1 << 31;

/// Checks that a picture of `width × height` at `spp` stays within [`MAX_RENDER_PIXELS`] and
/// [`MAX_RENDER_SAMPLES`].
pub fn check_render_budget(width: u32, height: u32, spp: u32) -> std::result::Result<(), String> {
    let pixels = u64::from(width) * u64::from(height);
    let samples = pixels * u64::from(spp);
    if pixels > MAX_RENDER_PIXELS {
        Err(format!(
            "{width}×{height} is over the limit of {MAX_RENDER_PIXELS} pixels (4096×4096)"
        ))
    } else if samples > MAX_RENDER_SAMPLES {
        Err(format!(
            "{width}×{height} at {spp} spp is {samples} samples, over the limit of \
             {MAX_RENDER_SAMPLES}; lower the size or the samples per pixel"
        ))
    } else {
        Ok(())
    }
}

/// Checks samples per pixel (`--spp`, `render.spp`).
pub fn check_spp(spp: u32) -> std::result::Result<(), String> {
    if (1..=MAX_SPP).contains(&spp) {
        Ok(())
    } else {
        Err(format!(
            "must be 1 to {MAX_SPP} samples per pixel, got {spp}"
        ))
    }
}

impl RenderSettings {
    /// Checks every value; the error names the field (`render.…`) and the scene.
    pub fn validate(&self, name: &str) -> Result<()> {
        let bad = |field: &str, message: String| Error::InvalidScene {
            path: name.to_string(),
            field: format!("render.{field}"),
            message,
        };
        check_render_side(self.width).map_err(|m| bad("width", m))?;
        check_render_side(self.height).map_err(|m| bad("height", m))?;
        check_spp(self.spp).map_err(|m| bad("spp", m))?;
        check_render_budget(self.width, self.height, self.spp).map_err(|m| bad("spp", m))?;
        for (field, colour) in [
            ("skin_colour", self.skin_colour),
            ("background", self.background),
        ] {
            if colour
                .iter()
                .any(|c| !(c.is_finite() && (0.0..=1.0).contains(c)))
            {
                return Err(bad(
                    field,
                    format!("each channel must be in [0, 1], got {colour:?}"),
                ));
            }
        }
        let l = self.light_direction;
        if !l.iter().all(|c| c.is_finite()) || l.iter().all(|&c| c == 0.0) {
            return Err(bad(
                "light_direction",
                format!("must be a finite, non-zero vector, got {l:?}"),
            ));
        }
        for (field, value) in [
            ("light_intensity", self.light_intensity),
            ("ambient", self.ambient),
            ("yarn_sheen", self.yarn_sheen),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(bad(field, format!("must be zero or positive, got {value}")));
            }
        }
        let e = self.yarn_sheen_exponent;
        if !(e.is_finite() && e >= 1.0) {
            return Err(bad(
                "yarn_sheen_exponent",
                format!("must be at least 1, got {e}"),
            ));
        }
        if let Some(camera) = &self.camera {
            let finite = camera
                .position
                .iter()
                .chain(&camera.target)
                .all(|c| c.is_finite());
            if !finite || camera.position == camera.target {
                return Err(bad(
                    "camera",
                    "position and target must be finite and different points".into(),
                ));
            }
            let fov = camera.fov_deg;
            if !(fov.is_finite() && fov > 0.5 && fov < 170.0) {
                return Err(bad(
                    "camera.fov_deg",
                    format!("must be between 0.5 and 170 degrees, got {fov}"),
                ));
            }
        }
        Ok(())
    }
}

/// Largest stretch factor accepted: beyond it the mass-spring model has long stopped being yarn.
pub const MAX_STRETCH: f64 = 10.0;
/// Largest patch accepted without an override, in points.
pub const MAX_PATCH_POINTS: usize = 4_000_000;

impl Scene {
    /// Reads and validates a scene file. `name` is how the file is called in messages.
    pub fn from_json(text: &str, name: &str) -> Result<Scene> {
        let scene: Scene = serde_json::from_str(text).map_err(|e| syntax_error(name, &e))?;
        scene.validate(name)?;
        Ok(scene)
    }

    /// Reads a scene from a file, or the bundled sample scene when `path` is `None`.
    pub fn load(path: Option<&Path>) -> Result<Scene> {
        match path {
            None => Scene::from_json(BUNDLED_SCENE, BUNDLED_SCENE_NAME),
            Some(path) => {
                let text = std::fs::read_to_string(path).map_err(|source| Error::Read {
                    path: path.to_path_buf(),
                    source,
                })?;
                Scene::from_json(&text, &path.display().to_string())
            }
        }
    }

    /// True when the scene lists `effect`.
    pub fn has(&self, effect: Effect) -> bool {
        self.effects.contains(&effect)
    }

    /// True when the scene asks for `output`.
    pub fn wants(&self, output: Output) -> bool {
        self.outputs.contains(&output)
    }

    /// Checks every value; the error names the field (dotted path) and the scene.
    pub fn validate(&self, name: &str) -> Result<()> {
        let bad = |field: &str, message: String| Error::InvalidScene {
            path: name.to_string(),
            field: field.to_string(),
            message,
        };
        let positive = |field: &str, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(bad(
                    field,
                    format!("must be a positive number, got {value}"),
                ))
            }
        };
        positive("knit.course_spacing_m", self.knit.course_spacing_m)?;
        positive("knit.wale_spacing_m", self.knit.wale_spacing_m)?;
        let c2 = self.knit.connection_factor;
        if !(c2.is_finite() && (0.0..1.0).contains(&c2)) {
            return Err(bad(
                "knit.connection_factor",
                format!("must be in [0, 1), got {c2}"),
            ));
        }
        for kind in YarnKind::ALL {
            let yarn = self.yarns.get(kind);
            positive(&format!("yarns.{}.stiffness", kind.name()), yarn.stiffness)?;
            positive(&format!("yarns.{}.radius_m", kind.name()), yarn.radius_m)?;
            if yarn
                .colour
                .iter()
                .any(|c| !(c.is_finite() && (0.0..=1.0).contains(c)))
            {
                return Err(bad(
                    &format!("yarns.{}.colour", kind.name()),
                    format!("each channel must be in [0, 1], got {:?}", yarn.colour),
                ));
            }
        }
        positive("solver.time_step", self.solver.time_step)?;
        let damping = self.solver.damping;
        if !(damping.is_finite() && damping >= 0.0) {
            return Err(bad(
                "solver.damping",
                format!("must be zero or positive, got {damping}"),
            ));
        }
        check_tolerance(self.solver.tolerance).map_err(|m| bad("solver.tolerance", m))?;
        if self.solver.max_steps == 0 {
            return Err(bad("solver.max_steps", "must be at least 1".into()));
        }
        if self.knit.pattern == Pattern::Plain && self.has(Effect::AlternatingYarns) {
            return Err(bad(
                "effects",
                "\"alternating_yarns\" needs knit.pattern \"alternating\" (a plain pattern has \
                 one yarn)"
                    .into(),
            ));
        }
        self.validate_patch(name)?;
        self.render.validate(name)?;
        self.validate_fit(name)
    }

    fn validate_fit(&self, name: &str) -> Result<()> {
        let bad = |field: &str, message: String| Error::InvalidScene {
            path: name.to_string(),
            field: field.to_string(),
            message,
        };
        let (w, c) = (self.tube.wales, self.tube.courses);
        if w < 3 || c < 2 {
            return Err(bad(
                "tube",
                format!("needs at least 3 wales and 2 courses, got {w}×{c}"),
            ));
        }
        check_tube_points(w, c).map_err(|m| bad("tube", m))?;
        let lengths = [
            (
                "tube.relaxed_circumference_m",
                Some(self.tube.relaxed_circumference_m),
            ),
            ("tube.relaxed_length_m", self.tube.relaxed_length_m),
        ];
        for (field, value) in lengths {
            if let Some(value) = value.filter(|v| !(v.is_finite() && *v > 0.0)) {
                return Err(bad(
                    field,
                    format!("must be a positive number, got {value}"),
                ));
            }
        }
        if let Some(offset) = self.contact.offset_m {
            if !(offset.is_finite() && offset >= 0.0) {
                return Err(bad(
                    "contact.offset_m",
                    format!("must be zero or positive, got {offset}"),
                ));
            }
        }
        if let Some(axis) = &self.leg.axis {
            check_axis(axis).map_err(|m| bad("leg.axis", m))?;
        }
        if self.leg.file.is_empty() {
            return Err(bad("leg.file", "must name a .glb or .gltf file".into()));
        }
        if let Some(gib) = self.limits.memory_gib {
            check_memory_limit(gib).map_err(|m| bad("limits.memory_gib", m))?;
        }
        Ok(())
    }

    fn validate_patch(&self, name: &str) -> Result<()> {
        let [wales, courses] = self.patch.size;
        if wales < 2 || courses < 2 {
            return Err(Error::InvalidScene {
                path: name.to_string(),
                field: "patch.size".into(),
                message: format!(
                    "must be at least 2×2 points (two held edges), got {wales}×{courses}"
                ),
            });
        }
        check_patch_points(wales, courses).map_err(|message| Error::InvalidScene {
            path: name.to_string(),
            field: "patch.size".into(),
            message,
        })?;
        if self.patch.stretch.is_empty() {
            return Err(Error::InvalidScene {
                path: name.to_string(),
                field: "patch.stretch".into(),
                message: "needs at least one stretch, e.g. {\"axis\": \"course\", \"factor\": 1.5}"
                    .into(),
            });
        }
        for (i, s) in self.patch.stretch.iter().enumerate() {
            check_stretch_factor(s.factor).map_err(|message| Error::InvalidScene {
                path: name.to_string(),
                field: format!("patch.stretch[{i}].factor"),
                message,
            })?;
        }
        Ok(())
    }
}

/// Checks a patch size against [`MAX_PATCH_POINTS`].
pub fn check_patch_points(wales: usize, courses: usize) -> std::result::Result<(), String> {
    match wales.checked_mul(courses) {
        Some(n) if n <= MAX_PATCH_POINTS => Ok(()),
        _ => Err(format!(
            "{wales}×{courses} points is over the patch limit of {MAX_PATCH_POINTS} points"
        )),
    }
}

/// Largest tube a knit can hold, in points: its points, springs (two per point) and entries of
/// its per-point spring lists (four per point) are numbered in 32 bits. Below it, what limits a tube is the memory
/// it needs ([`crate::limits`]), which can be overridden; this cannot.
pub const MAX_TUBE_POINTS: usize = (u32::MAX / 4) as usize;

/// Checks a tube size against [`MAX_TUBE_POINTS`].
pub fn check_tube_points(wales: usize, courses: usize) -> std::result::Result<(), String> {
    match wales.checked_mul(courses) {
        Some(n) if n <= MAX_TUBE_POINTS => Ok(()),
        _ => Err(format!(
            "{wales}×{courses} points is over the {MAX_TUBE_POINTS} points a knit's 32-bit \
             indices can number"
        )),
    }
}

/// Checks a memory limit in GiB is a positive number.
pub fn check_memory_limit(gib: f64) -> std::result::Result<(), String> {
    if gib.is_finite() && gib > 0.0 {
        Ok(())
    } else {
        Err(format!("must be a positive number of GiB, got {gib}"))
    }
}

/// Checks that axis points are finite and distinct.
pub fn check_axis(axis: &LegAxis) -> std::result::Result<(), String> {
    let finite = axis.bottom.iter().chain(&axis.top).all(|c| c.is_finite());
    if !finite {
        return Err("coordinates must be finite numbers".into());
    }
    if axis.bottom == axis.top {
        return Err("bottom and top must be different points".into());
    }
    Ok(())
}

/// Checks a convergence tolerance is in (0, 1).
pub fn check_tolerance(tolerance: f64) -> std::result::Result<(), String> {
    if tolerance.is_finite() && tolerance > 0.0 && tolerance < 1.0 {
        Ok(())
    } else {
        Err(format!("must be in (0, 1), got {tolerance}"))
    }
}

/// Checks a stretch factor is usable.
pub fn check_stretch_factor(factor: f64) -> std::result::Result<(), String> {
    if factor.is_finite() && factor > 0.0 && factor <= MAX_STRETCH {
        Ok(())
    } else {
        Err(format!("must be in (0, {MAX_STRETCH}], got {factor}"))
    }
}

/// Turns a serde_json error into a one-line `path:line:column: message` error.
fn syntax_error(name: &str, e: &serde_json::Error) -> Error {
    let full = e.to_string();
    // serde_json appends " at line L column C"; we print the position in front instead.
    let message = match full.rfind(" at line ") {
        Some(at) => full[..at].to_string(),
        None => full,
    };
    Error::SceneSyntax {
        path: name.to_string(),
        line: e.line(),
        column: e.column(),
        message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_object_is_the_default_scene() {
        let scene = Scene::from_json("{}", "t").unwrap();
        assert_eq!(
            scene,
            Scene {
                effects: default_effects(),
                outputs: default_outputs(),
                ..Scene::default()
            }
        );
    }

    #[test]
    fn bundled_scene_is_valid() {
        Scene::load(None).unwrap();
    }

    #[test]
    fn malformed_json_reports_line_and_column() {
        let err = Scene::from_json(
            "{\n  \"knit\": {\n    \"pattern\": \"plain\",,\n}",
            "s.json",
        )
        .unwrap_err();
        let text = err.to_string();
        assert!(text.starts_with("s.json:3:"), "{text}");
        assert!(!text.contains(" at line "), "{text}");
    }

    #[test]
    fn unknown_field_is_named() {
        let err = Scene::from_json("{\"solver\": {\"timestep\": 0.1}}", "s.json").unwrap_err();
        assert!(
            err.to_string().contains("unknown field `timestep`"),
            "{err}"
        );
    }

    #[test]
    fn negative_stiffness_names_the_field() {
        let err = Scene::from_json(
            r#"{"yarns": {"support": {"stiffness": -1, "radius_m": 1e-5}}}"#,
            "s.json",
        )
        .unwrap_err();
        assert_eq!(
            err.to_string(),
            "s.json: yarns.support.stiffness: must be a positive number, got -1"
        );
    }

    #[test]
    fn plain_pattern_with_alternating_yarns_is_refused() {
        let err = Scene::from_json(
            r#"{"knit": {"pattern": "plain"}, "effects": ["alternating_yarns"]}"#,
            "s.json",
        )
        .unwrap_err();
        assert!(err.to_string().contains("alternating_yarns"), "{err}");
    }

    #[test]
    fn render_settings_are_checked_by_field() {
        let err = Scene::from_json(r#"{"render": {"spp": 0}}"#, "s.json").unwrap_err();
        assert!(
            err.to_string()
                .starts_with("s.json: render.spp: must be 1 to"),
            "{err}"
        );
        let err = Scene::from_json(r#"{"render": {"width": 8192, "height": 8192}}"#, "s.json")
            .unwrap_err();
        assert!(err.to_string().contains("over the limit"), "{err}");
        let err = Scene::from_json(r#"{"render": {"view": "top"}}"#, "s.json").unwrap_err();
        assert!(err.to_string().contains("unknown variant `top`"), "{err}");
        let scene = Scene::from_json(r#"{"render": {"view": "three-quarter"}}"#, "s").unwrap();
        assert_eq!(scene.render.view, View::ThreeQuarter);
    }

    #[test]
    fn zero_patch_size_is_refused() {
        let err = Scene::from_json(r#"{"patch": {"size": [0, 10]}}"#, "s.json").unwrap_err();
        assert!(err.to_string().contains("patch.size"), "{err}");
    }
}
