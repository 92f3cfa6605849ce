//! The leg as something to collide with: closest point with inside/outside, and the first
//! surface a straight move meets.
//!
//! Two methods answer the same questions. `Bvh` uses parry's bounding-volume hierarchy over the
//! triangles. `Brute` tests every triangle, as the paper did (§6.2, §9): it is the slow reference
//! that the fast path is checked against. Inside/outside comes from angle-weighted pseudo-normals
//! (Bærentzen & Aanæs), which parry computes for an oriented mesh; for a leg in pieces, where the
//! nearest skin is an open seam of its outer skin, from the pieces themselves
//! ([`Collider::with_pieces`]).

use std::collections::HashMap;

use nalgebra::{Point3, Vector3};
use parry3d_f64::query::{PointQuery, PointQueryWithLocation, Ray, RayCast};
use parry3d_f64::shape::{TriMesh, TriMeshFlags, TrianglePointLocation};

use super::{solid, Leg};
use crate::error::{Error, Result};
use crate::leg::ContactMethod;

/// The closest point of the leg to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    /// The closest surface point, metres.
    pub point: Point3<f64>,
    /// Distance to it, negative when the query point is inside the leg.
    pub signed_distance: f64,
    /// Unit vector pointing out of the leg at the closest point.
    pub outward: Vector3<f64>,
    /// The triangle the closest point lies on: an index into [`Collider::triangles`].
    pub triangle: u32,
}

/// A leg prepared for contact queries.
pub struct Collider {
    mesh: TriMesh,
    method: ContactMethod,
    seams: Option<Seams>,
}

/// Where the skin of a leg in pieces is open (its edges used by one triangle: where a piece's
/// skin was clipped against another's, where a split triangle meets a whole one, at a cut), and
/// the pieces, which tell inside from outside there. The pseudo-normal of an open edge is no
/// guide: where one piece's rim sits on another's side, a point a hair below the rim read as
/// inside through it.
struct Seams {
    pieces: solid::Pieces,
    /// Per triangle, whether each of its edges is open, in parry's order (AB, BC, AC).
    open_edge: Vec<[bool; 3]>,
    /// Per vertex, whether an open edge ends there.
    on_seam: Vec<bool>,
}

impl Seams {
    fn new(mesh: &TriMesh, pieces: solid::Pieces) -> Seams {
        let key = |a: u32, b: u32| (a.min(b), a.max(b));
        let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
        for t in mesh.indices() {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])] {
                *uses.entry(key(a, b)).or_default() += 1;
            }
        }
        let mut on_seam = vec![false; mesh.vertices().len()];
        let open_edge = (mesh.indices().iter())
            .map(|t| {
                [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])].map(|(a, b)| {
                    let open = uses[&key(a, b)] == 1;
                    if open {
                        on_seam[a as usize] = true;
                        on_seam[b as usize] = true;
                    }
                    open
                })
            })
            .collect();
        Seams {
            pieces,
            open_edge,
            on_seam,
        }
    }

    /// True when the closest point, on `triangle` (corners `corners`) at `location`, lies on
    /// an open edge or a vertex where one ends.
    fn at(&self, triangle: u32, corners: &[u32; 3], location: TrianglePointLocation) -> bool {
        match location {
            TrianglePointLocation::OnEdge(i, _) => self.open_edge[triangle as usize][i as usize],
            TrianglePointLocation::OnVertex(i) => self.on_seam[corners[i as usize] as usize],
            TrianglePointLocation::OnFace(..) | TrianglePointLocation::OnSolid => false,
        }
    }
}

impl Collider {
    /// Builds the collider (the BVH and pseudo-normals). Duplicate vertices are merged and
    /// zero-area triangles dropped first.
    pub fn new(leg: &Leg, method: ContactMethod) -> Result<Collider> {
        let flags = TriMeshFlags::ORIENTED
            | TriMeshFlags::MERGE_DUPLICATE_VERTICES
            | TriMeshFlags::DELETE_DEGENERATE_TRIANGLES;
        let mesh = TriMesh::with_flags(leg.positions.clone(), leg.triangles.clone(), flags)
            .map_err(|e| Error::Leg {
                path: leg.path.clone(),
                message: format!("cannot use the mesh for contact: {e}"),
            })?;
        // Parry drops triangles by an absolute area threshold where cleaning's is relative, so
        // a leg of tiny triangles could keep none; every query below needs one.
        if mesh.indices().is_empty() {
            return Err(Error::Leg {
                path: leg.path.clone(),
                message: "cannot use the mesh for contact: every triangle is too small to \
                          collide with"
                    .into(),
            });
        }
        Ok(Collider {
            mesh,
            method,
            seams: None,
        })
    }

    /// The collider of a leg's outer skin, told the `pieces` the skin was made from
    /// ([`solid::outer_skin`]): where the closest point lies on the skin's open edges, inside is
    /// inside some piece.
    pub fn with_pieces(self, pieces: Option<solid::Pieces>) -> Collider {
        let seams = pieces.map(|pieces| Seams::new(&self.mesh, pieces));
        Collider { seams, ..self }
    }

    /// The triangles used for contact, as indices into [`Collider::vertices`] (duplicates
    /// merged, degenerate triangles dropped: not the file's numbering).
    pub fn triangles(&self) -> &[[u32; 3]] {
        self.mesh.indices()
    }

    /// The vertices the triangles index, metres.
    pub fn vertices(&self) -> &[Point3<f64>] {
        self.mesh.vertices()
    }

    /// The contact method in use.
    pub fn method(&self) -> ContactMethod {
        self.method
    }

    /// The closest point of the leg to `p`, or `None` if it is further than `max_distance`.
    pub fn closest_within(&self, p: &Point3<f64>, max_distance: f64) -> Option<Closest> {
        let (projection, (triangle, location)) = match self.method {
            ContactMethod::Bvh => self
                .mesh
                .project_local_point_and_get_location_with_max_dist(p, false, max_distance)?,
            ContactMethod::Brute => {
                let (proj, loc) = self.brute_closest(p)?;
                if (proj.point - p).norm() > max_distance {
                    return None;
                }
                (proj, loc)
            }
        };
        Some(self.closest_from(p, projection.point, triangle, location))
    }

    /// The [`Closest`] of `p` whose nearest point is `point`, on `triangle` at `location`.
    fn closest_from(
        &self,
        p: &Point3<f64>,
        point: Point3<f64>,
        triangle: u32,
        location: TrianglePointLocation,
    ) -> Closest {
        let offset = p - point;
        let distance = offset.norm();
        let inside = self.is_inside(p, &point, triangle, location);
        let outward = if distance > 1e-12 {
            if inside {
                -offset / distance
            } else {
                offset / distance
            }
        } else {
            self.face_normal(triangle)
        };
        Closest {
            point,
            signed_distance: if inside { -distance } else { distance },
            outward,
            triangle,
        }
    }

    /// The closest point of the leg to `p`. The BVH's best-first search ranks triangles by
    /// distance and finds none when it cannot compare them (a non-finite query point, or
    /// distances that overflow); then every triangle is tried in turn, ordered by
    /// `total_cmp`, which always picks one, and the distance it gives is what the caller's
    /// finiteness checks see.
    pub fn closest(&self, p: &Point3<f64>) -> Closest {
        if let Some(closest) = self.closest_within(p, f64::MAX) {
            return closest;
        }
        let (projection, (triangle, location)) = self
            .brute_closest(p)
            .expect("Collider::new refuses a mesh without triangles");
        self.closest_from(p, projection.point, triangle, location)
    }

    /// The first surface met moving from `from` along the unit vector `dir` within `max_distance`:
    /// the distance travelled and the surface normal facing `from`.
    pub fn first_hit(
        &self,
        from: &Point3<f64>,
        dir: &Vector3<f64>,
        max_distance: f64,
    ) -> Option<(f64, Vector3<f64>)> {
        let ray = Ray::new(*from, *dir);
        let hit = match self.method {
            ContactMethod::Bvh => {
                self.mesh
                    .cast_local_ray_and_get_normal(&ray, max_distance, false)
            }
            ContactMethod::Brute => self
                .mesh
                .triangles()
                .filter_map(|t| t.cast_local_ray_and_get_normal(&ray, max_distance, false))
                .min_by(|a, b| a.time_of_impact.total_cmp(&b.time_of_impact)),
        }?;
        Some((hit.time_of_impact, hit.normal))
    }

    fn brute_closest(
        &self,
        p: &Point3<f64>,
    ) -> Option<(
        parry3d_f64::query::PointProjection,
        (u32, TrianglePointLocation),
    )> {
        self.mesh
            .triangles()
            .enumerate()
            .map(|(i, t)| {
                let (proj, loc) = t.project_local_point_and_get_location(p, false);
                (proj, (i as u32, loc))
            })
            .min_by(|a, b| {
                (a.0.point - p)
                    .norm_squared()
                    .total_cmp(&(b.0.point - p).norm_squared())
            })
    }

    /// Inside test by the pseudo-normal of the closest feature (face, edge or vertex); on an
    /// open edge of a leg in pieces, by the pieces.
    fn is_inside(
        &self,
        p: &Point3<f64>,
        closest: &Point3<f64>,
        triangle: u32,
        location: TrianglePointLocation,
    ) -> bool {
        if let Some(seams) = &self.seams {
            if seams.at(triangle, &self.mesh.indices()[triangle as usize], location) {
                return seams.pieces.contain(p);
            }
        }
        solid::is_inside(&self.mesh, p, closest, triangle, location)
    }

    /// Outward unit normal of a triangle (+Y for a degenerate one).
    pub fn face_normal(&self, triangle: u32) -> Vector3<f64> {
        solid::face_normal(&self.mesh, triangle)
    }

    /// True when `p` is inside the leg (a cheaper question than [`Collider::closest`] only in
    /// name: it needs the closest feature too).
    pub fn contains(&self, p: &Point3<f64>) -> bool {
        self.closest(p).signed_distance < 0.0
    }

    /// Plain distance from `p` to the surface (no sign), for tests and checks.
    pub fn distance(&self, p: &Point3<f64>) -> f64 {
        self.mesh.distance_to_local_point(p, false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::leg::test_meshes::add_box;

    #[test]
    fn a_point_whose_nearest_skin_is_a_seam_is_told_inside_or_out_by_the_pieces() {
        // A mannequin's knee: a shin 10 cm square passing up into a thigh 4 mm wider each side
        // at its rim, narrowing upwards. The skin where the thigh's rim meets the shin lost the
        // thigh's cap (as clipping can leave it), so the rim is an open edge, 4 mm out from the
        // shin's side.
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        add_box(&mut positions, &mut triangles, [0.0; 3], [0.1, 0.3, 0.1]);
        add_box(
            &mut positions,
            &mut triangles,
            [-0.004, 0.28, -0.004],
            [0.104, 0.5, 0.104],
        );
        for p in &mut positions[12..] {
            if p.y > 0.4 {
                (p.x, p.z) = (p.x.clamp(-0.001, 0.101), p.z.clamp(-0.001, 0.101));
            }
        }
        // The skin: the shin below the thigh's rim, the thigh without its cap.
        let mut skin_positions = positions.clone();
        let mut skin_triangles = triangles[12..].to_vec();
        skin_triangles.retain(|t| {
            !t.iter()
                .all(|&i| (positions[i as usize].y - 0.28).abs() < 1e-12)
        });
        for p in &mut skin_positions[..8] {
            p.y = p.y.min(0.28);
        }
        skin_triangles.extend(&triangles[..12]);
        skin_triangles.retain(|t| {
            !t.iter()
                .all(|&i| (skin_positions[i as usize].y - 0.28).abs() < 1e-12)
        });
        let skin = Leg::from_world("mannequin".into(), &skin_positions, &skin_triangles);
        let pieces = solid::Pieces::of(&positions, &triangles);
        assert!(pieces.is_some());
        // Just under the thigh's rim, 4 mm out from the shin: outside both, nearest the rim.
        let under_the_rim = Point3::new(0.104, 0.2796, 0.05);
        let seen = Collider::new(&skin, ContactMethod::Bvh).unwrap();
        // The rim's pseudo-normal (its one face's, tilted up) reads it as inside.
        assert!(seen.contains(&under_the_rim));
        let seen = seen.with_pieces(pieces);
        assert!(!seen.contains(&under_the_rim));
        // Inside the shin under the gap, and inside the thigh just above its rim.
        assert!(seen.contains(&Point3::new(0.05, 0.2796, 0.05)));
        assert!(seen.contains(&Point3::new(0.102, 0.2804, 0.05)));
    }
}
