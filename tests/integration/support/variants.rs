//! Ways to remake a leg as users' files bring it: cut on a plane, closed at the cut, written as
//! quads (convex or not), fanned by a careless exporter. Used by the cut-leg tests and the leg
//! zoo.

use std::collections::HashMap;

use nalgebra::{Point3, Vector3};

use super::RawMesh;

/// `mesh` with every hole closed by a fan from the hole's centre: the edges used by one
/// triangle only (vertices welded by position) are chained into loops, and each loop gets a
/// centre vertex and one triangle per edge, wound against the edge's own triangle so the cap
/// faces out with the skin.
pub fn closed_at_the_cut(mesh: &RawMesh) -> RawMesh {
    let mut welded: HashMap<[u64; 3], u32> = HashMap::new();
    let id: Vec<u32> = mesh
        .positions
        .iter()
        .map(|p| {
            let key = [p.x, p.y, p.z].map(f64::to_bits);
            let next = welded.len() as u32;
            *welded.entry(key).or_insert(next)
        })
        .collect();
    let mut first_of: HashMap<u32, u32> = HashMap::new();
    for (i, &w) in id.iter().enumerate() {
        first_of.entry(w).or_insert(i as u32);
    }
    // Directed edges by welded ids; an edge whose reverse is absent is on a hole's rim.
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &mesh.triangles {
        let w = t.map(|i| id[i as usize]);
        for k in 0..3 {
            *directed.entry((w[k], w[(k + 1) % 3])).or_default() += 1;
        }
    }
    let mut next: HashMap<u32, u32> = HashMap::new();
    for (&(a, b), _) in directed
        .iter()
        .filter(|(&(a, b), _)| !directed.contains_key(&(b, a)))
    {
        next.insert(a, b);
    }
    let mut positions = mesh.positions.clone();
    let mut triangles = mesh.triangles.clone();
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut done = std::collections::HashSet::new();
    for start in starts {
        if done.contains(&start) {
            continue;
        }
        let mut rim = vec![start];
        let mut at = start;
        while let Some(&b) = next.get(&at) {
            done.insert(at);
            if b == start {
                break;
            }
            rim.push(b);
            at = b;
            if rim.len() > next.len() {
                break;
            }
        }
        let centre = rim
            .iter()
            .map(|&w| positions[first_of[&w] as usize].coords)
            .sum::<Vector3<f64>>()
            / rim.len() as f64;
        let c = positions.len() as u32;
        positions.push(Point3::from(centre));
        for k in 0..rim.len() {
            let (a, b) = (rim[k], rim[(k + 1) % rim.len()]);
            triangles.push([first_of[&b], first_of[&a], c]);
        }
    }
    RawMesh {
        name: mesh.name.clone(),
        positions,
        triangles,
    }
}

/// The part of `mesh` below the plane through `at` with upward normal `up` (not unit needed),
/// whose triangles `keep` accepts by their centre: triangles that cross the plane are clipped
/// to it, and the new rim vertices are computed from each edge's ends in one order so that the
/// two triangles sharing an edge get the same point (the rim is then one welded loop).
pub fn cut_below(
    mesh: &RawMesh,
    at: Point3<f64>,
    up: Vector3<f64>,
    keep: impl Fn(&Point3<f64>) -> bool,
) -> RawMesh {
    let up = up.normalize();
    let side = |p: &Point3<f64>| (p - at).dot(&up);
    let mut positions: Vec<Point3<f64>> = Vec::new();
    let mut triangles = Vec::new();
    let on_edge = |a: Point3<f64>, b: Point3<f64>| {
        let (a, b) = if [a.x, a.y, a.z] < [b.x, b.y, b.z] {
            (a, b)
        } else {
            (b, a)
        };
        let (sa, sb) = (side(&a), side(&b));
        a + (b - a) * (sa / (sa - sb))
    };
    for t in &mesh.triangles {
        let corners = t.map(|i| mesh.positions[i as usize]);
        let centre =
            Point3::from((corners[0].coords + corners[1].coords + corners[2].coords) / 3.0);
        if !keep(&centre) {
            continue;
        }
        // Sutherland–Hodgman against the one plane: the kept polygon, 0, 3 or 4 corners.
        let mut kept = Vec::new();
        for k in 0..3 {
            let (a, b) = (corners[k], corners[(k + 1) % 3]);
            let (below_a, below_b) = (side(&a) < 0.0, side(&b) < 0.0);
            if below_a {
                kept.push(a);
            }
            if below_a != below_b {
                kept.push(on_edge(a, b));
            }
        }
        for k in 1..kept.len().saturating_sub(1) {
            let base = positions.len() as u32;
            positions.extend([kept[0], kept[k], kept[k + 1]]);
            triangles.push([base, base + 1, base + 2]);
        }
    }
    RawMesh {
        name: mesh.name.clone(),
        positions,
        triangles,
    }
}

/// The mesh of `positions` (welded) and `triangles` as an ASCII PLY of quads, each two triangles
/// sharing an edge within 30° of one plane, written from the corner
/// that makes a fan from the first corner take the other diagonal wherever the quad is concave
/// (as a quad-dominant modeller's export may); with the concave quads' outside diagonals.
pub fn leg_as_quads(positions: &[Point3<f64>], triangles: &[[u32; 3]]) -> (String, Vec<[u32; 2]>) {
    let mut by_edge: std::collections::HashMap<(u32, u32), usize> = Default::default();
    for (k, t) in triangles.iter().enumerate() {
        for e in 0..3 {
            by_edge.insert((t[e], t[(e + 1) % 3]), k);
        }
    }
    let mut used = vec![false; triangles.len()];
    let (mut faces, mut outside) = (Vec::new(), Vec::new());
    for k in 0..triangles.len() {
        if used[k] {
            continue;
        }
        used[k] = true;
        let t = triangles[k];
        // A neighbour across one of t's edges, not yet used: t = (a, b, c), it = (c, b, d).
        let normal = |t: [u32; 3]| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            (b - a).cross(&(c - a)).normalize()
        };
        // A modeller's quad is nearly flat: no quad across a crease (a cap's rim, an edge of
        // a box) is made, where a careless pairing would fold it double.
        let pair = (0..3).find_map(|e| {
            let (b, c) = (t[(e + 1) % 3], t[(e + 2) % 3]);
            let n = *by_edge.get(&(c, b))?;
            let flat = normal(t).dot(&normal(triangles[n])) > 30f64.to_radians().cos();
            (!used[n] && flat).then(|| {
                let d = triangles[n]
                    .into_iter()
                    .find(|&v| v != b && v != c)
                    .unwrap();
                (n, [t[e], b, d, c])
            })
        });
        let Some((n, [a, b, d, c])) = pair else {
            faces.push(t.to_vec());
            continue;
        };
        used[n] = true;
        let p = |i: u32| positions[i as usize];
        // Concave where a corner turns against the quad's normal (the two triangles' summed).
        let normal = (p(b) - p(a)).cross(&(p(c) - p(a))) + (p(b) - p(c)).cross(&(p(d) - p(c)));
        let ring = [a, b, d, c];
        // Clearly: a reflex corner turning back by more than 6°, in a quad whose halves are
        // within 20° of one plane (a quad folded more is no polygon of one plane, and either
        // diagonal is a reading of it).
        let (n1, n2) = (
            (p(b) - p(a)).cross(&(p(c) - p(a))).normalize(),
            (p(b) - p(c)).cross(&(p(d) - p(c))).normalize(),
        );
        let normal = normal.normalize();
        let is_concave = n1.dot(&n2) > 20f64.to_radians().cos()
            && (0..4).any(|k| {
                let (u, v, w) = (p(ring[k]), p(ring[(k + 1) % 4]), p(ring[(k + 2) % 4]));
                (v - u).cross(&(w - v)).dot(&normal) < -0.1 * (v - u).norm() * (w - v).norm()
            });
        if is_concave {
            outside.push([a.min(d), a.max(d)]);
            faces.push(vec![a, b, d, c]); // the fan from a takes the diagonal a–d, outside
        } else {
            faces.push(vec![b, d, c, a]); // the fan from b gives back the two triangles
        }
    }
    let mut text = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        positions.len(),
        faces.len()
    );
    for q in positions {
        text += &format!("{} {} {}\n", q.x as f32, q.y as f32, q.z as f32);
    }
    for f in &faces {
        let corners: Vec<String> = f.iter().map(u32::to_string).collect();
        text += &format!("{} {}\n", f.len(), corners.join(" "));
    }
    (text, outside)
}

/// `ply`, a PLY of `leg_as_quads`, with every polygon fanned from its first corner into
/// triangles: how a careless exporter triangulates, and the concave quads folded back over the
/// skin.
pub fn fanned(ply: &str) -> String {
    let (header, body) = ply.split_once("end_header\n").unwrap();
    let count = |element: &str| -> usize {
        let line = header.lines().find(|l| l.starts_with(element)).unwrap();
        line.rsplit(' ').next().unwrap().parse().unwrap()
    };
    let (vertices, faces) = (count("element vertex "), count("element face "));
    let lines: Vec<&str> = body.lines().collect();
    let triangles: Vec<String> = (lines[vertices..vertices + faces].iter())
        .flat_map(|face| {
            let corners: Vec<&str> = face.split(' ').skip(1).collect();
            (1..corners.len() - 1)
                .map(|k| format!("3 {} {} {}", corners[0], corners[k], corners[k + 1]))
                .collect::<Vec<_>>()
        })
        .collect();
    let header = header.replace(
        &format!("element face {faces}"),
        &format!("element face {}", triangles.len()),
    );
    format!(
        "{header}end_header\n{}\n{}\n",
        lines[..vertices].join("\n"),
        triangles.join("\n")
    )
}

/// The closed axis-aligned box of half side `half` around `centre`, wound outwards.
pub fn cube(centre: &Point3<f64>, half: f64) -> (Vec<Point3<f64>>, Vec<[u32; 3]>) {
    let corner = |k: u32| {
        let s = |bit: u32| if k & bit == 0 { -half } else { half };
        centre + Vector3::new(s(1), s(2), s(4))
    };
    let quads: [[u32; 4]; 6] = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let triangles = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    ((0..8).map(corner).collect(), triangles)
}
