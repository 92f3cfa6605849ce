//! Cross-sections of the leg square to an axis, and the loops in them that go around it: what
//! "the leg around this axis" means in a file that holds more than one leg (both legs and the
//! pelvis, a whole body), where the nearest vertices at a height may belong to the other leg.
//!
//! A plane at height `s` cuts each triangle that spans it in a segment between two of its edges.
//! Segments sharing an edge (on welded vertices) join into loops. A loop goes around the axis
//! point when a ray from that point, in the plane, crosses it an odd number of times (the
//! crossing-number test, with the half-open rule so a crossing through a shared point counts
//! once). A hole or a non-manifold edge in the plane breaks that test for its loop, which then
//! simply does not count.

use std::collections::HashMap;

use nalgebra::{Point3, Vector3};

use super::weld::{welded_ids, welded_triangle};
use crate::base::perpendicular_frame;

/// For each of `heights` (metres along the unit vector `a` from `origin`, ascending), the
/// largest distance from the axis of any vertex of the triangles whose cut by that plane makes
/// up a loop around the axis; `None` where no loop goes around it (the axis is outside the mesh
/// there, or the loop is broken).
pub fn enclosing_radii(
    positions: &[Point3<f64>],
    triangles: &[[u32; 3]],
    origin: &Point3<f64>,
    a: &Vector3<f64>,
    heights: &[f64],
) -> Vec<Option<f64>> {
    let welded = welded_ids(positions);
    let height: Vec<f64> = positions.iter().map(|p| (p - origin).dot(a)).collect();
    let radial = |p: &Point3<f64>| {
        let d = p - origin;
        (d - a * d.dot(a)).norm()
    };
    // The triangles each plane cuts: those with a vertex below it and one at or above it.
    let mut cut: Vec<Vec<[u32; 3]>> = vec![Vec::new(); heights.len()];
    for t in triangles.iter().filter_map(|t| welded_triangle(&welded, t)) {
        let h = t.map(|i| height[i as usize]);
        let (lo, hi) = (h[0].min(h[1]).min(h[2]), h[0].max(h[1]).max(h[2]));
        let first = heights.partition_point(|&s| s <= lo);
        let last = heights.partition_point(|&s| s <= hi);
        for planes in &mut cut[first..last] {
            planes.push(t);
        }
    }
    let (u, v) = perpendicular_frame(a);
    cut.iter()
        .zip(heights)
        .map(|(triangles, &s)| {
            let centre = origin + a * s;
            // Each edge the plane crosses is a node; a segment joins two nodes.
            let mut node: HashMap<(u32, u32), usize> = HashMap::new();
            let mut root: Vec<usize> = Vec::new();
            let mut segments = Vec::with_capacity(triangles.len());
            for t in triangles {
                let mut ends = [(0, [0.0; 2]); 2];
                let mut found = 0;
                for (i, j) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                    let (i, j) = (i.min(j), i.max(j));
                    let (hi, hj) = (height[i as usize], height[j as usize]);
                    if (hi >= s) == (hj >= s) || found == 2 {
                        continue;
                    }
                    let (pi, pj) = (positions[i as usize], positions[j as usize]);
                    let q = pi + (pj - pi) * ((s - hi) / (hj - hi)) - centre;
                    let id = *node.entry((i, j)).or_insert_with(|| {
                        root.push(root.len());
                        root.len() - 1
                    });
                    ends[found] = (id, [q.dot(&u), q.dot(&v)]);
                    found += 1;
                }
                if found < 2 {
                    continue;
                }
                let [(n0, p), (n1, q)] = ends;
                let (r0, r1) = (find(&mut root, n0), find(&mut root, n1));
                root[r0.max(r1)] = r0.min(r1);
                // Does the segment cross the ray from the centre along +u?
                let crosses = (p[1] >= 0.0) != (q[1] >= 0.0)
                    && p[0] + (q[0] - p[0]) * (-p[1] / (q[1] - p[1])) > 0.0;
                let reach = t
                    .iter()
                    .map(|&i| radial(&positions[i as usize]))
                    .fold(0.0, f64::max);
                segments.push((n0, crosses, reach));
            }
            let mut loops: HashMap<usize, (bool, f64)> = HashMap::new();
            for (n, crosses, reach) in segments {
                let entry = loops.entry(find(&mut root, n)).or_insert((false, 0.0));
                entry.0 ^= crosses;
                entry.1 = entry.1.max(reach);
            }
            loops
                .values()
                .filter(|(around, _)| *around)
                .map(|&(_, reach)| reach)
                .reduce(f64::max)
        })
        .collect()
}

fn find(root: &mut [usize], mut n: usize) -> usize {
    while root[n] != n {
        root[n] = root[root[n]];
        n = root[n];
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An open square tube of half-width `w` around the vertical line through `(x, z)`, from
    /// y = 0 to 1.
    fn square_tube(x: f64, z: f64, w: f64, first: u32) -> (Vec<Point3<f64>>, Vec<[u32; 3]>) {
        let corners = [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)];
        let mut positions = Vec::new();
        for y in [0.0, 1.0] {
            for (cx, cz) in corners {
                positions.push(Point3::new(x + w * cx, y, z + w * cz));
            }
        }
        let triangles = (0..4u32)
            .flat_map(|i| {
                let (a, b) = (first + i, first + (i + 1) % 4);
                [[a, b, b + 4], [a, b + 4, a + 4]]
            })
            .collect();
        (positions, triangles)
    }

    #[test]
    fn only_the_loop_around_the_axis_counts() {
        let (mut positions, mut triangles) = square_tube(0.0, 0.0, 0.1, 0);
        let (p, t) = square_tube(0.5, 0.0, 0.1, 8);
        positions.extend(p);
        triangles.extend(t);
        let up = Vector3::y();
        let heights = [0.25, 0.5, 0.75];
        let around_first =
            enclosing_radii(&positions, &triangles, &Point3::origin(), &up, &heights);
        let corner = 0.1 * 2f64.sqrt();
        for r in around_first {
            assert!((r.unwrap() - corner).abs() < 1e-12, "{r:?}");
        }
        // Between the two tubes no loop goes around the axis.
        let between = Point3::new(0.25, 0.0, 0.0);
        let none = enclosing_radii(&positions, &triangles, &between, &up, &heights);
        assert_eq!(none, [None; 3]);
    }
}
