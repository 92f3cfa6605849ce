//! A posed leg: the stocking is fitted on the leg in a rest pose and carried to the pose the
//! file shows by the skin's own motion (stage [`crate::stage::Stage::Pose`]).
//!
//! Method: the rest pose is a rigged leg's mesh as stored, before its skin moves it (glTF's
//! bind pose), standing as rigs are built; or, without a rig, the leg straightened at the joints
//! its sections show ([`crate::leg::unbend`]), whose per-vertex matrices carry it back as a
//! skin's would. Landmarks, path and fit work there as on any standing leg. Each
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

use super::levels::contact_query_radius;
use super::solve::{skin_contact, RestFit};
use super::{SolveSettings, SolvedFit};
use crate::error::Result;
use crate::knit::tube::end_rings;
use crate::leg::curvature::barycentric;
use crate::leg::load::matrices_at;
use crate::leg::solid::outer_skin;
use crate::leg::unbend::Bend;
use crate::leg::{Collider, Leg};
use crate::sim::accelerated::relax_accelerated;
use crate::sim::contact::LegContact;

/// Most iterations of the relaxation in the pose: a fit carried by its skin starts near its
/// rest, and where the pose folds the skin into itself it would spend the whole step cap there.
pub const POSE_MAX_ITERATIONS: usize = 3000;

/// A posed leg as the file shows it, with each of its rest pose's vertices' matrix into the
/// pose (file coordinates and units), from [`super::in_rest_pose`].
pub struct Posed {
    /// The leg as posed.
    pub leg: Leg,
    /// Per vertex of the rest pose's leg.
    pub pose_from_rest: Vec<Matrix4<f64>>,
    /// Furthest a skin vertex moves from the rest pose to the pose, metres.
    pub skin_moved_m: f64,
    /// Where the rest pose was made from the leg's own joints (no rig): how it bends.
    pub bend: Option<Bend>,
}

/// What carrying the stocking into the pose did (`report.json`'s `details.pose`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseStats {
    /// Furthest any skin vertex moves from the rest pose to the pose, metres.
    pub skin_moved_m: f64,
    /// Where the file has no rig and the leg bends: the joints its sections show and the bends
    /// straightened for the fit ([`crate::leg::unbend`]); `null` for a rig's pose.
    #[serde(default)]
    pub bend: Option<Bend>,
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
/// vertex moved by its matrix: its knit, leg, collider, toes' box (carried as the yarn is) and
/// penetration become the pose's; the leg and knit as fitted are kept in [`SolvedFit::rest`].
pub fn carry(solved: &mut SolvedFit, posed: Posed, settings: &SolveSettings) -> Result<PoseStats> {
    let Posed {
        leg: posed,
        pose_from_rest,
        skin_moved_m,
        bend,
    } = posed;
    let method = settings.contact;
    let rest_leg = &solved.leg;
    // The skin the fit rested on: the rest leg's outer skin, whose vertices are the leg's but
    // where pieces meet (split there: those take the nearest vertex's matrix).
    let on_rest = &solved.collider;
    let matrix_of = matrices_at(on_rest.vertices(), &rest_leg.positions, &pose_from_rest);
    // A point on the rest pose, as the skin it rests on carries it into the pose.
    let carried = |x: &Point3<f64>| {
        let near = on_rest.closest(x);
        let corners = on_rest.triangles()[near.triangle as usize];
        let weights = barycentric(&near.point, corners.map(|i| on_rest.vertices()[i as usize]));
        let m = (corners.iter().zip(weights)).fold(Matrix4::zeros(), |sum, (&i, w)| {
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
    let lock_axis = (carried(&top) - carried(&(top - solved.lock_axis * 0.05)))
        .try_normalize(1e-12)
        .unwrap_or(solved.lock_axis);
    let (positions, triangles, pieces) = outer_skin(&posed.positions, &posed.triangles);
    let skin = Leg {
        positions,
        triangles,
        ..posed.clone()
    };
    let collider = Collider::new(&skin, method)?.with_pieces(pieces);
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
    let rest_knit = solved.knit.clone();
    for (x, (y, _)) in solved.knit.particles.x.iter_mut().zip(&out) {
        *x = y.coords;
    }
    // Relaxed again on the posed leg, from where the skin carried it, as the fit's last level.
    let knit = &mut solved.knit;
    let mut contact = LegContact::new(
        rested_on,
        offset,
        contact_query_radius(&solved.spec, knit),
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
    let stats = PoseStats {
        skin_moved_m,
        bend,
        points_moved_out: out.iter().filter(|(_, d)| *d > 0.0).count(),
        max_moved_out_m: out.iter().map(|(_, d)| *d).fold(0.0, f64::max),
        iterations: relaxed.iterations,
        residual: relaxed.residual,
        force_step: relaxed.force_step,
        converged: relaxed.converged,
    };
    solved.max_penetration_m = skin_contact(&solved.knit, &collider).0;
    let rest_leg = std::mem::replace(&mut solved.leg, posed);
    solved.rest = Some(RestFit {
        leg: rest_leg,
        knit: rest_knit,
    });
    solved.collider = collider;
    solved.toe_box = toe_box;
    solved.lock_axis = lock_axis;
    Ok(stats)
}
