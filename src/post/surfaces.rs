//! The fitted knit and the leg as the triangle surfaces the writers and the preview take: the
//! leg with its per-vertex fields and a density heat map, and the stocking as a surface over the
//! knit's faces whose texture coordinates run along the knit (u around, v along) without a jump
//! where the courses close, white vertex colours and its coverage as their opacity, so a
//! blending material of the yarn's colour (`stocking.glb`'s) draws it as sheer as the knit is.

use std::collections::{BTreeMap, HashMap};

use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

use super::fields::KnitFields;
use crate::base::{colour, SurfaceMesh, YarnGeometry};
use crate::knit::{Knit, PointId};
use crate::leg::{Collider, Leg};

/// The leg with its fields as attributes (`stitch_density`, `stretch_course`, `stretch_wale`,
/// `coverage`) and the density's heat map as vertex colours.
pub fn leg_surface(leg: &Leg, fields: &KnitFields) -> SurfaceMesh {
    let positions = leg.positions.iter().map(|p| p.coords.into()).collect();
    let mut mesh = SurfaceMesh::new("leg", positions, leg.triangles.clone());
    let density = &fields.stitch_density;
    if density.len() != leg.positions.len() {
        // No attributes asked for.
        return mesh;
    }
    let covered = density.iter().copied().filter(|&d| d > 0.0);
    let (lo, hi) = covered.fold((f64::INFINITY, 0.0f64), |(lo, hi), d| {
        (lo.min(d), hi.max(d))
    });
    let uncovered = [0.2f32, 0.2, 0.2];
    mesh.colours = Some(
        density
            .iter()
            .map(|&d| {
                if d > 0.0 {
                    colour::heat(if hi > lo { (d - lo) / (hi - lo) } else { 0.5 })
                } else {
                    uncovered
                }
            })
            .collect(),
    );
    for (name, values) in fields.named() {
        mesh.point_attributes
            .insert(name.into(), values.iter().map(|&v| v as f32).collect());
    }
    mesh
}

/// How far the stocking surface is lifted off the fitted knit along its normals, metres
/// ([`lift_clear_of`]): enough for a depth buffer to tell it from the skin at any framing
/// distance (24-bit depth with the near plane at 1 cm resolves about 25 µm at 2 m, 0.15 mm at
/// 5 m), small beside a leg (a 4 cm ankle's radius grows by 2.5 %). The knit's points rest
/// 0.03 mm off the skin, which no depth buffer resolves.
pub const STOCKING_LIFT_M: f64 = 0.001;

/// The least clearance between the lifted stocking surface and the skin, metres, at every
/// triangle's edge midpoints and centre: where the skin turns faster than the knit's
/// spacing (a toe's tip on a coarse grid), the chords between lifted points still dip toward
/// it, and their corners are lifted further.
pub const STOCKING_CLEARANCE_M: f64 = 0.5 * STOCKING_LIFT_M;

/// Rounds of [`lift_clear_of`]'s further lifting; each clears what the one before left, and
/// the few triangles still dipping after them are left as they are (counted).
const CLEARANCE_ROUNDS: usize = 4;

/// Barycentric weights of the points of a triangle checked for clearance: its edges' midpoints
/// and its centre, where chords dip. Its corners are knit points lifted along their own normals,
/// a lift away from the skin (the test `look::the_stocking_surface_lies_clear_of_the_skin`
/// checks them too).
const CLEARANCE_SAMPLES: [[f64; 3]; 4] = [
    [0.5, 0.5, 0.0],
    [0.0, 0.5, 0.5],
    [0.5, 0.0, 0.5],
    [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
];

/// Lifts `mesh` (the stocking surface) [`STOCKING_LIFT_M`] along its vertex normals, then lifts
/// the corners of any triangle a point of which is closer than [`STOCKING_CLEARANCE_M`] to the
/// skin by twice what it lacks, along the skin's outward normal, up to four times, so that the
/// leg's flat faces never poke through it and no viewer mixes the two up. Returns how many
/// triangles still dip closer (a handful of 45,000 on the sample feet at 150×150, in the toes'
/// clefts, still clear of the skin by a fifth of the clearance or more). Points the surface
/// repeats (its texture's seam) move together. The same surface for the same input, whatever the thread count.
pub fn lift_clear_of(mesh: &mut SurfaceMesh, collider: &Collider) -> usize {
    // A vertex repeated for the texture's seam (the same point, the same normal) must move with
    // its twin, or the surface would open there.
    let mut first_at: HashMap<[u64; 3], usize> = HashMap::new();
    let twin_of: Vec<usize> = (0..mesh.positions.len())
        .map(|v| {
            *first_at
                .entry(mesh.positions[v].map(f64::to_bits))
                .or_insert(v)
        })
        .collect();
    for (p, n) in mesh.positions.iter_mut().zip(&mesh.normals) {
        for k in 0..3 {
            p[k] += STOCKING_LIFT_M * f64::from(n[k]);
        }
    }
    // Each round checks the triangles whose corners the round before moved (all, at first).
    let mut checked: Vec<usize> = (0..mesh.triangles.len()).collect();
    let mut dipping = 0;
    for round in 0..=CLEARANCE_ROUNDS {
        // What each triangle lacks, in parallel; then the most each corner lacks, in order.
        let lacking: Vec<f64> = checked
            .par_iter()
            .map(|&t| {
                let corners = mesh.triangles[t].map(|v| Vector3::from(mesh.positions[v as usize]));
                CLEARANCE_SAMPLES
                    .iter()
                    .map(|w| {
                        let p =
                            Point3::from(corners[0] * w[0] + corners[1] * w[1] + corners[2] * w[2]);
                        // Most points lie about the lift off the skin: a bounded query finds
                        // them fast. Farther than that, the whole query says whether
                        // the point floats off the skin (fine) or lies deep inside it.
                        let closest = collider
                            .closest_within(&p, 1.25 * STOCKING_LIFT_M)
                            .unwrap_or_else(|| collider.closest(&p));
                        STOCKING_CLEARANCE_M - closest.signed_distance
                    })
                    .fold(0.0, f64::max)
            })
            .collect();
        let mut by = vec![0.0; mesh.positions.len()];
        dipping = 0;
        // Twice what it lacks: lifting the corners along their own normals moves a point between
        // them less than that away from the skin where the normals fan out (a toe's tip).
        for (&t, &lack) in checked.iter().zip(&lacking) {
            if lack > 0.0 {
                dipping += 1;
                for &v in &mesh.triangles[t] {
                    by[v as usize] = f64::max(by[v as usize], 2.0 * lack);
                }
            }
        }
        if dipping == 0 || round == CLEARANCE_ROUNDS {
            break;
        }
        for v in 0..by.len() {
            let first = twin_of[v];
            by[first] = by[first].max(by[v]);
        }
        for v in 0..by.len() {
            by[v] = by[twin_of[v]];
        }
        // Along the skin's outward normal at each corner's closest point, not the corner's own
        // normal: where slack fabric crumples (a toe seam's corners, over a graded toe's fine
        // cells) a vertex normal can lie along the skin or point into it, and lifting along it
        // would deepen the dip round after round. Twins, at one place, go the same way.
        for (v, &d) in by.iter().enumerate() {
            if d > 0.0 {
                let out = collider.closest(&Point3::from(mesh.positions[v])).outward;
                for k in 0..3 {
                    mesh.positions[v][k] += d * out[k];
                }
            }
        }
        checked = (0..mesh.triangles.len())
            .filter(|&t| mesh.triangles[t].iter().any(|&v| by[v as usize] > 0.0))
            .collect();
    }
    dipping
}

/// The fitted knit as a triangle surface: its faces ([`Knit::faces`]: the grid, the heel
/// pocket's short rows, the toe seam that closes it) triangulated, with a vertex per knit point
/// and the points of the first wale repeated where a face wraps round to it, so texture
/// coordinates run 0–1 without a jump (u = wale / wales, v = 1 − course / (courses − 1), from
/// [`Knit::fabric_coords`]; on a graded grid v follows the relaxed fabric instead); per vertex,
/// the yarn point's attributes and its fields (density, stretch, coverage: what a sheer shader
/// on this surface needs). With the coverage, the vertex
/// colours are white and their opacity is the coverage clamped to 0–1 (a rendering aid: the
/// `coverage` attribute stays as it is); without it (no fields measured), no colours. Only the
/// knit's own points are used: `yarns` may hold points the penetration fix inserted after them.
pub fn stocking_surface(
    knit: &Knit,
    knit_fields: &KnitFields,
    yarns: &YarnGeometry,
) -> SurfaceMesh {
    let (wales, courses) = (knit.wales, knit.courses);
    let point_fields: Vec<(&str, &[f32])> = yarns
        .point_attributes
        .iter()
        .map(|(k, v)| (k.as_str(), &v[..knit.len()]))
        .collect();
    let knit_fields: Vec<(&str, Vec<f32>)> = knit_fields
        .named()
        .into_iter()
        .filter(|(_, v)| v.len() == knit.len())
        .map(|(k, v)| (k, v.iter().map(|&x| x as f32).collect()))
        .collect();
    let sources: Vec<(&str, &[f32])> = point_fields
        .into_iter()
        .chain(knit_fields.iter().map(|(k, v)| (*k, &v[..])))
        .collect();

    // Vertices: the grid course by course, each course's first point repeated after its last
    // when the courses close; then the short rows' points, likewise.
    let mut vertices = Vertices {
        knit,
        source: Vec::with_capacity(knit.len() + courses),
        texcoords: Vec::with_capacity(knit.len() + courses),
        of_point: vec![0; knit.len()],
        wrapped: vec![None; knit.len()],
        places: knit.is_graded().then(|| knit.course_places()),
    };
    for c in 0..courses {
        for w in 0..wales {
            vertices.add(knit.point(w, c));
        }
        if knit.closed_courses {
            vertices.add_wrapped(knit.point(0, c));
        }
    }
    for i in knit.grid_len()..knit.len() {
        let p = PointId(i as u32);
        vertices.add(p);
        if knit.closed_courses && knit.fabric_coords(p)[0] == 0.0 {
            vertices.add_wrapped(p);
        }
    }

    let mut triangles = Vec::with_capacity(2 * knit.len());
    let wale_of = |p: PointId| knit.fabric_coords(p)[0];
    let last_wale = wales.saturating_sub(1) as f64;
    for face in knit.faces() {
        // A face across the wrap takes the first wale's repeated points.
        let wraps = knit.closed_courses
            && face.corners.iter().any(|&p| wale_of(p) == 0.0)
            && face.corners.iter().any(|&p| wale_of(p) == last_wale);
        let vertex = |p: PointId| match vertices.wrapped[p.index()] {
            Some(v) if wraps => v,
            _ => vertices.of_point[p.index()],
        };
        for t in triangulate(knit, &face.corners) {
            triangles.push(t.map(vertex));
        }
    }

    let positions = vertices
        .source
        .iter()
        .map(|p| {
            let x = knit.particles.x[p.index()];
            [x.x, x.y, x.z]
        })
        .collect();
    let attributes: BTreeMap<String, Vec<f32>> = sources
        .iter()
        .map(|(name, values)| {
            let per_vertex = vertices.source.iter().map(|p| values[p.index()]);
            (name.to_string(), per_vertex.collect())
        })
        .collect();
    let mut mesh = SurfaceMesh::new("stocking", positions, triangles);
    // A repeated point must share the normal of the point it repeats.
    for (first, last) in vertices.of_point.iter().zip(&vertices.wrapped) {
        let Some(last) = last else { continue };
        let (first, last) = (*first as usize, *last as usize);
        let n = nalgebra::Vector3::from(mesh.normals[first])
            + nalgebra::Vector3::from(mesh.normals[last]);
        let n = if n.norm() > 0.0 {
            n.normalize()
        } else {
            nalgebra::Vector3::y()
        };
        mesh.normals[first] = n.into();
        mesh.normals[last] = n.into();
    }
    mesh.texcoords = Some(vertices.texcoords);
    if let Some(coverage) = attributes.get("coverage") {
        mesh.colours = Some(vec![[1.0; 3]; coverage.len()]);
        mesh.opacity = Some(coverage.iter().map(|c| c.clamp(0.0, 1.0)).collect());
    }
    mesh.point_attributes = attributes;
    mesh
}

/// The stocking surface's vertices as they are made: the knit point each stands for and its
/// texture coordinates.
struct Vertices<'a> {
    knit: &'a Knit,
    /// The knit point of each vertex.
    source: Vec<PointId>,
    /// `TEXCOORD_0` of each vertex.
    texcoords: Vec<[f32; 2]>,
    /// Per knit point, its vertex.
    of_point: Vec<u32>,
    /// Per knit point of the first wale of a closed knit, its repeat at u = 1.
    wrapped: Vec<Option<u32>>,
    /// On a graded grid, each course's relaxed place, which v follows so that a texture's
    /// stitches keep their size over the toe's finer cells.
    places: Option<Vec<f64>>,
}

impl Vertices<'_> {
    fn add(&mut self, p: PointId) {
        let [wale, _] = self.knit.fabric_coords(p);
        self.of_point[p.index()] = self.push(p, wale as f32 / self.knit.wales as f32);
    }

    fn add_wrapped(&mut self, p: PointId) {
        self.wrapped[p.index()] = Some(self.push(p, 1.0));
    }

    fn push(&mut self, p: PointId, u: f32) -> u32 {
        let [_, course] = self.knit.fabric_coords(p);
        let last_course = self.knit.courses.saturating_sub(1).max(1);
        let along = match &self.places {
            Some(places) => {
                let c = (course.floor() as usize).min(last_course - 1);
                let place = places[c] + (places[c + 1] - places[c]) * (course - c as f64);
                (place / places[last_course]) as f32
            }
            None => course as f32 / last_course as f32,
        };
        self.source.push(p);
        self.texcoords.push([u, 1.0 - along]);
        (self.source.len() - 1) as u32
    }
}

/// A face's triangles, counter-clockwise as the face is. A face with a wale up each side (a
/// grid cell, a heel-pocket cell) is laced up its two sides, each step taking the shorter
/// diagonal in the fabric, so a side with short rows the other lacks meets both of the other's
/// corners rather than a sliver fan from one (a grid cell gives its two triangles either side
/// of the diagonal from its first corner). Any other face (the toe seam's) is fanned from its
/// first corner.
fn triangulate(knit: &Knit, corners: &[PointId]) -> Vec<[PointId; 3]> {
    let coords = |p: PointId| knit.fabric_coords(p);
    let fan = || {
        corners[1..]
            .windows(2)
            .map(|pair| [corners[0], pair[0], pair[1]])
            .collect()
    };
    // Corners run up the right side, then down the left back to the first.
    let Some(&first) = corners.first() else {
        return Vec::new();
    };
    let (left_wale, right_wale) = match corners.get(1) {
        Some(&p) => (coords(first)[0], coords(p)[0]),
        None => return Vec::new(),
    };
    let up_right = corners[1..]
        .iter()
        .take_while(|&&p| coords(p)[0] == right_wale)
        .count();
    let right = &corners[1..1 + up_right];
    let down_left = &corners[1 + up_right..];
    if left_wale == right_wale
        || right.len() < 2
        || down_left.is_empty()
        || down_left.iter().any(|&p| coords(p)[0] != left_wale)
    {
        return fan();
    }
    let left: Vec<PointId> = std::iter::once(first)
        .chain(down_left.iter().rev().copied())
        .collect();
    let course = |p: PointId| coords(p)[1];
    let (mut l, mut r) = (0, 0);
    let mut triangles = Vec::with_capacity(corners.len() - 2);
    while l + 1 < left.len() || r + 1 < right.len() {
        let up_the_right = if l + 1 == left.len() {
            true
        } else if r + 1 == right.len() {
            false
        } else {
            // The diagonal each step would leave; the right on a tie, as a grid cell has it.
            let right_diagonal = (course(right[r + 1]) - course(left[l])).abs();
            let left_diagonal = (course(left[l + 1]) - course(right[r])).abs();
            right_diagonal <= left_diagonal
        };
        if up_the_right {
            triangles.push([left[l], right[r], right[r + 1]]);
            r += 1;
        } else {
            triangles.push([left[l], right[r], left[l + 1]]);
            l += 1;
        }
    }
    triangles
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;
    use std::f64::consts::TAU;

    use super::*;
    use crate::base::Vec3;
    use crate::knit::{Pattern, Tile};
    use crate::leg::{ContactMethod, SkinCurvature};

    const WALES: usize = 8;
    const COURSES: usize = 5;
    const RADIUS: f64 = 0.05;
    const SPACING: f64 = 0.01;

    /// A round tube up +Y, its courses running counter-clockwise seen from outside, closed by a
    /// toe seam across its (flat, round) last course, with a heel pocket above course 1 whose
    /// points lie on the tube between the courses.
    fn shaped_tube() -> Knit {
        let tile = Tile::of(Pattern::Alternating);
        let at = |w: usize, c: f64| {
            let theta = TAU * w as f64 / WALES as f64;
            Vec3::new(RADIUS * theta.sin(), c * SPACING, RADIUS * theta.cos())
        };
        let rest_course = TAU * RADIUS / WALES as f64;
        Knit::grid(WALES, COURSES, true, &tile, rest_course, SPACING, |w, c| {
            at(w, c as f64)
        })
        .with_toe_seam(SPACING)
        .with_short_rows(
            1,
            vec![2, 1, 0, 0, 0, 1, 2, 2],
            &tile,
            rest_course,
            SPACING,
            |w, f| at(w, 1.0 + f),
        )
    }

    /// The fields of `knit` as a 20-den stocking's, of the paper's two yarns.
    fn surface_fields(knit: &Knit) -> KnitFields {
        let d = crate::knit::nylon::yarn_diameter_m;
        let fabric = crate::knit::Fabric {
            needles: 400.0,
            stitch_m: crate::base::PerDirection::new(0.0005, 0.00074),
            yarn_diameter_m: [d(20.0), d(40.0), d(20.0)],
            loop_stiffness_n_per_m: 6.8,
        };
        let terms = crate::sim::ForceTerms {
            stiffness: [1.0, 10.0, 1.0],
            connection_factor: Some(0.2),
        };
        let leg = Collider::new(&Leg::round(RADIUS, 0.1, 48, 10), ContactMethod::Bvh).unwrap();
        let skin = SkinCurvature::of(&leg, 0.008);
        KnitFields::measure(knit, &fabric, &terms, &skin, 0.0)
    }

    fn surface(knit: &Knit) -> SurfaceMesh {
        let fields = surface_fields(knit);
        stocking_surface(knit, &fields, &knit.yarn_geometry("stocking", [0.0; 3]))
    }

    fn vector(p: [f64; 3]) -> Vec3 {
        Vec3::from(p)
    }

    #[test]
    fn a_shaped_stocking_has_every_knit_point_and_is_closed_at_the_toe() {
        let knit = shaped_tube();
        let mesh = surface(&knit);
        // Each vertex stands for the knit point with its (wale, course).
        let point_of: BTreeMap<[u32; 2], usize> = (0..knit.len())
            .map(|i| {
                let coords = knit.fabric_coords(PointId(i as u32));
                (coords.map(|x| (x as f32).to_bits()), i)
            })
            .collect();
        let source: Vec<usize> = (0..mesh.positions.len())
            .map(|v| {
                let key = ["wale", "course"].map(|name| mesh.point_attributes[name][v].to_bits());
                let i = point_of[&key];
                assert_eq!(vector(mesh.positions[v]), knit.particles.x[i]);
                i
            })
            .collect();
        let mut seen = vec![false; knit.len()];
        source.iter().for_each(|&i| seen[i] = true);
        assert!(seen.iter().all(|&s| s), "every knit point is a vertex");

        // Every edge between knit points joins two triangles, but the welt's.
        let mut edges: BTreeMap<(usize, usize), u32> = BTreeMap::new();
        for t in &mesh.triangles {
            for k in 0..3 {
                let (a, b) = (source[t[k] as usize], source[t[(k + 1) % 3] as usize]);
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        let open: Vec<(usize, usize)> = edges
            .iter()
            .filter(|(_, &n)| n != 2)
            .map(|(&e, _)| e)
            .collect();
        let welt: Vec<(usize, usize)> = (0..WALES)
            .map(|w| (w.min((w + 1) % WALES), w.max((w + 1) % WALES)))
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .collect();
        assert_eq!(open, welt);
    }

    #[test]
    fn a_stockings_vertex_colours_are_white_with_its_coverage_as_opacity() {
        let knit = shaped_tube();
        let mesh = surface(&knit);
        let coverage = &mesh.point_attributes["coverage"];
        assert!(coverage.iter().any(|&c| c > 0.0 && c < 1.0), "{coverage:?}");
        assert_eq!(mesh.opacity.as_ref(), Some(coverage));
        assert_eq!(mesh.colours, Some(vec![[1.0; 3]; mesh.positions.len()]));

        // Clamped to 0–1 whatever the coverage: a yarn thicker than its spacing covers it all.
        let fields = KnitFields {
            coverage: vec![1.7; knit.len()],
            ..surface_fields(&knit)
        };
        let mesh = stocking_surface(&knit, &fields, &knit.yarn_geometry("stocking", [0.0; 3]));
        assert!(mesh.opacity.unwrap().iter().all(|&a| a == 1.0));
        assert!(mesh.point_attributes["coverage"].iter().all(|&c| c == 1.7));

        // Without fields, no colours.
        let bare = stocking_surface(
            &knit,
            &KnitFields::default(),
            &knit.yarn_geometry("stocking", [0.0; 3]),
        );
        assert_eq!((bare.colours, bare.opacity), (None, None));
    }

    #[test]
    fn a_shaped_stockings_triangles_face_out_and_its_texture_does_not_jump() {
        let knit = shaped_tube();
        let mesh = surface(&knit);
        let uv = mesh.texcoords.as_ref().unwrap();
        let middle = Vec3::new(0.0, (COURSES - 1) as f64 * SPACING / 2.0, 0.0);
        let mut wrapping = 0;
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|v| vector(mesh.positions[v as usize]));
            let normal = (b - a).cross(&(c - a));
            // The smallest: a fifth of a course high (the pocket) by a wale across.
            assert!(
                normal.norm() / 2.0 > 1e-5,
                "{t:?}: area {}",
                normal.norm() / 2.0
            );
            let out = (a + b + c) / 3.0 - middle;
            assert!(normal.dot(&out) > 0.0, "{t:?} faces in");
            let [u, v] = [0, 1].map(|k| t.map(|i| uv[i as usize][k]));
            let on_the_toe = v.iter().all(|&v| v == 0.0);
            if !on_the_toe {
                // Around by at most a wale, the seam's folded faces aside.
                let span = u.iter().fold(f32::MIN, |m, &x| m.max(x))
                    - u.iter().fold(f32::MAX, |m, &x| m.min(x));
                assert!(span <= 1.0 / WALES as f32 + 1e-6, "{t:?}: u {u:?}");
                wrapping += u.contains(&1.0) as usize;
            }
        }
        // Two triangles a cell across the wrap; the pocket's cell there, with four short rows on
        // both sides, is five cells.
        assert_eq!(wrapping, 2 * (COURSES - 1) + 2 * 4);
        // The repeated first wale shares its normals.
        for (v, t) in uv.iter().enumerate() {
            if t[0] == 1.0 {
                let twin = (0..uv.len())
                    .find(|&o| uv[o] == [0.0, t[1]])
                    .expect("a point of the first wale");
                assert_eq!(mesh.normals[v], mesh.normals[twin]);
            }
        }
    }
    #[test]
    fn the_lifted_surface_clears_the_skin_between_coarse_wales_and_keeps_its_seam_closed() {
        // A round leg of radius 30 mm (96 sides) under a 12-wale tube whose points rest on it:
        // the chords between wales cut 1 mm into the round, so the 1 mm lift alone leaves the
        // edges' midpoints on the skin, and the further rounds must clear them.
        let r = 0.03;
        let leg = Leg::round(r, 0.2, 96, 4);
        let collider = Collider::new(&leg, ContactMethod::Bvh).unwrap();
        let (wales, courses) = (12, 8);
        let knit = Knit::grid(
            wales,
            courses,
            true,
            &Tile::of(Pattern::Plain),
            TAU * r / wales as f64,
            0.02,
            |w, c| {
                let a = TAU * w as f64 / wales as f64;
                Vec3::new(r * a.cos(), 0.02 + 0.02 * c as f64, r * a.sin())
            },
        );
        let mut mesh = surface(&knit);
        let before: Vec<[f64; 3]> = mesh.positions.clone();
        let dipping = lift_clear_of(&mut mesh, &collider);
        assert_eq!(dipping, 0);
        // The rounds lifted the corners past the first millimetre.
        let most = mesh
            .positions
            .iter()
            .zip(&before)
            .map(|(p, q)| (Vector3::from(*p) - Vector3::from(*q)).norm())
            .fold(0.0, f64::max);
        assert!(most > 1.5 * STOCKING_LIFT_M, "{most}");
        let corners = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        for t in &mesh.triangles {
            for w in CLEARANCE_SAMPLES.into_iter().chain(corners) {
                let p = (0..3).fold(Vector3::zeros(), |acc, k| {
                    acc + Vector3::from(mesh.positions[t[k] as usize]) * w[k]
                });
                let clearance = collider.closest(&Point3::from(p)).signed_distance;
                assert!(clearance >= STOCKING_CLEARANCE_M - 1e-9, "{clearance}");
            }
        }
        // Every repeated seam point moved with its twin: no vertex of wale 0 lies apart from a
        // vertex that started with it.
        let repeated = mesh.positions.len() - knit.len();
        assert_eq!(repeated, courses);
        for c in 0..courses {
            let row = c * (wales + 1);
            assert_eq!(
                mesh.positions[row],
                mesh.positions[row + wales],
                "course {c}"
            );
        }
    }
}
