//! The skin a fit can trust, cleaned of what character exports carry besides it.
//!
//! Exporters write a vertex once per face corner (flat shading, UV seams), repeat faces, leave
//! zero-area slivers and T-junctions, and put eyes, teeth, nails or stray debris in the same
//! file. Each of these breaks a question the fit asks of the leg: a repeated face makes its edges
//! non-manifold, so the pseudo-normals that tell inside from outside (Bærentzen & Aanæs) and the
//! cross-section loops both go wrong there; a piece of debris inside the leg is a second surface
//! that contact may snap to. So, before anything else looks at the mesh:
//!
//! 1. vertices at exactly the same position become one (the first of them);
//! 2. triangles with two corners on one vertex, or with no area to speak of (a corner within
//!    [`SLIVER`] of the longest edge's length, or within [`F32_ROUNDING`] of the coordinates'
//!    size, of the line through that edge), are dropped;
//! 3. a triangle on the same three vertices as an earlier one, in either winding, is dropped;
//! 4. T-junctions are closed: where a vertex at the end of an open edge lies on another open
//!    edge, between its ends (as a sliver's corner would, by the test of step 2), the triangle of
//!    that edge is split there, fanned from its opposite corner. Exporters leave these where one
//!    side of a seam was subdivided and the other not; the surface is closed, but its sides share
//!    no vertices along the seam, so each section loop crossing it would break into open chains
//!    there, and the seam's edges would be open to the pseudo-normals;
//! 5. connected pieces (sharing vertices) with less than [`DEBRIS_AREA_FRACTION`] of the largest
//!    body-like piece's area are dropped (eyes, teeth, nails, debris), and so are sheets (a
//!    floor, a backdrop: open at [`SHEET_OPEN_FRACTION`] of their edges) beside a body. The legs
//!    of a body exported in pieces that do not share vertices stay, each a large share of it.
//! 6. small holes are closed: a loop of open edges at most [`HOLE_PERIMETER_M`] around (a face
//!    or two an exporter or a boolean lost) gets a fan of triangles from its centre, wound as
//!    its neighbours are. A hole lets contact and the pseudo-normals see through the skin, and
//!    opens every section that crosses it; a cut, far larger, stays open.
//!
//! The result is what every later stage sees: orientation, landmarks, tube, contact, and the
//! leg written with the fit's attributes. The counts go to the report.

use std::collections::{HashMap, HashSet};

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use super::solid::{touching_groups, triangle_pieces};
use super::weld::welded_ids;

/// Pieces smaller than this fraction of the largest body-like piece's area are dropped as
/// debris.
pub const DEBRIS_AREA_FRACTION: f64 = 0.02;
/// A piece that neither touches nor passes into the body's solid ([`touching_groups`]) and has
/// at most this fraction of its area is dropped too: a box or a prop beside the leg. A second
/// leg or body modelled apart is far larger.
pub const APART_AREA_FRACTION: f64 = 0.1;
/// A piece with at least this fraction of its triangles' edges open (used by one triangle) is a
/// sheet, not a body: a floor, a backdrop, a card for hair or lashes.
pub const SHEET_OPEN_FRACTION: f64 = 0.2;

/// A loop of open edges at most this long (metres) is a hole in the skin, and is closed. A leg
/// is cut at 0.18 m around or more (an adult's ankle); a lost face of a coarse export (a whole
/// body's 3 cm triangles at the knee) is up to about 9 cm around.
pub const HOLE_PERIMETER_M: f64 = 0.12;

/// A loop of open edges is a hole in its piece only where its length squared is at most this
/// fraction of the piece's area: a lost face of a whole leg is a few thousandths of it, of a
/// mannequin's coarse shin 0.10–0.15; the rim of a patch is 4π times it or more when flat (the
/// isoperimetric bound), 2π for a hemisphere's shell, and that of a tube open at one end about
/// 2π times its radius over its length, so such a tube keeps its opening up to about 21 radii
/// long. A small coarse piece (a 3 cm ball in 3 cm triangles: about 0.7) keeps a lost face open.
pub const HOLE_OF_PIECE: f64 = 0.3;

/// A triangle whose doubled area (the cross product of two edges) is at most this times its
/// longest edge squared has no area worth the name: its third corner lies within a millionth of
/// an edge from the line of the other two.
pub const SLIVER: f64 = 1e-6;

/// A triangle whose third corner lies within this times its largest coordinate (in absolute
/// value) of the line through its longest edge has no area either: that is a point on the edge
/// rounded to 32-bit floats, as glTF stores positions. Rounding moves each coordinate by up to
/// half an f32 epsilon of its size, which on a 5 mm edge 0.8 m from the origin is a few
/// millionths of the edge, more than [`SLIVER`] allows; twice the epsilon covers all three
/// coordinates' rounding with room to spare, and is 0.24 µm at 1 m.
pub const F32_ROUNDING: f64 = 2.0 * f32::EPSILON as f64;

/// What cleaning removed from the file's mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cleaned {
    /// Vertices merged into an earlier one at the same position.
    pub merged_vertices: usize,
    /// Triangles with no area.
    pub degenerate_triangles: usize,
    /// Triangles on the same vertices as an earlier one.
    pub duplicate_triangles: usize,
    /// Triangles split at the T-junctions on their edges.
    pub split_triangles: usize,
    /// Triangles of pieces too small to be the skin.
    pub debris_triangles: usize,
    /// Pieces dropped as debris.
    pub debris_pieces: usize,
    /// Small holes closed ([`HOLE_PERIMETER_M`]).
    pub filled_holes: usize,
}

/// Cleans `positions` and `triangles` as the module docs say: returns the kept vertices
/// (renumbered, in the file's order), the kept triangles and the counts.
pub fn clean_mesh(
    positions: &[Point3<f64>],
    triangles: &[[u32; 3]],
) -> (Vec<Point3<f64>>, Vec<[u32; 3]>, Cleaned) {
    let mut cleaned = Cleaned::default();
    // 1. One id per position.
    let welded = welded_ids(positions);
    cleaned.merged_vertices = welded
        .iter()
        .enumerate()
        .filter(|&(i, &w)| w as usize != i)
        .count();
    // 2. and 3. Triangles with area, once each.
    let mut seen: HashMap<[u32; 3], ()> = HashMap::with_capacity(triangles.len());
    let mut kept: Vec<[u32; 3]> = Vec::with_capacity(triangles.len());
    for t in triangles {
        let w = t.map(|i| welded[i as usize]);
        let [a, b, c] = w.map(|i| positions[i as usize]);
        if w[0] == w[1] || w[1] == w[2] || w[2] == w[0] || is_sliver(&a, &b, &c) {
            cleaned.degenerate_triangles += 1;
            continue;
        }
        let mut key = w;
        key.sort_unstable();
        if seen.insert(key, ()).is_some() {
            cleaned.duplicate_triangles += 1;
            continue;
        }
        kept.push(w);
    }
    // 4. T-junctions closed.
    cleaned.split_triangles = close_t_junctions(positions, &mut kept);
    // 5. Pieces, by shared vertices; the small ones go.
    let piece = triangle_pieces(positions, &kept);
    let mut piece_area: HashMap<u32, f64> = HashMap::new();
    for (t, p) in kept.iter().zip(&piece) {
        *piece_area.entry(*p).or_default() += area(positions, t);
    }
    // Sheets (a floor, a backdrop, a card) are open nearly everywhere; a body, even cut, is
    // closed nearly everywhere. The largest body-like piece is what debris is measured against,
    // and sheets go with the debris wherever there is one.
    let mut edge_uses: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &kept {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *edge_uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut piece_edges: HashMap<u32, (usize, usize)> = HashMap::new();
    for (t, p) in kept.iter().zip(&piece) {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            let entry = piece_edges.entry(*p).or_default();
            entry.0 += 1;
            entry.1 += usize::from(edge_uses[&(a.min(b), a.max(b))] == 1);
        }
    }
    let sheet = |p: &u32| {
        let (edges, open) = piece_edges[p];
        open as f64 >= SHEET_OPEN_FRACTION * edges as f64
    };
    let bodies = piece_area.iter().filter(|(p, _)| !sheet(p));
    let largest_body = bodies.map(|(_, &a)| a).fold(0.0, f64::max);
    let largest = if largest_body > 0.0 {
        largest_body
    } else {
        piece_area.values().copied().fold(0.0, f64::max)
    };
    // The solid the largest body-like piece belongs to (pieces that touch or pass into it, a
    // mannequin's limbs): a piece apart from it, a tenth of its size or less, is a prop or a
    // box beside the body, not a part of it. Asked only where pieces are left to ask about.
    let main = (piece_area.iter())
        .filter(|(p, _)| !sheet(p) || largest_body == 0.0)
        .max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(a.0)))
        .map(|(&p, _)| p);
    let big = |p: &u32| piece_area[p] >= DEBRIS_AREA_FRACTION * largest && !sheet(p);
    let group = match piece_area.keys().filter(|p| big(p)).count() {
        0 | 1 => None,
        _ => Some(touching_groups(positions, &kept, &piece)),
    };
    let solid_area: f64 = (piece_area.iter())
        .filter(|(p, _)| match (&group, main) {
            (Some(g), Some(m)) => g[**p as usize] == g[m as usize],
            _ => Some(**p) == main,
        })
        .map(|(_, a)| a)
        .sum();
    let apart = |p: &u32| match (&group, main) {
        (Some(g), Some(m)) => {
            g[*p as usize] != g[m as usize] && piece_area[p] < APART_AREA_FRACTION * solid_area
        }
        _ => false,
    };
    let debris = |p: &u32| {
        piece_area[p] < DEBRIS_AREA_FRACTION * largest
            || (largest_body > 0.0 && sheet(p))
            || apart(p)
    };
    cleaned.debris_pieces = piece_area.keys().filter(|p| debris(p)).count();
    let before = kept.len();
    let mut keep_piece = piece.iter().map(|p| !debris(p));
    kept.retain(|_| keep_piece.next().unwrap_or(false));
    cleaned.debris_triangles = before - kept.len();
    // 6. Small holes closed, each fan's centre a vertex after the file's.
    let mut positions = positions.to_vec();
    cleaned.filled_holes = fill_small_holes(&mut positions, &mut kept);
    // Renumber the vertices the kept triangles use, keeping the file's order.
    let mut new_id: Vec<u32> = vec![u32::MAX; positions.len()];
    for &i in kept.iter().flatten() {
        new_id[i as usize] = 0;
    }
    let mut kept_positions = Vec::new();
    for (i, id) in new_id.iter_mut().enumerate() {
        if *id == 0 {
            *id = kept_positions.len() as u32;
            kept_positions.push(positions[i]);
        }
    }
    for i in kept.iter_mut().flatten() {
        *i = new_id[*i as usize];
    }
    (kept_positions, kept, cleaned)
}

/// True when the triangle `a b c` has no area worth the name: twice its area, over its longest
/// edge, is the height of the third corner over that edge.
fn is_sliver(a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>) -> bool {
    let longest = (b - a).norm().max((c - b).norm()).max((a - c).norm());
    (b - a).cross(&(c - a)).norm() <= flat_height(longest, [a, b, c]) * longest
}

/// The height over its longest edge (of length `longest`) up to which a triangle with
/// `corners` is flat ([`SLIVER`], [`F32_ROUNDING`]).
fn flat_height(longest: f64, corners: [&Point3<f64>; 3]) -> f64 {
    let size = corners
        .iter()
        .flat_map(|p| p.iter())
        .fold(0.0f64, |m, x| m.max(x.abs()));
    (SLIVER * longest).max(F32_ROUNDING * size)
}

/// Closes the T-junctions of `triangles` (step 4 of the module docs) and returns how many
/// triangles were split. A triangle with T-junctions on more than one edge is split one edge per
/// pass, its pieces' edges then looked at again.
fn close_t_junctions(positions: &[Point3<f64>], triangles: &mut Vec<[u32; 3]>) -> usize {
    let mut split = 0;
    for _pass in 0..3 {
        let open = open_edges(triangles);
        // Vertices at the ends of open edges, in cells as wide as the longest open edge, so an
        // edge's own box meets at most two cells a side.
        let cell = open
            .iter()
            .map(|e| (positions[e.b as usize] - positions[e.a as usize]).norm())
            .fold(0.0, f64::max);
        if open.is_empty() || !(cell > 0.0 && cell.is_finite()) {
            break;
        }
        let cell_of = |p: &Point3<f64>| p.coords.map(|c| (c / cell).floor() as i64);
        let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        let mut listed = HashSet::new();
        for e in &open {
            for v in [e.a, e.b] {
                if listed.insert(v) {
                    let c = cell_of(&positions[v as usize]);
                    grid.entry([c.x, c.y, c.z]).or_default().push(v);
                }
            }
        }
        let mut done = vec![false; triangles.len()];
        let mut added = Vec::new();
        for e in &open {
            if done[e.triangle] {
                continue;
            }
            let (pa, pb) = (positions[e.a as usize], positions[e.b as usize]);
            let ab = pb - pa;
            let length = ab.norm();
            let (lo, hi) = (cell_of(&pa.inf(&pb)), cell_of(&pa.sup(&pb)));
            let mut on_edge: Vec<(f64, u32)> = Vec::new();
            for x in lo.x - 1..=hi.x + 1 {
                for y in lo.y - 1..=hi.y + 1 {
                    for z in lo.z - 1..=hi.z + 1 {
                        for &v in grid.get(&[x, y, z]).into_iter().flatten() {
                            let pv = positions[v as usize];
                            let along = (pv - pa).dot(&ab) / length;
                            let height = (pv - pa).cross(&ab).norm() / length;
                            let flat = flat_height(length, [&pa, &pb, &pv]);
                            if v != e.a
                                && v != e.b
                                && along > flat
                                && along < length - flat
                                && height <= flat
                            {
                                on_edge.push((along, v));
                            }
                        }
                    }
                }
            }
            if on_edge.is_empty() {
                continue;
            }
            on_edge.sort_unstable_by(|p, q| p.0.total_cmp(&q.0).then(p.1.cmp(&q.1)));
            // Fanned from the opposite corner, in the triangle's winding.
            let t = triangles[e.triangle];
            // `e` is an edge of this triangle, unsplit this pass (`done`), so `e.b` is a corner.
            let c = t[(t.iter().position(|&i| i == e.b).unwrap() + 1) % 3];
            let chain: Vec<u32> = std::iter::once(e.a)
                .chain(on_edge.iter().map(|&(_, v)| v))
                .chain(std::iter::once(e.b))
                .collect();
            triangles[e.triangle] = [chain[0], chain[1], c];
            added.extend(chain[1..].windows(2).map(|w| [w[0], w[1], c]));
            done[e.triangle] = true;
            split += 1;
        }
        if added.is_empty() {
            break;
        }
        triangles.extend(added);
    }
    split
}

/// Closes the loops of open edges at most [`HOLE_PERIMETER_M`] long (step 6 of the module docs)
/// and returns how many. Left open: a loop through a vertex where open edges branch (which edges
/// form the hole is not clear there), and a loop about as big as its piece (its length squared
/// over [`HOLE_OF_PIECE`] of the piece's area: the rim of a lone triangle or a patch is its
/// shape, not a hole in it).
fn fill_small_holes(positions: &mut Vec<Point3<f64>>, triangles: &mut Vec<[u32; 3]>) -> usize {
    let open = open_edges(triangles);
    if open.is_empty() {
        return 0;
    }
    let piece = triangle_pieces(positions, triangles);
    let mut piece_area: HashMap<u32, f64> = HashMap::new();
    for (t, p) in triangles.iter().zip(&piece) {
        *piece_area.entry(*p).or_default() += area(positions, t);
    }
    // The boundary runs against its triangles' winding: from `b` to `a` of each open edge.
    let mut next: HashMap<u32, u32> = HashMap::with_capacity(open.len());
    let mut branching = HashSet::new();
    for e in &open {
        if next.insert(e.b, e.a).is_some() {
            branching.insert(e.b);
        }
    }
    let mut visited = HashSet::new();
    let mut filled = 0;
    for e in &open {
        if visited.contains(&e.b) {
            continue;
        }
        // Walk the loop from `e.b`, at most as many steps as there are open edges.
        let mut hole = vec![e.b];
        let mut length = 0.0;
        let mut closed = false;
        let mut at = e.b;
        while let Some(&to) = next.get(&at) {
            length += (positions[to as usize] - positions[at as usize]).norm();
            if to == e.b {
                closed = true;
                break;
            }
            if visited.contains(&to) || hole.len() > open.len() || length > HOLE_PERIMETER_M {
                break;
            }
            hole.push(to);
            at = to;
        }
        visited.extend(hole.iter().copied());
        let small = length <= HOLE_PERIMETER_M
            && length * length <= HOLE_OF_PIECE * piece_area[&piece[e.triangle]];
        if !closed || !small || hole.iter().any(|v| branching.contains(v)) {
            continue;
        }
        // `hole` runs b → a along each open edge, so triangles over it in its order are wound
        // as the neighbours across those edges.
        if hole.len() == 3 {
            triangles.push([hole[0], hole[1], hole[2]]);
        } else {
            let centre = hole.iter().fold(Point3::origin(), |c, &v| {
                c + positions[v as usize].coords / hole.len() as f64
            });
            let c = positions.len() as u32;
            positions.push(centre);
            for k in 0..hole.len() {
                triangles.push([hole[k], hole[(k + 1) % hole.len()], c]);
            }
        }
        filled += 1;
    }
    filled
}

/// An edge used by one triangle only, as that triangle runs along it (`a` then `b`).
struct OpenEdge {
    a: u32,
    b: u32,
    triangle: usize,
}

/// The open edges of `triangles`, in the order of the triangles and their edges.
fn open_edges(triangles: &[[u32; 3]]) -> Vec<OpenEdge> {
    // Every edge once per use, by its ends in either order, sorted: an edge used once is open.
    // (Sorting is several times faster than hashing here, on the millions of edges of a large
    // leg that almost never has an open one.)
    let mut uses: Vec<(u64, usize)> = Vec::with_capacity(3 * triangles.len());
    for (k, t) in triangles.iter().enumerate() {
        for slot in 0..3 {
            let (a, b) = (t[slot], t[(slot + 1) % 3]);
            uses.push((
                (u64::from(a.min(b)) << 32) | u64::from(a.max(b)),
                3 * k + slot,
            ));
        }
    }
    uses.sort_unstable_by_key(|u| u.0);
    let mut open: Vec<usize> = uses
        .chunk_by(|u, v| u.0 == v.0)
        .filter(|run| run.len() == 1)
        .map(|run| run[0].1)
        .collect();
    open.sort_unstable();
    open.into_iter()
        .map(|w| {
            let (triangle, slot) = (w / 3, w % 3);
            let t = triangles[triangle];
            OpenEdge {
                a: t[slot],
                b: t[(slot + 1) % 3],
                triangle,
            }
        })
        .collect()
}

fn area(positions: &[Point3<f64>], t: &[u32; 3]) -> f64 {
    let [a, b, c] = t.map(|i| positions[i as usize]);
    (b - a).cross(&(c - a)).norm() / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64, z: f64) -> Point3<f64> {
        Point3::new(x, y, z)
    }

    #[test]
    fn a_short_edge_far_out_with_its_midpoint_rounded_to_f32_is_a_sliver() {
        // A 5 mm edge 0.9 m from the origin, as a glTF file stores it, and its midpoint rounded
        // to f32: about 1e-8 m off the edge, more than SLIVER edge lengths (so the relative test
        // alone keeps it), far less than f32 rounding at that size.
        let a = Point3::new(0.8123f32, -0.4531, 0.1017).cast::<f64>();
        let b = Point3::new(0.815_001_55f32, -0.449_245_75, 0.103_994_53).cast::<f64>();
        let mid = nalgebra::center(&a, &b).cast::<f32>().cast::<f64>();
        let off = (mid - a).cross(&(b - a)).norm() / (b - a).norm();
        assert!(off > SLIVER * (b - a).norm() && off < 1e-7, "{off}");
        let c = Point3::new(0.81, -0.44, 0.11);
        let (_, kept, cleaned) = clean_mesh(&[a, b, c, mid], &[[0, 1, 2], [0, 3, 1]]);
        assert_eq!(kept, [[0, 1, 2]]);
        assert_eq!(cleaned.degenerate_triangles, 1);
        // A thin triangle that is not a rounding artefact stays: 1 µm high on a 5 mm edge.
        let thin = nalgebra::center(&a, &b) + (c - a).normalize() * 1e-6;
        let (_, kept, _) = clean_mesh(&[a, b, c, thin], &[[0, 1, 2], [0, 3, 1]]);
        assert_eq!(kept.len(), 2);
    }

    #[test]
    fn a_t_junction_splits_the_triangle_across_it_so_both_sides_share_the_vertex() {
        // Two triangles on the edge 0–1; the one above it subdivided at the edge's midpoint 4
        // (rounded to f32, as a file stores it), twice over on the next edge, the one below not.
        let a = Point3::new(0.8123f32, -0.4531, 0.1017).cast::<f64>();
        let b = Point3::new(0.815_001_55f32, -0.449_245_75, 0.103_994_53).cast::<f64>();
        let mid =
            |p: &Point3<f64>, q: &Point3<f64>| nalgebra::center(p, q).cast::<f32>().cast::<f64>();
        let above = Point3::new(0.81, -0.44, 0.11);
        let below = Point3::new(0.82, -0.46, 0.10);
        let positions = vec![a, b, above, below, mid(&a, &b)];
        let triangles = vec![[0, 4, 2], [4, 1, 2], [1, 0, 3]];
        let (_, kept, cleaned) = clean_mesh(&positions, &triangles);
        assert_eq!(cleaned.split_triangles, 1);
        assert_eq!(kept, [[0, 4, 2], [4, 1, 2], [1, 4, 3], [4, 0, 3]]);
        assert!(open_edges(&kept).iter().all(|e| ![e.a, e.b].contains(&4)));
        // Three vertices on one edge, in any order, split it into four, in order along it.
        let quarter = |k: f64| (a + (b - a) * k).cast::<f32>().cast::<f64>();
        let positions = vec![
            a,
            b,
            above,
            below,
            quarter(0.75),
            quarter(0.25),
            quarter(0.5),
        ];
        let triangles = vec![[0, 5, 2], [5, 6, 2], [6, 4, 2], [4, 1, 2], [1, 0, 3]];
        let (_, kept, cleaned) = clean_mesh(&positions, &triangles);
        assert_eq!(cleaned.split_triangles, 1);
        assert_eq!(kept[4..], [[1, 4, 3], [4, 6, 3], [6, 5, 3], [5, 0, 3]]);
        // A vertex near an edge but off it by more than rounding is no T-junction.
        let off = nalgebra::center(&a, &b) + (above - a).normalize() * 1e-5;
        let positions = vec![a, b, above, below, off];
        let (_, kept, cleaned) = clean_mesh(&positions, &[[0, 4, 2], [4, 1, 2], [1, 0, 3]]);
        assert_eq!(cleaned.split_triangles, 0);
        assert_eq!(kept.len(), 3);
    }

    #[test]
    fn repeats_slivers_and_debris_go_and_the_skin_stays() {
        // A unit square in two triangles, each corner written twice (flat shading), one face
        // repeated the other way round, a sliver, and a speck far away.
        let positions = vec![
            p(0.0, 0.0, 0.0),
            p(1.0, 0.0, 0.0),
            p(1.0, 1.0, 0.0),
            p(0.0, 0.0, 0.0),
            p(1.0, 1.0, 0.0),
            p(0.0, 1.0, 0.0),
            p(0.5, 0.5, 0.0),
            p(5.0, 5.0, 5.0),
            p(5.001, 5.0, 5.0),
            p(5.0, 5.001, 5.0),
        ];
        let triangles = vec![
            [0, 1, 2],
            [3, 4, 5],
            [4, 3, 5],
            [0, 6, 2],
            [0, 0, 1],
            [7, 8, 9],
        ];
        let (kept_positions, kept, cleaned) = clean_mesh(&positions, &triangles);
        assert_eq!(kept, [[0, 1, 2], [0, 2, 3]]);
        assert_eq!(kept_positions.len(), 4);
        assert_eq!(
            cleaned,
            Cleaned {
                merged_vertices: 2,
                degenerate_triangles: 2,
                duplicate_triangles: 1,
                split_triangles: 0,
                debris_triangles: 1,
                debris_pieces: 1,
                filled_holes: 0,
            }
        );
    }

    /// True when every edge of `triangles` is used twice, once each way: closed and wound alike.
    fn closed_and_consistent(triangles: &[[u32; 3]]) -> bool {
        let mut uses: HashMap<(u32, u32), i32> = HashMap::new();
        for t in triangles {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *uses.entry((a, b)).or_default() += 1;
            }
        }
        (uses.iter()).all(|(&(a, b), &n)| n == 1 && uses.get(&(b, a)) == Some(&1))
    }

    #[test]
    fn a_small_hole_is_closed_wound_as_its_neighbours_and_a_cut_stays_open() {
        use crate::leg::test_meshes::add_sphere;
        // A ball 0.2 m across, its triangles about 1.3 cm a side, wound outwards.
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        add_sphere(&mut positions, &mut triangles, [0.0; 3], 0.1, 48, 24);
        assert!(closed_and_consistent(&triangles));
        let n = triangles.len();
        // The first band's triangles are the pole's; then each band's in pairs (a quad each).
        let quad = 2 * 48 + 2 * 48 * 10;
        // One triangle lost: closed by one triangle.
        let mut one = triangles.clone();
        one.remove(quad);
        let (kept_positions, kept, cleaned) = clean_mesh(&positions, &one);
        assert_eq!((cleaned.filled_holes, kept.len()), (1, n));
        assert_eq!(kept_positions.len(), positions.len());
        assert!(closed_and_consistent(&kept));
        // A quad (two triangles, about 5 cm around) lost: a fan from its centre, a vertex added.
        let mut two = triangles.clone();
        two.drain(quad..quad + 2);
        let (kept_positions, kept, cleaned) = clean_mesh(&positions, &two);
        assert_eq!((cleaned.filled_holes, kept.len()), (1, n + 2));
        assert_eq!(kept_positions.len(), positions.len() + 1);
        assert!(closed_and_consistent(&kept));
        // The north pole's cap and the next band cut off (every triangle on the pole or the
        // first ring): an opening 0.16 m around, left open.
        let cut: Vec<[u32; 3]> = (triangles.iter())
            .filter(|t| t.iter().all(|&i| i > 48))
            .copied()
            .collect();
        let (_, kept, cleaned) = clean_mesh(&positions, &cut);
        assert_eq!((cleaned.filled_holes, kept.len()), (0, cut.len()));
        // A lone triangle's rim is its shape: it stays a triangle.
        let lone = [triangles[quad]];
        let (_, kept, cleaned) = clean_mesh(&positions, &lone);
        assert_eq!((cleaned.filled_holes, kept.len()), (0, 1));
    }

    #[test]
    fn a_face_lost_from_a_coarse_piece_is_closed() {
        use crate::leg::test_meshes::add_sphere;
        // A mannequin's coarse piece: a ball 0.16 m across, 0.08 m² of skin, in 3 cm triangles.
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        add_sphere(&mut positions, &mut triangles, [0.0; 3], 0.08, 16, 9);
        let n = triangles.len();
        // A triangle of the band below the equator lost: its rim is a tenth of a metre, its
        // square more than a tenth of the piece's area.
        let lost = 2 * 16 + 2 * 16 * 4;
        let rim: f64 = (0..3)
            .map(|k| {
                let t = triangles[lost];
                (positions[t[k] as usize] - positions[t[(k + 1) % 3] as usize]).norm()
            })
            .sum();
        let area: f64 = triangles.iter().map(|t| area(&positions, t)).sum();
        assert!((0.09..HOLE_PERIMETER_M).contains(&rim), "{rim}");
        assert!(rim * rim > 0.1 * area && rim * rim <= HOLE_OF_PIECE * area);
        let mut one = triangles.clone();
        one.remove(lost);
        let (_, kept, cleaned) = clean_mesh(&positions, &one);
        assert_eq!((cleaned.filled_holes, kept.len()), (1, n));
        assert!(closed_and_consistent(&kept));
    }
}
