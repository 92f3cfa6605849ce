//! The fit as a library: a leg in, the stocking fitted onto it out (Sakaguchi & Miyata §6), in
//! typed stages, each given the settings it owns and never the whole scene:
//!
//! 1. [`load()`]: the leg file read, the fit's memory checked, the leg decoded;
//! 2. [`place()`]: the leg's landmarks, the stocking's axis and, to the toe, its path;
//! 3. [`size()`]: the tube's grid and relaxed size on that path, and the scene's values that
//!    need the leg checked;
//! 4. [`solve()`]: the tube knitted and relaxed onto the leg with sliding contact, and the rest
//!    state checked (a stall says where and why: [`crate::sim::stall`]);
//!    A posed leg (by its rig, or bent where its sections show it) is placed, sized and
//!    solved in its rest pose ([`in_rest_pose`]), then
//!    [`pose`] carries the stocking into the pose the file shows and relaxes it there;
//! 5. [`measure`]: density, coverage, stretch, tension and pressure per point and per leg
//!    vertex, in the real stocking's units at any grid;
//! 6. [`products()`]: the yarns, the real stitches, the stocking surface; then each file's bytes
//!    ([`Products::encode`]) and the preview ([`Products::render_preview`]);
//! 7. [`checks`]: what a converged fit must also be to be done (no yarn left through the skin,
//!    no tenfold density jump between neighbours).
//!
//! [`fit()`] runs 2–7 in one call. `knitfit fit`, `bench`, `plan` and the tests call the same
//! functions: a command builds the [`FitSettings`] from its scene and plan
//! ([`crate::plan::Plan::fit_settings`]) and times each stage on its clock ([`StageTimes`]).
//!
//! ```
//! let mut scene = knitfit::scene::LoadedScene::load(None, Vec::new())?; // the bundled scene
//! scene.scene.tube.wales = 60; // a coarse grid, for a quick example
//! let settings = knitfit::plan::Plan::fit(&scene.scene).fit_settings(&scene);
//! let (leg, _memory) = knitfit::fit::load(&scene.leg_path(), &settings, &mut ())?;
//! let fitted = knitfit::fit::fit(leg, &settings, &mut (), &mut knitfit::stage::NoProgress)?;
//! assert!(fitted.solved.solver.converged() && fitted.solved.max_penetration_m == 0.0);
//! let density = &fitted.fields.on_leg.stitch_density; // stitches per cm², per leg vertex
//! assert!(density.iter().any(|&d| d > 0.0));
//! # Ok::<(), knitfit::Error>(())
//! ```

pub mod checks;
mod levels;
pub mod measure;
pub mod place;
pub mod pose;
pub mod products;
pub mod size;
pub mod solve;

use std::path::Path;

pub use checks::FitChecks;
pub use measure::Fields;
pub use place::{place, PlaceSettings, Placement};
pub use products::{products, ProductSettings, Products};
pub use size::{size, RealStitches, SizedTube};
pub use solve::{solve, SolveSettings, SolvedFit, SolverRun};

use crate::base::settings::{self, Invalid};
use crate::error::{Error, Result};
use crate::knit::{Fabric, Pattern, TubeSettings};
use crate::leg::{decode_leg, read_leg_file, Leg, Units, UpChoice};
use crate::limits::{FitMemory, MemoryCheck};
use crate::sim::settings::MAX_OFFSET_M;
use crate::stage::{timed, Progress, Stage, StageTimes};

/// What each stage of a fit is given: the parts of the scene it owns, and what the plan decided
/// (the force terms, which products to make). Built from a validated scene by
/// [`crate::plan::Plan::fit_settings`]; `fabric`, `solve.offset_m` and `solve.forces` are
/// derived from the scene's `knit`, `yarns`, `tube` and `effects` there, so a script changes
/// the scene and builds the settings again rather than editing them.
#[derive(Clone, Debug, PartialEq)]
pub struct FitSettings {
    /// How the leg file is read.
    pub load: LoadSettings,
    /// Where the stocking goes.
    pub place: PlaceSettings,
    /// The scene's `tube`: its grid, relaxed size, ends and heel.
    pub tube: TubeSettings,
    /// The real stocking the grid stands for.
    pub fabric: Fabric,
    /// The knit's pattern.
    pub pattern: Pattern,
    /// What the memory estimate reads besides the grid and the leg.
    pub memory: FitMemory,
    /// The solver, contact and force terms.
    pub solve: SolveSettings,
    /// Measure the fields ([`Stage::LegAttributes`]); without, [`Fitted::fields`] is empty.
    pub measure: bool,
    /// The products to make; `None` makes none.
    pub products: Option<ProductSettings>,
}

impl FitSettings {
    /// Checks the values a fit divides by or bounds loops with, as the scene's validation does,
    /// so settings built or edited by hand meet the same limits; the error names the field as
    /// the scene spells it.
    pub fn validate(&self) -> std::result::Result<(), Invalid> {
        self.tube.validate().map_err(|e| e.within("tube"))?;
        self.solve
            .solver
            .validate()
            .map_err(|e| e.within("solver"))?;
        self.memory
            .limits
            .validate()
            .map_err(|e| e.within("limits"))?;
        let stitch = self.fabric.stitch_m;
        settings::positive("knit.course_spacing_m", stitch.course)?;
        settings::positive("knit.wale_spacing_m", stitch.wale)?;
        settings::positive("knit.needles", self.fabric.needles)?;
        settings::within("contact.offset_m", self.solve.offset_m, 0.0, MAX_OFFSET_M)?;
        let stiffness = self.solve.yarn_stiffness;
        settings::positive("yarns.nylon.stiffness", stiffness.nylon)?;
        settings::positive("yarns.support.stiffness", stiffness.support)
    }
}

/// How a leg file is read: the scene's `leg.units` and `leg.up_axis`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadSettings {
    /// Units of the file's coordinates.
    pub units: Units,
    /// Which file axis points up, or found from the anatomy.
    pub up: UpChoice,
}

/// A fitted stocking: the knit at rest on its leg, its fields and its products.
pub struct Fitted {
    /// The knit at rest on the leg, and what the solver did.
    pub solved: SolvedFit,
    /// Its fields, where measured.
    pub fields: Fields,
    /// Its products, where asked for.
    pub products: Option<Products>,
    /// The checks a finished fit must pass to be done, besides converging.
    pub checks: FitChecks,
    /// Where the leg was fitted in a rest pose: what carrying it into the pose did.
    pub pose: Option<pose::PoseStats>,
}

/// The leg the stocking is fitted on where no axis is given (a given axis is in the pose's
/// coordinates): a rigged leg's rest pose where its skin poses it, else the leg straightened
/// where it bends ([`crate::leg::unbend`]), with the leg as posed and each rest vertex's matrix
/// into the pose ([`pose`]); else `leg` itself.
///
/// Errors: [`Error::Leg`] for a foot seen pointed down that cannot be turned back to stand
/// ([`crate::leg::unbend::straightened`]).
pub fn in_rest_pose(mut leg: Leg, place: &PlaceSettings) -> Result<(Leg, Option<pose::Posed>)> {
    if place.axis.is_some() {
        return Ok((leg, None));
    }
    let (rest, bend) = match leg.rest.take() {
        Some(rest) => (*rest, None),
        // No rig: the geometry's own joints, where the leg bends.
        None => match crate::leg::unbend::straightened(&leg, place.side) {
            Ok(Some((rest, bend))) => (rest, Some(bend)),
            Ok(None) => return Ok((leg, None)),
            Err(message) => {
                return Err(Error::Leg {
                    path: leg.path.clone(),
                    message,
                })
            }
        },
    };
    let crate::leg::RestPose {
        leg: rest_leg,
        pose_from_rest,
        skin_moved_m,
    } = rest;
    let posed = pose::Posed {
        leg,
        pose_from_rest,
        skin_moved_m,
        bend,
    };
    Ok((rest_leg, Some(posed)))
}

/// Reads the leg file at `path`, refuses a fit too large for memory before the leg is decoded
/// or a knit allocated, then decodes it: stage [`Stage::LoadLeg`]. Returns the leg and the
/// memory check made.
pub fn load(
    path: &Path,
    settings: &FitSettings,
    times: &mut dyn StageTimes,
) -> Result<(Leg, MemoryCheck)> {
    timed(times, Stage::LoadLeg, || {
        let file = read_leg_file(path)?;
        let memory = settings.memory.before_the_leg(
            settings.tube.wales,
            settings.tube.courses,
            file.declared_triangles(),
        );
        memory.enforce(&path.display().to_string())?;
        let leg = decode_leg(file, settings.load.units, settings.load.up)?;
        Ok((leg, memory))
    })
}

/// Fits a stocking onto `leg` with `settings`: places, sizes and solves it, then measures it
/// and makes its products where `settings` asks; each stage timed in `times`, the solver's
/// steps told to `progress`.
///
/// Errors: [`Error::Settings`] for settings [`FitSettings::validate`] refuses; each stage's
/// (see [`place()`], [`size()`], [`solve()`]).
pub fn fit(
    leg: Leg,
    settings: &FitSettings,
    times: &mut dyn StageTimes,
    progress: &mut dyn Progress,
) -> Result<Fitted> {
    settings.validate().map_err(Error::Settings)?;
    let (leg, posed) = in_rest_pose(leg, &settings.place)?;
    let placement = place(&leg, &settings.place, &settings.tube, times)?;
    let real_stitches = settings
        .products
        .as_ref()
        .map_or(RealStitches::None, |p| p.real_stitches);
    let tube = size(
        &placement,
        &leg,
        &settings.tube,
        &settings.fabric,
        settings.pattern,
        &settings.memory,
        real_stitches,
    )?;
    let mut solved = solve(leg, placement, tube, &settings.solve, times, progress)?;
    let pose = match posed {
        Some(posed) => Some(timed(times, Stage::Pose, || {
            pose::carry(&mut solved, posed, &settings.solve)
        })?),
        None => None,
    };
    let forces = &settings.solve.forces;
    let fields = match settings.measure {
        true => timed(times, Stage::LegAttributes, || {
            measure::fields(&solved, &settings.fabric, forces)
        }),
        false => Fields::default(),
    };
    let products = settings
        .products
        .as_ref()
        .map(|wanted| products(&solved, &fields, &settings.fabric, forces, wanted, times));
    let fix = products.as_ref().and_then(|p| p.penetration_fix.as_ref());
    let checks = FitChecks::of(
        &solved.leg,
        solved.max_penetration_m,
        &fields.on_leg.stitch_density,
        fix,
    );
    Ok(Fitted {
        solved,
        fields,
        products,
        checks,
        pose,
    })
}
