//! The leg as something to collide with: closest point with inside/outside, and the first
//! surface a straight move meets.
//!
//! Two methods answer the same questions. `Bvh` uses parry's bounding-volume hierarchy over the
//! triangles. `Brute` tests every triangle, as the paper did (§6.2, §9): it is the slow reference
//! that the fast path is checked against. Inside/outside comes from angle-weighted pseudo-normals
//! (Bærentzen & Aanæs), which parry computes for an oriented mesh.

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
        Ok(Collider { mesh, method })
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

    /// Inside test by the pseudo-normal of the closest feature (face, edge or vertex).
    fn is_inside(
        &self,
        p: &Point3<f64>,
        closest: &Point3<f64>,
        triangle: u32,
        location: TrianglePointLocation,
    ) -> bool {
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
