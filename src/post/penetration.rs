//! The penetration fix (paper §6.3): after the fit every yarn point is outside the leg, but a
//! straight yarn segment between two points on different triangles can still cut through it
//! (over a sharp shin, a coarse facet, a thin tendon). This pass finds such segments and makes
//! the yarn follow the skin instead.
//!
//! **Detection.** The paper's angle test: a segment whose direction makes more than 90° with
//! the outward normal at its start (or whose reverse does at its end) heads into the skin. It is
//! neither sufficient nor necessary: on a convex leg almost every chord heads in slightly without
//! reaching the skin, and a segment between two hollows can leave both ends outwards and still
//! cut through the bump between them. So every segment is also tested directly, with a ray cast
//! from one end to the other against the exact triangles (one BVH query per segment); a segment
//! the ray does not cross never enters the leg, as both ends are outside. The report counts both,
//! and the crossings the angle test would have missed.
//!
//! **Repair.** From the closest skin point of the start, walk over the mesh towards the closest
//! skin point of the end: in each triangle, head straight for the target projected into the
//! triangle's plane, and where that line leaves the triangle through an edge, insert a point on
//! the edge, lifted off the skin by the yarn offset along the edge's normal (the mean of its two
//! faces'), then continue in the triangle across the edge, until the target's triangle is
//! reached. Every inserted point lies on a triangle edge, so the yarn lies on the skin from
//! triangle to triangle. Where the walk cannot finish (an open edge, a non-manifold edge, a
//! mesh that folds back) or a piece still crosses the skin (two sheets of skin close together),
//! the piece is split at a point on the skin out across it, near the top of the bump or crest
//! it passes under, recursively: a fallback, counted separately.
//!
//! Inserted points carry the attributes of the segment they split: `course`, `wale` and
//! `tension` are interpolated by arc length where they are continuous (not across the seam,
//! where the wale number jumps), the others (`class`, `yarn_kind`) are taken from the nearer end.

use std::collections::HashMap;

use nalgebra::{Matrix2, Point3, Vector2};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::base::{Segment, Vec3, YarnGeometry};
use crate::leg::{Closest, Collider};

/// Attributes interpolated along a repaired segment; others come from the nearer end.
const INTERPOLATED: [&str; 3] = ["course", "wale", "tension"];
/// How many edges one segment's walk may cross before it gives up.
const MAX_CROSSINGS: usize = 512;
/// How many times the fallback may split a piece: a piece that never clears becomes at most
/// 2¹⁰ parts (each split a few ray casts and closest-point queries, and a point inserted). A
/// yarn piece cutting the corner of a millimetre ledge's rim, on a leg in pieces, took nine.
const MAX_SPLIT_DEPTH: u32 = 10;
/// The least determinant of the fallback's two planes, in the plane of the piece, for them to
/// meet at an apex (about the sine of the angle between their traces; 1e-6: not parallel).
const MIN_APEX_DETERMINANT: f64 = 1e-6;
/// How far out across a piece the fallback looks for the skin, in piece lengths: a crest whose
/// flanks rise 3 in 1 stands 1.5 lengths above the middle of a chord under it.
const ACROSS_REACH: f64 = 4.0;
/// The least length, across the piece, of the sum of the skin's normals where a piece enters
/// and leaves the leg, for the fallback to look out across it (0.05: normals 177° apart, as
/// through a thin sheet).
const MIN_ACROSS: f64 = 0.05;

/// What the fix did, for the report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PenetrationStats {
    /// Yarn segments looked at.
    pub segments: usize,
    /// Segments the angle test flagged as heading into the skin at an end.
    pub flagged_by_angle: usize,
    /// Segments the ray cast found crossing the skin.
    pub crossing: usize,
    /// Crossing segments the angle test alone would have missed (both ends heading out of the
    /// skin, a bump between them).
    pub crossing_missed_by_angle: usize,
    /// Crossing segments that no longer cross after the fix.
    pub repaired: usize,
    /// Points inserted in all.
    pub points_inserted: usize,
    /// Repaired segments that needed the fallback for some piece.
    pub used_fallback: usize,
    /// Pieces that still cross the skin after the fix (0 unless the mesh is broken).
    pub still_crossing: usize,
    /// Where one of them lies (the middle of the first, in the yarns' order), world space,
    /// metres; `null` where none does.
    #[serde(default)]
    pub still_crossing_at_m: Option<[f64; 3]>,
}

/// Returns `yarns` with every segment that cuts through the leg replaced by a polyline on the
/// skin (see module docs). Original points keep their indices; inserted points follow them.
/// `offset` is how far off the skin inserted points lie (the yarn radius), metres.
pub fn fix_penetrations(
    yarns: &YarnGeometry,
    collider: &Collider,
    offset: f64,
) -> (YarnGeometry, PenetrationStats) {
    let closest: Vec<Closest> = yarns
        .positions
        .par_iter()
        .map(|p| collider.closest(&Point3::from(*p)))
        .collect();
    let walker = SurfaceWalker::new(collider, offset);
    let repairs: Vec<Option<Repair>> = yarns
        .segments
        .par_iter()
        .map(|s| walker.check_and_repair(yarns, &closest, s))
        .collect();

    let mut stats = PenetrationStats {
        segments: yarns.segments.len(),
        ..PenetrationStats::default()
    };
    let mut out = yarns.clone();
    out.segments.clear();
    for (segment, repair) in yarns.segments.iter().zip(repairs) {
        let Some(repair) = repair else {
            out.segments.push(*segment);
            continue;
        };
        stats.flagged_by_angle += usize::from(repair.flagged_by_angle);
        if !repair.crossing {
            out.segments.push(*segment);
            continue;
        }
        stats.crossing += 1;
        stats.crossing_missed_by_angle += usize::from(!repair.flagged_by_angle);
        stats.used_fallback += usize::from(repair.used_fallback);
        stats.still_crossing += repair.still_crossing;
        if stats.still_crossing_at_m.is_none() {
            stats.still_crossing_at_m = repair.stuck_at.map(|p| p.into());
        }
        if repair.still_crossing == 0 {
            stats.repaired += 1;
        }
        stats.points_inserted += repair.points.len();
        append_chain(&mut out, yarns, segment, &repair.points);
    }
    (out, stats)
}

/// Appends `points` (inserted between the ends of `segment`) to `out` with their attributes, and
/// the chain of segments through them.
fn append_chain(out: &mut YarnGeometry, yarns: &YarnGeometry, segment: &Segment, points: &[Vec3]) {
    let (a, b) = (segment.a as usize, segment.b as usize);
    let ends = [
        Vec3::from(yarns.positions[a]),
        Vec3::from(yarns.positions[b]),
    ];
    // Arc length along the chain, for interpolation.
    let mut along = Vec::with_capacity(points.len());
    let mut length = 0.0;
    let mut previous = ends[0];
    for p in points {
        length += (p - previous).norm();
        along.push(length);
        previous = *p;
    }
    length += (ends[1] - previous).norm();

    let mut chain = vec![segment.a];
    for (p, s) in points.iter().zip(&along) {
        let t = if length > 0.0 { s / length } else { 0.5 };
        chain.push(out.positions.len() as u32);
        out.positions.push([p.x, p.y, p.z]);
        for (name, values) in out.point_attributes.iter_mut() {
            let (va, vb) = (values[a], values[b]);
            let continuous = INTERPOLATED.contains(&name.as_str()) && (vb - va).abs() <= 1.5;
            let v = if continuous {
                va + (vb - va) * t as f32
            } else if t < 0.5 {
                va
            } else {
                vb
            };
            values.push(v);
        }
    }
    chain.push(segment.b);
    for pair in chain.windows(2) {
        out.segments.push(Segment {
            a: pair[0],
            b: pair[1],
            ..*segment
        });
    }
}

/// The outcome for one segment the angle test flagged or the ray found crossing.
struct Repair {
    flagged_by_angle: bool,
    /// Whether the segment crossed the skin (if not, nothing was inserted).
    crossing: bool,
    /// Points inserted between its ends, in order from `a` to `b`.
    points: Vec<Vec3>,
    used_fallback: bool,
    /// Pieces still crossing after the fix.
    still_crossing: usize,
    /// The middle of the first of them.
    stuck_at: Option<Vec3>,
}

/// The leg's triangles with their edge neighbours, for walking over the skin.
struct SurfaceWalker<'a> {
    collider: &'a Collider,
    offset: f64,
    /// For each undirected edge (smaller vertex first), the triangles on it: two for an inner
    /// edge, one ([`NONE`] in the second slot) on an open boundary, and [`NONE`] in both slots
    /// for a non-manifold edge (three or more), which the walk does not cross.
    edges: HashMap<(u32, u32), [u32; 2]>,
}

/// Sentinel for "no triangle".
const NONE: u32 = u32::MAX;

impl<'a> SurfaceWalker<'a> {
    fn new(collider: &'a Collider, offset: f64) -> SurfaceWalker<'a> {
        let mut uses: HashMap<(u32, u32), (u32, [u32; 2])> = HashMap::new();
        for (t, tri) in collider.triangles().iter().enumerate() {
            for k in 0..3 {
                let key = edge_key(tri[k], tri[(k + 1) % 3]);
                let (count, slots) = uses.entry(key).or_insert((0, [NONE, NONE]));
                if let Some(slot) = slots.get_mut(*count as usize) {
                    *slot = t as u32;
                }
                *count += 1;
            }
        }
        let edges = uses
            .into_iter()
            .map(|(key, (count, slots))| (key, if count <= 2 { slots } else { [NONE, NONE] }))
            .collect();
        SurfaceWalker {
            collider,
            offset,
            edges,
        }
    }

    /// The angle test and the ray test, and if the segment crosses the skin, the repair;
    /// `None` when neither test flags it.
    fn check_and_repair(
        &self,
        yarns: &YarnGeometry,
        closest: &[Closest],
        s: &Segment,
    ) -> Option<Repair> {
        let (a, b) = (s.a as usize, s.b as usize);
        let (pa, pb) = (
            Vec3::from(yarns.positions[a]),
            Vec3::from(yarns.positions[b]),
        );
        let d = pb - pa;
        let flagged_by_angle = d.dot(&closest[a].outward) < 0.0 || d.dot(&closest[b].outward) > 0.0;
        if !self.crosses(&pa, &pb) {
            return flagged_by_angle.then_some(Repair {
                flagged_by_angle,
                crossing: false,
                points: Vec::new(),
                used_fallback: false,
                still_crossing: 0,
                stuck_at: None,
            });
        }
        let walked = self.walk(&closest[a], &closest[b]).unwrap_or_default();
        // Check every piece of the chain; split the ones that still cross.
        let mut points = Vec::with_capacity(walked.len());
        let mut used_fallback = false;
        let mut still_crossing = 0;
        let mut stuck_at = None;
        let mut from = pa;
        for to in walked.iter().copied().chain(std::iter::once(pb)) {
            if self.crosses(&from, &to) {
                used_fallback = true;
                let mut stuck = Vec::new();
                still_crossing += self.split(&from, &to, MAX_SPLIT_DEPTH, &mut points, &mut stuck);
                stuck_at = stuck_at.or(stuck.first().copied());
            }
            if to != pb {
                points.push(to);
            }
            from = to;
        }
        Some(Repair {
            flagged_by_angle,
            crossing: true,
            points,
            used_fallback,
            still_crossing,
            stuck_at,
        })
    }

    /// True when the straight piece from `a` to `b` meets the skin.
    fn crosses(&self, a: &Vec3, b: &Vec3) -> bool {
        let d = b - a;
        let length = d.norm();
        length > 0.0
            && self
                .collider
                .first_hit(&Point3::from(*a), &(d / length), length)
                .is_some()
    }

    /// Splits the piece `a`–`b` at [`Self::split_point`], recursively while a part crosses
    /// and `depth` lasts, pushing the points between `a` and `b` in order, and the middles of
    /// the parts that still cross to `stuck`. Returns how many pieces still cross.
    fn split(
        &self,
        a: &Vec3,
        b: &Vec3,
        depth: u32,
        points: &mut Vec<Vec3>,
        stuck: &mut Vec<Vec3>,
    ) -> usize {
        if depth == 0 {
            stuck.push((a + b) / 2.0);
            return 1;
        }
        let mid = self.split_point(a, b);
        let mut left = 0;
        if self.crosses(a, &mid) {
            left = self.split(a, &mid, depth - 1, points, stuck);
        }
        points.push(mid);
        let mut right = 0;
        if self.crosses(&mid, b) {
            right = self.split(&mid, b, depth - 1, points, stuck);
        }
        left + right
    }

    /// Where the fallback splits the piece `a`–`b`: near the top of the bump or crest it
    /// passes under, so each part crosses less of it. From the middle of its stretch inside
    /// the leg (halfway between where it enters and last leaves the skin) towards the apex,
    /// where the skin's tangent planes at the entry and the exit meet above the piece, to the
    /// skin, plus the offset. Over two flat flanks that is the crest itself, however lopsided
    /// the piece. Where the planes meet nowhere above the piece, it looks out along the
    /// normals' mean (less its part along the piece). The closest skin point would not do:
    /// under a sharp crest it lies on a flank, and the parts straddle the crest again, many
    /// splits short of clearing it. The closest skin point (plus the offset) is used where the
    /// normals are nearly opposite (a thin sheet), where the stretch's middle is not inside the
    /// leg, and where the point found is within half the offset of the skin or beyond
    /// [`ACROSS_REACH`].
    fn split_point(&self, a: &Vec3, b: &Vec3) -> Vec3 {
        let midpoint = (a + b) / 2.0;
        let closest = self.collider.closest(&Point3::from(midpoint));
        let fallback = closest.point.coords + closest.outward * self.offset;
        let length = (b - a).norm();
        let Some(dir) = (b - a).try_normalize(0.0) else {
            return fallback;
        };
        let enters = self.collider.first_hit(&Point3::from(*a), &dir, length);
        let leaves = self.collider.first_hit(&Point3::from(*b), &-dir, length);
        let (Some((enter, n_enter)), Some((leave, n_leave))) = (enters, leaves) else {
            return fallback;
        };
        let (entry, exit) = (a + dir * enter, b - dir * leave);
        let inside_middle = (entry + exit) / 2.0;
        let sum = n_enter + n_leave;
        let Some(across) = (sum - dir * sum.dot(&dir)).try_normalize(MIN_ACROSS) else {
            return fallback;
        };
        if self
            .collider
            .closest(&Point3::from(inside_middle))
            .signed_distance
            >= 0.0
        {
            return fallback;
        }
        // The apex may lie beyond the stretch's ends along the piece (a crest high above a
        // slanting piece does); the ray's reach bounds how far out it is looked for.
        let planes = ((&entry, &n_enter), (&exit, &n_leave));
        let towards = apex(&inside_middle, &dir, &across, planes.0, planes.1)
            .and_then(|apex| (apex - inside_middle).try_normalize(1e-12))
            .unwrap_or(across);
        let from = Point3::from(inside_middle);
        if let Some((t, _)) = self
            .collider
            .first_hit(&from, &towards, ACROSS_REACH * length)
        {
            let point = inside_middle + towards * (t + self.offset);
            let clear = self.collider.closest(&Point3::from(point)).signed_distance;
            if clear >= 0.5 * self.offset {
                return point;
            }
        }
        fallback
    }

    /// Walks over the skin from the closest point `start` to the closest point `goal`,
    /// returning the lifted points where the path crosses triangle edges; `None` when it cannot
    /// get there (see module docs).
    fn walk(&self, start: &Closest, goal: &Closest) -> Option<Vec<Vec3>> {
        let vertices = self.collider.vertices();
        let triangles = self.collider.triangles();
        let target = goal.point.coords;
        let mut triangle = start.triangle;
        let mut at = start.point.coords;
        let mut entered_by: Option<(u32, u32)> = None;
        let mut points = Vec::new();
        for _ in 0..MAX_CROSSINGS {
            if triangle == goal.triangle {
                return Some(points);
            }
            let n = self.collider.face_normal(triangle);
            let to_target = target - at;
            let dir = to_target - n * to_target.dot(&n);
            if dir.norm() < 1e-12 {
                return Some(points);
            }
            // Where the line at + s·dir leaves the triangle: the nearest edge it meets ahead.
            let tri = triangles[triangle as usize];
            let mut exit: Option<(f64, (u32, u32), Vec3)> = None;
            for k in 0..3 {
                let (i, j) = (tri[k], tri[(k + 1) % 3]);
                let key = edge_key(i, j);
                if Some(key) == entered_by {
                    continue;
                }
                let (vi, vj) = (vertices[i as usize].coords, vertices[j as usize].coords);
                let e = vj - vi;
                let denom = dir.cross(&e).dot(&n);
                if denom.abs() < 1e-30 {
                    continue;
                }
                let s = (vi - at).cross(&e).dot(&n) / denom;
                let u = (vi - at).cross(&dir).dot(&n) / denom;
                if s > 1e-12 && (-1e-9..=1.0 + 1e-9).contains(&u) && exit.is_none_or(|x| s < x.0) {
                    exit = Some((s, key, vi + e * u.clamp(0.0, 1.0)));
                }
            }
            let (s, key, q) = exit?;
            let in_plane = to_target.dot(&n).abs() <= 1e-6 * to_target.norm();
            if s >= 1.0 && in_plane {
                // The target lies in this triangle, or in its plane just beside it: arrived.
                return Some(points);
            }
            // Otherwise the target is on another face; one whose projection falls inside this
            // triangle (round a corner) is reached through the edge the line leaves by.
            let [t0, t1] = *self.edges.get(&key)?;
            let next = if t0 == triangle { t1 } else { t0 };
            if next == NONE || t0 == NONE {
                return None;
            }
            let normal = (n + self.collider.face_normal(next)).normalize();
            let lift = if normal.iter().all(|c| c.is_finite()) {
                normal
            } else {
                n
            };
            points.push(q + lift * self.offset);
            at = q;
            triangle = next;
            entered_by = Some(key);
        }
        None
    }
}

fn edge_key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// Where the planes through `entry` and `exit` with normals `n_entry` and `n_exit` meet in
/// the plane through `origin` spanned by `dir` and `across`, if there on the `across` side
/// (and the planes not nearly parallel there, [`MIN_APEX_DETERMINANT`]).
fn apex(
    origin: &Vec3,
    dir: &Vec3,
    across: &Vec3,
    (entry, n_entry): (&Vec3, &Vec3),
    (exit, n_exit): (&Vec3, &Vec3),
) -> Option<Vec3> {
    // origin + s·dir + t·across on both planes: two equations in (s, t).
    let m = Matrix2::new(
        dir.dot(n_entry),
        across.dot(n_entry),
        dir.dot(n_exit),
        across.dot(n_exit),
    );
    let rhs = Vector2::new((entry - origin).dot(n_entry), (exit - origin).dot(n_exit));
    if m.determinant().abs() <= MIN_APEX_DETERMINANT {
        return None;
    }
    let st = m.try_inverse()? * rhs;
    (st.y > 0.0).then(|| origin + dir * st.x + across * st.y)
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;
    use crate::base::{Direction, YarnKind};
    use crate::leg::{ContactMethod, Leg};

    /// A closed prism along Y with a sharp ridge on +Z, like a shin: its cross-section is a
    /// square of half-width `w` with a triangular ridge of height `h` on top; as few triangles
    /// as possible, so a yarn segment spans several.
    fn ridge(w: f64, h: f64) -> Leg {
        let section = [(w, -w), (w, w), (0.0, w + h), (-w, w), (-w, -w)];
        let mut positions = Vec::new();
        for y in [0.0, 0.1] {
            for &(x, z) in &section {
                positions.push(Point3::new(x, y, z));
            }
        }
        let m = section.len() as u32;
        let mut triangles = Vec::new();
        for i in 0..m {
            let j = (i + 1) % m;
            triangles.push([i, i + m, j]);
            triangles.push([j, i + m, j + m]);
        }
        // Caps (fans), bottom facing -Y, top facing +Y.
        for i in 1..m - 1 {
            triangles.push([0, i, i + 1]);
            triangles.push([m, m + i + 1, m + i]);
        }
        Leg::from_world("ridge".into(), &positions, &triangles)
    }

    fn two_points(a: [f64; 3], b: [f64; 3]) -> YarnGeometry {
        let mut point_attributes = BTreeMap::new();
        point_attributes.insert("course".to_string(), vec![3.0, 3.0]);
        point_attributes.insert("wale".to_string(), vec![7.0, 8.0]);
        point_attributes.insert("class".to_string(), vec![1.0, 4.0]);
        YarnGeometry {
            name: "yarns".into(),
            offset_m: [0.0; 3],
            positions: vec![a, b],
            point_attributes,
            segments: vec![Segment {
                a: 0,
                b: 1,
                yarn: YarnKind::Nylon,
                direction: Direction::Course,
            }],
        }
    }

    /// The deepest point of any segment inside the leg, sampled every 10 µm.
    fn deepest(yarns: &YarnGeometry, collider: &Collider) -> f64 {
        let mut deepest: f64 = 0.0;
        for s in &yarns.segments {
            let (a, b) = (
                Vec3::from(yarns.positions[s.a as usize]),
                Vec3::from(yarns.positions[s.b as usize]),
            );
            let n = ((b - a).norm() / 1e-5).ceil() as usize + 1;
            for k in 0..=n {
                let p = a + (b - a) * (k as f64 / n as f64);
                let d = collider.closest(&Point3::from(p)).signed_distance;
                deepest = deepest.min(d);
            }
        }
        -deepest
    }

    #[test]
    fn a_segment_cutting_through_a_ridge_is_walked_over_it() {
        let (w, h, offset) = (0.01, 0.004, 0.00003);
        let collider = Collider::new(&ridge(w, h), ContactMethod::Bvh).unwrap();
        assert!(
            collider.contains(&Point3::new(0.0, 0.05, 0.0)),
            "faces point out"
        );
        // Two points on either flank of the ridge: the chord between them passes under the
        // ridge's crest, 4 mm inside.
        let z = |x: f64| w + h * (1.0 - x.abs() / w);
        let yarns = two_points(
            [-0.008, 0.05, z(-0.008) + offset],
            [0.008, 0.05, z(0.008) + offset],
        );
        assert!(deepest(&yarns, &collider) > 0.001);
        let (fixed, stats) = fix_penetrations(&yarns, &collider, offset);
        assert_eq!((stats.crossing, stats.repaired), (1, 1), "{stats:?}");
        assert_eq!(stats.still_crossing, 0);
        assert!(stats.points_inserted >= 1);
        assert_eq!(fixed.positions.len(), 2 + stats.points_inserted);
        assert_eq!(fixed.segments.len(), 1 + stats.points_inserted);
        assert!(
            deepest(&fixed, &collider) <= 5e-8,
            "{}",
            deepest(&fixed, &collider)
        );
        // One point on the crest, offset above it (others on the faces' diagonals).
        let crest = fixed.positions[2..]
            .iter()
            .copied()
            .max_by(|a, b| a[2].total_cmp(&b[2]))
            .unwrap();
        assert!((crest[0]).abs() < 1e-9 && (crest[2] - (w + h)).abs() < offset * 1.01);
        // Attributes: course constant, wale by arc length (the crest halfway), class from the
        // nearer end.
        let crest_index = fixed.positions.iter().position(|p| *p == crest).unwrap();
        assert!(fixed.point_attributes["course"].iter().all(|&c| c == 3.0));
        assert!((fixed.point_attributes["wale"][crest_index] - 7.5).abs() < 1e-3);
        let wale = &fixed.point_attributes["wale"];
        assert!(wale[2] > 7.0 && wale[2] < wale[crest_index]);
        assert_eq!(fixed.point_attributes["class"][2], 1.0);
    }

    #[test]
    fn the_fallback_clears_a_sharp_crest() {
        // Flanks rising 3 in 1: their normals 143° apart. A chord between points on them passes
        // 24 mm under the crest; split at its midpoint's closest skin point (on a flank), it
        // took more splits than the depth allows.
        let (w, h, offset) = (0.01, 0.03, 0.00003);
        let collider = Collider::new(&ridge(w, h), ContactMethod::Bvh).unwrap();
        let walker = SurfaceWalker::new(&collider, offset);
        let on_flank = |x: f64| {
            let normal = Vec3::new(x.signum() * h, 0.0, w).normalize();
            Vec3::new(x, 0.05, w + h * (1.0 - x.abs() / w)) + normal * offset
        };
        let (a, b) = (on_flank(-0.008), on_flank(0.008));
        assert!(walker.crosses(&a, &b));
        let mut points = Vec::new();
        assert_eq!(
            walker.split(&a, &b, MAX_SPLIT_DEPTH, &mut points, &mut Vec::new()),
            0
        );
        assert_eq!(points.len(), 1, "{points:?}");
        // The one point is on the crest, offset above it.
        assert!(points[0].x.abs() < 1e-9 && (points[0].z - (w + h + offset)).abs() < 1e-9);
        let chain: Vec<Vec3> = [a].into_iter().chain(points).chain([b]).collect();
        assert!(chain.windows(2).all(|p| !walker.crosses(&p[0], &p[1])));
        // Lopsided, the one point is on the crest too: the flanks' planes meet there.
        let (a, b) = (on_flank(-0.008), on_flank(0.003));
        let mut points = Vec::new();
        assert_eq!(
            walker.split(&a, &b, MAX_SPLIT_DEPTH, &mut points, &mut Vec::new()),
            0
        );
        assert_eq!(points.len(), 1, "{points:?}");
        assert!(points[0].x.abs() < 1e-4 && (points[0].z - (w + h)).abs() < 3.0 * offset);
        let chain: Vec<Vec3> = [a].into_iter().chain(points).chain([b]).collect();
        assert!(chain.windows(2).all(|p| !walker.crosses(&p[0], &p[1])));
        let outside = |p: &Vec3| collider.closest(&Point3::from(*p)).signed_distance > 0.0;
        assert!(chain.iter().all(outside));
    }

    #[test]
    fn edges_know_their_triangles_and_a_non_manifold_edge_is_not_crossed() {
        // Four triangles fanned around the edge 0–1: non-manifold however many there are.
        let mut leg = ridge(0.01, 0.004);
        let base = leg.positions.len() as u32;
        for k in 0..4 {
            let t = k as f64 * 1.5;
            leg.positions
                .push(Point3::new(0.5 + t.cos(), 0.5, 0.5 + t.sin()));
        }
        leg.positions.push(Point3::new(0.5, 0.0, 0.5));
        leg.positions.push(Point3::new(0.5, 1.0, 0.5));
        let (a, b) = (base + 4, base + 5);
        for k in 0..4 {
            leg.triangles.push([a, b, base + k]);
        }
        let collider = Collider::new(&leg, ContactMethod::Bvh).unwrap();
        let walker = SurfaceWalker::new(&collider, 0.00003);
        let slots: Vec<[u32; 2]> = walker.edges.values().copied().collect();
        let non_manifold = slots.iter().filter(|s| **s == [NONE, NONE]).count();
        assert_eq!(non_manifold, 1, "the fanned edge only");
        // The closed prism's edges all have two triangles; the fan's outer edges one.
        let open = slots
            .iter()
            .filter(|s| s[0] != NONE && s[1] == NONE)
            .count();
        assert_eq!(open, 8, "each fan triangle's two outer edges");
    }

    #[test]
    fn a_piece_the_fix_cannot_clear_is_counted_where_it_lies() {
        // A plate 10 µm thick, a yarn straight through its middle: its two faces' normals are
        // opposite, so the fallback has no crest to lift the yarn over, and the piece stays.
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        crate::leg::test_meshes::add_box(
            &mut positions,
            &mut triangles,
            [0.0, 0.0, 0.0],
            [0.1, 1e-5, 0.1],
        );
        let plate = Leg::from_world("plate".into(), &positions, &triangles);
        let collider = Collider::new(&plate, ContactMethod::Bvh).unwrap();
        let yarns = two_points([0.05, 0.001, 0.05], [0.05, -0.001, 0.05]);
        let (_, stats) = fix_penetrations(&yarns, &collider, 0.00003);
        assert!(stats.still_crossing >= 1, "{stats:?}");
        let [x, y, z] = stats.still_crossing_at_m.unwrap();
        assert!(
            (x - 0.05).abs() < 0.01 && y.abs() < 0.002 && (z - 0.05).abs() < 0.01,
            "{stats:?}"
        );
    }

    #[test]
    fn a_segment_above_the_skin_is_left_alone() {
        let (w, h, offset) = (0.01, 0.004, 0.00003);
        let collider = Collider::new(&ridge(w, h), ContactMethod::Bvh).unwrap();
        // Both on the same flat side face (x = w), a chord on a flat face: nothing to do.
        let yarns = two_points([w + offset, 0.03, 0.0], [w + offset, 0.06, 0.002]);
        let (fixed, stats) = fix_penetrations(&yarns, &collider, offset);
        assert_eq!(fixed, yarns);
        assert_eq!(stats.crossing, 0);
    }

    #[test]
    fn a_segment_over_a_corner_walks_across_two_edges() {
        let (w, h, offset) = (0.01, 0.004, 0.00003);
        let collider = Collider::new(&ridge(w, h), ContactMethod::Bvh).unwrap();
        // From the +X side face round the corner at (w, -w) to the -Z face.
        let yarns = two_points([w + offset, 0.05, -0.006], [0.006, 0.052, -w - offset]);
        let (fixed, stats) = fix_penetrations(&yarns, &collider, offset);
        assert_eq!(stats.repaired, 1, "{stats:?}");
        assert_eq!(stats.used_fallback, 0, "{stats:?}");
        assert!(deepest(&fixed, &collider) <= 5e-8);
        // The attribute of the seam rule: a wale jump larger than 1 is not interpolated.
        let mut seam = yarns.clone();
        seam.point_attributes.get_mut("wale").unwrap()[1] = 0.0;
        let (fixed, _) = fix_penetrations(&seam, &collider, offset);
        assert!(fixed.point_attributes["wale"][2..]
            .iter()
            .all(|&w| w == 7.0 || w == 0.0));
    }
}
