//! The limb's own centreline, followed through its pose by sections square to it: where the
//! sections along up ([`super::landmarks`]) cut a foot pointed down through its toes, or a shin
//! lying forward lengthwise, these still go around the limb.
//!
//! Method: predictor–corrector traversal of a tube's centreline, after Aylward & Bullitt 2002
//! ("Initialization, noise, singularities, and scale in height ridge traversal for tubular
//! object centerline extraction", IEEE TMI 21(2)), with the mesh's plane sections in place of
//! intensity ridges: from a point and a direction, step [`STEP_M`] along the direction, cut the
//! skin there square to it, take the outermost loop around the stepped point, and its centre is
//! the next point; the chord from the last centre is the new direction, and the section is cut
//! again square to it through the new centre, so each station's section is square to the
//! centreline there, not to the last one.
//!
//! Contract: the stations run from the start along the limb until the section holds no closed
//! loop around the stepped point (the limb's end: a toe's cleft, a cut, the sole), the loop's girth
//! jumps by more than [`STEP_GIRTH_JUMP`] (the plane has reached the body or the other leg), the
//! direction turns more than [`MAX_TURN_DEG`] in one step, or [`MAX_LENGTH_M`] is followed.
//! Loops are of the skin without caps over cuts, across pieces as the landmarks' are (a
//! mannequin's shin and its ankle ball are one section). Nothing is smoothed: a station is
//! where the skin's own section put it.

use nalgebra::{Point3, Vector3};

use super::caps::open_cut_caps;
use super::slice::{encloses_in, girth_in, section};
use super::solid::triangle_pieces;
use crate::base::perpendicular_frame;

/// Distance between stations, metres: a few per ankle radius, so a joint's turn is seen.
pub const STEP_M: f64 = 0.01;
/// A loop more than this many times as far round as the last station's, a step before, is not
/// the limb's.
pub const STEP_GIRTH_JUMP: f64 = 1.5;
/// A step that turns the centreline more than this, degrees, has left the limb.
pub const MAX_TURN_DEG: f64 = 40.0;
/// The longest centreline followed, metres: longer than any leg.
pub const MAX_LENGTH_M: f64 = 1.6;

/// One section of the limb, square to its centreline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Station {
    /// The section's centre, world space.
    pub centre: Point3<f64>,
    /// Unit vector along the centreline, the way it is followed: the chord from the last
    /// station (its section was cut square to it).
    pub along: Vector3<f64>,
    /// Girth of the section (convex perimeter), metres.
    pub girth_m: f64,
}

/// The skin a limb is followed on: its triangles without caps over cuts, and each one's piece.
pub struct Skin<'a> {
    positions: &'a [Point3<f64>],
    triangles: Vec<[u32; 3]>,
    piece: Vec<u32>,
}

impl<'a> Skin<'a> {
    /// The skin of `triangles` (indices into `positions`), less its caps across `up`.
    pub fn new(positions: &'a [Point3<f64>], triangles: &[[u32; 3]], up: &Vector3<f64>) -> Self {
        let (triangles, _) = open_cut_caps(positions, triangles, up);
        let piece = triangle_pieces(positions, &triangles);
        Skin {
            positions,
            triangles,
            piece,
        }
    }

    /// The stations from `start` (a point inside the limb) along the unit vector `towards`
    /// (module docs); the first is the section through `start` itself, where it goes around it.
    pub fn follow(&self, start: &Point3<f64>, towards: &Vector3<f64>) -> Vec<Station> {
        let Some(first) = self.station(start, towards, f64::INFINITY) else {
            return Vec::new();
        };
        let mut stations = vec![first];
        let cos_turn = MAX_TURN_DEG.to_radians().cos();
        while stations.len() as f64 * STEP_M < MAX_LENGTH_M {
            let last = stations[stations.len() - 1];
            let ahead = last.centre + last.along * STEP_M;
            let Some(probe) = self.station(&ahead, &last.along, last.girth_m) else {
                break;
            };
            let Some(along) = (probe.centre - last.centre).try_normalize(1e-9) else {
                break;
            };
            if along.dot(&last.along) < cos_turn {
                break;
            }
            let Some(next) = self.station(&probe.centre, &along, last.girth_m) else {
                break;
            };
            let Some(along) = (next.centre - last.centre).try_normalize(1e-9) else {
                break;
            };
            if along.dot(&last.along) < cos_turn {
                break;
            }
            stations.push(Station { along, ..next });
        }
        stations
    }

    /// The section through `p` square to `normal`: the outermost closed loop around `p` (the
    /// skin, not a wall inside it), unless it is more than [`STEP_GIRTH_JUMP`] times
    /// `last_girth` round.
    fn station(&self, p: &Point3<f64>, normal: &Vector3<f64>, last_girth: f64) -> Option<Station> {
        let (u, v) = perpendicular_frame(normal);
        let loops = section(self.positions, &self.triangles, &self.piece, p, normal);
        let (around, girth_m) = (loops.iter())
            .filter(|l| encloses_in(l, &u, &v, p))
            .map(|l| (l, girth_in(l, &u, &v)))
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        (girth_m <= STEP_GIRTH_JUMP * last_girth).then(|| Station {
            centre: around.centre(),
            along: *normal,
            girth_m,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tube of radius `r` around the polyline `path`, closed at neither end: rings of 24
    /// points at each corner and between, joined by quads.
    fn tube(path: &[Point3<f64>], r: f64) -> (Vec<Point3<f64>>, Vec<[u32; 3]>) {
        let mut centres = Vec::new();
        for w in path.windows(2) {
            for k in 0..20 {
                centres.push(w[0] + (w[1] - w[0]) * (k as f64 / 20.0));
            }
        }
        centres.push(path[path.len() - 1]);
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        let n = 24u32;
        for (i, c) in centres.iter().enumerate() {
            let prev = centres[i.saturating_sub(1)];
            let next = centres[(i + 1).min(centres.len() - 1)];
            let (u, v) = perpendicular_frame(&(next - prev).normalize());
            for k in 0..n {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                positions.push(c + (u * a.cos() + v * a.sin()) * r);
            }
            if i > 0 {
                let (b, t) = ((i as u32 - 1) * n, i as u32 * n);
                for k in 0..n {
                    let k1 = (k + 1) % n;
                    triangles.push([b + k, b + k1, t + k1]);
                    triangles.push([b + k, t + k1, t + k]);
                }
            }
        }
        (positions, triangles)
    }

    #[test]
    fn a_bent_tube_is_followed_round_its_bend_with_its_girth() {
        // Down 40 cm, then 45° forward for 20 cm: a shin and a pointed foot.
        let turn = Vector3::new(0.0, -1.0, 1.0).normalize();
        let path = [
            Point3::new(0.0, 0.6, 0.0),
            Point3::new(0.0, 0.2, 0.0),
            Point3::new(0.0, 0.2, 0.0) + turn * 0.2,
        ];
        let (positions, triangles) = tube(&path, 0.03);
        let skin = Skin::new(&positions, &triangles, &Vector3::y());
        let stations = skin.follow(&Point3::new(0.0, 0.55, 0.0), &-Vector3::y());
        let length = stations.len() as f64 * STEP_M;
        assert!(length > 0.5, "followed {length} m");
        for s in &stations {
            // Every centre on the path, within a few millimetres, and every girth the tube's.
            let off = [(path[0], path[1]), (path[1], path[2])]
                .iter()
                .map(|(a, b)| {
                    let t = ((s.centre - a).dot(&(b - a)) / (b - a).norm_squared()).clamp(0.0, 1.0);
                    (s.centre - (a + (b - a) * t)).norm()
                })
                .fold(f64::INFINITY, f64::min);
            assert!(off < 0.005, "{s:?} is {off} m off the path");
            assert!(
                (s.girth_m - std::f64::consts::TAU * 0.03).abs() < 0.01,
                "{s:?}"
            );
        }
        let end = stations.last().unwrap();
        assert!(end.along.dot(&turn) > 0.95, "{end:?}");
    }
}
