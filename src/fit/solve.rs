//! The tube knitted and relaxed onto the leg (Sakaguchi & Miyata §6.2): the collider the yarn
//! slides on, the scene's solver (the paper's explicit steps, or the multilevel one over the
//! tube at each of its grid sizes), the exact contact pass, and the checks of the rest state:
//! how deep any point is inside the skin, whether the stocking is on the leg at all, and
//! whether its courses bunched. Stages [`Stage::BuildCollider`] to [`Stage::CheckPenetration`] of a fit.
//!
//! A level that stops as going nowhere is refused with where and why
//! ([`crate::sim::stall`]); a fit that runs out of steps is kept, and says where it had not
//! settled.

use nalgebra::{Point3, Vector3};

use crate::base::GridSize;
use crate::error::{Error, Result};
use crate::knit::tube::{Centreline, TubeSpec};
use crate::knit::{Knit, TubeHeel};
use crate::leg::solid::outer_skin;
use crate::leg::{Collider, ContactMethod, Leg};
use crate::limits::MemoryCheck;
use crate::post::stitches::refuse_bunched;
use crate::sim::accelerated::OutOfBalance;
use crate::sim::contact::ContactCounters;
use crate::sim::stall::{StockingOnLeg, YarnStiffness};
use crate::sim::{
    relax_constrained, relax_multilevel, ForceTerms, LevelStats, Levels, MultilevelStats,
    RelaxStats, SolverMethod, SolverSettings,
};
use crate::stage::{timed, Progress, Stage, StageTimes, StepProgress};

use super::levels::TubeLevels;
use super::{Placement, SizedTube};

/// What the solve stage reads: the scene's `solver` and `contact`, the force terms its effects
/// switch on, and its yarns' stiffness (what a bunched or stalled fit's advice names).
#[derive(Clone, Debug, PartialEq)]
pub struct SolveSettings {
    /// The scene's `solver`.
    pub solver: SolverSettings,
    /// The force terms the effects switch on ([`crate::plan::Plan::forces`]).
    pub forces: ForceTerms,
    /// How contact is found (`contact.method`).
    pub contact: ContactMethod,
    /// Distance kept between yarn centre line and skin, metres (`contact.offset_m`, or the
    /// nylon's radius).
    pub offset_m: f64,
    /// The yarns' stiffness, whatever the effects: `yarns.nylon.stiffness` and
    /// `yarns.support.stiffness`.
    pub yarn_stiffness: YarnStiffness,
}

/// A fitted knit on its leg, before any post-processing or file: what `fit` goes on to measure
/// and write, and what `bench` measures.
pub struct SolvedFit {
    /// The leg, in world space (metres, +Y up).
    pub leg: Leg,
    /// Where the stocking went: landmarks, axis, path, centreline.
    pub placement: Placement,
    /// The leg's collider.
    pub collider: Collider,
    /// The toes boxed (`TubePath::box_the_toes`), where the path has toes: the surface the fit's
    /// contact saw there, the fabric bridging the gaps between toes.
    pub toe_box: Option<Collider>,
    /// The tube knitted.
    pub spec: TubeSpec,
    /// Its heel (a stocking to the toe's).
    pub heel: TubeHeel,
    /// The real stitch count the tube stands for.
    pub real_count: GridSize,
    /// Distance kept between yarn centre line and skin, metres.
    pub offset: f64,
    /// The knit at rest on the leg, after the exact contact pass.
    pub knit: Knit,
    /// Where the knit was fitted on a posed leg's rest pose and carried into its pose
    /// ([`super::pose`]): the leg and knit as fitted, which `placement` (landmarks, axis,
    /// centreline) describes.
    pub rest: Option<RestFit>,
    /// The direction the top ring is held along: the placement's, or carried into the pose.
    pub lock_axis: Vector3<f64>,
    /// What the solver did.
    pub solver: SolverRun,
    /// Where the grid asked for had not settled when the solver ran out of steps, in words:
    /// the courses, their place and whether the residual was within the tolerance (multilevel
    /// only); `None` when it converged.
    pub unsettled_at: Option<String>,
    /// Contact counters over all levels.
    pub counters: ContactCounters,
    /// Deepest yarn point inside the leg against the exact triangles, metres (0 when none is).
    pub max_penetration_m: f64,
    /// Nearest and furthest yarn along the centreline, metres from its start.
    pub axial_range_m: [f64; 2],
    /// Courses that came to rest below a course before them (a small fold above a slack ankle;
    /// more than [`crate::post::stitches::MAX_BUNCHED_FRACTION`] of them is refused as bunched).
    pub bunched_courses: usize,
    /// The memory check made once the grid was known, where the size stage made one.
    pub memory: Option<MemoryCheck>,
}

/// A fit made on a posed leg's rest pose before it was carried into the pose.
pub struct RestFit {
    /// The leg in its rest pose.
    pub leg: Leg,
    /// The knit at rest on it.
    pub knit: Knit,
}

impl SolvedFit {
    /// The leg the placement was made on: the rest pose's where the fit was carried into a
    /// pose, else the leg.
    pub fn placed_on(&self) -> &Leg {
        self.rest.as_ref().map_or(&self.leg, |r| &r.leg)
    }

    /// The knit as fitted where the placement was made (see [`SolvedFit::placed_on`]).
    pub fn knit_as_placed(&self) -> &Knit {
        self.rest.as_ref().map_or(&self.knit, |r| &r.knit)
    }

    /// The surface the fitted fabric rests on: the skin, with the toes boxed where it has toes.
    pub fn rested_on(&self) -> &Collider {
        self.toe_box.as_ref().unwrap_or(&self.collider)
    }
}

/// Knits the `tube` on `placement` and relaxes it onto `leg` with `settings`, its stages
/// timed in `times` and its steps told to `progress`.
///
/// Errors: those of the solvers ([`Error::Diverged`], [`Error::SolverDiverged`], …);
/// [`Error::Stalled`] for a fit going nowhere; [`Error::Bunched`]; [`Error::Leg`] for a
/// stocking that came to rest off the leg.
pub fn solve(
    leg: Leg,
    placement: Placement,
    tube: SizedTube,
    settings: &SolveSettings,
    times: &mut dyn StageTimes,
    progress: &mut dyn Progress,
) -> Result<SolvedFit> {
    let (collider, toe_box) = timed(times, Stage::BuildCollider, || -> Result<_> {
        // Contact sees the solid's skin: a piece's triangles inside another piece (a ball joint
        // in its shin) are not where yarn rests (leg::solid).
        let (positions, triangles, pieces) = outer_skin(&leg.positions, &leg.triangles);
        let skin = Leg {
            positions,
            triangles,
            ..leg.clone()
        };
        let collider = Collider::new(&skin, settings.contact)?.with_pieces(pieces);
        // The fit's contact sees the toes boxed (TubePath::box_the_toes).
        let boxed = placement
            .path
            .as_ref()
            .and_then(|path| path.box_the_toes(&skin.positions, &skin.triangles));
        let toe_box = match boxed {
            Some((positions, triangles)) => {
                let mut boxed = leg.clone();
                (boxed.positions, boxed.triangles) = (positions, triangles);
                Some(Collider::new(&boxed, settings.contact)?)
            }
            None => None,
        };
        Ok((collider, toe_box))
    })?;
    let (spec, solver) = (tube.spec, &settings.solver);
    let mut levels = TubeLevels {
        spec,
        path: placement.path.as_ref(),
        heel: tube.heel,
        centreline: &placement.centreline,
        lock_axis: placement.lock_axis(),
        axis: &placement.axis,
        leg: &leg,
        collider: toe_box.as_ref().unwrap_or(&collider),
        offset: settings.offset_m,
        support_ratio: settings.yarn_stiffness.support_ratio(),
        real_count: tube.real_count,
        contact: None,
        retired: ContactCounters::default(),
    };
    let (mut knit, run) = match solver.method {
        SolverMethod::Paper => {
            let mut knit = timed(times, Stage::KnitTube, || levels.knit(spec.grid, true));
            progress.begin("fit", solver.max_steps as u64);
            let stats = timed(times, Stage::Fit, || {
                let contact = levels.constraints(&knit);
                relax_constrained(
                    &mut knit,
                    &settings.forces,
                    solver,
                    contact,
                    &mut StepProgress(progress),
                )
            });
            progress.end();
            (knit, SolverRun::Paper(stats?))
        }
        SolverMethod::Multilevel => {
            progress.begin("fit", solver.max_steps as u64);
            let solved = timed(times, Stage::Fit, || {
                relax_multilevel(
                    &mut levels,
                    spec.grid,
                    &settings.forces,
                    solver.tolerance,
                    solver.max_steps,
                    &mut StepProgress(progress),
                )
            });
            progress.end();
            let (knit, stats) = solved?;
            (knit, SolverRun::Multilevel(stats))
        }
    };
    let on_leg = StockingOnLeg {
        leg: &leg,
        side: placement.side,
        axis: &placement.axis,
        centreline: &placement.centreline,
        landmarks: placement.landmarks.as_ref(),
        circumference_m: spec.relaxed_circumference_m,
        yarn_stiffness: settings.yarn_stiffness,
    };
    if let Some(level) = run.stalled() {
        // A stocking stopped while bunched is refused as that: it says more.
        let centreline = &placement.centreline;
        refuse_bunched(
            &knit,
            centreline,
            spec.relaxed_circumference_m,
            settings.yarn_stiffness.support_ratio(),
        )?;
        return Err(on_leg.stalled(&knit, level));
    }
    // A fit that ran out of steps is written, and says where it had not settled.
    let unsettled_at = run
        .unsettled()
        .map(|(level, at)| on_leg.unsettled(&knit, level, at, solver.tolerance));
    let mut contact = levels
        .contact
        .take()
        .expect("the solver made the fine grid's contact");
    timed(times, Stage::ExactContactPass, || {
        contact.finish_on(&collider, &mut knit.particles.x, &knit.particles.inv_mass)
    });
    let mut counters = levels.retired;
    counters.add(&contact.counters());
    let ((max_penetration_m, touching), axial_range_m) =
        timed(times, Stage::CheckPenetration, || {
            (
                skin_contact(&knit, &collider),
                axial_range(&knit, &placement.centreline),
            )
        });
    if touching < MIN_TOUCHING_FRACTION {
        return Err(Error::Leg {
            path: leg.path.clone(),
            message: format!(
                "the fitted stocking is not on the leg: only {:.0}% of its points came to rest \
                 on the skin (a fit touches it nearly everywhere); {} misses the leg or the \
                 stocking is far too wide for it",
                100.0 * touching,
                placement.axis.source.describe(),
            ),
        });
    }
    let bunched_courses = refuse_bunched(
        &knit,
        &placement.centreline,
        spec.relaxed_circumference_m,
        settings.yarn_stiffness.support_ratio(),
    )?;
    let lock_axis = placement.lock_axis();
    Ok(SolvedFit {
        leg,
        placement,
        collider,
        toe_box,
        spec,
        heel: tube.heel,
        real_count: tube.real_count,
        offset: settings.offset_m,
        knit,
        rest: None,
        lock_axis,
        solver: run,
        unsettled_at,
        counters,
        max_penetration_m,
        axial_range_m,
        bunched_courses,
        memory: tube.memory,
    })
}

/// A fit whose yarn rests on the skin at fewer than this fraction of its points is no stocking
/// on this leg: a tight fit touches nearly everywhere, and even one far wider than the leg
/// (support yarn 1000× nylon's relaxed at the thigh's girth) rests on a fifth of its points.
const MIN_TOUCHING_FRACTION: f64 = 0.1;
/// A point within this distance of the skin rests on it, metres.
const TOUCHING_M: f64 = 0.002;

/// From exact closest-point queries: the deepest yarn point inside the leg, metres (0 when none
/// is), and the fraction of points within [`TOUCHING_M`] of the skin.
pub(super) fn skin_contact(knit: &Knit, collider: &Collider) -> (f64, f64) {
    use rayon::prelude::*;
    let (deepest, touching) = knit
        .particles
        .x
        .par_iter()
        .map(|p| {
            let d = collider.closest(&Point3::from(*p)).signed_distance;
            ((-d).max(0.0), usize::from(d <= TOUCHING_M))
        })
        .reduce(|| (0.0, 0), |a, b| (a.0.max(b.0), a.1 + b.1));
    (deepest, touching as f64 / knit.len().max(1) as f64)
}

/// Nearest and furthest yarn along `centreline`, metres from its start: every grid point's
/// place along an open tube's straight axis; along a stocking to the toe's bent line, its
/// courses' (the mean of each).
fn axial_range(knit: &Knit, centreline: &Centreline) -> [f64; 2] {
    let range = |values: &mut dyn Iterator<Item = f64>| {
        values.fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], s| {
            [lo.min(s), hi.max(s)]
        })
    };
    if knit.has_toe_seam() {
        range(&mut (0..knit.courses).map(|c| centreline.course_along(knit, c)))
    } else {
        let grid = &knit.particles.x[..knit.grid_len()];
        range(&mut grid.iter().map(|p| centreline.along(p)))
    }
}

/// What the fit's solver did.
pub enum SolverRun {
    /// The paper's explicit solver.
    Paper(RelaxStats),
    /// The multilevel solver.
    Multilevel(MultilevelStats),
}

impl SolverRun {
    /// Steps (paper) or iterations over all levels (multilevel).
    pub fn steps(&self) -> usize {
        match self {
            SolverRun::Paper(s) => s.steps,
            SolverRun::Multilevel(s) => s.total_iterations(),
        }
    }

    /// Final relative residual on the grid asked for.
    pub fn residual(&self) -> f64 {
        match self {
            SolverRun::Paper(s) => s.residual,
            SolverRun::Multilevel(s) => s.fine().residual,
        }
    }

    /// Final largest move per step on the grid asked for, over the shortest rest length.
    pub fn max_move(&self) -> f64 {
        match self {
            SolverRun::Paper(s) => s.max_move,
            SolverRun::Multilevel(s) => s.fine().max_move,
        }
    }

    /// Multilevel only: the final force step on the grid asked for.
    pub fn force_step(&self) -> Option<f64> {
        match self {
            SolverRun::Paper(_) => None,
            SolverRun::Multilevel(s) => Some(s.fine().force_step),
        }
    }

    /// The level that stopped as futile, if one did (multilevel only).
    pub fn stalled(&self) -> Option<&LevelStats> {
        match self {
            SolverRun::Paper(_) => None,
            SolverRun::Multilevel(s) => s.levels.last().filter(|l| l.stall.is_some()),
        }
    }

    /// The grid asked for, and where it had not settled when it ran out of steps (multilevel
    /// only).
    pub fn unsettled(&self) -> Option<(&LevelStats, &OutOfBalance)> {
        match self {
            SolverRun::Paper(_) => None,
            SolverRun::Multilevel(s) => {
                let fine = s.fine();
                fine.unsettled.as_ref().map(|at| (fine, at))
            }
        }
    }

    /// True when the grid asked for converged.
    pub fn converged(&self) -> bool {
        match self {
            SolverRun::Paper(s) => s.converged,
            SolverRun::Multilevel(s) => s.fine().converged,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::place::{place, PlaceSettings};
    use crate::knit::TubeSettings;
    use crate::leg::Side;
    use crate::leg::{load_leg, Units, UpChoice};

    #[test]
    fn a_stocking_to_the_toe_stopped_at_the_foot_counts_from_its_top_and_offers_the_ankle() {
        let leg_path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("samples")
            .join("lowpoly_leg.glb");
        let leg = load_leg(&leg_path, Units::Metres, UpChoice::Auto).unwrap();
        let settings = PlaceSettings {
            axis: None,
            side: Side::Left,
        };
        let placed = place(&leg, &settings, &TubeSettings::default(), &mut ()).unwrap();
        assert!(
            placed.path.is_some(),
            "a leg with a foot gets a path to the toe"
        );
        let tip = placed.landmarks.as_ref().unwrap().foot.unwrap().toe_tip;
        let level = LevelStats {
            wales: 150,
            courses: 150,
            iterations: 1700,
            polish_iterations: 0,
            restarts: 1500,
            stall_restarts: 0,
            start_residual: 1.5,
            residual: 2.7e-3,
            force_step: 0.1,
            max_move: 0.1,
            converged: false,
            stall: Some(OutOfBalance {
                courses: [140, 148],
                worst_point: tip,
                worst_force_step: 0.1,
            }),
            unsettled: None,
            seconds: 1.0,
        };
        let on_leg = StockingOnLeg {
            leg: &leg,
            side: Side::Left,
            axis: &placed.axis,
            centreline: &placed.centreline,
            landmarks: placed.landmarks.as_ref(),
            circumference_m: 0.2,
            yarn_stiffness: YarnStiffness {
                nylon: 1.0,
                support: 10.0,
            },
        };
        let places: Vec<f64> = (0..level.courses).map(|c| c as f64).collect();
        let message = on_leg.stalled_at(&level, &places).to_string();
        for expected in [
            "going nowhere",
            "courses 140–148 of 150",
            "down the stocking from its top",
            "at the foot",
            "--bottom ankle",
        ] {
            assert!(
                message.contains(expected),
                "expected {expected:?} in {message}"
            );
        }
        assert_eq!(message.lines().count(), 1, "{message}");
    }
}
