//! A rigged leg in a pose: the stocking is fitted on the leg in its rig's rest pose and carried
//! to the pose the file shows by the skin's own motion (stage [`crate::stage::Stage::Pose`]).
//!
//! Method: the rest pose is the mesh as stored, before its skin moves it (glTF's bind pose),
//! standing as rigs are built; landmarks, path and fit work there as on any standing leg. Each
//! yarn point then follows the skin point it rests on: the nearest point of the rest leg's
//! skin, a triangle and its barycentric weights, whose vertices' skinning matrices, blended by
//! those weights, move the point as they move the skin (linear blend skinning, as a game
//! engine poses a garment bound to its body). Where the pose folds the skin (behind a bent
//! knee) points land inside it; each is moved out along the skin's normal to the contact
//! offset, as the fit's contact does. The fields are measured on the posed knit, so stretch over a
//! bent knee shows.
//!
//! The knit is then relaxed on the posed leg from there, as the fit's last level is (with the
//! solver's tolerance and step cap), its top ring held along the axis as the thigh turns it.

use nalgebra::{Matrix4, Point3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

use super::{SolveSettings, SolvedFit};
use crate::error::Result;
use crate::knit::tube::end_rings;
use crate::leg::solid::outer_skin;
use crate::leg::{Collider, Leg};
use crate::sim::accelerated::relax_accelerated;
use crate::sim::contact::LegContact;

/// Most iterations of the relaxation in the pose: a fit carried by its skin starts near its
/// rest, and where the pose folds the skin into itself it would spend the whole step cap there.
pub const POSE_MAX_ITERATIONS: usize = 3000;

/// A rigged leg as its skin poses it, with each of its rest pose's vertices' matrix into the
/// pose (file coordinates and units), from [`super::in_rest_pose`].
pub struct Posed {
    /// The leg as posed.
    pub leg: Leg,
    /// Per vertex of the rest pose's leg.
    pub pose_from_rest: Vec<Matrix4<f64>>,
}

/// What carrying the stocking into the pose did (`report.json`'s `details.pose`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseStats {
    /// Furthest any skin vertex moves from the rest pose to the pose, metres.
    pub skin_moved_m: f64,
    /// Yarn points the pose left closer to the skin than the contact offset, moved out.
    pub points_moved_out: usize,
    /// Furthest a point was moved out, metres.
    pub max_moved_out_m: f64,
    /// Iterations of the relaxation on the posed leg.
    pub iterations: usize,
    /// Its final relative residual.
    pub residual: f64,
    /// Its final force step over the shortest rest length (the max-norm companion of the
    /// residual; both must meet the tolerance).
    pub force_step: f64,
    /// True when it met the solver's tolerance.
    pub converged: bool,
}

/// Carries `solved`, fitted on the rest pose's leg, into `posed` (module docs), each rest
/// vertex moved by its matrix: its knit, leg, collider and penetration
/// become the pose's (the toes' box carried as the yarn is), the knit as fitted is kept in
/// [`SolvedFit::rest_knit`].
pub fn carry(solved: &mut SolvedFit, posed: Posed, settings: &SolveSettings) -> Result<PoseStats> {
    let Posed {
        leg: posed,
        pose_from_rest,
    } = posed;
    let method = settings.contact;
    let rest_leg = &solved.leg;
    let on_rest = Collider::new(rest_leg, method)?;
    // The collider's vertices are the rest leg's (welded already); its numbering may differ.
    let index: HashMap<[u64; 3], usize> = rest_leg
        .positions
        .iter()
        .enumerate()
        .map(|(i, p)| (p.coords.map(f64::to_bits).into(), i))
        .collect();
    let matrix_of: Vec<Matrix4<f64>> = on_rest
        .vertices()
        .iter()
        .map(|p| {
            let key: [u64; 3] = p.coords.map(f64::to_bits).into();
            index
                .get(&key)
                .map_or_else(Matrix4::identity, |&i| pose_from_rest[i])
        })
        .collect();
    // A point on the rest pose, as the skin it rests on carries it into the pose.
    let carried = |x: &Point3<f64>| {
        let near = on_rest.closest(x);
        let corners = on_rest.triangles()[near.triangle as usize];
        let [a, b, c] = corners.map(|i| on_rest.vertices()[i as usize]);
        let w = barycentric(&near.point, &a, &b, &c);
        let m = (corners.iter().zip(w)).fold(Matrix4::zeros(), |sum, (&i, w)| {
            sum + matrix_of[i as usize] * w
        });
        posed.world_from_file(&m.transform_point(&rest_leg.file_from_world(x)))
    };
    let moved: Vec<Point3<f64>> = (solved.knit.particles.x)
        .par_iter()
        .map(|x| carried(&Point3::from(*x)))
        .collect();
    // The top ring is held along the stocking's axis as the fit held it: that axis as the thigh
    // turns.
    let top = solved.placement.axis.top();
    let lock_axis = (carried(&top) - carried(&(top - solved.placement.lock_axis() * 0.05)))
        .try_normalize(1e-12)
        .unwrap_or_else(|| solved.placement.lock_axis());
    let (positions, triangles) = outer_skin(&posed.positions, &posed.triangles);
    let skin = Leg {
        positions,
        triangles,
        ..posed.clone()
    };
    let collider = Collider::new(&skin, method)?;
    // The toes boxed as the fit saw them, carried as the yarn is: the fabric bridges the gaps
    // between toes in the pose too.
    let toe_box = match &solved.toe_box {
        Some(rest_box) => {
            let boxed = Leg {
                positions: rest_box.vertices().par_iter().map(carried).collect(),
                triangles: rest_box.triangles().to_vec(),
                ..posed.clone()
            };
            Some(Collider::new(&boxed, method)?)
        }
        None => None,
    };
    let rested_on = toe_box.as_ref().unwrap_or(&collider);
    let offset = solved.offset;
    let out: Vec<(Point3<f64>, f64)> = moved
        .par_iter()
        .map(|y| {
            let near = rested_on.closest(y);
            if near.signed_distance >= offset {
                (*y, 0.0)
            } else {
                (
                    near.point + near.outward * offset,
                    offset - near.signed_distance,
                )
            }
        })
        .collect();
    solved.rest_knit = Some(solved.knit.clone());
    for (x, (y, _)) in solved.knit.particles.x.iter_mut().zip(&out) {
        *x = y.coords;
    }
    // Relaxed again on the posed leg, from where the skin carried it, as the fit's last level.
    let knit = &mut solved.knit;
    let rest_spacing = solved.spec.relaxed_circumference_m / knit.wales as f64;
    let mut contact = LegContact::new(
        rested_on,
        offset,
        (10.0 * rest_spacing).max(0.005),
        lock_axis,
        end_rings(knit),
    );
    let relaxed = relax_accelerated(
        knit,
        &settings.forces,
        settings.solver.tolerance,
        settings.solver.max_steps.min(POSE_MAX_ITERATIONS),
        None,
        &mut contact,
        &mut (),
        0,
    )?;
    contact.finish_on(&collider, &mut knit.particles.x, &knit.particles.inv_mass);
    let skin_moved_m = rest_leg
        .positions
        .iter()
        .zip(&pose_from_rest)
        .map(|(p, m)| {
            let file = rest_leg.file_from_world(p);
            (posed.world_from_file(&m.transform_point(&file)) - p).norm()
        })
        .fold(0.0, f64::max);
    let stats = PoseStats {
        skin_moved_m,
        iterations: relaxed.iterations,
        residual: relaxed.residual,
        force_step: relaxed.force_step,
        converged: relaxed.converged,
        points_moved_out: out.iter().filter(|(_, d)| *d > 0.0).count(),
        max_moved_out_m: out.iter().map(|(_, d)| *d).fold(0.0, f64::max),
    };
    solved.max_penetration_m = solved
        .knit
        .particles
        .x
        .par_iter()
        .map(|p| (-collider.closest(&Point3::from(*p)).signed_distance).max(0.0))
        .reduce(|| 0.0, f64::max);
    solved.leg = posed;
    solved.collider = collider;
    solved.toe_box = toe_box;
    Ok(stats)
}

/// Barycentric weights of `p` (on the triangle's plane) in triangle `a b c`; a degenerate
/// triangle gives its first corner.
fn barycentric(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>) -> [f64; 3] {
    let (v0, v1, v2) = (b - a, c - a, p - a);
    let (d00, d01, d11) = (v0.dot(&v0), v0.dot(&v1), v1.dot(&v1));
    let (d20, d21) = (v2.dot(&v0), v2.dot(&v1));
    let denom = d00 * d11 - d01 * d01;
    if denom.abs() <= f64::EPSILON * d00 * d11 {
        return [1.0, 0.0, 0.0];
    }
    let v = (d11 * d20 - d01 * d21) / denom;
    let w = (d00 * d21 - d01 * d20) / denom;
    [1.0 - v - w, v, w]
}
