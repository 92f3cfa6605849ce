//! Outward winding for every triangle. Contact tells inside from outside by the triangles'
//! normals (pseudo-normals, see `collider.rs`), so a leg exported inside out, or with patches
//! of triangles wound the other way (a mirrored part joined without fixing it), would put the
//! stocking inside the leg. As a mesh tool's "recalculate normals outside" does: make each
//! connected surface's winding agree across its manifold edges (breadth-first from its first
//! triangle; an edge of one triangle or of three or more does not propagate), then flip a whole
//! surface whose signed volume, taken about the centre of its bounds, is negative. An open
//! surface (a leg cut from a body) still has a positive volume this way when wound outwards:
//! the missing caps only remove the cones from the centre to the cuts.

use std::collections::{HashMap, VecDeque};

use nalgebra::Point3;

use super::weld::{welded_ids, welded_triangle};

/// Rewinds `triangles` (indices into `positions`) outwards, as the module docs say; returns how
/// many were flipped. Triangles with no area are left as they are.
pub fn orient_outward(positions: &[Point3<f64>], triangles: &mut [[u32; 3]]) -> usize {
    let welded = welded_ids(positions);
    let corners: Vec<Option<[u32; 3]>> = triangles
        .iter()
        .map(|t| welded_triangle(&welded, t))
        .collect();
    // Per undirected edge: the triangles using it (the first two) and how many do.
    let mut edges: HashMap<(u32, u32), ([u32; 2], u32)> = HashMap::new();
    for (k, w) in corners.iter().enumerate() {
        for (a, b) in w.iter().flat_map(directed_edges) {
            let entry = edges.entry((a.min(b), a.max(b))).or_insert(([0; 2], 0));
            if entry.1 < 2 {
                entry.0[entry.1 as usize] = k as u32;
            }
            entry.1 += 1;
        }
    }
    let mut flip = vec![false; triangles.len()];
    let mut seen = vec![false; triangles.len()];
    let mut queue = VecDeque::new();
    for start in 0..triangles.len() {
        if seen[start] || corners[start].is_none() {
            continue;
        }
        seen[start] = true;
        queue.push_back(start);
        let mut surface = Vec::new();
        while let Some(k) = queue.pop_front() {
            surface.push(k);
            let w = corners[k].expect("only triangles with area are queued");
            for (a, b) in directed_edges(&w) {
                let ([first, second], uses) = edges[&(a.min(b), a.max(b))];
                if uses != 2 {
                    continue;
                }
                let n = if first as usize == k { second } else { first } as usize;
                if seen[n] {
                    continue;
                }
                seen[n] = true;
                // Agreeing windings run a shared edge in opposite directions.
                let same_direction =
                    directed_edges(&corners[n].expect("on an edge with area")).any(|e| e == (a, b));
                flip[n] = flip[k] ^ same_direction;
                queue.push_back(n);
            }
        }
        if signed_volume(positions, triangles, &surface, &flip) < 0.0 {
            for &k in &surface {
                flip[k] = !flip[k];
            }
        }
    }
    let mut flipped = 0;
    for (t, _) in triangles.iter_mut().zip(&flip).filter(|(_, &f)| f) {
        t.swap(1, 2);
        flipped += 1;
    }
    flipped
}

fn directed_edges(w: &[u32; 3]) -> impl Iterator<Item = (u32, u32)> {
    [(w[0], w[1]), (w[1], w[2]), (w[2], w[0])].into_iter()
}

/// Six times the signed volume enclosed by `surface` (triangle indices, wound as `flip` says)
/// about the centre of its bounds.
fn signed_volume(
    positions: &[Point3<f64>],
    triangles: &[[u32; 3]],
    surface: &[usize],
    flip: &[bool],
) -> f64 {
    let (mut lo, mut hi) = (
        Point3::from([f64::INFINITY; 3]),
        Point3::from([f64::MIN; 3]),
    );
    for p in surface
        .iter()
        .flat_map(|&k| triangles[k].map(|i| positions[i as usize]))
    {
        lo = lo.inf(&p);
        hi = hi.sup(&p);
    }
    let centre = nalgebra::center(&lo, &hi);
    surface
        .iter()
        .map(|&k| {
            let [a, b, c] = triangles[k].map(|i| positions[i as usize] - centre);
            let v = a.dot(&b.cross(&c));
            if flip[k] {
                -v
            } else {
                v
            }
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed octahedron, wound outwards.
    fn octahedron() -> (Vec<Point3<f64>>, Vec<[u32; 3]>) {
        let p = |x, y, z| Point3::new(x, y, z);
        let positions = vec![
            p(1.0, 0.0, 0.0),
            p(-1.0, 0.0, 0.0),
            p(0.0, 1.0, 0.0),
            p(0.0, -1.0, 0.0),
            p(0.0, 0.0, 1.0),
            p(0.0, 0.0, -1.0),
        ];
        let triangles = vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        (positions, triangles)
    }

    #[test]
    fn an_outward_mesh_is_left_alone_and_flipped_ones_are_put_back() {
        let (positions, outward) = octahedron();
        let mut t = outward.clone();
        assert_eq!(orient_outward(&positions, &mut t), 0);
        assert_eq!(t, outward);
        // Inside out.
        let mut t: Vec<[u32; 3]> = outward.iter().map(|t| [t[0], t[2], t[1]]).collect();
        assert_eq!(orient_outward(&positions, &mut t), 8);
        assert_eq!(t, outward);
        // Three triangles flipped.
        let mut t = outward.clone();
        for k in [1, 4, 6] {
            t[k].swap(1, 2);
        }
        assert_eq!(orient_outward(&positions, &mut t), 3);
        assert_eq!(t, outward);
    }
}
