//! The stocking as a tube of mass points (Sakaguchi & Miyata §6.1–6.2, Fig. 10–11): `wales`
//! points around × `courses` rings along, placed so that every ring encloses the leg before the
//! fit starts. Two shapes: an open tube stretched between two axis points ([`build_tube`], held
//! at both ends), and a whole stocking along the path over the foot ([`build_stocking`], held
//! at its welt, closed by a toe seam, with an optional heel pocket). Either way, where each
//! course came to rest along its [`Centreline`] tells slack from sliding.
//!
//! Rest lengths come from a physical stocking lying relaxed: a course spring is the relaxed
//! circumference over the number of wales, a wale spring the relaxed length over the number of
//! courses minus one. The paper instead scaled one rest length to the leg; ours keeps the
//! stocking's own size, so a thinner ankle really is covered by more stitches per cm².
//!
//! The grid is usually coarser than the stitches (150×150 points for a stocking of some 400
//! wales), and its cells need not have the stitch's shape: the springs are scaled so that the
//! tube is the knit's fabric at any grid size ([`Knit::with_stitch_shape`]). The grid a
//! stocking's fit ends on has its courses graded finer over the toe's tip where even ones would
//! be too long to wrap it ([`toe_graded_intervals`], docs/decisions/0073).
//!
//! Each ring clears the part of the leg that goes around the axis at its height (the loop of the
//! cross-section around the axis point, [`crate::leg::slice::enclosing_radii`]), not every
//! vertex at that height: in a file with both legs, the ring around one leg must not take in the
//! other.

use nalgebra::Point3;

use super::model::places_along;
use super::path::{PathPart, TubePath};
use super::settings::{TubeBottom, TubeHeel, TubeTop};
use super::{Knit, Pattern, Tile};
use crate::base::{perpendicular_frame, GridSize, PerDirection, Vec3};
use crate::leg::{slice, Axis, AxisSource, Landmarks, ThighTopKind};

/// Fraction of the leg's height kept between the stocking's end and a cut in the mesh, where
/// inside and outside are not defined.
pub const CUT_CLEARANCE: f64 = 0.03;
/// Least distance kept between the stocking's top and the other leg, metres: a thigh-high's
/// welt stays clear of the other thigh.
pub const OTHER_LEG_CLEARANCE_M: f64 = 0.025;
/// Shortest stocking the landmarks may give, metres.
pub const MIN_TUBE_LENGTH_M: f64 = 0.1;

/// Gap kept between the leg and a ring before the fit, as a fraction of the ring radius.
const RADIAL_MARGIN: f64 = 0.08;
/// Gap kept in any case, metres (a ring must start clear of the skin).
const MIN_GAP_M: f64 = 0.003;

/// Size and rest lengths of the tube.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TubeSpec {
    /// Points around (wales) by rings along (courses).
    pub grid: GridSize,
    /// Knit pattern.
    pub pattern: Pattern,
    /// Circumference of the relaxed stocking, metres.
    pub relaxed_circumference_m: f64,
    /// Length of the relaxed stocking along its centreline, metres.
    pub relaxed_length_m: f64,
    /// The knit's stitch: distance between wales along a course and between courses along a
    /// wale, metres (`knit.course_spacing_m`, `knit.wale_spacing_m`). Their ratio sets how much
    /// stiffer the fabric is around than along; the distance between courses is also the toe
    /// seam's rest, one real course on every grid (docs/decisions/0070).
    pub stitch_m: PerDirection,
}

impl TubeSpec {
    /// Rest lengths of a course spring and a wale spring on this grid, metres.
    pub fn rest_lengths(&self) -> PerDirection {
        PerDirection::new(
            self.relaxed_circumference_m / self.grid.wales as f64,
            self.relaxed_length_m / (self.grid.courses - 1).max(1) as f64,
        )
    }
}

/// The stocking's axis on the leg's landmarks: from the centre of the section at `bottom` to
/// the centre of the section at `top`, kept below where the thighs, from the knee up, come closer
/// than [`OTHER_LEG_CLEARANCE_M`] to the other leg. The error says why there is no room for a stocking.
pub fn tube_axis(landmarks: &Landmarks, bottom: TubeBottom, top: TubeTop) -> Result<Axis, String> {
    let sole = landmarks.sole_s();
    let thigh = landmarks.thigh_top.s;
    let leg_height = thigh - sole;
    let highest = match landmarks.thigh_top_kind {
        ThighTopKind::Crotch => thigh,
        ThighTopKind::Cut => thigh - CUT_CLEARANCE * leg_height,
    };
    // A stocking to the toe has this axis too: its leg part, what the report and the checks
    // of the axis read.
    let bottom_s = match bottom {
        TubeBottom::Ankle | TubeBottom::Toe => landmarks.ankle.s,
    };
    let asked = match top {
        TubeTop::BelowCrotchM(d) => thigh - d,
        TubeTop::Fraction(f) => sole + f * leg_height,
    }
    .min(highest);
    let clear = landmarks.clear_of_other_leg(OTHER_LEG_CLEARANCE_M);
    let top_s = asked.min(clear);
    if top_s - bottom_s < MIN_TUBE_LENGTH_M && clear < asked {
        return Err(format!(
            "the legs come within {:.1} cm of each other {:.3} m above the sole, so the \
             stocking would end there, only {:.3} m above the ankle; give the stocking's ends \
             as leg.axis (--axis)",
            100.0 * OTHER_LEG_CLEARANCE_M,
            clear - sole,
            (top_s - bottom_s).max(0.0)
        ));
    }
    if top_s - bottom_s < MIN_TUBE_LENGTH_M {
        return Err(format!(
            "the stocking would run only {:.3} m, from the ankle ({:.3} m above the sole) to \
             {:.3} m above the sole; end it higher (a smaller tube.top.below_crotch_m, or a \
             larger tube.top.fraction)",
            (top_s - bottom_s).max(0.0),
            bottom_s - sole,
            top_s - sole
        ));
    }
    Ok(Axis {
        bottom: landmarks.ring_at(bottom_s).centre,
        top: landmarks.ring_at(top_s).centre,
        source: AxisSource::Landmarks,
    })
}

/// Builds the open tube around the leg (world-space `leg_vertices` and the `leg_triangles` that
/// index them) between the axis points.
pub fn build_tube(
    spec: &TubeSpec,
    axis: &Axis,
    leg_vertices: &[Point3<f64>],
    leg_triangles: &[[u32; 3]],
) -> Knit {
    let GridSize {
        wales: w_count,
        courses: c_count,
    } = spec.grid;
    let bottom = axis.bottom();
    let a = axis.direction();
    let length = axis.length();
    let (u, v) = perpendicular_frame(&a);
    let radii = enclosing_radii(c_count, &bottom, &a, length, leg_vertices, leg_triangles);
    let tile = Tile::of(spec.pattern);
    let PerDirection {
        course: rest_course,
        wale: rest_wale,
    } = spec.rest_lengths();
    Knit::grid(
        w_count,
        c_count,
        true,
        &tile,
        rest_course,
        rest_wale,
        |w, c| {
            let s = length * c as f64 / (c_count - 1).max(1) as f64;
            let theta = std::f64::consts::TAU * w as f64 / w_count as f64;
            bottom.coords + a * s + (u * theta.cos() + v * theta.sin()) * radii[c]
        },
    )
    .with_stitch_shape(spec.stitch_m)
}

/// Per point of a tube's knit, true on a held end ring (held at its height along the axis during
/// the fit): the first and last ring of an open tube; only the first (the welt) of a stocking
/// closed at the toe, whose toe rests on the foot.
pub fn end_rings(knit: &Knit) -> Vec<bool> {
    let grid = knit.grid_len();
    (0..knit.len())
        .map(|i| {
            let c = i / knit.wales;
            i < grid && (c == 0 || (c + 1 == knit.courses && !knit.has_toe_seam()))
        })
        .collect()
}

/// Builds a whole stocking along `path` (top to toe): course 0 is the welt, held; the last
/// course is closed by a toe seam; with [`TubeHeel::Pocket`], short rows over the back half at
/// the middle of the heel (see [`heel_pocket_depths`]).
pub fn build_stocking(
    spec: &TubeSpec,
    path: &TubePath,
    heel: TubeHeel,
    spacing: CourseSpacing,
) -> Knit {
    let GridSize {
        wales: w_count,
        courses: c_count,
    } = spec.grid;
    let tile = Tile::of(spec.pattern);
    let PerDirection {
        course: rest_course,
        wale: even,
    } = spec.rest_lengths();
    let intervals = match spacing {
        CourseSpacing::Even => None,
        CourseSpacing::FinerAtTheToe => toe_graded_intervals(spec),
    }
    .unwrap_or_else(|| vec![even; c_count.saturating_sub(1)]);
    // The shaping's steps are the first interval's (the welt's, even on every grid).
    let rest_wale = intervals.first().copied().unwrap_or(even);
    // Each course starts as far along the path as it lies along the relaxed fabric.
    let places = places_along(&intervals);
    let graded = intervals.iter().any(|&r| r != even);
    let length = path.length();
    let along = |c: usize| match graded {
        true => length * places[c] / places[c_count - 1],
        false => length * c as f64 / (c_count - 1).max(1) as f64,
    };
    let rings: Vec<Vec<Point3<f64>>> = (0..c_count).map(|c| path.ring(along(c), w_count)).collect();
    let mut knit = Knit::grid(
        w_count,
        c_count,
        true,
        &tile,
        rest_course,
        rest_wale,
        |w, c| rings[c][w].coords,
    )
    .with_course_intervals(&intervals)
    .with_stitch_shape(spec.stitch_m)
    .with_toe_seam(spec.stitch_m.wale);
    if heel == TubeHeel::Pocket {
        let [lo, hi] = path.heel_range();
        let middle = 0.5 * (lo + hi);
        let course = match graded {
            true => (0..c_count)
                .min_by(|&a, &b| {
                    (along(a) - middle)
                        .abs()
                        .total_cmp(&(along(b) - middle).abs())
                })
                .unwrap_or(0),
            false => ((middle / length) * (c_count - 1) as f64).round() as usize,
        };
        // `c_count ≥ 2` (tube.courses is checked, a real count takes at least 2), so the
        // pocket's course and the next one exist, as `with_short_rows` asserts.
        let course = course.min(c_count - 2);
        let depth = heel_pocket_depths(spec, w_count, rest_wale);
        let (centre, ..) = path.frame_at(along(course));
        // Each new point starts on the straight line between its wale's two rings, bowed out
        // from the path by up to a quarter of its chain's length, so the folded-up pocket starts
        // clear of the heel.
        let place = |w: usize, f: f64| {
            let (a, b) = (rings[course][w], rings[course + 1][w]);
            let on_line = a + (b - a) * f;
            let out = (on_line - centre).normalize();
            let bow =
                0.25 * (2 * depth[w] + 1) as f64 * rest_wale * (std::f64::consts::PI * f).sin();
            (on_line + out * bow).coords
        };
        knit = knit.with_short_rows(course, depth.clone(), &tile, rest_course, rest_wale, place);
    }
    knit
}

/// How a stocking's courses are spread along its relaxed fabric.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CourseSpacing {
    /// All one rest length apart: the real stitches, and the levels a fit starts from.
    Even,
    /// Finer over the toe's tip where an even grid's cells would be longer than
    /// [`TOE_TIP_CELL_M`] ([`toe_graded_intervals`]): the grid a fit ends on.
    FinerAtTheToe,
}

/// Longest cell, metres of relaxed fabric, a stocking's grid gives the toe's tip: the fabric
/// wraps a tip of some 6 mm radius over its last 10–20 mm, and a cell much longer than a third
/// of that cuts the tip, its points resting on the skin with their wale springs at different
/// angles to it, so that the wale's tension jumps across them (docs/decisions/0071, 0073).
pub const TOE_TIP_CELL_M: f64 = 0.002;
/// Relaxed fabric at the toe's end over which the cells are [`TOE_TIP_CELL_M`], metres.
pub const TOE_TIP_FABRIC_M: f64 = 0.02;
/// Relaxed fabric over which the cells shrink from the grid's to the tip's, metres.
pub const TOE_TIP_RAMP_M: f64 = 0.02;
/// Most the tip's cells may be finer than the rest of the grid's.
pub const MAX_TOE_GRADING: f64 = 4.0;

/// The intervals (metres of relaxed fabric, welt to toe) of a stocking's courses graded finer
/// over the toe's tip: `k` courses per even one over the last [`TOE_TIP_FABRIC_M`], rising
/// linearly to it over the [`TOE_TIP_RAMP_M`] before, even above, with `k` such that the tip's
/// cells are [`TOE_TIP_CELL_M`] (at most [`MAX_TOE_GRADING`]). The same courses in all, so the
/// rest of the stocking's cells are a little longer than an even grid's. `None` where an even
/// grid's cells are already that short, or the stocking too short to grade.
pub fn toe_graded_intervals(spec: &TubeSpec) -> Option<Vec<f64>> {
    let length = spec.relaxed_length_m;
    let steps = spec.grid.courses.checked_sub(1).filter(|&n| n >= 2)? as f64;
    let (tip, ramp) = (TOE_TIP_FABRIC_M, TOE_TIP_RAMP_M);
    if length / steps <= TOE_TIP_CELL_M || length <= 2.0 * (tip + ramp) {
        return None;
    }
    // Courses per metre over the even courses' is 1 above the ramp and `k` over the tip, so the
    // grid's even interval is `(length + (k − 1)(tip + ramp / 2)) / steps`, and the tip's that
    // over `k`.
    let graded = tip + 0.5 * ramp;
    let room = TOE_TIP_CELL_M * steps - graded;
    let k = match room > 0.0 {
        true => ((length - graded) / room).clamp(1.0, MAX_TOE_GRADING),
        false => MAX_TOE_GRADING,
    };
    let ramp_start = length - tip - ramp;
    // Courses up to relaxed distance `s`, in even courses: the density's integral.
    let count = |s: f64| {
        let into_ramp = (s - ramp_start).clamp(0.0, ramp);
        let into_tip = (s - length + tip).max(0.0);
        s + (k - 1.0) * (0.5 * into_ramp * into_ramp / ramp + into_tip)
    };
    let total = count(length);
    let places: Vec<f64> = (0..=steps as usize)
        .map(|c| {
            let target = total * c as f64 / steps;
            let (mut lo, mut hi) = (0.0, length);
            for _ in 0..100 {
                let mid = 0.5 * (lo + hi);
                if count(mid) < target {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            0.5 * (lo + hi)
        })
        .collect();
    // The ends exactly where they are, not where the bisection left them.
    let mut places = places;
    places[0] = 0.0;
    places[steps as usize] = length;
    Some(places.windows(2).map(|p| p[1] - p[0]).collect())
}

/// Short rows per half of a heel pocket over each of `wales` wales, on a grid whose wale springs
/// are `rest_wale` long. A real short-row heel is knitted on the back half of the stitches,
/// each row one stitch shorter at both ends until a third of them remain, then one longer again:
/// so `n / 6` rows each way for a tube of `n` stitches around (`n` from the relaxed
/// circumference and the stitch), over the middle third of the heel, fewer towards its sides.
/// The same length of fabric at any grid size: rows on the grid are that length over
/// `rest_wale`. The back half is `v < 0`: wales `wales / 2..wales`, centred on `3 wales / 4`.
pub fn heel_pocket_depths(spec: &TubeSpec, wales: usize, rest_wale: f64) -> Vec<usize> {
    // At most the grid's courses: a fit refuses a pocket longer than the relaxed stocking
    // (`heel_pocket_half_length_m`), and `rest_wale` is that length over the courses.
    let rows = (heel_pocket_half_length_m(spec) / rest_wale)
        .round()
        .max(1.0);
    let n = wales as f64;
    let centre = 0.75 * n;
    (0..wales)
        .map(|w| {
            let off = (w as f64 - centre).abs();
            // Full depth over the middle third of the back half, none at its sides.
            let f = ((n / 4.0 - off) / (n / 4.0 - n / 12.0)).clamp(0.0, 1.0);
            (rows * f).round() as usize
        })
        .collect()
}

/// The length of fabric each half of a heel pocket knits ([`heel_pocket_depths`]): `n / 6` rows
/// of the relaxed stitch, `n` the stitches around. Metres.
pub fn heel_pocket_half_length_m(spec: &TubeSpec) -> f64 {
    let stitches_around = spec.relaxed_circumference_m / spec.stitch_m.course;
    stitches_around / 6.0 * spec.stitch_m.wale
}

/// The stocking's centreline, from course 0's end to the last course's: the path's centres for
/// a stocking to the toe, the axis (bottom to top) for an open tube. It tells slack from
/// sliding: where each course came to rest along it.
#[derive(Clone, Debug)]
pub struct Centreline {
    points: Vec<Point3<f64>>,
    /// Distance along the line at each point, metres.
    distance: Vec<f64>,
}

impl Centreline {
    /// The open tube's: its axis from bottom to top.
    pub fn straight(axis: &Axis) -> Centreline {
        Centreline::through(vec![axis.bottom(), axis.top()])
    }

    /// A stocking's to the toe: the path's centres.
    pub fn of_path(path: &TubePath) -> Centreline {
        Centreline::through(path.centreline())
    }

    fn through(points: Vec<Point3<f64>>) -> Centreline {
        let mut distance = Vec::with_capacity(points.len());
        let mut total = 0.0;
        for (k, p) in points.iter().enumerate() {
            if k > 0 {
                total += (p - points[k - 1]).norm();
            }
            distance.push(total);
        }
        Centreline { points, distance }
    }

    /// Length, metres.
    pub fn length(&self) -> f64 {
        self.distance.last().copied().unwrap_or(0.0)
    }

    /// How far along the line `p` lies: the distance to its closest point on the line, the first
    /// and last pieces extended beyond the ends (so a point past an end is below 0 or beyond the
    /// length).
    pub fn along(&self, p: &Vec3) -> f64 {
        let n = self.points.len();
        let mut best = (f64::INFINITY, 0.0);
        for k in 0..n.saturating_sub(1) {
            let (a, b) = (self.points[k].coords, self.points[k + 1].coords);
            let ab = b - a;
            let len = ab.norm();
            if len <= 0.0 {
                continue;
            }
            let mut s = (p - a).dot(&ab) / len;
            if k > 0 {
                s = s.max(0.0);
            }
            if k + 2 < n {
                s = s.min(len);
            }
            let d = (a + ab * (s / len) - p).norm_squared();
            if d < best.0 {
                best = (d, self.distance[k] + s);
            }
        }
        best.1
    }

    /// Where course `c` of `knit` came to rest: how far along the line its points' mean lies.
    pub fn course_along(&self, knit: &Knit, c: usize) -> f64 {
        let ring = &knit.particles.x[c * knit.wales..(c + 1) * knit.wales];
        let mean = ring.iter().sum::<Vec3>() / knit.wales as f64;
        self.along(&mean)
    }
}

/// The path's part at distance `s` along it.
pub fn part_at(path: &TubePath, s: f64) -> PathPart {
    let k = path.stations.partition_point(|st| st.s < s);
    path.stations[k.min(path.stations.len() - 1)].part
}

/// Per ring, a radius that clears the leg near that ring's height, with margin. Each ring's
/// height has a bin: the vertices of the triangles whose cross-section loop goes around the
/// axis there, or, where none does (the axis outside the mesh, a hole in that plane), every
/// vertex nearest that height. Each ring takes the largest radius of its own and the
/// neighbouring bins, so a ring also clears the skin between it and the next.
fn enclosing_radii(
    courses: usize,
    bottom: &Point3<f64>,
    a: &Vec3,
    length: f64,
    leg_vertices: &[Point3<f64>],
    leg_triangles: &[[u32; 3]],
) -> Vec<f64> {
    let bins = courses.max(2);
    let heights: Vec<f64> = (0..bins)
        .map(|c| length * c as f64 / (bins - 1) as f64)
        .collect();
    let around = slice::enclosing_radii(leg_vertices, leg_triangles, bottom, a, &heights);
    let mut bin_radius = vec![0.0f64; bins];
    for p in leg_vertices {
        let d = p - bottom;
        let s = d.dot(a);
        let r = (d - a * s).norm();
        let t = (s / length * (bins - 1) as f64).round();
        if t >= -1.0 && t <= bins as f64 {
            let b = t.clamp(0.0, (bins - 1) as f64) as usize;
            bin_radius[b] = bin_radius[b].max(r);
        }
    }
    for (r, loop_radius) in bin_radius.iter_mut().zip(around) {
        *r = loop_radius.unwrap_or(*r);
    }
    let widest = bin_radius.iter().copied().fold(0.0, f64::max);
    (0..courses)
        .map(|c| {
            let lo = c.saturating_sub(1);
            let hi = (c + 1).min(bins - 1);
            let r = bin_radius[lo..=hi].iter().copied().fold(0.0, f64::max);
            // A ring with no vertex near it (a gap in the mesh) takes the widest ring.
            let r = if r > 0.0 { r } else { widest };
            r + (r * RADIAL_MARGIN).max(MIN_GAP_M)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(courses: usize, length: f64) -> TubeSpec {
        TubeSpec {
            grid: GridSize::new(100, courses),
            pattern: Pattern::Alternating,
            relaxed_circumference_m: 0.2,
            relaxed_length_m: length,
            stitch_m: PerDirection::new(0.0005, 0.00074),
        }
    }

    #[test]
    fn a_coarse_stockings_courses_are_graded_finer_over_the_toes_tip() {
        // 100 courses over 0.52 m of fabric: 5.3 mm cells even, too long for the tip.
        let intervals = toe_graded_intervals(&spec(100, 0.52)).expect("graded");
        assert_eq!(intervals.len(), 99);
        let total: f64 = intervals.iter().sum();
        assert!((total - 0.52).abs() < 1e-9, "{total}");
        // Even above the ramp, never longer further on, the tip's cells as asked.
        assert!(intervals.windows(2).all(|p| p[1] <= p[0] * (1.0 + 1e-9)));
        let first = intervals[0];
        assert!(first > 0.52 / 99.0 && first < 1.2 * 0.52 / 99.0, "{first}");
        let tip = intervals[98];
        assert!(
            (tip - TOE_TIP_CELL_M).abs() < 0.02 * TOE_TIP_CELL_M,
            "{tip}"
        );
        // The tip's fabric is in those cells: the last 20 mm in tip-sized ones.
        let mut back = 0.0;
        for &r in intervals.iter().rev() {
            back += r;
            if back > TOE_TIP_FABRIC_M - 1e-4 {
                break;
            }
            assert!((r - tip).abs() < 1e-6 * tip, "{r} at {back}");
        }
        // Cells already short enough stay even, and so does a stocking too short to grade.
        assert_eq!(toe_graded_intervals(&spec(300, 0.52)), None);
        assert_eq!(toe_graded_intervals(&spec(10, 0.07)), None);
        // A grid too coarse to reach the tip's cell grades as far as it may.
        let coarse = toe_graded_intervals(&spec(20, 0.52)).expect("graded");
        let ratio = coarse[0] / coarse[18];
        assert!((ratio - MAX_TOE_GRADING).abs() < 1e-3, "{ratio}");
    }
}
