//! The leg as a solid, however it was modelled: a character's limb may be one closed skin, or
//! pieces that touch or pass into one another (a mannequin's ball joints inside its shin and
//! thigh, a foot modelled apart and pushed into the leg). The solid is their union; its skin is
//! what a yarn can rest on. A triangle of one piece that lies inside another piece is inside the
//! solid, not on its skin: contact that found it nearest would hold yarn inside the leg, and the
//! penetration check would count every yarn that passes over it.
//!
//! Inside a piece is told by the sign of the closest point's angle-weighted pseudo-normal
//! (Bærentzen & Aanæs 2005), as contact does, against that piece alone: each piece is a closed,
//! outward-wound surface once cleaned ([`super::clean`], [`super::orient`]), where the sign is
//! exact. A piece open at a cut still reads right away from its opening. A triangle across the
//! line where two pieces meet is split until its parts are a millimetre long, and keeps those
//! outside, the last ones clipped where their edges enter the other piece (searched for within
//! the bracket the depth's sign gives): the skin ends on the other piece's, with no gap a
//! triangle wide that yarn falls through and no part poking inside. The skin is open along
//! those seams (and where split triangles meet whole ones), where its pseudo-normals say
//! nothing, so contact asks the pieces ([`Pieces`]) about a point whose nearest skin is an open
//! edge ([`super::Collider::with_pieces`]). The generalized winding number (Jacobson, Kavan &
//! Sorkine-Hornung 2013) would also read pieces with holes; a mesh in one piece, the common
//! case, needs neither and is returned whole.

use std::collections::HashMap;

use nalgebra::{Point3, Vector3};
use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry3d_f64::query::{PointQuery, PointQueryWithLocation, Ray, RayCast};
use parry3d_f64::shape::{TriMesh, TriMeshFlags, TrianglePointLocation};

/// How far inside another piece a triangle's centre must lie to be buried, metres: pieces that
/// only touch (a face on a face) keep both their skins.
const BURIED_DEPTH_M: f64 = 1e-5;

/// Per vertex, its connected piece (vertices joined by triangles), numbered from 0 in the order
/// of their first vertex; `u32::MAX` for a vertex no triangle uses.
pub fn connected_pieces(vertices: usize, triangles: &[[u32; 3]]) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..vertices as u32).collect();
    fn root(parent: &mut [u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            parent[i as usize] = parent[parent[i as usize] as usize];
            i = parent[i as usize];
        }
        i
    }
    let mut used = vec![false; vertices];
    for t in triangles {
        for k in 0..3 {
            used[t[k] as usize] = true;
            let (a, b) = (root(&mut parent, t[k]), root(&mut parent, t[(k + 1) % 3]));
            parent[a.max(b) as usize] = a.min(b);
        }
    }
    let mut number: HashMap<u32, u32> = HashMap::new();
    (0..vertices as u32)
        .map(|i| {
            if !used[i as usize] {
                return u32::MAX;
            }
            let r = root(&mut parent, i);
            let next = number.len() as u32;
            *number.entry(r).or_insert(next)
        })
        .collect()
}

/// How near a piece must come to another to touch it, metres.
pub const TOUCH_M: f64 = 0.002;

/// Per piece (numbered as `piece`, each triangle's), the group it belongs to: pieces that touch
/// (a vertex within [`TOUCH_M`] of the other) or pass into one another (an edge through the
/// other's skin), transitively, numbered by their lowest piece. A piece wholly inside another
/// without touching it stays apart.
pub fn touching_groups(
    positions: &[Point3<f64>],
    triangles: &[[u32; 3]],
    piece: &[u32],
) -> Vec<u32> {
    let count = piece.iter().copied().max().map_or(0, |p| p as usize + 1);
    let mut own: Vec<Vec<[u32; 3]>> = vec![Vec::new(); count];
    for (t, &p) in triangles.iter().zip(piece) {
        own[p as usize].push(*t);
    }
    let meshes: Vec<Option<TriMesh>> = (own.iter())
        .map(|ts| TriMesh::new(positions.to_vec(), ts.clone()).ok())
        .collect();
    let boxes: Vec<Option<Aabb>> = (meshes.iter())
        .map(|m| m.as_ref().map(|m| m.local_aabb().loosened(TOUCH_M)))
        .collect();
    let touches = |a: usize, b: usize| {
        let (Some(mesh), Some(aabb)) = (&meshes[a], &boxes[a]) else {
            return false;
        };
        own[b].iter().any(|t| {
            let corners = t.map(|i| positions[i as usize]);
            corners.iter().any(|c| {
                aabb.contains_local_point(c) && mesh.distance_to_local_point(c, false) <= TOUCH_M
            }) || (0..3).any(|k| {
                let (from, to) = (corners[k], corners[(k + 1) % 3]);
                let ray = Ray::new(from, to - from);
                mesh.intersects_local_ray(&ray, 1.0)
            })
        })
    };
    let mut group: Vec<u32> = (0..count as u32).collect();
    fn root(group: &mut [u32], mut i: u32) -> u32 {
        while group[i as usize] != i {
            i = group[i as usize];
        }
        i
    }
    for a in 0..count {
        for b in a + 1..count {
            let overlap = match (&boxes[a], &boxes[b]) {
                (Some(x), Some(y)) => x.intersects(y),
                _ => false,
            };
            if overlap && (touches(a, b) || touches(b, a)) {
                let (ra, rb) = (root(&mut group, a as u32), root(&mut group, b as u32));
                group[ra.max(rb) as usize] = ra.min(rb);
            }
        }
    }
    (0..count as u32).map(|p| root(&mut group, p)).collect()
}

/// Per triangle, its connected piece (triangles sharing vertices), numbered as
/// [`connected_pieces`] numbers them.
pub fn triangle_pieces(positions: &[Point3<f64>], triangles: &[[u32; 3]]) -> Vec<u32> {
    let vertex_piece = connected_pieces(positions.len(), triangles);
    (triangles.iter())
        .map(|t| vertex_piece[t[0] as usize])
        .collect()
}

/// A triangle across the line where two pieces meet is split in four, again and again, until
/// its parts are this long or [`MEETING_SPLITS`] deep; the last parts are clipped where their
/// edges enter another piece, with a straight cut between, so this is about how far the cut
/// may stray from the curved line where the pieces meet.
const MEETING_EDGE_M: f64 = 1e-3;
/// At most this many splits of a triangle across the meeting line: a 3 cm triangle reaches
/// [`MEETING_EDGE_M`] in five. Fewer are cheaper but fit fewer legs in pieces (decision 0076).
const MEETING_SPLITS: u32 = 5;

/// A leg's pieces (numbered as [`triangle_pieces`] numbers them), each its own surface, for
/// telling how deep a point lies inside them: where pieces meet, the solid's skin has seams
/// that its pseudo-normals cannot read, and each piece alone can (exactly where it is closed;
/// a piece open at a cut reads right away from its opening, and beyond its box is outside).
pub struct Pieces {
    meshes: Vec<Option<TriMesh>>,
    boxes: Vec<Option<Aabb>>,
}

impl Pieces {
    /// The pieces of `triangles` (each wound outwards), where there are two or more.
    pub fn of(positions: &[Point3<f64>], triangles: &[[u32; 3]]) -> Option<Pieces> {
        let piece = triangle_pieces(positions, triangles);
        let count = piece.iter().copied().max().map_or(0, |p| p as usize + 1);
        (count > 1).then(|| Pieces::new(positions, triangles, &piece, count))
    }

    /// The pieces of `triangles`, each piece's triangle `piece[t]`; `count` of them.
    fn new(positions: &[Point3<f64>], triangles: &[[u32; 3]], piece: &[u32], count: usize) -> Self {
        let mut own: Vec<Vec<[u32; 3]>> = vec![Vec::new(); count];
        for (t, &p) in triangles.iter().zip(piece) {
            own[p as usize].push(*t);
        }
        let flags = TriMeshFlags::ORIENTED | TriMeshFlags::MERGE_DUPLICATE_VERTICES;
        let meshes: Vec<Option<TriMesh>> = own
            .into_iter()
            .map(|ts| TriMesh::with_flags(positions.to_vec(), ts, flags).ok())
            .collect();
        let boxes = (meshes.iter())
            .map(|m| m.as_ref().map(|m| m.local_aabb().loosened(BURIED_DEPTH_M)))
            .collect();
        Pieces { meshes, boxes }
    }

    /// How deep `p` lies inside the union of the pieces other than `except`: positive inside
    /// (by its distance to the skin of the piece it is deepest in), negative outside (by its
    /// distance to the nearest, or to its box where `p` is outside that: finite, for clipping).
    pub fn depth(&self, p: &Point3<f64>, except: Option<u32>) -> f64 {
        (self.meshes.iter().zip(&self.boxes).enumerate())
            .filter(|(k, _)| Some(*k as u32) != except)
            .filter_map(|(_, (mesh, aabb))| {
                let (mesh, aabb) = (mesh.as_ref()?, aabb.as_ref()?);
                if !aabb.contains_local_point(p) {
                    return Some(-aabb.distance_to_local_point(p, true));
                }
                let (projection, (triangle, location)) =
                    mesh.project_local_point_and_get_location(p, false);
                let distance = (projection.point - p).norm();
                Some(
                    match is_inside(mesh, p, &projection.point, triangle, location) {
                        true => distance,
                        false => -distance,
                    },
                )
            })
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// True when `p` lies inside some piece.
    pub fn contain(&self, p: &Point3<f64>) -> bool {
        self.depth(p, None) > 0.0
    }
}

/// The solid's skin: the vertices (`positions`, then the new corners where triangles across a
/// meeting line were split) and the triangles of `triangles` that lie outside every other piece,
/// in their order, a triangle across a meeting line replaced by its parts outside (see module
/// docs); and the pieces, where there are two or more.
pub fn outer_skin(
    positions: &[Point3<f64>],
    triangles: &[[u32; 3]],
) -> (Vec<Point3<f64>>, Vec<[u32; 3]>, Option<Pieces>) {
    let piece = triangle_pieces(positions, triangles);
    let count = piece.iter().copied().max().map_or(0, |p| p as usize + 1);
    if count <= 1 {
        return (positions.to_vec(), triangles.to_vec(), None);
    }
    let pieces = Pieces::new(positions, triangles, &piece, count);
    let depth_in_others = |p: &Point3<f64>, own: u32| pieces.depth(p, Some(own));
    let buried = |p: &Point3<f64>, own: u32| depth_in_others(p, own) > BURIED_DEPTH_M;
    // Each vertex's own answer, asked once.
    let vertex_piece = connected_pieces(positions.len(), triangles);
    let vertex_buried: Vec<bool> = (positions.iter().zip(&vertex_piece))
        .map(|(p, &own)| own != u32::MAX && buried(p, own))
        .collect();
    let mut skin = SplitSkin::new(positions);
    for (t, &own) in triangles.iter().zip(&piece) {
        let corners = t.map(|i| positions[i as usize]);
        let inside = t.map(|i| vertex_buried[i as usize]);
        match Across::of(inside, buried(&centre(&corners), own)) {
            Across::Outside => skin.triangles.push(*t),
            Across::Buried => {}
            Across::Both => skin.split(corners, 0, &|p| depth_in_others(p, own)),
        }
    }
    (skin.positions, skin.triangles, Some(pieces))
}

/// Where a triangle lies against the other pieces, from whether its corners and its centre are
/// buried in them.
enum Across {
    Outside,
    Buried,
    Both,
}

impl Across {
    fn of(corners_buried: [bool; 3], centre_buried: bool) -> Across {
        match (corners_buried, centre_buried) {
            ([false, false, false], false) => Across::Outside,
            ([true, true, true], true) => Across::Buried,
            _ => Across::Both,
        }
    }
}

fn centre(c: &[Point3<f64>; 3]) -> Point3<f64> {
    Point3::from((c[0].coords + c[1].coords + c[2].coords) / 3.0)
}

/// The skin being built: every vertex, the file's and the split triangles' new corners (one per
/// position: two neighbours split alike share them), and the triangles kept.
struct SplitSkin {
    positions: Vec<Point3<f64>>,
    triangles: Vec<[u32; 3]>,
    added: HashMap<[u64; 3], u32>,
}

impl SplitSkin {
    fn new(positions: &[Point3<f64>]) -> Self {
        SplitSkin {
            positions: positions.to_vec(),
            triangles: Vec::new(),
            added: HashMap::new(),
        }
    }

    fn vertex(&mut self, p: Point3<f64>) -> u32 {
        let key = [p.x, p.y, p.z].map(f64::to_bits);
        let next = self.positions.len() as u32;
        let id = *self.added.entry(key).or_insert(next);
        if id == next {
            self.positions.push(p);
        }
        id
    }

    /// Splits the triangle `c` across a meeting line in four and keeps, or splits again, each
    /// part: whole where its corners and centre are all outside (`depth` at most
    /// [`BURIED_DEPTH_M`]), dropped where all are buried. The last parts are clipped
    /// ([`SplitSkin::clipped`]): no part pokes into another piece.
    fn split(&mut self, c: [Point3<f64>; 3], splits: u32, depth: &dyn Fn(&Point3<f64>) -> f64) {
        let longest = (c[1] - c[0])
            .norm()
            .max((c[2] - c[1]).norm())
            .max((c[0] - c[2]).norm());
        if splits == MEETING_SPLITS || longest <= MEETING_EDGE_M {
            self.clipped(c, depth);
            return;
        }
        let mid = |a: &Point3<f64>, b: &Point3<f64>| Point3::from((a.coords + b.coords) / 2.0);
        let (ab, bc, ca) = (mid(&c[0], &c[1]), mid(&c[1], &c[2]), mid(&c[2], &c[0]));
        for part in [[c[0], ab, ca], [ab, c[1], bc], [ca, bc, c[2]], [ab, bc, ca]] {
            let buried = |p: &Point3<f64>| depth(p) > BURIED_DEPTH_M;
            match Across::of(part.map(|p| buried(&p)), buried(&centre(&part))) {
                Across::Outside => {
                    let t = part.map(|p| self.vertex(p));
                    self.triangles.push(t);
                }
                Across::Buried => {}
                Across::Both => self.split(part, splits + 1, depth),
            }
        }
    }

    /// Keeps the part of the triangle `c` where `depth` is at most zero: a triangle or a quad
    /// (two triangles), wound as `c`. Where an edge crosses into another piece, the crossing is
    /// searched for ([`crossing`]), not taken from the depth at the ends as linear: near a ledge
    /// (a piece a millimetre wider than the one it sits on) the depth is the distance to the
    /// other piece's nearer wall, not to the face being crossed, and a linear guess put the
    /// crossing tens of micrometres inside it.
    fn clipped(&mut self, c: [Point3<f64>; 3], depth: &dyn Fn(&Point3<f64>) -> f64) {
        let outside = c.map(|p| depth(&p) <= 0.0);
        let mut kept: Vec<Point3<f64>> = Vec::with_capacity(4);
        for k in 0..3 {
            let (a, b) = (k, (k + 1) % 3);
            if outside[a] {
                kept.push(c[a]);
            }
            if outside[a] != outside[b] {
                // Searched from the lower-ordered end, so that the triangle across the edge
                // finds the same point.
                let (p, q) = match (c[a].x, c[a].y, c[a].z) < (c[b].x, c[b].y, c[b].z) {
                    true => (c[a], c[b]),
                    false => (c[b], c[a]),
                };
                kept.push(crossing(&p, &q, depth));
            }
        }
        let ids: Vec<u32> = kept.into_iter().map(|p| self.vertex(p)).collect();
        for k in 1..ids.len().saturating_sub(1) {
            let t = [ids[0], ids[k], ids[k + 1]];
            if t[0] != t[1] && t[1] != t[2] && t[2] != t[0] {
                self.triangles.push(t);
            }
        }
    }
}

/// How near the crossing of an edge into another piece is found, metres: a hundredth of
/// [`BURIED_DEPTH_M`].
const CROSSING_TOLERANCE_M: f64 = 1e-7;
/// At most this many depths are asked for one crossing (bisection alone needs 14 on a
/// millimetre edge).
const CROSSING_STEPS: u32 = 40;

/// The point of the segment `p`–`q`, whose ends lie on either side of the other pieces' skin
/// (`depth` at most zero at one end only), where it crosses that skin, to
/// [`CROSSING_TOLERANCE_M`] (or as near as [`CROSSING_STEPS`] bring it): regula falsi on the
/// depth, bracketed by its sign, which is exact, with the Illinois rule (an end kept twice has
/// its depth halved, so the bracket shrinks from both sides however the depth bends), the
/// outer end of the last bracket returned, so the point is never inside.
fn crossing(p: &Point3<f64>, q: &Point3<f64>, depth: &dyn Fn(&Point3<f64>) -> f64) -> Point3<f64> {
    let at = |t: f64| p + (q - p) * t;
    let (dp, dq) = (depth(p), depth(q));
    // Along p → q: the outer end (depth at most 0) and the inner one (depth above 0).
    let ((mut t_out, mut d_out), (mut t_in, mut d_in)) = match dp <= 0.0 {
        true => ((0.0_f64, dp), (1.0_f64, dq)),
        false => ((1.0, dq), (0.0, dp)),
    };
    let length = (q - p).norm();
    // How many steps running have moved the outer end (below 0) or the inner one (above 0).
    let mut streak: i32 = 0;
    for _ in 0..CROSSING_STEPS {
        if (t_in - t_out).abs() * length <= CROSSING_TOLERANCE_M {
            break;
        }
        // Where the depth, taken as linear across the bracket, is zero; off its ends by a
        // hundredth of it at least, so that every step shrinks it.
        let f = (d_out / (d_out - d_in)).clamp(0.01, 0.99);
        let t = t_out + (t_in - t_out) * f;
        let d = depth(&at(t));
        if d <= 0.0 {
            (t_out, d_out) = (t, d);
            streak = streak.min(0) - 1;
            if streak <= -2 {
                d_in /= 2.0;
            }
        } else {
            (t_in, d_in) = (t, d);
            streak = streak.max(0) + 1;
            if streak >= 2 {
                d_out /= 2.0;
            }
        }
    }
    at(t_out)
}

/// True when `p`, whose closest point on the oriented `mesh` is `closest`, on `triangle` at
/// `location`, is inside it: behind the pseudo-normal of the closest feature (face, edge or
/// vertex).
pub fn is_inside(
    mesh: &TriMesh,
    p: &Point3<f64>,
    closest: &Point3<f64>,
    triangle: u32,
    location: TrianglePointLocation,
) -> bool {
    let normal = match (mesh.pseudo_normals_if_oriented(), location) {
        (Some(pn), TrianglePointLocation::OnEdge(i, _)) => {
            pn.edges_pseudo_normal[triangle as usize][i as usize]
        }
        (Some(pn), TrianglePointLocation::OnVertex(i)) => {
            let v = mesh.indices()[triangle as usize][i as usize];
            pn.vertices_pseudo_normal[v as usize]
        }
        _ => face_normal(mesh, triangle),
    };
    (p - closest).dot(&normal) < 0.0
}

/// Outward unit normal of `triangle` of `mesh` (+Y for a degenerate one).
pub fn face_normal(mesh: &TriMesh, triangle: u32) -> Vector3<f64> {
    mesh.triangle(triangle)
        .normal()
        .map(|n| n.into_inner())
        .unwrap_or_else(Vector3::y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::leg::test_meshes;

    /// Appends the cube from `lo` to `hi` along every axis.
    fn add_box(positions: &mut Vec<Point3<f64>>, triangles: &mut Vec<[u32; 3]>, lo: f64, hi: f64) {
        test_meshes::add_box(positions, triangles, [lo; 3], [hi; 3]);
    }

    #[test]
    fn a_piece_inside_another_is_buried_and_pieces_apart_keep_their_skins() {
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        add_box(&mut positions, &mut triangles, 0.0, 1.0);
        add_box(&mut positions, &mut triangles, 0.25, 0.75); // inside the first
        add_box(&mut positions, &mut triangles, 2.0, 3.0); // apart
        let pieces = connected_pieces(positions.len(), &triangles);
        assert_eq!(pieces.iter().copied().max(), Some(2));
        let (_, skin, _) = outer_skin(&positions, &triangles);
        assert_eq!(skin.len(), 24, "the inner box's 12 triangles go");
        assert!(skin
            .iter()
            .all(|t| t.iter().all(|&i| !(8..16).contains(&i))));
    }

    #[test]
    fn pieces_that_touch_or_pass_into_each_other_group_and_others_stay_apart() {
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        add_box(&mut positions, &mut triangles, 0.0, 1.0);
        add_box(&mut positions, &mut triangles, 0.25, 0.75); // inside, not touching
        add_box(&mut positions, &mut triangles, 0.9, 1.9); // passing into the first
        add_box(&mut positions, &mut triangles, 1.9005, 2.5); // touching the third
        add_box(&mut positions, &mut triangles, 3.0, 3.5); // apart
        let piece = triangle_pieces(&positions, &triangles);
        assert_eq!(
            touching_groups(&positions, &triangles, &piece),
            [0, 1, 0, 0, 4]
        );
    }

    #[test]
    fn pieces_that_pass_into_each_other_lose_what_is_inside() {
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        add_box(&mut positions, &mut triangles, 0.0, 1.0);
        // A second box passing into the first: each loses the three faces' parts inside the
        // other, its triangles across the meeting lines split and clipped there.
        add_box(&mut positions, &mut triangles, 0.25, 1.25);
        let (skin_positions, skin, _) = outer_skin(&positions, &triangles);
        let corners = |t: &[u32; 3]| t.map(|i| skin_positions[i as usize]);
        // No part pokes into either box (strictly inside both its ranges on every axis).
        let strictly_in =
            |p: &Point3<f64>, lo: f64, hi: f64| p.iter().all(|&x| x > lo + 1e-9 && x < hi - 1e-9);
        for t in &skin {
            let c = corners(t);
            let m = centre(&c);
            assert!(
                !strictly_in(&m, 0.0, 1.0) && !strictly_in(&m, 0.25, 1.25),
                "{c:?}"
            );
        }
        // What is kept is the union's surface: 6 + 6 - 2 × 3 × 0.75² m² (faces kept or
        // dropped whole had covered 6 m² of it).
        let area = |t: &[u32; 3]| {
            let [a, b, c] = corners(t);
            (b - a).cross(&(c - a)).norm() / 2.0
        };
        let total: f64 = skin.iter().map(area).sum();
        let union = 12.0 - 6.0 * 0.75 * 0.75;
        assert!((total - union).abs() < 1e-6, "{total} against {union}");
        // One piece alone is returned whole, with no pieces to ask.
        let one = &triangles[..12];
        let (whole_positions, whole, pieces) = outer_skin(&positions, one);
        assert_eq!((whole_positions, whole), (positions.clone(), one.to_vec()));
        assert!(pieces.is_none());
    }

    #[test]
    fn a_piece_on_a_ledge_is_clipped_at_the_ledge_not_inside_the_piece_above() {
        // A mannequin's shin (10 cm square) passing 2 cm up into its thigh, 1 mm wider each
        // side: inside the thigh, the shin's faces are 1 mm from the thigh's walls, nearer than
        // from the ledge they cross, so the depth is no guide to where they cross it.
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        test_meshes::add_box(&mut positions, &mut triangles, [0.0; 3], [0.1, 0.3, 0.1]);
        let (lo, hi) = ([-0.001, 0.28, -0.001], [0.101, 0.5, 0.101]);
        test_meshes::add_box(&mut positions, &mut triangles, lo, hi);
        let (skin_positions, skin, _) = outer_skin(&positions, &triangles);
        // How deep a point lies inside the thigh (negative: outside it).
        let in_thigh = |p: &Point3<f64>| {
            (0..3)
                .map(|k| (p[k] - lo[k]).min(hi[k] - p[k]))
                .fold(f64::INFINITY, f64::min)
        };
        let deepest = (skin.iter().flatten())
            .map(|&i| in_thigh(&skin_positions[i as usize]))
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(
            deepest < 1e-6,
            "a corner of the skin lies {deepest} m inside the thigh"
        );
        // The shin's sides still reach the ledge: no gap under it for yarn to fall into.
        let missing = (skin.iter().flatten())
            .map(|&i| skin_positions[i as usize])
            .filter(|p| (p.x.abs() < 1e-12 || (p.x - 0.1).abs() < 1e-12) && p.y > 0.2)
            .map(|p| p.y)
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(
            (missing - 0.28).abs() < 1e-6,
            "the shin's side ends at {missing} m, not at the ledge"
        );
    }
}
