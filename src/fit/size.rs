//! The tube a fit knits, sized on the placed stocking: its relaxed length (given, or
//! [`RELAXED_LENGTH_FRACTION`] of the centreline), its grid (courses given, or following the
//! stitch, [`Fabric::grid_courses`]), and the memory that grid needs once it is known.
//!
//! The scene's values that can only be checked against the leg are checked here, in one place
//! ([`check_tube_on_leg`], then [`check_stitches_on_leg`] once the grid's memory is known to
//! fit), each refusal naming its fields as an [`Invalid`] that the command reports under the
//! scene file or the flag that set them.

use crate::base::settings::{number, Invalid};
use crate::base::GridSize;
use crate::error::{Error, Result};
use crate::knit::settings::{check_grid_size, MAX_TUBE_POINTS};
use crate::knit::tube::{heel_pocket_half_length_m, TubeSpec};
use crate::knit::{Fabric, Pattern, TubeHeel, TubeSettings, RELAXED_LENGTH_FRACTION};
use crate::leg::Leg;
use crate::limits::{FitMemory, MemoryCheck};
use crate::sim::multilevel::{grid_sizes_following, largest_level, STOCKING_COARSEST};

use super::Placement;

/// The tube a fit knits, and the memory check made once its grid was known (`None` where the
/// grid was known before the leg was read, so the check made then stands).
#[derive(Clone, Debug)]
pub struct SizedTube {
    /// The grid and relaxed size of the tube.
    pub spec: TubeSpec,
    /// Its heel (a stocking to the toe's).
    pub heel: TubeHeel,
    /// The real stitch count of the stocking, whose levels a stocking's grids follow.
    pub real_count: GridSize,
    /// The check of the grid's memory, where it was made here.
    pub memory: Option<MemoryCheck>,
}

/// What a fit's real stitches are drawn as, where it lays them
/// ([`crate::stage::Stage::LayStitches`]): their count is checked against what a knit's
/// indices can number when the stocking is sized.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RealStitches {
    /// The fit lays no real stitches.
    None,
    /// Laid as crossings, one point a stitch.
    Crossings,
    /// Drawn as loops, [`crate::post::loops::SAMPLES_PER_LOOP`] points a stitch.
    Loops,
}

/// Sizes the tube on `placement` over `leg` (module docs): `tube`'s grid on
/// the stocking `fabric` knits in `pattern`, its memory checked against `memory` where its grid
/// was not known before, and the real stitches, where the fit lays them, checked as well.
///
/// Errors: [`Error::Settings`] for a value the checks refuse; [`Error::TooLarge`] over the
/// memory limit.
pub fn size(
    placement: &Placement,
    leg: &Leg,
    tube: &TubeSettings,
    fabric: &Fabric,
    pattern: Pattern,
    memory: &FitMemory,
    real_stitches: RealStitches,
) -> Result<SizedTube> {
    let to_toe = placement.path.is_some();
    let (leg_name, leg_triangles) = (leg.path.display().to_string(), leg.triangles.len());
    let centreline_m = placement.centreline.length();
    let checked =
        check_tube_on_leg(tube, fabric, pattern, centreline_m, to_toe).map_err(Error::Settings)?;
    // Courses left out, or a larger level, are known only now: the estimate made before the
    // leg was read is replaced.
    let checked_memory = (tube.courses.is_none() || checked.solved_on.is_some())
        .then(|| memory.check(checked.spec.grid, leg_triangles, checked.solved_on, false));
    if let Some(check) = &checked_memory {
        check.enforce(&leg_name)?;
    }
    check_stitches_on_leg(&checked, to_toe, tube.heel, real_stitches).map_err(Error::Settings)?;
    // The real stitches are checked as a fit of that size would be (an upper bound: no solver
    // runs on them).
    let CheckedTube {
        spec, real_count, ..
    } = checked;
    if real_stitches != RealStitches::None {
        let loops = real_stitches == RealStitches::Loops;
        memory
            .check(real_count, leg_triangles, None, loops)
            .enforce_real_stitches(&leg_name)?;
    }
    Ok(SizedTube {
        spec,
        heel: tube.heel,
        real_count,
        memory: checked_memory,
    })
}

/// What [`check_tube_on_leg`] found: the tube (its relaxed length and courses known), its real
/// stitch count, and the larger level a stocking to the toe is relaxed on first, if any.
pub struct CheckedTube {
    /// The tube, its relaxed length and courses known.
    pub spec: TubeSpec,
    /// The real stitch count of the stocking.
    pub real_count: GridSize,
    /// The real stitch count's level relaxed first, where larger than the tube's grid.
    pub solved_on: Option<GridSize>,
}

/// The checks of the scene's `tube` that need the leg: on a stocking whose centreline is
/// `centreline_m` long (to the toe where `to_toe`) knitted as `fabric` in `pattern`,
///
/// - `tube.relaxed_length_m` is shorter than the centreline (else the stocking would bunch);
/// - `tube.courses` left out follow the stitch: the grid they make is one a knit can number,
///   and for a stocking to the toe not too coarse ([`TubeSettings::check_to_the_toe`]);
/// - the real stitch count's level a stocking to the toe is relaxed on first is one a knit can
///   number.
pub fn check_tube_on_leg(
    tube: &TubeSettings,
    fabric: &Fabric,
    pattern: Pattern,
    centreline_m: f64,
    to_toe: bool,
) -> std::result::Result<CheckedTube, Invalid> {
    let relaxed_length_m = match tube.relaxed_length_m {
        None => RELAXED_LENGTH_FRACTION * centreline_m,
        Some(l) if l < centreline_m => l,
        Some(l) => {
            return Err(Invalid::new(
                "tube.relaxed_length_m",
                format!(
                    "{l} m is not shorter than the stocking's centreline ({centreline_m:.3} m): \
                     the stocking would bunch up instead of being stretched onto the leg; give a \
                     shorter length, leave it out ({RELAXED_LENGTH_FRACTION} × the centreline), \
                     or place the axis points further apart"
                ),
            ))
        }
    };
    let wales = tube.wales;
    let grid = GridSize::new(
        wales,
        (tube.courses).unwrap_or_else(|| fabric.grid_courses(wales, relaxed_length_m)),
    );
    if tube.courses.is_none() {
        let refuse = |message: String| {
            Invalid::new(
                "tube.courses",
                format!(
                    "left out, it follows the stitch: {message}; give tube.courses \
                     (--resolution WxC)"
                ),
            )
        };
        check_grid_size(grid).map_err(refuse)?;
        if to_toe {
            let given = TubeSettings {
                courses: Some(grid.courses),
                ..tube.clone()
            };
            given.check_to_the_toe().map_err(|e| refuse(e.message))?;
        }
    }
    // A stocking with fewer courses than the stitch's is relaxed first on the real count's
    // level with its wales, which has more points (`grid_sizes_following`).
    let real = fabric.real_count(relaxed_length_m);
    let solved_on = to_toe
        .then(|| largest_level(&grid_sizes_following(real, grid, STOCKING_COARSEST)))
        .filter(|level| level.points() > grid.points());
    if let Some(level) = solved_on {
        check_grid_size(level).map_err(|message| {
            Invalid::new(
                "tube.wales",
                format!("relaxed first on the real stitch count's {level} level: {message}"),
            )
            .with(&[
                "tube.courses",
                "tube.relaxed_length_m",
                "knit.wale_spacing_m",
            ])
        })?;
    }
    let spec = TubeSpec {
        grid,
        pattern,
        relaxed_circumference_m: fabric.relaxed_circumference_m(),
        relaxed_length_m,
        stitch_m: fabric.stitch_m,
    };
    Ok(CheckedTube {
        spec,
        real_count: real,
        solved_on,
    })
}

/// The checks of the scene's `tube` and `knit` that need the stitches laid on the leg, on
/// `checked`'s tube (to the toe where `to_toe`, with `heel`), laying `real_stitches`:
///
/// - a heel pocket is no longer than the relaxed stocking (its rows would be without bound);
/// - the real stitches, where the fit lays them, are a count 32-bit indices can number.
pub fn check_stitches_on_leg(
    checked: &CheckedTube,
    to_toe: bool,
    heel: TubeHeel,
    real_stitches: RealStitches,
) -> std::result::Result<(), Invalid> {
    let (spec, real) = (&checked.spec, checked.real_count);
    let relaxed_length_m = spec.relaxed_length_m;
    let half = heel_pocket_half_length_m(spec);
    if heel == TubeHeel::Pocket && to_toe && half > relaxed_length_m {
        // Millimetres as millimetres; a length far below them as the number it is.
        let length = match relaxed_length_m >= 1e-3 {
            true => format!("{relaxed_length_m:.3}"),
            false => number(relaxed_length_m),
        };
        return Err(Invalid::new(
            "tube.heel",
            format!(
                "the heel pocket would be {half:.3} m of fabric each way ({:.0} stitches around \
                 / 6 courses of {} m), longer than the relaxed stocking ({length} m): ask for \
                 fewer stitches around (knit.needles) or a shorter knit.wale_spacing_m, or give a \
                 longer tube.relaxed_length_m",
                spec.relaxed_circumference_m / spec.stitch_m.course,
                number(spec.stitch_m.wale),
            ),
        ));
    }
    if real_stitches != RealStitches::None {
        // Point ids are 32-bit, and drawn as loops each stitch is `SAMPLES_PER_LOOP` points: a
        // bound on the count, not on memory, so `allow_large` does not lift it.
        let (most, what) = match real_stitches {
            RealStitches::Loops => (
                MAX_TUBE_POINTS / crate::post::loops::SAMPLES_PER_LOOP,
                "stitches that 32-bit indices can number drawn as loops (\"loops\", \"preview\")",
            ),
            _ => (MAX_TUBE_POINTS, "points a knit's 32-bit indices can number"),
        };
        if real.points() > most {
            return Err(Invalid::new(
                "knit.needles",
                format!(
                    "the real stitches of this stocking, {real}, are over the {most} {what}; \
                     ask for fewer knit.needles or a larger stitch (knit.course_spacing_m, \
                     knit.wale_spacing_m)"
                ),
            )
            .with(&["knit.course_spacing_m", "knit.wale_spacing_m", "outputs"]));
        }
    }
    Ok(())
}
