//! `report.json`: what ran, why, how long each stage took, how accurate the result is, and which
//! files were written. Every command writes one; its `details` are the command's own typed
//! record ([`FitDetails`], [`PatchDetails`], [`RenderDetails`]), so what a report holds is
//! written down here, once. Every report type reads back (`Deserialize`) as the exact inverse of
//! what it writes, a field it does not know refused, so tests read reports typed; the fields a
//! type leaves out of the JSON (`#[serde(skip)]`: a patch's sorted aspects, the estimate's grid
//! for messages) read back as their defaults.

use std::time::Instant;

use nalgebra::{Point3, Vector3};
use serde::{de, Deserialize, Deserializer, Serialize};

use crate::base::{GridSize, PerDirection};
use crate::export::YarnsWritten;
use crate::fit::pose::PoseStats;
use crate::fit::FitChecks;
use crate::knit::{Pattern, Stretch, TubeBottom, TubeHeel};
use crate::leg::landmarks::Ring;
use crate::leg::{
    Axis, Cleaned, ContactMethod, Landmarks, Leg, Side, ThighTopKind, Units, UpAxis, UpFrom,
};
use crate::limits::MemoryCheck;
use crate::plan::{Plan, PlannedStage};
use crate::post::lattice::LaidStitches;
use crate::post::penetration::PenetrationStats;
use crate::post::regions::RegionStretch;
use crate::post::stitches::SlackDetails;
use crate::post::StitchStats;
use crate::preview::PreviewStats;
use crate::scene::Effect;
use crate::sim::contact::ContactCounters;
use crate::sim::{LevelStats, RelaxStats};
use crate::stage::{timed, Stage, StageTimes};

/// One stage as it ran.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StageRecord {
    /// The stage, by name (`relax course=1.5`).
    pub name: Stage,
    /// Why it ran, as the plan said.
    pub why: String,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// Accuracy and size of a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Metrics {
    /// Mass points simulated (summed over all relaxations of the run).
    pub points: usize,
    /// Solver steps (summed over all relaxations).
    pub steps: usize,
    /// Worst final relative residual over the relaxations.
    pub residual: f64,
    /// Worst final largest move per step (iteration), relative to the shortest rest length.
    pub max_move: f64,
    /// Multilevel fit only: the final force step (largest move the unbalanced force alone would
    /// make in one iteration, over the shortest rest length), which with the residual decides
    /// convergence there.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub force_step: Option<f64>,
    /// True when every relaxation converged below the tolerance.
    pub converged: bool,
    /// Fit only: deepest yarn point inside the leg after the fit, measured against the exact
    /// triangles, metres (0 when none is inside).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_penetration_m: Option<f64>,
    /// Fit and render: triangles of the leg mesh.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub leg_triangles: Option<usize>,
}

/// The report of one run; `D` is the command's details.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report<D> {
    /// The command that ran (`patch`).
    pub command: &'static str,
    /// The scene file (or the bundled one).
    pub scene: String,
    /// Effects that ran.
    pub effects: Vec<Effect>,
    /// Stages in the order they ran.
    pub stages: Vec<StageRecord>,
    /// Accuracy and size.
    pub metrics: Metrics,
    /// What this command measured beyond the metrics.
    pub details: D,
    /// Files written, by name, the report last.
    pub outputs: Vec<String>,
    /// Wall-clock seconds of the whole run.
    pub wall_seconds: f64,
}

/// The `details` of one command's report, and the command that writes them: a report read back
/// as `Report<D>` must be that command's.
pub trait CommandDetails {
    /// The command's name, as `report.json`'s `command` holds it (`fit`).
    const COMMAND: &'static str;
}

impl CommandDetails for FitDetails {
    const COMMAND: &'static str = "fit";
}

impl CommandDetails for PatchDetails {
    const COMMAND: &'static str = "patch";
}

impl CommandDetails for RenderDetails {
    const COMMAND: &'static str = "render";
}

impl<'de, D: Deserialize<'de> + CommandDetails> Deserialize<'de> for Report<D> {
    /// The inverse of the report's JSON: every field, none unknown, and `command` that of `D`
    /// (a patch's report is not read as a fit's). Exact given exact numbers: serde_json's own
    /// parser, without its `float_roundtrip` feature, may read a 17-digit number one unit in the
    /// last place off (the integration tests read reports with a correctly rounding reader).
    fn deserialize<De: Deserializer<'de>>(deserializer: De) -> Result<Report<D>, De::Error> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Fields<D> {
            command: String,
            scene: String,
            effects: Vec<Effect>,
            stages: Vec<StageRecord>,
            metrics: Metrics,
            details: D,
            outputs: Vec<String>,
            wall_seconds: f64,
        }
        let f = Fields::<D>::deserialize(deserializer)?;
        if f.command != D::COMMAND {
            return Err(de::Error::custom(format!(
                "a report of `{}`, read as one of `{}`",
                f.command,
                D::COMMAND
            )));
        }
        Ok(Report {
            command: D::COMMAND,
            scene: f.scene,
            effects: f.effects,
            stages: f.stages,
            metrics: f.metrics,
            details: f.details,
            outputs: f.outputs,
            wall_seconds: f.wall_seconds,
        })
    }
}

/// Reads an `f64` that may have been written as `null`: `serde_json` writes every non-finite
/// number so, and where a field's only non-finite value is +∞ (nothing covered, no free point),
/// `null` reads back as +∞.
fn infinity_from_null<'de, De: Deserializer<'de>>(deserializer: De) -> Result<f64, De::Error> {
    Ok(Option::<f64>::deserialize(deserializer)?.unwrap_or(f64::INFINITY))
}

impl<D: Serialize> Report<D> {
    /// Pretty JSON, newline-terminated.
    pub fn to_json(&self) -> Vec<u8> {
        let mut bytes = serde_json::to_vec_pretty(self).expect("a report always serialises");
        bytes.push(b'\n');
        bytes
    }
}

/// `details` of a fit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitDetails {
    /// The leg as loaded.
    pub leg: LegDetails,
    /// The axis the tube was stretched along, world space.
    pub axis: Axis,
    /// The tube asked for and where it came to rest.
    pub tube: TubeDetails,
    /// What the solver did.
    pub solver: SolverDetails,
    /// Contact settings and counters over every level.
    pub contact: ContactDetails,
    /// The penetration fix's counters; `null` when it did not run.
    pub penetration_fix: Option<PenetrationStats>,
    /// Where the leg is posed (by the file's skin, or bent where its sections show the joints:
    /// `bend`): the stocking was fitted in the rest pose (`leg.landmarks`, `axis`, `tube` and `solver` are the rest pose's; the leg's
    /// `bounds_m`, `cleaned`, the fields, the checks and `metrics.max_penetration_m` the pose's)
    /// and carried into the pose; what that did. `null` otherwise.
    pub pose: Option<PoseStats>,
    /// The preview's counters; `null` when no preview was rendered.
    pub preview: Option<PreviewStats>,
    /// The memory estimate checked before the leg was decoded, and the peak measured.
    pub memory: MemoryDetails,
    /// The real stocking the grid stands for.
    pub knit: KnitDetails,
    /// The yarns `stocking.ply` and `stocking.glb` hold.
    pub yarns: YarnsDetails,
    /// `stocking.glb`'s stocking surface; `null` without `glb` in `outputs`.
    pub stocking_surface: Option<StockingSurfaceDetails>,
    /// Stitch density over the leg's vertices that yarn covers.
    pub stitch_density_per_cm2: DensityRange,
    /// Coverage (0–1) over the covered leg vertices.
    pub coverage: FieldRange,
    /// Pressure on the skin over the covered leg vertices, mmHg.
    pub pressure_mmhg: FieldRange,
    /// The checks a converged fit must also pass to be done (`knitfit fit` exits 4 when one
    /// fails).
    pub checks: FitChecks,
    /// Mean stretch of the knit on each part of the leg, toe to thigh (empty where the leg's
    /// landmarks were not looked for: a given axis).
    pub stretch_by_region: Vec<RegionStretch>,
}

/// The leg of a fit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LegDetails {
    /// The leg file.
    pub file: String,
    /// Units the file was read in (`m`).
    pub units: Units,
    /// The file's up axis (`+y`): given, or the nearest to the body's up.
    pub up_axis: UpAxis,
    /// Where `up_axis` came from: `given` (`leg.up_axis`), or with `leg.up_axis: "auto"`
    /// `anatomy` (the body's shape shows up) or `convention` (it does not: glTF's +Y).
    pub up_axis_from: UpFrom,
    /// Triangles whose winding was flipped to face outwards.
    pub reoriented_triangles: usize,
    /// What cleaning removed from the file's mesh (repeats, slivers, debris).
    pub cleaned: Cleaned,
    /// Bounds in world space, metres.
    pub bounds_m: Bounds,
    /// The landmarks the axis was placed on; `null` when the axis was given.
    pub landmarks: Option<LandmarkDetails>,
}

/// A landmark point: world space (metres, +Y up) and the leg file's own coordinates and units.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LandmarkPoint {
    /// World space, metres.
    pub m: [f64; 3],
    /// The leg file's coordinates and units.
    pub file: [f64; 3],
}

/// A section of the leg at a landmark.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LandmarkRing {
    /// Centre of the section.
    pub centre: LandmarkPoint,
    /// Girth (convex perimeter), metres.
    pub girth_m: f64,
    /// Height above the sole, metres.
    pub height_m: f64,
}

/// The landmarks of the dressed leg ([`crate::leg::landmarks`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LandmarkDetails {
    /// Unit vector up the body, world space.
    pub up: [f64; 3],
    /// Unit vector where the character faces, square to up, world space: where its standing
    /// feet point, on average; `null` without a foot or where they disagree. The pictures are
    /// seen from it (from +Z where that is within 20°, as glTF characters face, or `null`).
    pub facing: Option<[f64; 3]>,
    /// Legs found at the bottom of the mesh.
    pub legs_found: usize,
    /// The dressed leg's side (`left`, `right`); `null` when the file holds one leg.
    pub side: Option<Side>,
    /// The leg's lowest point.
    pub sole: LandmarkPoint,
    /// The foot's furthest point forward; `null` when the leg has no foot.
    pub toe_tip: Option<LandmarkPoint>,
    /// Unit vector from the ankle to the toe, world space; `null` without a foot.
    pub foot_direction: Option<[f64; 3]>,
    /// The narrowest section above the foot.
    pub ankle: LandmarkRing,
    /// The narrowest section between calf and thigh.
    pub knee: LandmarkRing,
    /// The highest section of the leg alone.
    pub thigh_top: LandmarkRing,
    /// `crotch` (where the legs join) or `cut` (where the mesh ends).
    pub thigh_top_kind: ThighTopKind,
    /// The joints of this leg as the file's rig names them; `null` where the file has no skin
    /// naming a leg's joints, or its joints do not lie in this leg's sections.
    pub rig: Option<RigDetails>,
}

/// The rig's joints of the dressed leg ([`crate::leg::rig`]), and how far they are from the
/// sections the geometry found.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigDetails {
    /// The joints' naming scheme: `mixamo`, `makehuman`, `rigify`, `unreal`, `vrm`, `smpl` or
    /// `named`.
    pub naming: String,
    /// The side the rig names this leg.
    pub side: Side,
    /// The hip joint.
    pub hip: LandmarkPoint,
    /// The knee joint.
    pub knee: LandmarkPoint,
    /// The ankle joint.
    pub ankle: LandmarkPoint,
    /// The ball of the foot; `null` where the rig has no toe joint.
    pub toe: Option<LandmarkPoint>,
    /// Distance from the ankle section's centre to the ankle joint, metres.
    pub ankle_from_section_m: f64,
    /// Distance from the knee section's centre to the knee joint, metres.
    pub knee_from_section_m: f64,
}

impl LandmarkDetails {
    /// The report's form of `landmarks` found on `leg`.
    pub fn of(landmarks: &Landmarks, leg: &Leg) -> LandmarkDetails {
        let point = |p: [f64; 3]| LandmarkPoint {
            m: p,
            file: leg.file_from_world(&Point3::from(p)).coords.into(),
        };
        let sole = landmarks.sole_s();
        let ring = |r: &Ring| LandmarkRing {
            centre: point(r.centre),
            girth_m: r.girth_m,
            height_m: r.s - sole,
        };
        LandmarkDetails {
            up: landmarks.up,
            facing: landmarks.facing,
            legs_found: landmarks.legs_found,
            side: landmarks.side,
            sole: point(landmarks.sole),
            toe_tip: landmarks.foot.map(|f| point(f.toe_tip)),
            foot_direction: landmarks.foot.map(|f| f.direction),
            ankle: ring(&landmarks.ankle),
            knee: ring(&landmarks.knee),
            thigh_top: ring(&landmarks.thigh_top),
            thigh_top_kind: landmarks.thigh_top_kind,
            rig: landmarks.rig.map(|r| RigDetails {
                naming: r.naming.to_string(),
                side: r.side,
                hip: point(r.joints.hip),
                knee: point(r.joints.knee),
                ankle: point(r.joints.ankle),
                toe: r.joints.toe.map(point),
                ankle_from_section_m: r.ankle_m,
                knee_from_section_m: r.knee_m,
            }),
        }
    }

    /// Height of `p_m` (world space, metres) above the sole, along up, metres.
    pub fn height_m(&self, p_m: [f64; 3]) -> f64 {
        (Vector3::from(p_m) - Vector3::from(self.sole.m)).dot(&Vector3::from(self.up))
    }
}

/// How near the ankle's height the stocking's bottom must be to be called the ankle, metres.
const AT_THE_ANKLE_M: f64 = 0.005;

/// Where the stocking runs, in words, metres to the millimetre: `the left leg, from the ankle
/// (0.117 m above the sole) to 0.050 m below the crotch, 0.580 m long`, `the left leg, from the
/// toe, over the heel, to 0.050 m below the crotch, 0.924 m long along the leg and foot` (a
/// stocking to the toe, `to_the_toe_m` its centreline's length), or `along --axis, 0.432 m
/// long`. `landmarks` are those `axis` was placed on (`None` for a given axis). What
/// `knitfit fit` prints after its summary and `knitfit plan` shows.
pub fn stocking_extent(
    axis: &Axis,
    landmarks: Option<&LandmarkDetails>,
    to_the_toe_m: Option<f64>,
) -> String {
    let length = axis.length();
    let Some(l) = landmarks else {
        return format!("along {}, {length:.3} m long", axis.source.describe());
    };
    let leg = l
        .side
        .map(|side| format!("the {} leg, ", side.name()))
        .unwrap_or_default();
    let bottom = l.height_m(axis.bottom);
    let from = if to_the_toe_m.is_some() {
        "the toe, over the heel,".to_string()
    } else if (bottom - l.ankle.height_m).abs() <= AT_THE_ANKLE_M {
        format!("the ankle ({bottom:.3} m above the sole)")
    } else {
        format!("{bottom:.3} m above the sole")
    };
    let below = l.thigh_top.height_m - l.height_m(axis.top);
    let thigh_top = match l.thigh_top_kind {
        ThighTopKind::Crotch => "the crotch",
        ThighTopKind::Cut => "the cut",
    };
    // A top at the thigh top itself is not "-0.000 m below" it.
    let to = if below < 0.0005 {
        thigh_top.to_string()
    } else {
        format!("{below:.3} m below {thigh_top}")
    };
    match to_the_toe_m {
        Some(path) => format!("{leg}from {from} to {to}, {path:.3} m long along the leg and foot"),
        None => format!("{leg}from {from} to {to}, {length:.3} m long"),
    }
}

/// An axis-aligned box, metres.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bounds {
    /// Lowest corner.
    pub min: [f64; 3],
    /// Highest corner.
    pub max: [f64; 3],
}

/// The tube of a fit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TubeDetails {
    /// Points around.
    pub wales: usize,
    /// Rings along.
    pub courses: usize,
    /// Rest length of a course spring, metres.
    pub rest_course_spacing_m: f64,
    /// Rest length of a wale spring, metres: the welt's, and every one's but over the toe's tip
    /// on a grid graded finer there.
    pub rest_wale_spacing_m: f64,
    /// On a grid graded finer over the toe's tip (a coarse grid of a stocking to the toe), the
    /// rest length of its last wale springs, metres; absent where the courses are even.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub toe_tip_wale_spacing_m: Option<f64>,
    /// Relaxed length between the axis points, metres.
    pub relaxed_length_m: f64,
    /// Relaxed circumference, metres.
    pub relaxed_circumference_m: f64,
    /// The springs' stiffness factors for the stitch's shape.
    pub stiffness_scale: PerDirection,
    /// Where the stocking ends at the bottom: `toe` (closed by a toe seam) or `ankle` (open).
    pub bottom: TubeBottom,
    /// Length of the stocking's centreline, metres (a stocking to the toe: along the leg, around
    /// the heel and along the foot).
    pub centreline_m: f64,
    /// The heel: `none` or `pocket` (short rows).
    pub heel: TubeHeel,
    /// Nearest and furthest yarn along the stocking's centreline, metres from its start (the
    /// bottom of an open tube, the welt of a stocking to the toe).
    pub axial_range_m: [f64; 2],
    /// Courses out of order along the centreline (the fit sliding; refused beyond 10%).
    pub bunched_courses: usize,
    /// Where the courses lie closer than knitted (surplus fabric that would wrinkle): never
    /// refused; per point, the `slack` attribute.
    pub slack: SlackDetails,
    /// Where the fabric rested on the toes boxed (bridging the gaps between them) rather than
    /// on the skin: every stocking to the toe whose box could be built; `null` on an open tube.
    pub toe_box: Option<ToeBoxDetails>,
}

/// The toe box of a stocking to the toe ([`crate::knit::path::TubePath::box_the_toes`]): the skin
/// beyond its rim's plane, towards the toe, was the convex hull of the toes' sections during
/// the fit. Its fields on the leg come from fabric that bridged the toes' clefts there.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToeBoxDetails {
    /// Centre of the box's open rim, on the foot's section there, metres.
    pub rim_centre_m: [f64; 3],
    /// Unit normal of the rim's plane, towards the toe.
    pub towards_toe: [f64; 3],
    /// From the rim's plane to just past the toe tip, metres.
    pub length_m: f64,
}

/// The solver of a fit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case", deny_unknown_fields)]
pub enum SolverDetails {
    /// The paper's explicit steps.
    Paper {
        /// `solver.tolerance`.
        tolerance: f64,
        /// `solver.time_step`.
        time_step: f64,
        /// The explicit stability limit, solver time units (+∞, written `null`, when no point
        /// is free).
        #[serde(deserialize_with = "infinity_from_null")]
        time_step_limit: f64,
        /// Sub-steps per step.
        substeps_per_step: usize,
    },
    /// The multilevel solver.
    Multilevel {
        /// `solver.tolerance`.
        tolerance: f64,
        /// Iterations weighted by each level's size over the finest's.
        fine_grid_equivalent_iterations: f64,
        /// Each level, coarsest first.
        levels: Vec<LevelStats>,
        /// Where the grid asked for had not settled when the solver ran out of steps, in
        /// words: its courses, how far along the stocking, the nearest landmark, and whether
        /// the residual was within the tolerance; `null` when it converged.
        unsettled_at: Option<String>,
    },
}

/// The contact of a fit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactDetails {
    /// `bvh` or `brute`.
    pub method: ContactMethod,
    /// Distance kept between yarn centre line and skin, metres.
    pub offset_m: f64,
    /// Counters over every level.
    #[serde(flatten)]
    pub counters: ContactCounters,
}

/// The memory of a fit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MemoryDetails {
    /// The estimate against the limit, checked before the leg was decoded.
    pub check: MemoryCheck,
    /// Peak resident set of the process, bytes (`null` where the system does not say).
    pub peak_resident_bytes: Option<u64>,
}

/// The range of the stitch density over the covered leg vertices.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DensityRange {
    /// Leg vertices with yarn near them.
    pub leg_vertices_covered: usize,
    /// All leg vertices.
    pub leg_vertices: usize,
    /// Lowest density, stitches per cm² (+∞, written `null`, when nothing is covered).
    #[serde(deserialize_with = "infinity_from_null")]
    pub min: f64,
    /// Highest density, stitches per cm².
    pub max: f64,
}

/// The lowest, median and highest value of a field over the covered leg vertices (0 when none
/// is covered).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FieldRange {
    /// Lowest value.
    pub min: f64,
    /// Median value.
    pub median: f64,
    /// Highest value.
    pub max: f64,
}

impl FieldRange {
    /// The range of `values` (all 0 when empty).
    pub fn of(values: &[f64]) -> FieldRange {
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        FieldRange {
            min: sorted.first().copied().unwrap_or(0.0),
            median: sorted.get(sorted.len() / 2).copied().unwrap_or(0.0),
            max: sorted.last().copied().unwrap_or(0.0),
        }
    }
}

/// The yarns a fit's files hold (`outputs`: the grid's, `stitches` or `loops`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct YarnsDetails {
    /// `grid`, `stitches` or `loops`.
    pub written: YarnsWritten,
    /// Yarn points written (after the penetration fix).
    pub points: usize,
    /// Yarn segments written.
    pub segments: usize,
    /// The real-count knit the stitches or loops come from; `null` for the grid's yarns.
    pub real_stitches: Option<LaidStitches>,
}

/// `stocking.glb`'s sheer stocking surface, lifted off the knit (`post::surfaces`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StockingSurfaceDetails {
    /// How far it is lifted along its normals, metres.
    pub lift_m: f64,
    /// The clearance from the skin every triangle's corners, edge midpoints and centre keep,
    /// metres.
    pub clearance_m: f64,
    /// Triangles still closer than that after the further lifting (0 expected).
    pub triangles_dipping: usize,
}

/// The real stocking a fit's grid stands for (`knit::Fabric`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KnitDetails {
    /// Needles: real stitches around (`knit.needles`, or the given relaxed circumference over
    /// the stitch's width).
    pub needles: f64,
    /// Real courses along the relaxed stocking.
    pub courses: f64,
    /// The relaxed stitch, metres: between wales along a course, between courses along a wale.
    pub stitch_m: PerDirection,
    /// Yarn diameters from their denier, micrometres.
    pub yarn_diameter_um: YarnValues,
    /// One nylon stitch's stiffness, newtons per metre of extension.
    pub loop_stiffness_n_per_m: f64,
    /// Real stitches one grid cell stands for, around (course) and along (wale).
    pub stitches_per_cell: PerDirection,
}

/// A value per yarn material.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct YarnValues {
    /// The nylon yarn.
    pub nylon: f64,
    /// The support yarn.
    pub support: f64,
}

/// `details` of the patch experiment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PatchDetails {
    /// `patch.size`, `[wales, courses]`.
    pub size: GridSize,
    /// `knit.pattern`.
    pub pattern: Pattern,
    /// One entry per stretch, in the scene's order.
    pub patches: Vec<PatchRun>,
    /// Course-over-wale anisotropy when a square patch was stretched by the same factor both
    /// ways (`crate::post::anisotropy`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub anisotropy: Option<f64>,
}

/// One relaxed patch. Read through `PatchRunFields`, which lists the relaxation's fields flat, as
/// written, and reads its stability limit's `null` back as infinite.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "PatchRunFields")]
pub struct PatchRun {
    /// The stretch applied.
    pub stretch: Stretch,
    /// Points.
    pub points: usize,
    /// What the relaxation did: steps, sub-steps per step, the stability limit, the final
    /// residual and largest move, whether it converged.
    #[serde(flatten)]
    pub relaxation: RelaxStats,
    /// Stitch shapes (`null` for a patch too small to measure).
    pub stitches: Option<StitchStats>,
}

/// A [`PatchRun`] as its JSON holds it: the relaxation's fields flat beside the patch's, the
/// stability limit `null` when infinite (a patch whose every point is held has no free point).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PatchRunFields {
    stretch: Stretch,
    points: usize,
    steps: usize,
    substeps_per_step: usize,
    #[serde(deserialize_with = "infinity_from_null")]
    time_step_limit: f64,
    residual: f64,
    max_move: f64,
    converged: bool,
    stitches: Option<StitchStats>,
}

impl From<PatchRunFields> for PatchRun {
    fn from(f: PatchRunFields) -> PatchRun {
        PatchRun {
            stretch: f.stretch,
            points: f.points,
            relaxation: RelaxStats {
                steps: f.steps,
                substeps_per_step: f.substeps_per_step,
                time_step_limit: f.time_step_limit,
                residual: f.residual,
                max_move: f.max_move,
                converged: f.converged,
            },
            stitches: f.stitches,
        }
    }
}

/// `details` of `knitfit render`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderDetails {
    /// The `stocking.glb` rendered.
    pub input: String,
    /// The render's counters.
    pub render: PreviewStats,
    /// Samples that hit yarn over samples that hit the leg.
    pub yarn_covered_fraction: f64,
}

/// Times the stages of a plan as they run.
#[derive(Debug)]
pub struct StageClock {
    started: Instant,
    planned: Vec<PlannedStage>,
    records: Vec<StageRecord>,
}

impl StageClock {
    /// A clock for the stages of `plan`, started now.
    pub fn new(plan: &Plan) -> StageClock {
        StageClock {
            started: Instant::now(),
            planned: plan.stages.clone(),
            records: Vec::new(),
        }
    }

    /// Runs `work` as `stage` and records its wall time with the plan's reason.
    pub fn time<T>(&mut self, stage: Stage, work: impl FnOnce() -> T) -> T {
        timed(self, stage, work)
    }

    /// The stages recorded so far, in order.
    pub fn records(&self) -> &[StageRecord] {
        &self.records
    }

    /// Seconds spent in `stages`, summed.
    pub fn seconds_in(&self, stages: &[Stage]) -> f64 {
        self.records
            .iter()
            .filter(|r| stages.contains(&r.name))
            .map(|r| r.seconds)
            .sum()
    }

    /// Seconds since the clock started.
    pub fn wall_seconds(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }
}

impl StageTimes for StageClock {
    /// Records `stage` with the plan's reason. A stage the plan does not list is a bug in the
    /// run, not in its input.
    fn record(&mut self, stage: Stage, seconds: f64) {
        let planned = self.planned.iter().find(|p| p.stage == stage);
        debug_assert!(planned.is_some(), "stage {stage} runs but is not planned");
        self.records.push(StageRecord {
            name: stage,
            why: planned.map(|p| p.why.clone()).unwrap_or_default(),
            seconds,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::knit::StretchAxis;
    use crate::stage::{File, FitFile, PatchFile};

    /// Every kind of stage once, a patch's with factors Rust writes in full (`0.30000000000000004`)
    /// or without a point (`2`).
    fn every_stage() -> Vec<Stage> {
        let awkward = Stretch {
            axis: StretchAxis::Course,
            factor: 0.1 + 0.2,
        };
        let whole = Stretch {
            axis: StretchAxis::Wale,
            factor: 2.0,
        };
        let mut stages = Stage::UNPARAMETERISED.to_vec();
        stages.extend([awkward, whole].map(Stage::KnitPatch));
        stages.extend([awkward, whole].map(Stage::RelaxPatch));
        stages.extend(FitFile::ALL.map(|f| Stage::Encode(File::Fit(f))));
        stages.extend(PatchFile::ALL.map(|f| Stage::Encode(File::Patch(f))));
        // No wildcard: a new kind of stage does not compile here until it is in the lists above.
        for stage in &stages {
            match stage {
                Stage::LoadLeg
                | Stage::FindLandmarks
                | Stage::FindAxis
                | Stage::BuildCollider
                | Stage::KnitTube
                | Stage::Fit
                | Stage::ExactContactPass
                | Stage::CheckPenetration
                | Stage::Pose
                | Stage::LegAttributes
                | Stage::LayStitches
                | Stage::KnitLoops
                | Stage::PenetrationFix
                | Stage::StockingSurface
                | Stage::KnitPatch(_)
                | Stage::RelaxPatch(_)
                | Stage::MeasureStitches
                | Stage::ReadStocking
                | Stage::Encode(File::Fit(_) | File::Patch(_))
                | Stage::RenderPreview
                | Stage::WriteFiles => {}
            }
        }
        stages
    }

    #[test]
    fn every_stage_reads_back_from_its_name() {
        for stage in every_stage() {
            let json = serde_json::to_string(&stage).unwrap();
            let back: Stage = serde_json::from_str(&json).unwrap();
            assert_eq!(back, stage, "{json}");
            assert_eq!(serde_json::to_string(&back).unwrap(), json);
        }
    }

    #[test]
    fn a_name_no_stage_has_is_refused() {
        for name in [
            "knit course=1.50",
            "relax diagonal=1.5",
            "knit course=",
            "encode report.json",
            "Fit",
            "fit ",
            "",
        ] {
            let json = serde_json::to_string(name).unwrap();
            let error = serde_json::from_str::<Stage>(&json).unwrap_err();
            assert!(error.to_string().contains("no stage is named"), "{name}");
        }
    }

    #[test]
    fn an_infinite_value_written_as_null_reads_back_infinite() {
        let nothing_covered = DensityRange {
            leg_vertices_covered: 0,
            leg_vertices: 12,
            min: f64::INFINITY,
            max: 0.0,
        };
        let json = serde_json::to_string(&nothing_covered).unwrap();
        assert!(json.contains(r#""min":null"#), "{json}");
        let back: DensityRange = serde_json::from_str(&json).unwrap();
        assert_eq!(back, nothing_covered);
    }

    #[test]
    fn a_field_no_report_type_has_is_refused() {
        let error = serde_json::from_str::<FieldRange>(r#"{"min":0,"median":1,"max":2,"mean":1}"#)
            .unwrap_err();
        assert!(
            error.to_string().contains("unknown field `mean`"),
            "{error}"
        );
    }
}
