//! Meshes unit tests build (the leg module's, the penetration fix's): closed boxes, as legs,
//! feet, pieces, debris and thin plates.

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

/// Appends a closed UV sphere of `radius` around `centre`, wound outwards: `around` vertices per
/// ring, `rings` bands from pole to pole, triangles about `π radius / rings` a side.
pub fn add_sphere(
    positions: &mut Vec<Point3<f64>>,
    triangles: &mut Vec<[u32; 3]>,
    centre: [f64; 3],
    radius: f64,
    around: u32,
    rings: u32,
) {
    use std::f64::consts::PI;
    let first = positions.len() as u32;
    let at = |polar: f64, azimuth: f64| {
        Point3::new(
            centre[0] + radius * polar.sin() * azimuth.cos(),
            centre[1] + radius * polar.cos(),
            centre[2] - radius * polar.sin() * azimuth.sin(),
        )
    };
    positions.push(at(0.0, 0.0)); // the north pole, `first`
    for ring in 1..rings {
        for k in 0..around {
            positions.push(at(
                PI * ring as f64 / rings as f64,
                2.0 * PI * k as f64 / around as f64,
            ));
        }
    }
    positions.push(at(PI, 0.0)); // the south pole
    let south = positions.len() as u32 - 1;
    let v = |ring: u32, k: u32| first + 1 + (ring - 1) * around + k % around;
    for k in 0..around {
        triangles.push([first, v(1, k), v(1, k + 1)]);
        triangles.push([south, v(rings - 1, k + 1), v(rings - 1, k)]);
    }
    for ring in 1..rings - 1 {
        for k in 0..around {
            let (a, b) = (v(ring, k), v(ring, k + 1));
            let (c, d) = (v(ring + 1, k), v(ring + 1, k + 1));
            triangles.push([a, c, d]);
            triangles.push([a, d, b]);
        }
    }
}
