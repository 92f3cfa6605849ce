//! Plane sections of the leg as ordered loops: the girth profile the landmarks are read from.
//!
//! A plane at height `s` along a unit vector cuts each triangle with a corner below it and one at
//! or above it (the half-open rule: a plane through a vertex counts it as above, so every cut
//! triangle crosses exactly two of its edges). Each crossed edge is a point of the section; each
//! cut triangle joins two of them. On a cleaned mesh (welded, no repeated faces, see
//! [`super::clean`]) every point has two neighbours where the surface is closed and one at an
//! open cut, so walking the joins gives closed loops around the limbs and open chains at cuts.
//! Where a non-manifold edge gives a point three or more neighbours (a fin inside the leg), a
//! walk that comes back to a point closes the loop there and leaves the fin an open tail; a
//! chain broken by a small hole in the skin still counts as closed.
//!
//! A loop's girth is the perimeter of its convex hull in the plane: what a tape measure reads
//! around a limb, blind to dents, folds and small self-intersections of the mesh. A loop goes
//! around a point when a ray from it crosses the loop an odd number of times (the
//! crossing-number test, half-open): how a tube's ring finds the leg it must clear
//! ([`enclosing_radii`]) and a followed leg its next section.

use std::collections::HashMap;

use nalgebra::{Point3, Vector3};

use super::solid::connected_pieces;
use crate::base::perpendicular_frame;

/// Widest gap an open chain may have and still count as a closed loop, metres: a small hole in
/// the skin, not a cut.
pub const SMALL_GAP_M: f64 = 0.02;

/// One connected piece of a plane section.
#[derive(Clone, Debug, PartialEq)]
pub struct Loop {
    /// The section's points in walking order, world space.
    pub points: Vec<Point3<f64>>,
    /// True when the walk came back to its start (the surface is closed around it).
    pub closed: bool,
    /// The cut triangles it runs through, as indices into the slicer's triangles.
    pub triangles: Vec<u32>,
}

/// The sections of a mesh by parallel planes: built once per direction, asked per height.
pub struct Slicer<'a> {
    positions: &'a [Point3<f64>],
    triangles: &'a [[u32; 3]],
    up: Vector3<f64>,
    /// Per vertex, its height along `up`.
    height: Vec<f64>,
    /// Triangle indices sorted by their lowest corner's height, with that height.
    by_low: Vec<(f64, u32)>,
    /// The tallest triangle's height span: a plane at `s` can only cut triangles whose lowest
    /// corner is within it below `s`.
    tallest: f64,
    u: Vector3<f64>,
    v: Vector3<f64>,
    /// Per triangle, its connected piece (triangles sharing vertices).
    piece: Vec<u32>,
    /// Per vertex, the piece of the triangles that use it (`u32::MAX` for none).
    vertex_piece: Vec<u32>,
}

impl<'a> Slicer<'a> {
    /// Prepares sections of `triangles` (indices into `positions`, welded) square to the unit
    /// vector `up`.
    pub fn new(positions: &'a [Point3<f64>], triangles: &'a [[u32; 3]], up: Vector3<f64>) -> Self {
        let height: Vec<f64> = positions.iter().map(|p| p.coords.dot(&up)).collect();
        let mut tallest: f64 = 0.0;
        let mut by_low: Vec<(f64, u32)> = triangles
            .iter()
            .enumerate()
            .map(|(k, t)| {
                let h = t.map(|i| height[i as usize]);
                let lo = h[0].min(h[1]).min(h[2]);
                tallest = tallest.max(h[0].max(h[1]).max(h[2]) - lo);
                (lo, k as u32)
            })
            .collect();
        by_low.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let (u, v) = perpendicular_frame(&up);
        let vertex_piece = connected_pieces(positions.len(), triangles);
        let piece = (triangles.iter())
            .map(|t| vertex_piece[t[0] as usize])
            .collect();
        Slicer {
            positions,
            triangles,
            up,
            height,
            by_low,
            tallest,
            u,
            v,
            piece,
            vertex_piece,
        }
    }

    /// The connected piece vertex `i` is on, where a triangle uses it.
    pub fn piece_of_vertex(&self, i: usize) -> Option<u32> {
        Some(self.vertex_piece[i]).filter(|&p| p != u32::MAX)
    }

    /// The pieces loop `l` runs through, as bits (piece `k` as bit `k % 64`).
    pub fn pieces_of(&self, l: &Loop) -> u64 {
        (l.triangles.iter()).fold(0, |bits, &k| bits | piece_bit(self.piece[k as usize]))
    }

    /// Lowest and highest vertex height.
    pub fn range(&self) -> (f64, f64) {
        self.height
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &h| {
                (lo.min(h), hi.max(h))
            })
    }

    /// The direction the heights are measured along.
    pub fn up(&self) -> Vector3<f64> {
        self.up
    }

    /// The loops of the section at height `s`.
    pub fn loops_at(&self, s: f64) -> Vec<Loop> {
        let first = self
            .by_low
            .partition_point(|&(lo, _)| lo < s - self.tallest);
        let last = self.by_low.partition_point(|&(lo, _)| lo < s);
        let cut = self.by_low[first..last].iter().map(|&(_, k)| k);
        let loops = loops_of_cut(self.positions, self.triangles, &self.height, s, cut);
        merged_across_pieces(loops, &self.piece, &self.up, s)
    }

    /// The girth of `l`: the perimeter of its convex hull in the plane, metres.
    pub fn girth(&self, l: &Loop) -> f64 {
        girth_in(l, &self.u, &self.v)
    }

    /// True when `p`, projected into the plane, lies inside the closed loop `l` (crossing
    /// number, half-open rule).
    pub fn encloses(&self, l: &Loop, p: &Point3<f64>) -> bool {
        encloses_in(l, &self.u, &self.v, p)
    }
}

/// The girth of the loop `l` in the plane spanned by the unit vectors `u` and `v`: the
/// perimeter of its convex hull there, metres.
pub fn girth_in(l: &Loop, u: &Vector3<f64>, v: &Vector3<f64>) -> f64 {
    let hull = convex_hull(
        (l.points.iter())
            .map(|p| [p.coords.dot(u), p.coords.dot(v)])
            .collect(),
    );
    hull.iter()
        .zip(hull.iter().cycle().skip(1))
        .map(|(a, b)| ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt())
        .sum()
}

/// True when `p`, projected into the plane spanned by the unit vectors `u` and `v`, lies inside
/// the closed loop `l` (crossing number, half-open rule).
pub fn encloses_in(l: &Loop, u: &Vector3<f64>, v: &Vector3<f64>, p: &Point3<f64>) -> bool {
    if !l.closed || l.points.len() < 3 {
        return false;
    }
    let flat = |q: &Point3<f64>| [q.coords.dot(u), q.coords.dot(v)];
    let corners: Vec<[f64; 2]> = l.points.iter().map(flat).collect();
    inside_polygon(&corners, flat(p))
}

impl Loop {
    /// The mean of its points, weighted by the length of the path around each: the loop's
    /// centre, independent of how densely the mesh is cut there.
    pub fn centre(&self) -> Point3<f64> {
        let n = self.points.len();
        let mut sum = Vector3::zeros();
        let mut total = 0.0;
        for k in 0..n {
            let (a, b) = (self.points[k], self.points[(k + 1) % n]);
            let w = (b - a).norm();
            sum += (a.coords + b.coords) * (w / 2.0);
            total += w;
        }
        if total > 0.0 {
            Point3::from(sum / total)
        } else {
            self.points.first().copied().unwrap_or_else(Point3::origin)
        }
    }
}

/// The loops of one plane's section: the plane through `origin` square to the unit vector
/// `normal`; `piece` is each triangle's connected piece ([`super::solid::triangle_pieces`]).
/// For a few planes of different directions; [`Slicer`] is faster for many parallel ones.
pub fn section(
    positions: &[Point3<f64>],
    triangles: &[[u32; 3]],
    piece: &[u32],
    origin: &Point3<f64>,
    normal: &Vector3<f64>,
) -> Vec<Loop> {
    let height: Vec<f64> = positions.iter().map(|p| p.coords.dot(normal)).collect();
    let s = origin.coords.dot(normal);
    let cut = (0..triangles.len() as u32).filter(|&k| {
        let h = triangles[k as usize].map(|i| height[i as usize] >= s);
        h[0] != h[1] || h[1] != h[2]
    });
    let loops = loops_of_cut(positions, triangles, &height, s, cut);
    merged_across_pieces(loops, piece, normal, s)
}

/// `loops`, of the plane at height `s` along the unit vector `normal`, with the closed ones of
/// different pieces (`piece`, per triangle) that overlap in the plane made one: the section of
/// a solid modelled in pieces (a mannequin's ball joint inside its shin, a foot modelled apart
/// and pushed into the leg) is their union, and a tape measure goes round its convex hull.
/// Loops of one piece never merge: two legs of one body that touch at the knees stay two.
fn merged_across_pieces(
    loops: Vec<Loop>,
    piece: &[u32],
    normal: &Vector3<f64>,
    s: f64,
) -> Vec<Loop> {
    let piece_at: Vec<Option<u32>> = (loops.iter())
        .map(|l| l.triangles.first().map(|&k| piece[k as usize]))
        .collect();
    if piece_at.iter().flatten().all(|&p| Some(p) == piece_at[0]) {
        return loops;
    }
    let (u, v) = perpendicular_frame(normal);
    let flats: Vec<Vec<[f64; 2]>> = (loops.iter())
        .map(|l| {
            (l.points.iter())
                .map(|p| [p.coords.dot(&u), p.coords.dot(&v)])
                .collect()
        })
        .collect();
    let closed: Vec<usize> = (0..loops.len())
        .filter(|&i| loops[i].closed && flats[i].len() >= 3 && piece_at[i].is_some())
        .collect();
    let inside = |a: usize, b: usize| flats[b].iter().all(|p| inside_polygon(&flats[a], *p));
    let overlap = |a: usize, b: usize| {
        flats[b].iter().any(|p| inside_polygon(&flats[a], *p))
            || flats[a].iter().any(|p| inside_polygon(&flats[b], *p))
    };
    // An open chain of one piece wholly inside a closed loop of another (a hole in a ball
    // joint inside the shin) is inside the solid: no opening of its skin.
    let buried: Vec<bool> = (0..loops.len())
        .map(|i| {
            !loops[i].closed
                && closed
                    .iter()
                    .any(|&j| piece_at[j] != piece_at[i] && inside(j, i))
        })
        .collect();
    // Groups of overlapping closed loops of different pieces, each named by its first loop.
    let mut group: Vec<usize> = (0..loops.len()).collect();
    let root = |group: &[usize], mut i: usize| {
        while group[i] != i {
            i = group[i];
        }
        i
    };
    for (n, &i) in closed.iter().enumerate() {
        for &j in &closed[n + 1..] {
            if piece_at[i] != piece_at[j] && overlap(i, j) {
                let (a, b) = (root(&group, i), root(&group, j));
                group[a.max(b)] = a.min(b);
            }
        }
    }
    let roots: Vec<usize> = (0..loops.len()).map(|i| root(&group, i)).collect();
    let mut merged: Vec<Option<Loop>> = loops.into_iter().map(Some).collect();
    let mut points: Vec<Vec<[f64; 2]>> = vec![Vec::new(); merged.len()];
    for (i, &r) in roots.iter().enumerate() {
        if r != i {
            let member = merged[i].take().expect("each loop is taken once");
            let into = merged[r].as_mut().expect("a group's first loop stays");
            into.triangles.extend(member.triangles);
            points[r].extend(&flats[i]);
        }
    }
    // A group is the convex hull of all its loops' points, walked in order.
    let lift = |[x, y]: [f64; 2]| Point3::from(u * x + v * y + normal * s);
    (0..merged.len())
        .filter_map(|i| {
            let l = merged[i].take()?;
            if buried[i] {
                return None;
            }
            if points[i].is_empty() {
                return Some(l);
            }
            points[i].extend(&flats[i]);
            let hull = convex_hull(std::mem::take(&mut points[i]));
            Some(Loop {
                points: hull.into_iter().map(lift).collect(),
                closed: true,
                triangles: l.triangles,
            })
        })
        .collect()
}

/// True when `p` lies inside the polygon `corners` (crossing number, half-open rule).
fn inside_polygon(corners: &[[f64; 2]], [px, py]: [f64; 2]) -> bool {
    let mut inside = false;
    for (a, b) in corners.iter().zip(corners.iter().cycle().skip(1)) {
        if (a[1] > py) != (b[1] > py) {
            let x = a[0] + (b[0] - a[0]) * (py - a[1]) / (b[1] - a[1]);
            if x > px {
                inside = !inside;
            }
        }
    }
    inside
}

/// The convex hull of `points` in the plane through `centre` spanned by the unit vectors `u`
/// and `v`, as 2-D coordinates from `centre`, counter-clockwise.
pub fn hull_in_plane(
    points: impl Iterator<Item = Point3<f64>>,
    centre: &Point3<f64>,
    u: &Vector3<f64>,
    v: &Vector3<f64>,
) -> Vec<[f64; 2]> {
    convex_hull(
        points
            .map(|p| {
                let d = p - centre;
                [d.dot(u), d.dot(v)]
            })
            .collect(),
    )
}

/// Bit `piece % 64`: a set of pieces in a word (two pieces 64 apart share a bit; a file with
/// that many pieces around one leg is not a leg).
pub fn piece_bit(piece: u32) -> u64 {
    1 << (piece % 64)
}

/// Loops of the section at height `s` (per-vertex `height`) through the triangles `cut` (those
/// that may cross it): each crossed edge is a node, each cut triangle joins two.
fn loops_of_cut(
    positions: &[Point3<f64>],
    triangles: &[[u32; 3]],
    height: &[f64],
    s: f64,
    cut: impl Iterator<Item = u32>,
) -> Vec<Loop> {
    let mut node: HashMap<(u32, u32), usize> = HashMap::new();
    let mut points: Vec<Point3<f64>> = Vec::new();
    let mut joins: Vec<[usize; 2]> = Vec::new();
    let mut join_triangle: Vec<u32> = Vec::new();
    for k in cut {
        let t = triangles[k as usize];
        let mut ends = [0usize; 2];
        let mut found = 0;
        for (i, j) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            let (i, j) = (i.min(j), i.max(j));
            let (hi, hj) = (height[i as usize], height[j as usize]);
            if (hi >= s) == (hj >= s) || found == 2 {
                continue;
            }
            let id = *node.entry((i, j)).or_insert_with(|| {
                let (pi, pj) = (positions[i as usize], positions[j as usize]);
                points.push(pi + (pj - pi) * ((s - hi) / (hj - hi)));
                points.len() - 1
            });
            ends[found] = id;
            found += 1;
        }
        if found == 2 && ends[0] != ends[1] {
            joins.push(ends);
            join_triangle.push(k);
        }
    }
    walk_loops(&points, &joins, &join_triangle)
}

/// For each of `heights` (metres along the unit vector `a` from `origin`), the largest distance
/// from the axis of any vertex of the triangles whose section by that plane makes a closed loop
/// around the axis point; `None` where no loop goes around it (the axis is outside the mesh
/// there, or the loop is open). In a file with both legs, only the leg around the axis counts:
/// a tube's ring must clear that leg, not take in the other.
pub fn enclosing_radii(
    positions: &[Point3<f64>],
    triangles: &[[u32; 3]],
    origin: &Point3<f64>,
    a: &Vector3<f64>,
    heights: &[f64],
) -> Vec<Option<f64>> {
    let slicer = Slicer::new(positions, triangles, *a);
    let base = origin.coords.dot(a);
    let radial = |p: &Point3<f64>| {
        let d = p - origin;
        (d - a * d.dot(a)).norm()
    };
    heights
        .iter()
        .map(|&h| {
            let centre = origin + a * h;
            slicer
                .loops_at(base + h)
                .iter()
                .filter(|l| l.closed && slicer.encloses(l, &centre))
                .flat_map(|l| &l.triangles)
                .flat_map(|&k| triangles[k as usize])
                .map(|i| radial(&positions[i as usize]))
                .reduce(f64::max)
        })
        .collect()
}

/// Walks the joins into loops (see module docs). A walk that comes back to a point it passed
/// closes a loop there and goes on from it, so a fin hanging off a loop (a non-manifold edge)
/// leaves the loop closed and itself an open tail. An open chain whose ends are within
/// [`SMALL_GAP_M`] and a tenth of its length of each other (a small hole in the skin) counts as
/// closed.
fn walk_loops(points: &[Point3<f64>], joins: &[[usize; 2]], join_triangle: &[u32]) -> Vec<Loop> {
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); points.len()];
    for (k, &[a, b]) in joins.iter().enumerate() {
        neighbours[a].push(k);
        neighbours[b].push(k);
    }
    let mut used = vec![false; joins.len()];
    let mut place: Vec<Option<usize>> = vec![None; points.len()];
    let mut loops = Vec::new();
    let mut walk = |start: usize, used: &mut Vec<bool>, loops: &mut Vec<Loop>| {
        // The points walked and, between each two, the join taken.
        let mut chain = vec![start];
        let mut taken: Vec<usize> = Vec::new();
        place[start] = Some(0);
        let mut at = start;
        while let Some(&k) = neighbours[at].iter().find(|&&k| !used[k]) {
            used[k] = true;
            let [a, b] = joins[k];
            at = if a == at { b } else { a };
            if let Some(i) = place[at] {
                let cycle: Vec<usize> = chain.drain(i..).collect();
                let cycle_joins = taken.drain(i..).chain([k]);
                for &n in &cycle {
                    place[n] = None;
                }
                loops.push(Loop {
                    points: cycle.iter().map(|&n| points[n]).collect(),
                    closed: true,
                    triangles: cycle_joins.map(|j| join_triangle[j]).collect(),
                });
            } else {
                taken.push(k);
            }
            place[at] = Some(chain.len());
            chain.push(at);
        }
        for &n in &chain {
            place[n] = None;
        }
        if chain.len() >= 2 {
            let points: Vec<Point3<f64>> = chain.iter().map(|&n| points[n]).collect();
            let length: f64 = points.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
            let gap = (points[points.len() - 1] - points[0]).norm();
            loops.push(Loop {
                points,
                closed: gap <= SMALL_GAP_M.min(0.1 * length),
                triangles: taken.iter().map(|&j| join_triangle[j]).collect(),
            });
        }
    };
    // Open chains from their ends first, so a chain is walked whole; then the closed loops.
    let ends: Vec<usize> = (0..points.len())
        .filter(|&n| neighbours[n].len() == 1)
        .collect();
    for start in ends {
        if !used[neighbours[start][0]] {
            walk(start, &mut used, &mut loops);
        }
    }
    for (start, joined) in neighbours.iter().enumerate() {
        if joined.iter().any(|&k| !used[k]) {
            walk(start, &mut used, &mut loops);
        }
    }
    loops
}

/// The convex hull of `points` (Andrew's monotone chain), counter-clockwise, no repeats.
/// The convex hull of 2-D `points`, counter-clockwise.
pub fn convex_hull(mut points: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    points.sort_unstable_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(2 * points.len());
    for pass in 0..2 {
        let start = hull.len();
        let ordered: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(points.iter())
        } else {
            Box::new(points.iter().rev())
        };
        for &p in ordered {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed box from y = 0 to 1 with a square cross-section of side `w`, centred on x.
    fn square_tube(x: f64, w: f64, first: u32) -> (Vec<Point3<f64>>, Vec<[u32; 3]>) {
        let h = w / 2.0;
        let corners = [(h, h), (-h, h), (-h, -h), (h, -h)];
        let mut positions = Vec::new();
        for y in [0.0, 1.0] {
            for (cx, cz) in corners {
                positions.push(Point3::new(x + cx, y, cz));
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
    fn two_limbs_give_two_loops_with_their_girths_and_centres() {
        let (mut positions, mut triangles) = square_tube(0.0, 0.1, 0);
        let (p, t) = square_tube(0.5, 0.2, 8);
        positions.extend(p);
        triangles.extend(t);
        let slicer = Slicer::new(&positions, &triangles, Vector3::y());
        let mut loops = slicer.loops_at(0.5);
        assert_eq!(loops.len(), 2);
        loops.sort_by(|a, b| a.centre().x.total_cmp(&b.centre().x));
        for (l, (x, w)) in loops.iter().zip([(0.0, 0.1), (0.5, 0.2)]) {
            assert!(l.closed);
            assert!((slicer.girth(l) - 4.0 * w).abs() < 1e-12);
            assert!((l.centre() - Point3::new(x, 0.5, 0.0)).norm() < 1e-12);
            assert!(slicer.encloses(l, &Point3::new(x, 0.3, 0.0)));
            assert!(!slicer.encloses(l, &Point3::new(x + 0.2, 0.3, 0.0)));
        }
        assert_eq!(slicer.range(), (0.0, 1.0));
        assert!(slicer.loops_at(1.5).is_empty());
    }

    #[test]
    fn only_the_loop_around_the_axis_counts_for_a_ring() {
        let (mut positions, mut triangles) = square_tube(0.0, 0.2, 0);
        let (p, t) = square_tube(0.5, 0.2, 8);
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

    #[test]
    fn an_open_surface_gives_an_open_chain() {
        let (positions, mut triangles) = square_tube(0.0, 0.1, 0);
        triangles.truncate(6);
        let slicer = Slicer::new(&positions, &triangles, Vector3::y());
        let loops = slicer.loops_at(0.5);
        assert_eq!(loops.len(), 1);
        assert!(!loops[0].closed);
        // Three sides, each crossed at its two vertical edges and its diagonal: 4 + 3 points.
        assert_eq!(loops[0].points.len(), 7);
    }
}
