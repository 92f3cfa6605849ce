//! `knitfit plan`: what a fit or patch would do, without doing it. Shows the [`Plan`] (effects,
//! force terms, stages with why each runs, what is left out and why, files) and, for a fit, the
//! memory estimate against the limit ([`crate::limits`]) and where the stocking goes. Reads the
//! scene and the leg file; unless the memory check would refuse the fit, decodes the leg and
//! finds its landmarks and axis as the fit does ([`fit::place()`]), so a plan refuses a leg the
//! fit would refuse. Simulates nothing and writes nothing.

use std::path::{Path, PathBuf};

use nalgebra::Point3;
use serde::Serialize;

use crate::error::Result;
use crate::fit;
use crate::leg::unbend::Bend;
use crate::leg::{
    decode_leg, read_leg_file, Axis, Landmarks, Leg, ThighTopKind, Units, UpAxis, UpFrom,
};
use crate::limits::{MemoryCheck, MemoryEstimate, MemoryLimit};
use crate::plan::{LeftOut, Plan, PlannedStage};
use crate::report::{stocking_extent, LandmarkDetails, LandmarkRing};
use crate::scene::{Effect, LoadedScene};
use crate::sim::ForceTerms;
use crate::stage::Stage;

/// What `knitfit plan` shows.
#[derive(Clone, Debug)]
pub struct PlanOutcome {
    /// The plan the run would follow.
    pub plan: Plan,
    /// How the scene is named.
    pub scene: String,
    /// Fit only: the leg file and the triangles it declares.
    pub leg: Option<(PathBuf, usize)>,
    /// Fit only: the memory estimate against the limit.
    pub memory: Option<MemoryCheck>,
    /// Fit only: where the stocking goes.
    pub placement: Option<Placement>,
    /// The files the run would write, report included, in its output directory.
    pub files: Vec<PathBuf>,
}

/// Where a planned fit puts the stocking.
#[derive(Clone, Debug)]
pub enum Placement {
    /// The fit would be refused for memory before decoding the leg, so the plan does not
    /// decode it either.
    NotDecoded,
    /// The leg decoded and the axis placed (on the landmarks, or given), as the fit will.
    Placed(Box<Placed>),
}

/// The leg of a planned fit as decoded, its landmarks, and the stocking's axis.
#[derive(Clone, Debug)]
pub struct Placed {
    /// Unit vector up the body, world space.
    pub up: [f64; 3],
    /// The file's up axis: given, or the nearest to the body's up.
    pub up_axis: UpAxis,
    /// Where `up_axis` came from.
    pub up_axis_from: UpFrom,
    /// The units the file was read in.
    pub units: Units,
    /// The landmarks, as `report.json` has them; `None` where the axis is given.
    pub landmarks: Option<LandmarkDetails>,
    /// The stocking's axis, world space.
    pub axis: Axis,
    /// The axis's bottom and top in the leg file's coordinates and units (what `--axis` takes).
    pub axis_file: [[f64; 3]; 2],
    /// For a stocking to the toe, the length of its path along the leg and foot, metres.
    pub to_the_toe_m: Option<f64>,
    /// True where the leg is placed in a rest pose ([`fit::in_rest_pose`]): its rig's, or
    /// straightened at the joints its sections show.
    pub in_rest_pose: bool,
    /// Where the rest pose is the leg straightened (no rig): how it bends.
    pub straightened: Option<Bend>,
}

/// The plan of `knitfit fit` for `loaded`, writing into `out_dir`.
///
/// Errors: the leg file's, as the fit would meet them (unreadable, not glTF or PLY, compressed);
/// unless the fit would be refused for memory first, the fit's refusals of the decoded leg as
/// well (implausible height, no landmarks, an axis the leg does not go around).
pub fn plan_fit(loaded: &LoadedScene, out_dir: &Path) -> Result<PlanOutcome> {
    let mut plan = Plan::fit(&loaded.scene);
    let settings = plan.fit_settings(loaded);
    let leg_path = loaded.leg_path();
    let file = read_leg_file(&leg_path)?;
    let triangles = file.declared_triangles();
    // As the fit does: the memory check before the leg is decoded.
    let tube = &settings.tube;
    let memory = settings
        .memory
        .before_the_leg(tube.wales, tube.courses, triangles);
    let placement = if memory.enforce(&leg_path.display().to_string()).is_err() {
        Placement::NotDecoded
    } else {
        let leg = decode_leg(file, settings.load.units, settings.load.up)?;
        // A posed leg is placed in its rest pose (its rig's, or straightened), as the fit does.
        let (leg, posed) = fit::in_rest_pose(leg, &settings.place)?;
        // The fit's own stage, untimed.
        let placed = fit::place(&leg, &settings.place, tube, &mut ())?;
        let mut shown = Placed::new(&leg, placed.landmarks.as_ref(), placed.axis);
        shown.to_the_toe_m = placed.path.as_ref().map(|p| p.length());
        shown.in_rest_pose = posed.is_some();
        shown.straightened = posed.as_ref().and_then(|p| p.bend);
        if posed.is_none() {
            plan.without(Stage::Pose);
        }
        Placement::Placed(Box::new(shown))
    };
    Ok(PlanOutcome {
        memory: Some(memory),
        leg: Some((leg_path, triangles)),
        placement: Some(placement),
        files: files(&plan, out_dir),
        scene: loaded.name.clone(),
        plan,
    })
}

impl Placed {
    fn new(leg: &Leg, landmarks: Option<&Landmarks>, axis: Axis) -> Placed {
        let file = |p: Point3<f64>| leg.file_from_world(&p).coords.into();
        Placed {
            up: leg.up.into(),
            up_axis: leg.up_axis,
            up_axis_from: leg.up_from,
            units: leg.units,
            landmarks: landmarks.map(|l| LandmarkDetails::of(l, leg)),
            axis_file: [file(axis.bottom()), file(axis.top())],
            axis,
            to_the_toe_m: None,
            in_rest_pose: false,
            straightened: None,
        }
    }
}

/// The plan of `knitfit patch` for `loaded`, writing into `out_dir`.
pub fn plan_patch(loaded: &LoadedScene, out_dir: &Path) -> PlanOutcome {
    let plan = Plan::patch(&loaded.scene);
    PlanOutcome {
        memory: None,
        leg: None,
        placement: None,
        files: files(&plan, out_dir),
        scene: loaded.name.clone(),
        plan,
    }
}

fn files(plan: &Plan, out_dir: &Path) -> Vec<PathBuf> {
    plan.file_names()
        .into_iter()
        .map(|name| out_dir.join(name))
        .collect()
}

impl PlanOutcome {
    /// The plan as JSON, for scripts: `command`, `scene`, `leg` (`file`, `declared_triangles`,
    /// and as decoded `up_axis`, `up_axis_from` (`given`, `anatomy` or `convention`), `in_rest_pose`, true where a posed leg is
    /// placed in a rest pose, and `straightened`, where that rest pose is the leg straightened
    /// without a rig, its bend as `details.pose.bend` gives it; null for a patch), `effects`,
    /// `forces`,
    /// `stages` and `left_out` (`name`, `why`), `files`, `memory` (`estimate` by part with
    /// `total_bytes`, `limit`, `allow_large`, `fits`; null for a patch), `landmarks` (as
    /// `details.leg.landmarks` of `report.json`; null where the axis is given), `axis` (as
    /// `details.axis`) and `axis_file` (its `bottom` and `top` in the leg file's coordinates).
    /// What comes from the decoded leg is null for a patch and for a fit the memory check
    /// would refuse.
    pub fn to_json(&self) -> serde_json::Value {
        let p = &self.plan;
        let placed = match &self.placement {
            Some(Placement::Placed(placed)) => Some(placed.as_ref()),
            _ => None,
        };
        let view = PlanJson {
            command: p.command,
            scene: &self.scene,
            leg: self.leg.as_ref().map(|(file, triangles)| LegJson {
                file: file.display().to_string(),
                declared_triangles: *triangles,
                up_axis: placed.map(|p| p.up_axis),
                up_axis_from: placed.map(|p| p.up_axis_from),
                in_rest_pose: placed.map(|p| p.in_rest_pose),
                straightened: placed.and_then(|p| p.straightened),
            }),
            effects: &p.effects,
            forces: &p.forces,
            stages: &p.stages,
            left_out: &p.left_out,
            files: self.files.iter().map(|f| f.display().to_string()).collect(),
            memory: self.memory.as_ref().map(|m| MemoryJson {
                estimate: &m.estimate,
                limit: &m.limit,
                allow_large: m.allow_large,
                fits: m.fits(),
            }),
            landmarks: placed.and_then(|p| p.landmarks.as_ref()),
            axis: placed.map(|p| &p.axis),
            axis_file: placed.map(|p| AxisFileJson {
                bottom: p.axis_file[0],
                top: p.axis_file[1],
            }),
        };
        serde_json::to_value(view).expect("a plan always serialises")
    }

    /// The plan as text for a person: a header, then one line per stage with why it runs.
    pub fn to_text(&self) -> String {
        let p = &self.plan;
        let mut out = format!("knitfit {}: scene {}", p.command, self.scene);
        if let Some((file, triangles)) = &self.leg {
            out += &format!(", leg {} ({triangles} triangles)", file.display());
        }
        out += "\n";
        let effects: Vec<&str> = p.effects.iter().map(|e| e.name()).collect();
        out += &format!(
            "effects: {}\n",
            if effects.is_empty() {
                "none".to_string()
            } else {
                effects.join(", ")
            }
        );
        let [nylon, support, _] = p.forces.stiffness;
        out += &format!("forces: springs (eq. 1, c1 = {nylon} nylon, {support} support)");
        if let Some(c2) = p.forces.connection_factor {
            out += &format!(" + yarn connection (eq. 2, c2 = {c2})");
        }
        out += "\n";
        let width = p
            .stages
            .iter()
            .map(|s| s.stage.to_string().chars().count())
            .chain(p.left_out.iter().map(|s| s.name.chars().count()))
            .max()
            .unwrap_or(0);
        out += "stages, in order:\n";
        for (i, s) in p.stages.iter().enumerate() {
            out += &format!(
                "  {:>2}. {:<width$}  {}\n",
                i + 1,
                s.stage.to_string(),
                s.why
            );
        }
        if !p.left_out.is_empty() {
            out += "left out:\n";
            for s in &p.left_out {
                out += &format!("      {:<width$}  {}\n", s.name, s.why);
            }
        }
        let files: Vec<String> = self.files.iter().map(|f| f.display().to_string()).collect();
        out += &format!("files: {}\n", files.join(", "));
        if let Some(memory) = &self.memory {
            out += &format!("memory: {}\n", memory.summary());
        }
        if let Some(placement) = &self.placement {
            out += &placement.to_text();
        }
        out
    }
}

impl Placement {
    /// Where the stocking goes, for a person: the landmarks in metres to the millimetre, the
    /// stocking's extent and its axis (also as `--axis` takes it).
    fn to_text(&self) -> String {
        let placed = match self {
            Placement::NotDecoded => {
                return "stocking: not placed: the fit would be refused for memory before the \
                        leg is decoded\n"
                    .into()
            }
            Placement::Placed(placed) => placed,
        };
        let m = |p: [f64; 3]| point_text(p, 3);
        let row = |name: &str, text: String| format!("  {name:<10} {text}\n");
        let mut out = "leg (world space, metres; heights above the sole, along up):\n".to_string();
        out += &row(
            "up",
            format!(
                "{}, the file's {} ({})",
                m(placed.up),
                placed.up_axis.name(),
                match placed.up_axis_from {
                    UpFrom::Anatomy => "found from the anatomy",
                    UpFrom::Convention =>
                        "glTF's convention: the shape does not show which end is up",
                    UpFrom::Given => "leg.up_axis",
                }
            ),
        );
        let a = &placed.axis;
        match (placed.in_rest_pose, &placed.straightened) {
            (true, Some(bend)) => {
                out += &row(
                    "pose",
                    format!(
                        "the leg bends (knee {:.0}°, thigh {:.0}° off up{}) and no rig poses \
                         it: the landmarks and axis below are the leg's straightened at the \
                         joints its sections show, where the stocking is fitted before it is \
                         carried into the pose",
                        bend.knee_deg,
                        bend.thigh_deg,
                        if bend.foot_deg > 0.0 {
                            format!(", the foot pointed {:.0}°", bend.foot_deg)
                        } else {
                            String::new()
                        }
                    ),
                )
            }
            (true, None) => out += &row(
                "pose",
                "the file's skin poses the leg: the landmarks and axis below are its rest pose's, \
                 where the stocking is fitted before the skin carries it into the pose"
                    .into(),
            ),
            _ => {}
        }
        if let Some(l) = &placed.landmarks {
            out += &landmark_rows(l, row);
        } else {
            out += &row("landmarks", "not looked for: the axis is given".into());
        }
        out += &format!(
            "stocking: {}\n",
            stocking_extent(a, placed.landmarks.as_ref(), placed.to_the_toe_m)
        );
        out += &row("axis", format!("{} → {}", m(a.bottom), m(a.top)));
        // Millimetres in the file's units, so the numbers can be given back as `--axis`.
        let decimals = (-(0.001 / placed.units.metres()).log10()).ceil().max(0.0) as usize;
        let [bottom, top] = placed.axis_file;
        let file: Vec<String> = bottom
            .iter()
            .chain(&top)
            .map(|&c| number_text(c, decimals))
            .collect();
        out += &row(
            "as --axis",
            format!("{} (the leg file's coordinates and units)", file.join(",")),
        );
        out
    }
}

/// The landmark rows of the plan's text, each made by `row(name, text)`.
fn landmark_rows(l: &LandmarkDetails, row: impl Fn(&str, String) -> String) -> String {
    let m = |p: [f64; 3]| point_text(p, 3);
    let mut out = row(
        "legs",
        match l.side {
            Some(side) => format!(
                "{} found, the {} dressed (leg.side)",
                l.legs_found,
                side.name()
            ),
            None => format!("{} found", l.legs_found),
        },
    );
    out += &row("sole", m(l.sole.m));
    out += &row(
        "toe tip",
        match (&l.toe_tip, l.foot_direction) {
            (Some(toe), Some(direction)) => {
                format!("{}, foot pointing {}", m(toe.m), m(direction))
            }
            _ => "no foot".into(),
        },
    );
    let ring = |r: &LandmarkRing| {
        format!(
            "{:.3} m above the sole, girth {:.3} m",
            r.height_m, r.girth_m
        )
    };
    out += &row("ankle", ring(&l.ankle));
    out += &row("knee", ring(&l.knee));
    let kind = match l.thigh_top_kind {
        ThighTopKind::Crotch => "the crotch",
        ThighTopKind::Cut => "the cut",
    };
    out += &row("thigh top", format!("{kind}, {}", ring(&l.thigh_top)));
    if let Some(r) = &l.rig {
        out += &row(
            "rig",
            format!(
                "{} joints of the {} leg: knee {}, ankle {}, {:.3} m and {:.3} m from the \
                 sections found",
                r.naming,
                r.side.name(),
                m(r.knee.m),
                m(r.ankle.m),
                r.knee_from_section_m,
                r.ankle_from_section_m
            ),
        );
    }
    out
}

/// A point or vector as `(x, y, z)` with `decimals` decimals.
fn point_text(p: [f64; 3], decimals: usize) -> String {
    let [x, y, z] = p.map(|c| number_text(c, decimals));
    format!("({x}, {y}, {z})")
}

/// `value` with `decimals` decimals, without the sign of a value that rounds to zero.
fn number_text(value: f64, decimals: usize) -> String {
    let text = format!("{value:.decimals$}");
    match text.strip_prefix('-') {
        Some(unsigned) if unsigned.chars().all(|c| c == '0' || c == '.') => unsigned.to_string(),
        _ => text,
    }
}

/// `knitfit plan --json`.
#[derive(Serialize)]
struct PlanJson<'a> {
    command: &'a str,
    scene: &'a str,
    leg: Option<LegJson>,
    effects: &'a [Effect],
    forces: &'a ForceTerms,
    stages: &'a [PlannedStage],
    left_out: &'a [LeftOut],
    files: Vec<String>,
    memory: Option<MemoryJson<'a>>,
    landmarks: Option<&'a LandmarkDetails>,
    axis: Option<&'a Axis>,
    axis_file: Option<AxisFileJson>,
}

#[derive(Serialize)]
struct LegJson {
    file: String,
    declared_triangles: usize,
    up_axis: Option<UpAxis>,
    up_axis_from: Option<UpFrom>,
    in_rest_pose: Option<bool>,
    straightened: Option<Bend>,
}

#[derive(Serialize)]
struct AxisFileJson {
    bottom: [f64; 3],
    top: [f64; 3],
}

#[derive(Serialize)]
struct MemoryJson<'a> {
    estimate: &'a MemoryEstimate,
    limit: &'a MemoryLimit,
    allow_large: bool,
    fits: bool,
}
