//! The tube at every grid size a fit is solved on, and its contact with the leg: what the
//! solvers knit and constrain ([`Levels`]). An open tube is solved on grids halving down to
//! [`COARSEST`]; a stocking to the toe follows the real stitch count's own levels
//! ([`grid_sizes_following`], docs/decisions/0063, 0066 and 0072), and the grid it ends on is
//! graded finer over the toe's tip (docs/decisions/0073).

use nalgebra::Vector3;

use crate::base::GridSize;
use crate::error::Result;
use crate::knit::path::TubePath;
use crate::knit::tube::{
    build_stocking, build_tube, end_rings, toe_graded_intervals, Centreline, CourseSpacing,
    TubeSpec,
};
use crate::knit::{Knit, TubeHeel};
use crate::leg::{Axis, Collider, Leg};
use crate::post::stitches::refuse_bunched;
use crate::sim::contact::{ContactCounters, LegContact};
use crate::sim::multilevel::{
    grid_sizes_down_to, grid_sizes_following, COARSEST, STOCKING_COARSEST,
};
use crate::sim::{Constraints, Levels};

/// The tube at any grid size, and its contact with the leg.
pub(super) struct TubeLevels<'a> {
    /// The tube asked for; other levels change only its wales and courses.
    pub spec: TubeSpec,
    /// A stocking to the toe's path (else an open tube along `axis`).
    pub path: Option<&'a TubePath>,
    pub heel: TubeHeel,
    pub centreline: &'a Centreline,
    /// The direction the held ring(s) may not move along.
    pub lock_axis: Vector3<f64>,
    pub axis: &'a Axis,
    pub leg: &'a Leg,
    /// What the fabric slides on: the skin, with the toes boxed where it has toes.
    pub collider: &'a Collider,
    /// Distance kept between yarn centre line and skin, metres.
    pub offset: f64,
    /// Support yarn's stiffness over nylon's, for the bunched refusal.
    pub support_ratio: f64,
    /// The real stitch count, whose levels a stocking's grids follow.
    pub real_count: GridSize,
    /// Contact of the level being solved.
    pub contact: Option<LegContact<'a>>,
    /// Counters of the levels solved before it.
    pub retired: ContactCounters,
}

impl Levels for TubeLevels<'_> {
    fn knit(&mut self, grid: GridSize, finest: bool) -> Knit {
        let spec = TubeSpec { grid, ..self.spec };
        match self.path {
            // The grid the fit ends on resolves the toe's tip; the levels it starts from
            // follow the real stitches' even courses (docs/decisions/0073).
            Some(path) => {
                let spacing = match finest {
                    true => CourseSpacing::FinerAtTheToe,
                    false => CourseSpacing::Even,
                };
                build_stocking(&spec, path, self.heel, spacing)
            }
            None => build_tube(&spec, self.axis, &self.leg.positions, &self.leg.triangles),
        }
    }

    fn constraints(&mut self, knit: &Knit) -> &mut dyn Constraints {
        if let Some(done) = self.contact.take() {
            self.retired.add(&done.counters());
        }
        let query_radius = contact_query_radius(&self.spec, knit);
        self.contact.insert(LegContact::new(
            self.collider,
            self.offset,
            query_radius,
            self.lock_axis,
            end_rings(knit),
        ))
    }

    fn grid_sizes(&self, grid: GridSize) -> Vec<GridSize> {
        // A heel and a toe need rings a few centimetres apart at most, and a foot rests where
        // its coarse levels leave it: a grid starts where the real count does, where it can.
        let Some(_) = self.path else {
            return grid_sizes_down_to(grid, COARSEST);
        };
        let mut sizes = grid_sizes_following(self.real_count, grid, STOCKING_COARSEST);
        // A grid graded at the toe's tip that is also one of the real count's levels (courses
        // following the stitch) solves that level, even, first: so it starts where the real
        // count's level rests, as an N×N grid does from the level with its wales.
        let chain = grid_sizes_down_to(self.real_count, STOCKING_COARSEST);
        let spec = TubeSpec { grid, ..self.spec };
        if chain.contains(&grid) && toe_graded_intervals(&spec).is_some() {
            sizes.insert(sizes.len() - 1, grid);
        }
        sizes
    }

    fn accept(&mut self, knit: &Knit) -> Result<()> {
        refuse_bunched(
            knit,
            self.centreline,
            self.spec.relaxed_circumference_m,
            self.support_ratio,
        )
        .map(|_| ())
    }
}

/// How far contact's exact queries look from a point of `knit` (a tube of `spec`), metres: ten
/// rest spacings around the tube, at least 5 mm (larger is safe, slower).
pub(super) fn contact_query_radius(spec: &TubeSpec, knit: &Knit) -> f64 {
    let rest_spacing = spec.relaxed_circumference_m / knit.wales as f64;
    (10.0 * rest_spacing).max(0.005)
}
