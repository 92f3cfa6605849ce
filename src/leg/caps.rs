//! A leg closed at its cut: the flat cap a watertight export puts over the cut (a prop, a
//! 3D-printed form, a boolean cut, "fill holes" before export), which the landmarks' sections
//! leave out. The leg keeps it: contact and the files see the solid as the user made it.
//!
//! Why: the landmarks follow the leg's cross-sections up to where the mesh is cut, and take the
//! last one as the top of the thigh. A cap is not skin: the sections through a flat cap are
//! slivers of it, and through a slanted one they are part skin and part chord, shrinking to
//! nothing, so the leg would seem to narrow to a point at its top (and be refused as upside
//! down). Without it, a capped leg's sections are those of the open cut the landmarks already read.
//!
//! Method: planar regions are grown across shared edges from each triangle (normals within
//! [`PLANAR_DEG`], corners within [`PLANE_TOLERANCE`] of the seed's plane). A region is a cap
//! when it is large ([`MIN_CAP_AREA_M2`]), faces up the body (within [`MAX_TILT_DEG`] of `up`,
//! so slanted cuts count), reaches the top of the mesh (within [`TOP_REACH_M`] of the highest
//! point along up) and has its whole connected piece below its plane (a supporting plane, as a
//! cut is; the sole, the other planar end of some legs, has its piece above it). Skin is never
//! flat over [`MIN_CAP_AREA_M2`]; a limb exported in pieces keeps the caps of its joints, which
//! lie below the top.

use std::collections::{HashMap, VecDeque};

use nalgebra::{Point3, Vector3};

/// Normals of one planar region agree within this, degrees.
pub const PLANAR_DEG: f64 = 1.0;
/// Corners of one planar region lie within this of its plane, metres.
pub const PLANE_TOLERANCE: f64 = 2e-4;
/// Smallest cap, square metres (20 cm²: an ankle's cross-section is about 30 cm², a thigh's
/// 200 cm²).
pub const MIN_CAP_AREA_M2: f64 = 20e-4;
/// Steepest cut whose cap is opened, degrees from horizontal.
pub const MAX_TILT_DEG: f64 = 60.0;
/// A cap reaches within this of the mesh's highest point along up, metres.
pub const TOP_REACH_M: f64 = 0.02;
/// The piece under a cap lies below its plane within this, metres.
pub const SUPPORT_TOLERANCE: f64 = 1e-3;

/// `triangles` less the caps over cuts (see the module docs) and how many triangles those were.
/// `up` is a unit vector up the body in the same space as `positions`; vertices only the caps
/// used are left in place (unreferenced).
pub fn open_cut_caps(
    positions: &[Point3<f64>],
    triangles: &[[u32; 3]],
    up: &Vector3<f64>,
) -> (Vec<[u32; 3]>, usize) {
    let normal_area: Vec<(Vector3<f64>, f64)> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            let cross = (b - a).cross(&(c - a));
            let area = cross.norm() / 2.0;
            (cross / cross.norm().max(f64::MIN_POSITIVE), area)
        })
        .collect();
    let mut by_edge: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for (k, t) in triangles.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            by_edge.entry((a.min(b), a.max(b))).or_default().push(k);
        }
    }
    let top = positions
        .iter()
        .map(|p| p.coords.dot(up))
        .fold(f64::NEG_INFINITY, f64::max);
    let (piece_of, pieces) = pieces(triangles, &by_edge);

    let cos_planar = PLANAR_DEG.to_radians().cos();
    let mut region_of = vec![usize::MAX; triangles.len()];
    let mut caps = vec![false; triangles.len()];
    for seed in 0..triangles.len() {
        if region_of[seed] != usize::MAX || normal_area[seed].1 == 0.0 {
            continue;
        }
        let (normal, _) = normal_area[seed];
        let origin = positions[triangles[seed][0] as usize];
        let on_plane =
            |i: u32| (positions[i as usize] - origin).dot(&normal).abs() <= PLANE_TOLERANCE;
        region_of[seed] = seed;
        let region = flood(triangles, &by_edge, seed, |n| {
            let joins = region_of[n] == usize::MAX
                && normal_area[n].1 > 0.0
                && normal_area[n].0.dot(&normal).abs() >= cos_planar
                && triangles[n].iter().all(|&i| on_plane(i));
            if joins {
                region_of[n] = seed;
            }
            joins
        });
        let area: f64 = region.iter().map(|&k| normal_area[k].1).sum();
        // The cap's normal pointed up the body: the side its piece must lie below.
        let outward = if normal.dot(up) >= 0.0 {
            normal
        } else {
            -normal
        };
        let is_cap = area >= MIN_CAP_AREA_M2
            && outward.dot(up) >= MAX_TILT_DEG.to_radians().cos()
            && region.iter().any(|&k| {
                triangles[k]
                    .iter()
                    .any(|&i| positions[i as usize].coords.dot(up) >= top - TOP_REACH_M)
            })
            && pieces[piece_of[seed]].iter().all(|&k| {
                triangles[k]
                    .iter()
                    .all(|&i| (positions[i as usize] - origin).dot(&outward) <= SUPPORT_TOLERANCE)
            });
        if is_cap {
            for &k in &region {
                caps[k] = true;
            }
        }
    }
    let kept: Vec<[u32; 3]> = triangles
        .iter()
        .zip(&caps)
        .filter(|(_, &cap)| !cap)
        .map(|(t, _)| *t)
        .collect();
    let opened = triangles.len() - kept.len();
    (kept, opened)
}

/// The connected pieces (triangles sharing an edge): each triangle's piece, and each piece's
/// triangles.
fn pieces(
    triangles: &[[u32; 3]],
    by_edge: &HashMap<(u32, u32), Vec<usize>>,
) -> (Vec<usize>, Vec<Vec<usize>>) {
    let mut piece_of = vec![usize::MAX; triangles.len()];
    let mut pieces = Vec::new();
    for start in 0..triangles.len() {
        if piece_of[start] != usize::MAX {
            continue;
        }
        let id = pieces.len();
        piece_of[start] = id;
        let piece = flood(triangles, by_edge, start, |n| {
            let joins = piece_of[n] == usize::MAX;
            if joins {
                piece_of[n] = id;
            }
            joins
        });
        pieces.push(piece);
    }
    (piece_of, pieces)
}

/// The triangles reached from `seed` across shared edges, `seed` first: `join` says whether a
/// neighbour joins (and marks it, so it is not offered again).
fn flood(
    triangles: &[[u32; 3]],
    by_edge: &HashMap<(u32, u32), Vec<usize>>,
    seed: usize,
    mut join: impl FnMut(usize) -> bool,
) -> Vec<usize> {
    let mut grown = vec![seed];
    let mut queue = VecDeque::from([seed]);
    while let Some(k) = queue.pop_front() {
        let t = triangles[k];
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            for &n in &by_edge[&(a.min(b), a.max(b))] {
                if join(n) {
                    grown.push(n);
                    queue.push_back(n);
                }
            }
        }
    }
    grown
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::leg::test_meshes::add_box;

    /// A closed box `w` wide and `h` tall standing on the origin: two triangles a face.
    fn closed_box(w: f64, h: f64) -> (Vec<Point3<f64>>, Vec<[u32; 3]>) {
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        add_box(&mut positions, &mut triangles, [0.0; 3], [w, h, w]);
        (positions, triangles)
    }

    #[test]
    fn the_top_of_a_closed_column_is_opened_and_its_bottom_kept() {
        let (positions, triangles) = closed_box(0.15, 0.8);
        let (kept, opened) = open_cut_caps(&positions, &triangles, &Vector3::y());
        assert_eq!(opened, 2);
        // The two top triangles (the second quad) are gone; the bottom, a sole, stays.
        assert!(kept
            .iter()
            .all(|t| t.iter().any(|&i| positions[i as usize].y == 0.0)));
        assert_eq!(kept.len(), 10);
    }

    #[test]
    fn a_top_smaller_than_an_ankle_is_not_a_cap() {
        let (positions, triangles) = closed_box(0.03, 0.8);
        assert_eq!(open_cut_caps(&positions, &triangles, &Vector3::y()).1, 0);
    }
}
