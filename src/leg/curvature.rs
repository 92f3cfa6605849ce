//! The skin's curvature, at the scale the fabric sees it: what Laplace's law multiplies the
//! fabric's tension by (`post::fields`).
//!
//! Method: at each vertex of the surface, a weighted least-squares height quadric
//! `z = a x² + b xy + c y² + d x + e y` over the vertices within `scale` of it, in the frame of
//! its area-weighted normal: the degree-2 osculating jet of Cazals & Pouget, "Estimating
//! differential quantities using polynomial fitting of osculating jets" (CAGD 22, 2005), with a
//! biweight in distance so the patch's rim fades out. The linear terms take up the normal's
//! error. The curvature tensor is the quadric's Hessian, negated, as a symmetric 3×3 tensor on
//! the tangent plane in world coordinates: **positive where the skin bulges out** (a cylinder of
//! radius `r` reads `1/r` around and 0 along), negative in a hollow.
//!
//! Fitted over `scale` (at least 2.5 median edges, on a coarse mesh) rather than a vertex's
//! one-ring, it reads the bulge the fabric wraps rather than the mesh's facets, and depends on the
//! mesh alone: every grid a fit runs at reads the same skin. Where fewer than six vertices lie
//! within it, or they lie nearly on a line (a strip of long thin triangles), the patch widens,
//! to four times at most; a vertex on no triangle, or whose widest fit is still singular, reads
//! flat (zero).

use nalgebra::{Matrix3, Point3, SMatrix, SVector};
use rayon::prelude::*;

use crate::base::{area_weighted_normals, perpendicular_frame, PointGrid, Vec3};
use crate::leg::{Closest, Collider};

/// Fewest neighbours a quadric is fitted to: its five coefficients and one to spare.
const MIN_NEIGHBOURS: usize = 6;
/// Smallest ratio of the fit's singular values taken as well posed: below it the neighbours lie
/// nearly on a line (a strip of long thin triangles) and the patch widens.
const MIN_CONDITION: f64 = 1e-4;
/// The fitting radius is at least this many times the mesh's median edge: a patch of the
/// fabric's size on a coarse mesh holds too few vertices.
const EDGES_PER_RADIUS: f64 = 2.5;

/// The curvature tensor at every vertex of a collider's surface (see the module docs).
pub struct SkinCurvature<'a> {
    surface: &'a Collider,
    tensors: Vec<Matrix3<f64>>,
}

impl<'a> SkinCurvature<'a> {
    /// The curvature of `surface` over `scale` metres about each vertex.
    pub fn of(surface: &'a Collider, scale: f64) -> SkinCurvature<'a> {
        let positions: Vec<Vec3> = surface.vertices().iter().map(|p| p.coords).collect();
        let normals = area_weighted_normals(&positions, surface.triangles());
        let radius = scale.max(EDGES_PER_RADIUS * median_edge(&positions, surface.triangles()));
        let grid = PointGrid::new(positions.iter().copied(), radius);
        let tensors = positions
            .par_iter()
            .zip(&normals)
            .enumerate()
            .map(|(i, (p, n))| match n {
                Some(n) => fit_quadric(i, p, n, &positions, &grid, radius),
                None => Matrix3::zeros(),
            })
            .collect();
        SkinCurvature { surface, tensors }
    }

    /// The tensor at the surface's closest point to `p` (interpolated over its triangle), or
    /// `None` where that lies further than `within` metres: skin the fabric does not rest on.
    pub fn near(&self, p: &Point3<f64>, within: f64) -> Option<Matrix3<f64>> {
        let closest = self.surface.closest_within(p, within)?;
        Some(self.at(&closest))
    }

    fn at(&self, closest: &Closest) -> Matrix3<f64> {
        let vertices = self.surface.vertices();
        let corners = self.surface.triangles()[closest.triangle as usize];
        let [a, b, c] = corners.map(|i| vertices[i as usize]);
        barycentric(&closest.point, [a, b, c])
            .iter()
            .zip(corners)
            .map(|(w, i)| self.tensors[i as usize] * *w)
            .sum()
    }
}

/// The curvature tensor at vertex `i` (at `p`, normal `n`) from its neighbours within `scale`,
/// widened where too few (see the module docs).
fn fit_quadric(
    i: usize,
    p: &Vec3,
    n: &Vec3,
    positions: &[Vec3],
    grid: &PointGrid,
    scale: f64,
) -> Matrix3<f64> {
    let (e1, e2) = perpendicular_frame(n);
    for radius in [scale, 2.0 * scale, 4.0 * scale] {
        // Coordinates over the radius, so the normal equations are well scaled at any size.
        let mut normal_matrix = SMatrix::<f64, 5, 5>::zeros();
        let mut rhs = SVector::<f64, 5>::zeros();
        let mut count = 0;
        grid.for_each_within(p, radius, |j| {
            let d = (positions[j] - p) / radius;
            let r2 = d.norm_squared();
            if j == i || r2 >= 1.0 {
                return;
            }
            let (x, y, z) = (d.dot(&e1), d.dot(&e2), d.dot(n));
            let w = (1.0 - r2) * (1.0 - r2);
            let row = SVector::<f64, 5>::new(x * x, x * y, y * y, x, y);
            normal_matrix += row * row.transpose() * w;
            rhs += row * (w * z);
            count += 1;
        });
        if count < MIN_NEIGHBOURS {
            continue;
        }
        let eigenvalues = normal_matrix.symmetric_eigenvalues();
        if eigenvalues.min() < MIN_CONDITION * eigenvalues.max() {
            continue;
        }
        let Some(coefficients) = normal_matrix.cholesky().map(|c| c.solve(&rhs)) else {
            continue;
        };
        // Back from coordinates over the radius: z/r = A (x/r)² … gives a = A / r.
        let [a, b, c] = [0, 1, 2].map(|k| coefficients[k] / radius);
        let tensor = -(e1 * e1.transpose() * (2.0 * a)
            + (e1 * e2.transpose() + e2 * e1.transpose()) * b
            + e2 * e2.transpose() * (2.0 * c));
        return if tensor.iter().all(|v| v.is_finite()) {
            tensor
        } else {
            Matrix3::zeros()
        };
    }
    Matrix3::zeros()
}

/// The median length of the triangles' edges, metres (0 for none).
fn median_edge(positions: &[Vec3], triangles: &[[u32; 3]]) -> f64 {
    let mut lengths: Vec<f64> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (positions[a as usize] - positions[b as usize]).norm())
        .collect();
    if lengths.is_empty() {
        return 0.0;
    }
    let middle = lengths.len() / 2;
    *lengths.select_nth_unstable_by(middle, f64::total_cmp).1
}

/// The barycentric weights of `p` (on or near the triangle) in `corners`, clamped to the
/// triangle; equal weights for a degenerate one.
pub(crate) fn barycentric(p: &Point3<f64>, [a, b, c]: [Point3<f64>; 3]) -> [f64; 3] {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d00, d01, d11) = (ab.dot(&ab), ab.dot(&ac), ac.dot(&ac));
    let (d20, d21) = (ap.dot(&ab), ap.dot(&ac));
    let denominator = d00 * d11 - d01 * d01;
    if denominator <= f64::EPSILON * d00 * d11 || !denominator.is_finite() {
        return [1.0 / 3.0; 3];
    }
    let v = ((d11 * d20 - d01 * d21) / denominator).clamp(0.0, 1.0);
    let w = ((d00 * d21 - d01 * d20) / denominator).clamp(0.0, 1.0 - v);
    [1.0 - v - w, v, w]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::leg::{ContactMethod, Leg};

    /// A UV sphere of `radius` about the origin.
    fn sphere(radius: f64) -> Leg {
        let (rings, sides) = (48u32, 96u32);
        let mut positions = vec![Point3::new(0.0, radius, 0.0)];
        for ring in 1..rings {
            let polar = std::f64::consts::PI * ring as f64 / rings as f64;
            for k in 0..sides {
                let a = std::f64::consts::TAU * k as f64 / sides as f64;
                positions.push(Point3::from(
                    Vec3::new(polar.sin() * a.cos(), polar.cos(), polar.sin() * a.sin()) * radius,
                ));
            }
        }
        positions.push(Point3::new(0.0, -radius, 0.0));
        let last = positions.len() as u32 - 1;
        let at = |ring: u32, k: u32| 1 + (ring - 1) * sides + k % sides;
        let mut triangles = Vec::new();
        for k in 0..sides {
            triangles.push([0, at(1, k + 1), at(1, k)]);
            triangles.push([last, at(rings - 1, k), at(rings - 1, k + 1)]);
            for ring in 1..rings - 1 {
                let (a, b) = (at(ring, k), at(ring, k + 1));
                let (c, d) = (at(ring + 1, k), at(ring + 1, k + 1));
                triangles.push([a, b, c]);
                triangles.push([b, d, c]);
            }
        }
        Leg::from_world("sphere".into(), &positions, &triangles)
    }

    #[test]
    fn a_cylinder_bends_one_way_at_one_over_its_radius() {
        let radius = 0.04;
        let leg = Leg::round(radius, 0.2, 96, 40);
        let collider = Collider::new(&leg, ContactMethod::Bvh).unwrap();
        let skin = SkinCurvature::of(&collider, 0.008);
        // Round the middle ring, away from the open ends.
        for k in 0..16 {
            let a = std::f64::consts::TAU * (k as f64 + 0.3) / 16.0;
            let around = Vec3::new(-a.sin(), 0.0, a.cos());
            let p = Point3::new(radius * a.cos(), 0.1, radius * a.sin());
            let tensor = skin.near(&p, 0.001).unwrap();
            let (bend_around, bend_along) = (
                around.dot(&(tensor * around)),
                Vec3::y().dot(&(tensor * Vec3::y())),
            );
            // A quadric over a circle's arc reads it a little tighter: its next term, ~1 %.
            assert!(
                (bend_around - 1.0 / radius).abs() < 0.02 / radius,
                "{bend_around}"
            );
            assert!(bend_along.abs() < 0.01 / radius, "{bend_along}");
        }
        // Skin further than asked is skin the fabric does not rest on.
        assert!(skin.near(&Point3::new(0.05, 0.1, 0.0), 0.005).is_none());
    }

    #[test]
    fn a_sphere_bends_every_way_at_one_over_its_radius_and_its_inside_reads_hollow() {
        let radius = 0.05;
        let leg = sphere(radius);
        let collider = Collider::new(&leg, ContactMethod::Bvh).unwrap();
        let skin = SkinCurvature::of(&collider, 0.008);
        let p = Point3::new(0.03, 0.02, -0.035).coords.normalize() * radius;
        let tensor = skin.near(&Point3::from(p), 0.001).unwrap();
        let (u, v) = perpendicular_frame(&p.normalize());
        for t in [u, v, (u + v).normalize()] {
            let bend = t.dot(&(tensor * t));
            assert!((bend - 1.0 / radius).abs() < 0.02 / radius, "{bend}");
        }
        // Wound the other way, the same surface is the inside of a hollow.
        let mut inside = leg.clone();
        inside.triangles.iter_mut().for_each(|t| t.swap(1, 2));
        let collider = Collider::new(&inside, ContactMethod::Bvh).unwrap();
        let hollow = SkinCurvature::of(&collider, 0.008)
            .near(&Point3::from(p), 0.001)
            .unwrap();
        assert!(u.dot(&(hollow * u)) < -0.98 / radius);
    }
}
