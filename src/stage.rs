//! The stages of a run: what a command's plan lists ([`crate::plan`]), its run executes and its
//! report records ([`crate::report`]), and the files a stage encodes. Also what a running stage
//! tells its caller: the time it took ([`StageTimes`]) and, for a long one, its progress
//! ([`Progress`]). It sits below the fit library ([`crate::fit`]), whose stages are these.

use std::fmt;
use std::time::Instant;

use serde::Serialize;

use crate::knit::Stretch;

/// One step of a run: what the plan lists, the run executes and the report records.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stage {
    /// Read the leg file and check the fit's memory estimate before decoding it.
    LoadLeg,
    /// Find the leg to dress and its landmarks (only where no axis is given).
    FindLandmarks,
    /// Convert the given axis to world space, or place it on the landmarks; check the leg goes
    /// around it.
    FindAxis,
    /// Build the contact queries' structure over the leg.
    BuildCollider,
    /// The paper's solver only: knit the tube at the asked-for size (the multilevel solver knits
    /// each of its grids inside [`Stage::Fit`]).
    KnitTube,
    /// Relax the tube onto the leg with sliding contact.
    Fit,
    /// Move out any point a cached tangent plane let dip below the offset.
    ExactContactPass,
    /// Measure the deepest yarn point inside the leg against the exact triangles.
    CheckPenetration,
    /// A posed leg fitted in its rest pose (its rig's, or straightened): carry the stocking into
    /// the pose the file shows.
    Pose,
    /// Stitch density, stretch and coverage per leg vertex.
    LegAttributes,
    /// Build the knit at the real stitch count and lay it on the skin in the fitted grid.
    LayStitches,
    /// Every real stitch as a loop polyline.
    KnitLoops,
    /// Reroute yarn segments that cut through the leg over the skin (paper §6.3).
    PenetrationFix,
    /// The knit as `stocking.glb`'s sheer surface, lifted clear of the skin.
    StockingSurface,
    /// Build a fresh patch for one stretch of the patch experiment.
    KnitPatch(Stretch),
    /// Relax that patch with its edges held.
    RelaxPatch(Stretch),
    /// Stitch shapes of every relaxed patch.
    MeasureStitches,
    /// `knitfit render`: read a fit's `stocking.glb`.
    ReadStocking,
    /// Encode one file in memory.
    Encode(File),
    /// Ray-trace the yarn-level preview and encode it.
    RenderPreview,
    /// Write every file, each to a temporary name then renamed.
    WriteFiles,
}

impl Stage {
    /// Every stage that carries no value (a patch stage carries its stretch, an encode its
    /// file), in the order a plan lists them.
    pub const UNPARAMETERISED: [Stage; 18] = [
        Stage::LoadLeg,
        Stage::FindLandmarks,
        Stage::FindAxis,
        Stage::BuildCollider,
        Stage::KnitTube,
        Stage::Fit,
        Stage::ExactContactPass,
        Stage::CheckPenetration,
        Stage::Pose,
        Stage::LegAttributes,
        Stage::LayStitches,
        Stage::KnitLoops,
        Stage::PenetrationFix,
        Stage::StockingSurface,
        Stage::MeasureStitches,
        Stage::ReadStocking,
        Stage::RenderPreview,
        Stage::WriteFiles,
    ];
}

impl fmt::Display for Stage {
    /// The stage's name, as in `knitfit plan` and `report.json` (`relax course=1.5`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Stage::LoadLeg => f.write_str("load leg"),
            Stage::FindLandmarks => f.write_str("find landmarks"),
            Stage::FindAxis => f.write_str("find axis"),
            Stage::BuildCollider => f.write_str("build collider"),
            Stage::KnitTube => f.write_str("knit tube"),
            Stage::Fit => f.write_str("fit"),
            Stage::ExactContactPass => f.write_str("exact contact pass"),
            Stage::CheckPenetration => f.write_str("check penetration"),
            Stage::Pose => f.write_str("pose"),
            Stage::LegAttributes => f.write_str("leg attributes"),
            Stage::LayStitches => f.write_str("lay stitches"),
            Stage::KnitLoops => f.write_str("knit loops"),
            Stage::PenetrationFix => f.write_str("penetration fix"),
            Stage::StockingSurface => f.write_str("stocking surface"),
            Stage::KnitPatch(stretch) => write!(f, "knit {stretch}"),
            Stage::RelaxPatch(stretch) => write!(f, "relax {stretch}"),
            Stage::MeasureStitches => f.write_str("measure stitches"),
            Stage::ReadStocking => f.write_str("read stocking.glb"),
            Stage::Encode(file) => write!(f, "encode {}", file.name()),
            Stage::RenderPreview => f.write_str("render preview"),
            Stage::WriteFiles => f.write_str("write files"),
        }
    }
}

impl Serialize for Stage {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_str(self)
    }
}

impl<'de> serde::Deserialize<'de> for Stage {
    /// The inverse of the name: the stage whose [`Display`](fmt::Display) is the string (a
    /// patch stage's factor read back as Rust writes it, shortest round trip, so exactly).
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Stage, D::Error> {
        use crate::knit::StretchAxis;
        let name = <String as serde::Deserialize>::deserialize(deserializer)?;
        let files = (FitFile::ALL.into_iter().map(File::Fit))
            .chain(PatchFile::ALL.into_iter().map(File::Patch));
        let stretch = |s: &str| -> Option<Stretch> {
            let (axis, factor) = s.split_once('=')?;
            let axis = [StretchAxis::Course, StretchAxis::Wale]
                .into_iter()
                .find(|a| a.name() == axis)?;
            Some(Stretch {
                axis,
                factor: factor.parse().ok()?,
            })
        };
        let stage = Stage::UNPARAMETERISED
            .into_iter()
            .chain(files.map(Stage::Encode))
            .find(|s| s.to_string() == name);
        let patch = |prefix: &str, stage: fn(Stretch) -> Stage| {
            name.strip_prefix(prefix).and_then(stretch).map(stage)
        };
        let stage = stage
            .or_else(|| patch("knit ", Stage::KnitPatch))
            .or_else(|| patch("relax ", Stage::RelaxPatch));
        // A name that reads back as another stage's (`knit course=1.50`) is not a stage's name.
        match stage {
            Some(stage) if stage.to_string() == name => Ok(stage),
            _ => Err(serde::de::Error::custom(format!(
                "no stage is named {name:?}"
            ))),
        }
    }
}

/// A file a fit encodes (the preview is rendered in [`Stage::RenderPreview`] instead).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FitFile {
    /// `stocking.glb`: the leg, the yarns and the stocking surface.
    StockingGlb,
    /// `stocking.ply`: the yarn points and segments.
    StockingPly,
    /// `leg.ply`: the leg with its attributes.
    LegPly,
    /// `density.png`: the leg coloured by stitch density.
    DensityPicture,
}

impl FitFile {
    /// Every file a fit can encode.
    pub const ALL: [FitFile; 4] = [
        FitFile::StockingGlb,
        FitFile::StockingPly,
        FitFile::LegPly,
        FitFile::DensityPicture,
    ];
}

/// A file the patch experiment encodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PatchFile {
    /// `patch.ply`: the relaxed patches' yarns.
    Ply,
    /// `patch.glb`: the same as glTF lines.
    Glb,
    /// `patch.png`: the stitch picture.
    Picture,
}

impl PatchFile {
    /// Every file the patch experiment can encode.
    pub const ALL: [PatchFile; 3] = [PatchFile::Ply, PatchFile::Glb, PatchFile::Picture];
}

/// A file one of the commands encodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum File {
    /// A fit's.
    Fit(FitFile),
    /// The patch experiment's.
    Patch(PatchFile),
}

impl File {
    /// The file's name in the output directory.
    pub fn name(self) -> &'static str {
        match self {
            File::Fit(FitFile::StockingGlb) => "stocking.glb",
            File::Fit(FitFile::StockingPly) => "stocking.ply",
            File::Fit(FitFile::LegPly) => "leg.ply",
            File::Fit(FitFile::DensityPicture) => "density.png",
            File::Patch(PatchFile::Ply) => "patch.ply",
            File::Patch(PatchFile::Glb) => "patch.glb",
            File::Patch(PatchFile::Picture) => "patch.png",
        }
    }
}

impl FitFile {
    /// The file's name in the output directory.
    pub fn name(self) -> &'static str {
        File::Fit(self).name()
    }
}

impl PatchFile {
    /// The file's name in the output directory.
    pub fn name(self) -> &'static str {
        File::Patch(self).name()
    }
}

/// Where stages report the time they took: a command's clock ([`crate::report::StageClock`])
/// records each against its plan; `()` records nothing (a library call that is not timed).
pub trait StageTimes {
    /// `stage` ran for `seconds`.
    fn record(&mut self, stage: Stage, seconds: f64);
}

impl StageTimes for () {
    fn record(&mut self, _stage: Stage, _seconds: f64) {}
}

/// Runs `work` as `stage`, its wall time recorded in `times`.
pub fn timed<T>(times: &mut dyn StageTimes, stage: Stage, work: impl FnOnce() -> T) -> T {
    let start = Instant::now();
    let out = work();
    times.record(stage, start.elapsed().as_secs_f64());
    out
}

/// Receives the progress of long stages (the CLI draws it as a progress bar); the library
/// itself prints nothing.
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
pub struct StepProgress<'a>(pub &'a mut dyn Progress);

impl crate::sim::RelaxObserver for StepProgress<'_> {
    fn on_step(&mut self, step: usize, residual: f64) {
        self.0.advance(step as u64, residual);
    }
}
