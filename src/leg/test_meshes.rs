//! Meshes the leg module's unit tests build: closed boxes, as legs, feet, pieces and debris.

use nalgebra::Point3;

/// Appends the closed box from `lo` to `hi` to `positions` and `triangles`, wound outwards, two
/// triangles a face.
pub fn add_box(
    positions: &mut Vec<Point3<f64>>,
    triangles: &mut Vec<[u32; 3]>,
    lo: [f64; 3],
    hi: [f64; 3],
) {
    let first = positions.len() as u32;
    for k in 0..8 {
        let pick = |axis: usize| {
            if k >> axis & 1 == 0 {
                lo[axis]
            } else {
                hi[axis]
            }
        };
        positions.push(Point3::new(pick(0), pick(1), pick(2)));
    }
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    for q in quads {
        triangles.push([q[0], q[1], q[2]].map(|i| first + i));
        triangles.push([q[0], q[2], q[3]].map(|i| first + i));
    }
}
