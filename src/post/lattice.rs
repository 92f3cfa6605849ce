//! Every real stitch: the knit at its real count (one point per stitch crossing, `knit.needles`
//! around and one course per relaxed `knit.wale_spacing_m`), laid on the skin by interpolating
//! the fitted grid.
//!
//! The fit solves a coarser grid whose springs are homogenized to the stitch's membrane
//! (docs/decisions/0053), so the fitted grid *is* the fabric's shape; the real stitches are
//! placed in it by the same interpolation the multilevel solver hands a coarse grid's state to a
//! finer one with ([`prolong`]: the same place in the fabric, bilinear around and along, along
//! the wale chains through a heel pocket). Interpolation cuts chords under a convex skin (the
//! sagitta of a grid cell, tens of micrometres at 150 around), so every point is then moved out
//! to the yarn's offset from the exact skin, by the fit's own exact contact pass.
//!
//! The real-count knit is built by the same tube builder as the fitted grid (path, toe seam,
//! heel pocket, held welt), so the stitches have the real pattern (nylon and support alternating
//! course by course) and the real topology; only its positions come from the fit. Its held
//! points (the welt, an open tube's ankle ring) stay where the builder put them, as the fitted
//! grid's did.

use nalgebra::Point3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::base::Vec3;
use crate::knit::tube::end_rings;
use crate::knit::Knit;
use crate::leg::Collider;
use crate::sim::contact::LegContact;
use crate::sim::multilevel::prolong;

/// What laying the real stitches did, for the report.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LaidStitches {
    /// Real stitches around (wales) and along (courses).
    pub wales: usize,
    /// Courses of the real-count knit.
    pub courses: usize,
    /// Points of the real-count knit (short rows' included).
    pub points: usize,
    /// Points the interpolation left closer to the skin than the yarn's offset (or inside it),
    /// moved out to it.
    pub moved_out: u64,
}

/// Places the free points of `real` (a knit of the real stitch count, built like `fitted`) in
/// the fitted grid `fitted` and moves every one closer to `collider`'s skin than `offset` out to
/// it. `axis` is the direction the held rings may not slide along (the fit's lock axis).
pub fn lay_stitches(
    fitted: &Knit,
    real: &mut Knit,
    collider: &Collider,
    offset: f64,
    axis: Vec3,
) -> LaidStitches {
    prolong(fitted, real);
    // The exact contact pass reads no contact state (each point is queried afresh), so a fresh
    // contact over the real knit is all it needs; it leaves the held rings where they are.
    let mut contact = LegContact::new(
        collider,
        offset,
        STITCH_QUERY_RADIUS_M,
        axis,
        end_rings(real),
    );
    contact.finish(&mut real.particles.x, &real.particles.inv_mass);
    LaidStitches {
        wales: real.wales,
        courses: real.courses,
        points: real.len(),
        moved_out: contact.counters().finished_out,
    }
}

/// Moves every point of `points` closer to `collider`'s skin than `offset` (or inside it) out
/// to it along the skin's normal; returns how many moved. For yarn drawn between laid stitches
/// (a loop bulges past its stitch's corners, where a lattice's bilinear cells sag under a convex
/// skin), before the penetration fix, which mends segments between points outside the leg.
pub fn lay_on_skin(points: &mut [[f64; 3]], collider: &Collider, offset: f64) -> u64 {
    const CHUNK: usize = 4096;
    points
        .par_chunks_mut(CHUNK)
        .map(|chunk| {
            let mut moved = 0;
            for p in chunk {
                let at = Point3::from(*p);
                if let Some(c) = collider.closest_within(&at, LOOP_QUERY_RADIUS_M) {
                    if c.signed_distance < offset * (1.0 - 1e-6) {
                        *p = (c.point + c.outward * offset).into();
                        moved += 1;
                    }
                }
            }
            moved
        })
        .sum()
}

/// How far from the skin laying a stitch looks for it, metres: an interpolated stitch lies
/// within a grid cell's sagitta of it, far inside a centimetre.
const STITCH_QUERY_RADIUS_M: f64 = 0.01;
/// How far from the skin laying a loop's samples looks for it, metres: a loop strays from its
/// laid stitch's corners by a fraction of a millimetre (a smaller radius prunes the BVH sooner;
/// the samples are many).
const LOOP_QUERY_RADIUS_M: f64 = 0.002;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::knit::tube::{build_tube, TubeSpec};
    use crate::knit::Pattern;
    use crate::leg::{Axis, AxisSource, ContactMethod, Leg};

    /// A closed cylinder of radius `r` along +Y from 0 to `h`, `n` facets around.
    fn cylinder(r: f64, h: f64, n: usize) -> Leg {
        let mut positions = Vec::new();
        for ring in 0..=20 {
            let y = h * ring as f64 / 20.0;
            for k in 0..n {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                positions.push(Point3::new(r * a.cos(), y, r * a.sin()));
            }
        }
        let mut triangles = Vec::new();
        for ring in 0..20u32 {
            for k in 0..n as u32 {
                let next = (k + 1) % n as u32;
                let (a, b) = (ring * n as u32 + k, ring * n as u32 + next);
                let (c, d) = (a + n as u32, b + n as u32);
                triangles.push([a, c, b]);
                triangles.push([b, c, d]);
            }
        }
        Leg::from_world("cylinder".into(), &positions, &triangles)
    }

    #[test]
    fn real_stitches_lie_on_the_skin_between_the_fitted_grid_points() {
        let (r, h) = (0.05, 0.3);
        let leg = cylinder(r, h, 256);
        let axis = Axis {
            bottom: [0.0, 0.02, 0.0],
            top: [0.0, h - 0.02, 0.0],
            source: AxisSource::Scene,
        };
        let spec = |wales, courses| TubeSpec {
            grid: crate::base::GridSize::new(wales, courses),
            pattern: Pattern::Alternating,
            relaxed_circumference_m: 0.25,
            relaxed_length_m: 0.25,
            stitch_m: crate::base::PerDirection::new(0.0005, 0.00074),
        };
        // A fitted grid on the skin: every point at the offset on the cylinder.
        let offset = 25e-6;
        let mut fitted = build_tube(&spec(24, 20), &axis, &leg.positions, &leg.triangles);
        for p in fitted.particles.x.iter_mut() {
            let radial = Vec3::new(p.x, 0.0, p.z).normalize();
            *p = radial * (r + offset) + Vec3::new(0.0, p.y, 0.0);
        }
        let mut real = build_tube(&spec(96, 58), &axis, &leg.positions, &leg.triangles);
        let collider = Collider::new(&leg, ContactMethod::Bvh).unwrap();
        let laid = lay_stitches(&fitted, &mut real, &collider, offset, Vec3::y());
        assert_eq!((laid.wales, laid.courses, laid.points), (96, 58, 96 * 58));
        // Chords between 24 points around cut 1.7 mm into a 5 cm cylinder: every free point
        // between them was moved out, to the offset, and none is inside.
        assert!(laid.moved_out > 0);
        for (i, p) in real.particles.x.iter().enumerate() {
            if !real.is_free(crate::knit::PointId(i as u32)) {
                continue;
            }
            let d = collider.distance(&Point3::from(*p));
            assert!(d >= offset * (1.0 - 1e-3), "point {i} at {d}");
            assert!(d < offset + 2e-4, "point {i} left {d} off the skin");
        }
        // Along the tube the real courses keep the fitted courses' places: real course 3k is
        // fitted course k (57 = 3 × 19 intervals).
        let y = |k: &Knit, c: usize| k.particles.x[k.point(0, c).index()].y;
        let fitted_top = y(&fitted, 18) - y(&fitted, 1);
        let real_top = y(&real, 54) - y(&real, 3);
        assert!((fitted_top - real_top).abs() < 1e-9);
    }
}
