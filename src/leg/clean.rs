//! The skin a fit can trust, cleaned of what character exports carry besides it.
//!
//! Exporters write a vertex once per face corner (flat shading, UV seams), repeat faces, leave
//! zero-area slivers, and put eyes, teeth, nails or stray debris in the same file. Each of these
//! breaks a question the fit asks of the leg: a repeated face makes its edges non-manifold, so
//! the pseudo-normals that tell inside from outside (Bærentzen & Aanæs) and the cross-section
//! loops both go wrong there; a piece of debris inside the leg is a second surface that contact
//! may snap to. So, before anything else looks at the mesh:
//!
//! 1. vertices at exactly the same position become one (the first of them);
//! 2. triangles with two corners on one vertex, or with no area to speak of ([`SLIVER`]), are
//!    dropped;
//! 3. a triangle on the same three vertices as an earlier one, in either winding, is dropped;
//! 4. connected pieces (sharing vertices) with less than [`DEBRIS_AREA_FRACTION`] of the largest
//!    piece's area are dropped: eyes, teeth, nails, debris. The legs of a body exported in
//!    pieces that do not share vertices stay, each being a large share of the whole.
//!
//! The result is what every later stage sees: orientation, landmarks, tube, contact, and the
//! leg written with the fit's attributes. The counts go to the report.

use std::collections::HashMap;

use nalgebra::Point3;
use serde::Serialize;

/// Pieces smaller than this fraction of the largest piece's area are dropped as debris.
pub const DEBRIS_AREA_FRACTION: f64 = 0.02;

/// A triangle whose area is at most this times its longest edge squared has no area worth the
/// name: its third corner lies within a millionth of an edge from the line of the other two (a
/// point on an edge, rounded to 32-bit floats).
pub const SLIVER: f64 = 1e-6;

/// What cleaning removed from the file's mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Cleaned {
    /// Vertices merged into an earlier one at the same position.
    pub merged_vertices: usize,
    /// Triangles with no area.
    pub degenerate_triangles: usize,
    /// Triangles on the same vertices as an earlier one.
    pub duplicate_triangles: usize,
    /// Triangles of pieces too small to be the skin.
    pub debris_triangles: usize,
    /// Pieces dropped as debris.
    pub debris_pieces: usize,
}

/// Cleans `positions` and `triangles` as the module docs say: returns the kept vertices
/// (renumbered, in the file's order), the kept triangles and the counts.
pub fn clean_mesh(
    positions: &[Point3<f64>],
    triangles: &[[u32; 3]],
) -> (Vec<Point3<f64>>, Vec<[u32; 3]>, Cleaned) {
    let mut cleaned = Cleaned::default();
    // 1. One id per position.
    let mut first: HashMap<[u64; 3], u32> = HashMap::with_capacity(positions.len());
    let welded: Vec<u32> = positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let key = [p.x, p.y, p.z].map(|c| (c + 0.0).to_bits());
            *first.entry(key).or_insert(i as u32)
        })
        .collect();
    cleaned.merged_vertices = positions.len() - first.len();
    // 2. and 3. Triangles with area, once each.
    let mut seen: HashMap<[u32; 3], ()> = HashMap::with_capacity(triangles.len());
    let mut kept: Vec<[u32; 3]> = Vec::with_capacity(triangles.len());
    for t in triangles {
        let w = t.map(|i| welded[i as usize]);
        let [a, b, c] = w.map(|i| positions[i as usize]);
        let longest = (b - a)
            .norm_squared()
            .max((c - b).norm_squared())
            .max((a - c).norm_squared());
        if w[0] == w[1]
            || w[1] == w[2]
            || w[2] == w[0]
            || (b - a).cross(&(c - a)).norm() <= SLIVER * longest
        {
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
    // 4. Pieces, by shared vertices; the small ones go.
    let piece = pieces(positions.len(), &kept);
    let mut piece_area: HashMap<u32, f64> = HashMap::new();
    for (t, p) in kept.iter().zip(&piece) {
        *piece_area.entry(*p).or_default() += area(positions, t);
    }
    let largest = piece_area.values().copied().fold(0.0, f64::max);
    let debris = |p: &u32| piece_area[p] < DEBRIS_AREA_FRACTION * largest;
    cleaned.debris_pieces = piece_area.keys().filter(|p| debris(p)).count();
    let before = kept.len();
    let mut keep_piece = piece.iter().map(|p| !debris(p));
    kept.retain(|_| keep_piece.next().unwrap_or(false));
    cleaned.debris_triangles = before - kept.len();
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

fn area(positions: &[Point3<f64>], t: &[u32; 3]) -> f64 {
    let [a, b, c] = t.map(|i| positions[i as usize]);
    (b - a).cross(&(c - a)).norm() / 2.0
}

/// Per triangle, the id of its connected piece (union-find over shared vertices).
fn pieces(vertex_count: usize, triangles: &[[u32; 3]]) -> Vec<u32> {
    let mut root: Vec<u32> = (0..vertex_count as u32).collect();
    fn find(root: &mut [u32], mut v: u32) -> u32 {
        while root[v as usize] != v {
            root[v as usize] = root[root[v as usize] as usize];
            v = root[v as usize];
        }
        v
    }
    for t in triangles {
        for k in 1..3 {
            let (a, b) = (find(&mut root, t[0]), find(&mut root, t[k]));
            root[a.max(b) as usize] = a.min(b);
        }
    }
    triangles.iter().map(|t| find(&mut root, t[0])).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64, z: f64) -> Point3<f64> {
        Point3::new(x, y, z)
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
                debris_triangles: 1,
                debris_pieces: 1,
            }
        );
    }
}
