//! The leg's long axis: two points, bottom (ankle end) and top (thigh end), between which the
//! stocking is stretched (paper §6.2). Given by the scene or the command line, or detected.
//!
//! Detection: the principal axis of the surface (eigenvector of the area-weighted covariance of
//! the triangles' centroids with the largest eigenvalue), oriented upwards; bottom and top are the
//! extreme projections of the vertices onto it, moved inwards by [`END_INSET`] of the length so
//! that the tube's end rings lie on skin rather than on an open cut.
//!
//! A leg cut from a body is open at its ends, and the cut need not be square to the axis (a
//! thigh leans inwards). A ring's plane crossing the cut would put yarn points beside the hole,
//! where inside and outside are not defined. So where the mesh has a cut near an end (within
//! [`END_ZONE`] of the length), that end is moved further in, until the ring's plane clears
//! every vertex of the cut by [`CUT_CLEARANCE`] of the length. A cut is a boundary (a connected
//! run of open edges, on welded vertices) that goes around the axis, leaving no gap wider than
//! [`CUT_MAX_GAP_RAD`]: a small hole in the skin, the free edges of an internal fin or a
//! degenerate sliver are boundaries too, but they do not go around the leg, and moving a
//! stocking's end past them would leave a band of skin bare.

use std::collections::{BTreeMap, HashMap};

use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use serde::Serialize;

use super::weld::{welded_ids, welded_triangle};
use super::{section, Leg};
use crate::base::perpendicular_frame;

/// Fraction of the leg's length kept free at each end by a detected axis.
pub const END_INSET: f64 = 0.03;
/// Fraction of the leg's length at each end where open edges count as the cut.
pub const END_ZONE: f64 = 0.25;
/// Fraction of the leg's length kept between an end ring's plane and the cut.
pub const CUT_CLEARANCE: f64 = 0.01;
/// Widest gap, in angle around the axis, that a boundary may leave and still count as a cut.
pub const CUT_MAX_GAP_RAD: f64 = std::f64::consts::FRAC_PI_2;

/// Where an axis came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AxisSource {
    /// `leg.axis` in the scene.
    Scene,
    /// `--axis` on the command line.
    CommandLine,
    /// Detected from the mesh (principal axis).
    Detected,
}

/// The stocking's axis, world space (metres, Y up).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Axis {
    /// Bottom point (ankle end).
    pub bottom: [f64; 3],
    /// Top point (thigh end).
    pub top: [f64; 3],
    /// Where it came from.
    pub source: AxisSource,
}

impl Axis {
    /// Bottom as a point.
    pub fn bottom(&self) -> Point3<f64> {
        Point3::from(self.bottom)
    }

    /// Top as a point.
    pub fn top(&self) -> Point3<f64> {
        Point3::from(self.top)
    }

    /// Distance from bottom to top, metres.
    pub fn length(&self) -> f64 {
        (self.top() - self.bottom()).norm()
    }

    /// Unit vector from bottom to top.
    pub fn direction(&self) -> Vector3<f64> {
        (self.top() - self.bottom()).normalize()
    }
}

/// Detects the leg's axis (see module docs). `None` for a mesh with no area, or one whose open
/// edges leave no room between the ends.
pub fn detect_axis(leg: &Leg) -> Option<Axis> {
    let mut area_sum = 0.0;
    let mut centroid = Vector3::zeros();
    let mut second = Matrix3::zeros();
    for t in &leg.triangles {
        let [a, b, c] = t.map(|i| leg.positions[i as usize].coords);
        let area = (b - a).cross(&(c - a)).norm() / 2.0;
        let m = (a + b + c) / 3.0;
        area_sum += area;
        centroid += m * area;
        second += m * m.transpose() * area;
    }
    if !(area_sum > 0.0 && area_sum.is_finite()) {
        return None;
    }
    centroid /= area_sum;
    let covariance = second / area_sum - centroid * centroid.transpose();
    let eigen = SymmetricEigen::new(covariance);
    let (k, _) =
        eigen
            .eigenvalues
            .iter()
            .enumerate()
            .fold((0, f64::NEG_INFINITY), |best, (i, &v)| {
                if v > best.1 {
                    (i, v)
                } else {
                    best
                }
            });
    let mut dir: Vector3<f64> = eigen.eigenvectors.column(k).into_owned();
    // Point it up (or, for a lying leg, along the largest positive component).
    let up_component = if dir.y.abs() > 1e-9 {
        dir.y
    } else {
        dir.x + dir.z
    };
    if up_component < 0.0 {
        dir = -dir;
    }
    let (lo, hi) = leg
        .positions
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            let s = (p.coords - centroid).dot(&dir);
            (lo.min(s), hi.max(s))
        });
    let length = hi - lo;
    let (mut bottom, mut top) = (lo + END_INSET * length, hi - END_INSET * length);
    for v in cut_vertices(leg, &centroid.into(), &dir) {
        let s = (leg.positions[v as usize].coords - centroid).dot(&dir);
        if s < lo + END_ZONE * length {
            bottom = bottom.max(s + CUT_CLEARANCE * length);
        } else if s > hi - END_ZONE * length {
            top = top.min(s - CUT_CLEARANCE * length);
        }
    }
    if bottom >= top {
        return None;
    }
    let at = |s: f64| (centroid + dir * s).into();
    Some(Axis {
        bottom: at(bottom),
        top: at(top),
        source: AxisSource::Detected,
    })
}

/// Where along `axis` (a fraction of its length, of 0.1, 0.5 and 0.9) no loop of the mesh's
/// cross-section goes around it, if anywhere: a detected axis that leaves the mesh is not a
/// leg's (it runs between two legs, or across a bent one), and a tube around it would not be a
/// stocking.
pub fn leaves_mesh(leg: &Leg, axis: &Axis) -> Option<f64> {
    let fractions = [0.1, 0.5, 0.9];
    let heights = fractions.map(|f| f * axis.length());
    let loops = section::enclosing_radii(
        &leg.positions,
        &leg.triangles,
        &axis.bottom(),
        &axis.direction(),
        &heights,
    );
    fractions
        .into_iter()
        .zip(loops)
        .find_map(|(f, around)| around.is_none().then_some(f))
}

/// Vertices of the cuts (see module docs): boundaries that go around the line through
/// `centre` along `dir`. Sorted, without repeats; welded ids.
fn cut_vertices(leg: &Leg, centre: &Point3<f64>, dir: &Vector3<f64>) -> Vec<u32> {
    let welded = welded_ids(&leg.positions);
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    for t in leg
        .triangles
        .iter()
        .filter_map(|t| welded_triangle(&welded, t))
    {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    // Boundaries: open edges joined where they share a vertex.
    let mut root: Vec<u32> = (0..leg.positions.len() as u32).collect();
    fn find(root: &mut [u32], mut v: u32) -> u32 {
        while root[v as usize] != v {
            root[v as usize] = root[root[v as usize] as usize];
            v = root[v as usize];
        }
        v
    }
    let mut open: Vec<u32> = Vec::new();
    for (&(a, b), _) in uses.iter().filter(|&(_, &n)| n == 1) {
        let (ra, rb) = (find(&mut root, a), find(&mut root, b));
        root[ra.max(rb) as usize] = ra.min(rb);
        open.extend([a, b]);
    }
    open.sort_unstable();
    open.dedup();
    let (u, v) = perpendicular_frame(dir);
    let mut angles: BTreeMap<u32, Vec<f64>> = BTreeMap::new();
    for &i in &open {
        let d = leg.positions[i as usize] - centre;
        angles
            .entry(find(&mut root, i))
            .or_default()
            .push(d.dot(&v).atan2(d.dot(&u)));
    }
    let goes_around = |angles: &mut [f64]| {
        angles.sort_unstable_by(f64::total_cmp);
        let wrap = angles[0] + std::f64::consts::TAU - angles[angles.len() - 1];
        let widest = angles.windows(2).map(|w| w[1] - w[0]).fold(wrap, f64::max);
        widest <= CUT_MAX_GAP_RAD
    };
    let cuts: Vec<u32> = angles
        .iter_mut()
        .filter_map(|(&r, a)| goes_around(a).then_some(r))
        .collect();
    open.retain(|&i| cuts.contains(&find(&mut root, i)));
    open
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::leg::{Units, UpAxis};

    /// An open tube of radius 5 cm from y = 0 to y = 0.5, cut square to Y at both ends but
    /// leaning by `lean` in x per metre of height, like a thigh.
    fn leaning_open_tube(lean: f64) -> Leg {
        let (around, along) = (32u32, 20u32);
        let mut positions = Vec::new();
        for j in 0..=along {
            let y = 0.5 * j as f64 / along as f64;
            for i in 0..around {
                let t = std::f64::consts::TAU * i as f64 / around as f64;
                positions.push(Point3::new(0.05 * t.cos() + lean * y, y, -0.05 * t.sin()));
            }
        }
        let mut triangles = Vec::new();
        for j in 0..along {
            for i in 0..around {
                let (a, b) = (j * around + i, j * around + (i + 1) % around);
                triangles.push([a, b, b + around]);
                triangles.push([a, b + around, a + around]);
            }
        }
        Leg {
            path: "tube".into(),
            positions,
            triangles,
            reoriented_triangles: 0,
            units: Units::Metres,
            up_axis: UpAxis::PosY,
        }
    }

    #[test]
    fn end_rings_clear_a_slanted_cut() {
        let leg = leaning_open_tube(0.3);
        let axis = detect_axis(&leg).unwrap();
        let dir = axis.direction();
        assert!(dir.x > 0.2, "the axis follows the lean: {dir:?}");
        let (bottom, top) = (axis.bottom(), axis.top());
        let open = cut_vertices(
            &leg,
            &Point3::new(0.075, 0.25, 0.0),
            &Vector3::new(0.3, 1.0, 0.0).normalize(),
        );
        assert_eq!(open.len(), 64, "both cuts are open");
        let length = axis.length();
        for v in open {
            let s = (leg.positions[v as usize] - bottom).dot(&dir);
            // Every open vertex lies beyond an end ring's plane, with room to spare.
            assert!(
                s < -0.005 * length || s > length * 1.005,
                "open vertex {v} at {s} m along a {length} m axis"
            );
        }
        // The ends still sit on the tube's centre line.
        for p in [bottom, top] {
            let centre_x = 0.3 * p.y;
            assert!((p.x - centre_x).abs() < 0.01, "{p:?}");
        }
        assert!((top - bottom).norm() > 0.3);
    }

    #[test]
    fn a_square_cut_keeps_the_plain_inset() {
        let leg = leaning_open_tube(0.0);
        let axis = detect_axis(&leg).unwrap();
        let inset = END_INSET * 0.5;
        assert!((axis.bottom[1] - inset.max(CUT_CLEARANCE * 0.5)).abs() < 1e-9);
        assert!((axis.top[1] - (0.5 - inset)).abs() < 1e-9);
    }
}
