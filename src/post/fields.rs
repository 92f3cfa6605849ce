//! Per-point fields of a fitted knit, in the real stocking's units whatever the grid
//! ([`Fabric`]: each grid cell stands for a block of real stitches), and their transfer to the
//! leg's vertices.
//!
//! * **Stitch density** at a yarn point: real stitches per cm² of fabric, the textile measure
//!   (courses per cm × wales per cm): the relaxed stitch's `1 / (a b)` over the stretch both
//!   ways. Per cm² of fabric, not of skin: where the fabric wrinkles, how finely a grid
//!   resolves the folds would otherwise set it. The heel pocket's short rows lengthen its wales'
//!   fabric, so they count as more stitches there.
//! * **Stretch** at a yarn point, along the course and along the wale: the fitted fabric's length
//!   over its relaxed length there (1 relaxed, 1.5 stretched by half), measured over
//!   [`MEASURE_SPAN_M`] either way (see [`stretch`]).
//! * **Coverage**, 0–1: the fraction of skin hidden by yarn seen along the normal. Each stitch
//!   is its yarn's loop (Choi & Lo 2003, [`crate::post::loops`]: the shape the `loops` output
//!   and the preview draw), stretched with the stitch; seen along the normal it hides its
//!   in-plane length `L(s_c, s_w)` times the yarn's diameter `d`, over the stitch's area
//!   `a s_c · b s_w`. Loops overlap where legs cross heads; taking the overlaps as random,
//!   `coverage = 1 − exp(−d L / (a s_c b s_w))`, which stays below 1 however thick the yarn.
//!   Yarn flattening is ignored.
//! * **Tension** around and along, newtons per metre of fitted fabric: the membrane of
//!   [`Fabric::membrane_n_per_m`] times that direction's blended yarn stiffness
//!   ([`ForceTerms::blended`]), times the strain `s − 1`, over the other direction's stretch.
//!   Fabric does not carry compression: where it is shorter than knitted (slack) it has none.
//! * **Pressure** on the skin, mmHg, by Laplace's law for a membrane: `P = T_c κ_c + T_w κ_w`,
//!   with `κ` the fitted fabric's normal curvature along the course and the wale (the skin's,
//!   where the fabric lies on it), taken over [`MEASURE_SPAN_M`] of relaxed fabric so that no
//!   grid's spacing sets it; around a leg it is the course tension over the radius. Where the
//!   fabric bridges a hollow (negative curvature) it presses nothing: 0. Only a tube has it.
//! * **On the leg**, a vertex takes the kernel-weighted mean of the yarn points within a bandwidth
//!   (a biweight kernel, compactly supported, so far-away yarn has no say): smooth where the fit is
//!   smooth, and 0 where no yarn is near (uncovered skin).

use std::collections::HashMap;

use nalgebra::Point3;

use crate::base::{Direction, Vec3};
use crate::knit::fabric::PA_PER_MMHG;
use crate::knit::{Fabric, Knit, PointId};
use crate::leg::Leg;
use crate::post::loops::loop_shapes;
use crate::sim::ForceTerms;

/// Square metres per square centimetre.
const M2_PER_CM2: f64 = 1e-4;
/// Length of relaxed fabric, metres, over which stretch and curvature are measured each way
/// from a point: about one cell of the coarsest grid a fit is run at (100 courses along a whole
/// stocking), so that every grid and the real stitches see the same fabric; an arc through the
/// ends and the point keeps a ring's curve (a fitted ankle is some 35 mm around its centre).
pub const MEASURE_SPAN_M: f64 = 0.008;

/// Stretch around and along at every point (`(course, wale)`, see [`stretch`]): what density,
/// coverage and tension are computed from.
pub type Stretch = (Vec<f64>, Vec<f64>);

/// Real stitches per cm² of fabric at every point, from its `stretch` (see module docs).
pub fn stitch_density(fabric: &Fabric, (course, wale): &Stretch) -> Vec<f64> {
    let relaxed = fabric.relaxed_stitches_per_m2() * M2_PER_CM2;
    course
        .iter()
        .zip(wale)
        .map(|(&sc, &sw)| {
            let area = sc * sw;
            if area > 0.0 {
                relaxed / area
            } else {
                0.0
            }
        })
        .collect()
}

/// Stretch along the course and along the wale at every point: `(course, wale)` (see module
/// docs): the arc through the points [`MEASURE_SPAN_M`] of relaxed fabric either way and the
/// point itself, over its rest length, so that a grid of the real stitches, whose alternate
/// courses zigzag by a loop's height, measures the fabric's stretch and not its loops'. Along
/// the wale the span follows the wale's chain through the heel pocket's short rows; around, a
/// short row's point has only its own springs. A point with no neighbour in a direction gets 1
/// there.
pub fn stretch(knit: &Knit) -> Stretch {
    let stencil = Stencil::of(knit);
    let x = &knit.particles.x;
    let [rest_course, rest_wale] = knit.grid_rest_m();
    let ratio = |lo: PointId, here: usize, hi: PointId, rest: f64| {
        if rest > 0.0 && lo != hi {
            arc_length(x[lo.index()], x[here], x[hi.index()]) / rest
        } else {
            1.0
        }
    };
    let course = (0..knit.len())
        .map(|i| {
            let p = PointId(i as u32);
            if i >= knit.grid_len() {
                return local_spacing(knit, p).stretch(0);
            }
            let (w, c) = knit.grid_coords(p);
            let (lo, hi, steps) = stencil.span(knit, w, c, Direction::Course);
            ratio(lo, i, hi, rest_course * steps as f64)
        })
        .collect();
    let mut wale = vec![1.0; knit.len()];
    let reach = stencil.reach[Direction::Wale.index()];
    for w in 0..knit.wales {
        let chain = knit.wale_chain(w);
        for (j, p) in chain.iter().enumerate() {
            let (lo, hi) = (j.saturating_sub(reach), (j + reach).min(chain.len() - 1));
            wale[p.index()] = ratio(
                chain[lo],
                p.index(),
                chain[hi],
                rest_wale * (hi - lo) as f64,
            );
        }
    }
    (course, wale)
}

/// Length of the circular arc from `a` through `b` to `c` (the chord where they lie on a line):
/// the fabric's length between two points of a curved ring, which its chord would shorten.
fn arc_length(a: Vec3, b: Vec3, c: Vec3) -> f64 {
    let chord = (c - a).norm();
    let (ab, bc) = ((b - a).norm(), (c - b).norm());
    if ab <= 0.0 || bc <= 0.0 || chord <= 0.0 {
        return chord.max(ab + bc);
    }
    // Curvature of the circle through the three points: 4 · area / (product of the sides).
    let curvature = 2.0 * (b - a).cross(&(c - a)).norm() / (ab * bc * chord);
    let half_angle_sine = (0.5 * chord * curvature).min(1.0);
    if half_angle_sine < 1e-6 {
        chord
    } else {
        chord * half_angle_sine.asin() / half_angle_sine
    }
}

/// How far either way of a grid point its fabric is measured: [`MEASURE_SPAN_M`] of relaxed
/// fabric in grid steps, even, so that a grid of the real stitches meets the same yarns of an
/// alternating pattern at both ends as at the point; at least one step.
struct Stencil {
    reach: [usize; 2],
}

impl Stencil {
    fn of(knit: &Knit) -> Stencil {
        let reach = knit.grid_rest_m().map(|rest| {
            let steps = if rest > 0.0 {
                (MEASURE_SPAN_M / rest / 2.0).round() * 2.0
            } else {
                1.0
            };
            (steps as usize).max(1)
        });
        Stencil { reach }
    }

    /// The grid points before and after `(w, c)` along `direction`, within reach, and how many
    /// steps apart they are: round a tube's courses, stopping at a patch's edges and at the
    /// first and last course.
    fn span(
        &self,
        knit: &Knit,
        w: usize,
        c: usize,
        direction: Direction,
    ) -> (PointId, PointId, usize) {
        let reach = self.reach[direction.index()];
        match direction {
            Direction::Course if knit.closed_courses && knit.wales >= 3 => {
                let k = reach.min((knit.wales - 1) / 2).max(1);
                let wales = knit.wales;
                (
                    knit.point((w + wales - k) % wales, c),
                    knit.point((w + k) % wales, c),
                    2 * k,
                )
            }
            Direction::Course => {
                let (lo, hi) = (w.saturating_sub(reach), (w + reach).min(knit.wales - 1));
                (knit.point(lo, c), knit.point(hi, c), hi - lo)
            }
            Direction::Wale => {
                let (lo, hi) = (c.saturating_sub(reach), (c + reach).min(knit.courses - 1));
                (knit.point(w, lo), knit.point(w, hi), hi - lo)
            }
        }
    }
}

/// Coverage at every point (see module docs), from the real yarns' loops: each stitch's loop
/// ([`LoopShape`](crate::post::loops::LoopShape), stretched with its stitch) hides its in-plane length times its yarn's diameter,
/// over the stitch's fitted area, the loops' overlaps taken as random. An alternating pattern's
/// stitches are of either yarn by their courses' shares, so it reads the fabric, not a grid
/// course.
pub fn coverage(
    knit: &Knit,
    fabric: &Fabric,
    (stretch_course, stretch_wale): &Stretch,
) -> Vec<f64> {
    let [course_shares, _] = knit.yarn_shares();
    let lengths = loop_shapes(fabric).map(|shape| shape.in_plane_length());
    let [w, c] = fabric.stitch_m;
    stretch_course
        .iter()
        .zip(stretch_wale)
        .map(|(&s_course, &s_wale)| {
            let yarn_area: f64 = course_shares
                .iter()
                .zip(&lengths)
                .zip(&fabric.yarn_diameter_m)
                .filter(|((&share, _), _)| share > 0.0)
                .map(|((share, length), d)| share * d * length.at([s_course, s_wale]))
                .sum();
            let stitch_area = w * s_course * c * s_wale;
            if stitch_area > 0.0 {
                1.0 - (-yarn_area / stitch_area).exp()
            } else {
                1.0
            }
        })
        .collect()
}

/// Tension around (along the courses) and along (the wales) at every point, newtons per metre
/// of fitted fabric, from its `stretch` (see module docs).
pub fn tension(
    knit: &Knit,
    fabric: &Fabric,
    terms: &ForceTerms,
    (course, wale): &Stretch,
) -> [Vec<f64>; 2] {
    let membrane = fabric.membrane_n_per_m();
    // The fabric's membrane, whatever yarn a point lies on: the grid's yarns blended.
    let shares = knit.yarn_shares();
    let stiffness =
        [Direction::Course, Direction::Wale].map(|d| terms.blended(shares[d.index()], d));
    let of = |d: usize, along: &[f64], across: &[f64]| -> Vec<f64> {
        along
            .iter()
            .zip(across)
            .map(|(&s, &other)| stiffness[d] * membrane[d] * (s - 1.0).max(0.0) / other)
            .collect()
    };
    [of(0, course, wale), of(1, wale, course)]
}

/// Pressure on the skin at every point of a tube, mmHg (see module docs); all 0 for a knit whose
/// courses do not close (a patch).
pub fn pressure(knit: &Knit, tension: &[Vec<f64>; 2]) -> Vec<f64> {
    let mut out = vec![0.0; knit.len()];
    if !knit.closed_courses || knit.wales < 3 || knit.courses < 3 {
        return out;
    }
    let stencil = Stencil::of(knit);
    let x = |p: PointId| knit.particles.x[p.index()];
    let (wales, courses) = (knit.wales, knit.courses);
    // The surface's normal, t_course × t_wale, points out of the tube on one side of the grid's
    // numbering and in on the other: one sign for the whole knit, from the rings' centres.
    let mut outward = 0.0;
    let mut normals = vec![Vec3::zeros(); knit.grid_len()];
    for c in 0..courses {
        let centre = (0..wales).map(|w| x(knit.point(w, c))).sum::<Vec3>() / wales as f64;
        for w in 0..wales {
            let (prev, next, _) = stencil.span(knit, w, c, Direction::Course);
            let (down, up, _) = stencil.span(knit, w, c, Direction::Wale);
            let n = (x(next) - x(prev)).cross(&(x(up) - x(down)));
            outward += n.dot(&(x(knit.point(w, c)) - centre)).signum();
            normals[knit.point(w, c).index()] = n.try_normalize(1e-30).unwrap_or_default();
        }
    }
    let sign = if outward < 0.0 { -1.0 } else { 1.0 };
    for c in 0..courses {
        for w in 0..wales {
            let here = knit.point(w, c);
            let i = here.index();
            let n_out = sign * normals[i];
            let curvature = |d: Direction| {
                let (lo, hi, _) = stencil.span(knit, w, c, d);
                // At the first and last course the stencil is one-sided: no curvature there.
                if lo == here || hi == here {
                    0.0
                } else {
                    convexity([x(lo), x(here), x(hi)], &n_out)
                }
            };
            let pa = tension[0][i] * curvature(Direction::Course)
                + tension[1][i] * curvature(Direction::Wale);
            out[i] = pa.max(0.0) / PA_PER_MMHG;
        }
    }
    // A short row's point takes the grid point below it on its wale.
    for i in knit.grid_len()..knit.len() {
        let [w, c] = knit.fabric_coords(PointId(i as u32));
        out[i] = out[knit.point(w as usize, c.floor() as usize).index()];
    }
    out
}

/// Normal curvature of the polyline `prev, here, next` against the outward normal, 1/m: the
/// turn of its tangent over its length, positive where it bends away from the normal (convex).
fn convexity([prev, here, next]: [Vec3; 3], n_out: &Vec3) -> f64 {
    let (a, b) = (here - prev, next - here);
    let (la, lb) = (a.norm(), b.norm());
    if la <= 0.0 || lb <= 0.0 {
        return 0.0;
    }
    let turn = b / lb - a / la;
    -2.0 * turn.dot(n_out) / (la + lb)
}

/// The springs at one point, summed per direction (index 0 course, 1 wale).
struct LocalSpacing {
    length: [f64; 2],
    rest: [f64; 2],
}

impl LocalSpacing {
    /// Length over rest length along direction `d`; 1 with no spring that way.
    fn stretch(&self, d: usize) -> f64 {
        if self.rest[d] > 0.0 {
            self.length[d] / self.rest[d]
        } else {
            1.0
        }
    }
}

fn local_spacing(knit: &Knit, p: PointId) -> LocalSpacing {
    let x = &knit.particles.x;
    let mut out = LocalSpacing {
        length: [0.0; 2],
        rest: [0.0; 2],
    };
    for inc in knit.incident(p) {
        let s = &knit.springs[inc.spring as usize];
        let d = s.direction.index();
        out.length[d] += (x[s.b.index()] - x[s.a.index()]).norm();
        out.rest[d] += s.rest;
    }
    out
}

/// The fields a fitted knit hands to a shader, one value per point (yarn point or leg vertex).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct KnitFields {
    /// Real stitches per cm².
    pub stitch_density: Vec<f64>,
    /// Spacing along the course over its rest spacing.
    pub stretch_course: Vec<f64>,
    /// Spacing along the wale over its rest spacing.
    pub stretch_wale: Vec<f64>,
    /// Fraction of skin hidden by the real yarn, 0–1.
    pub coverage: Vec<f64>,
    /// Tension around the leg (along the courses), newtons per metre of fabric.
    pub tension: Vec<f64>,
    /// Pressure on the skin, mmHg.
    pub pressure: Vec<f64>,
}

impl KnitFields {
    /// Every field at every point of `knit`, for the real stocking `fabric` with the stiffness
    /// of `terms`.
    pub fn measure(knit: &Knit, fabric: &Fabric, terms: &ForceTerms) -> KnitFields {
        let stretch = stretch(knit);
        let tension = tension(knit, fabric, terms, &stretch);
        let pressure = pressure(knit, &tension);
        let [around, _] = tension;
        let stitch_density = stitch_density(fabric, &stretch);
        let coverage = coverage(knit, fabric, &stretch);
        let (stretch_course, stretch_wale) = stretch;
        KnitFields {
            stitch_density,
            stretch_course,
            stretch_wale,
            coverage,
            tension: around,
            pressure,
        }
    }

    /// The fields with their attribute names (`_STITCH_DENSITY` … in glTF), in a fixed order.
    pub fn named(&self) -> [(&'static str, &[f64]); 6] {
        [
            ("stitch_density", &self.stitch_density),
            ("stretch_course", &self.stretch_course),
            ("stretch_wale", &self.stretch_wale),
            ("coverage", &self.coverage),
            ("tension", &self.tension),
            ("pressure", &self.pressure),
        ]
    }

    /// The fields carried over to leg vertices by [`transfer_to_leg`]: 0 where no yarn is near.
    pub fn transfer_to_leg(
        &self,
        yarn_points: &[Vec3],
        leg_vertices: &[Point3<f64>],
        bandwidth: f64,
    ) -> KnitFields {
        let fields = self.named().map(|(_, values)| values);
        let [stitch_density, stretch_course, stretch_wale, coverage, tension, pressure] =
            transfer_to_leg(yarn_points, &fields, leg_vertices, bandwidth)
                .try_into()
                .expect("six fields in, six out");
        KnitFields {
            stitch_density,
            stretch_course,
            stretch_wale,
            coverage,
            tension,
            pressure,
        }
    }
}

/// Transfers per-yarn-point fields to leg vertices with a biweight kernel of radius `bandwidth`
/// metres; vertices with no yarn point within the bandwidth get 0. Returns one vector per
/// field, in order.
pub fn transfer_to_leg(
    yarn_points: &[Vec3],
    fields: &[&[f64]],
    leg_vertices: &[Point3<f64>],
    bandwidth: f64,
) -> Vec<Vec<f64>> {
    let grid = PointGrid::new(yarn_points, bandwidth);
    let mut out = vec![Vec::with_capacity(leg_vertices.len()); fields.len()];
    let mut sums = vec![0.0; fields.len()];
    for v in leg_vertices {
        let mut weight_sum = 0.0;
        sums.iter_mut().for_each(|s| *s = 0.0);
        grid.for_each_near(&v.coords, |i| {
            let d2 = (yarn_points[i] - v.coords).norm_squared() / (bandwidth * bandwidth);
            if d2 < 1.0 {
                let w = (1.0 - d2) * (1.0 - d2);
                weight_sum += w;
                for (sum, field) in sums.iter_mut().zip(fields) {
                    *sum += w * field[i];
                }
            }
        });
        for (values, sum) in out.iter_mut().zip(&sums) {
            values.push(if weight_sum > 0.0 {
                sum / weight_sum
            } else {
                0.0
            });
        }
    }
    out
}

/// A uniform grid over points, cell size = query radius: a query visits 27 cells.
struct PointGrid {
    cell: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl PointGrid {
    fn new(points: &[Vec3], cell: f64) -> PointGrid {
        let mut cells: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (i, p) in points.iter().enumerate() {
            if let Some(key) = Self::key(p, cell) {
                cells.entry(key).or_default().push(i as u32);
            }
        }
        PointGrid { cell, cells }
    }

    fn key(p: &Vec3, cell: f64) -> Option<[i64; 3]> {
        let k = p.map(|c| (c / cell).floor());
        k.iter()
            .all(|c| c.is_finite() && c.abs() < 1e15)
            .then(|| [k.x as i64, k.y as i64, k.z as i64])
    }

    /// Calls `f` with every point in the 27 cells around `p`, in a fixed order.
    fn for_each_near(&self, p: &Vec3, mut f: impl FnMut(usize)) {
        let Some([x, y, z]) = Self::key(p, self.cell) else {
            return;
        };
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = self.cells.get(&[x + dx, y + dy, z + dz]) {
                        list.iter().for_each(|&i| f(i as usize));
                    }
                }
            }
        }
    }
}

/// Per-point stitch fields of `knit` and their transfer to the leg's vertices.
pub fn measure_fields(
    knit: &Knit,
    leg: &Leg,
    fabric: &Fabric,
    terms: &ForceTerms,
) -> (KnitFields, KnitFields) {
    let per_point = KnitFields::measure(knit, fabric, terms);
    // Wide enough to hold several grid points whichever way the knit runs, and never narrower
    // than the fabric the fields were measured over, so every grid hands the leg the same
    // fields.
    let bandwidth = (3.0
        * mean_spacing(knit, Direction::Course).max(mean_spacing(knit, Direction::Wale)))
    .max(2.0 * MEASURE_SPAN_M);
    let on_leg = per_point.transfer_to_leg(&knit.particles.x, &leg.positions, bandwidth);
    (per_point, on_leg)
}

/// Mean length of the springs along `direction`, metres.
fn mean_spacing(knit: &Knit, direction: Direction) -> f64 {
    let x = &knit.particles.x;
    let lengths: Vec<f64> = knit
        .springs
        .iter()
        .filter(|s| s.direction == direction)
        .map(|s| (x[s.b.index()] - x[s.a.index()]).norm())
        .collect();
    lengths.iter().sum::<f64>() / lengths.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::knit::fabric::yarn_diameter_m;
    use crate::knit::{Pattern, Tile};

    /// A stocking of `stitch_m` stitches in 20-den nylon and 40-den support yarn.
    fn fabric(stitch_m: [f64; 2]) -> Fabric {
        Fabric {
            needles: 400.0,
            stitch_m,
            yarn_diameter_m: [yarn_diameter_m(20.0), yarn_diameter_m(40.0), 0.0],
            loop_stiffness_n_per_m: 5.0,
        }
    }

    /// A flat `n × n` grid at `spacing` metres, stretched by `sx` along the course and `sy`
    /// along the wale.
    fn flat(pattern: Pattern, n: usize, spacing: f64, sx: f64, sy: f64) -> Knit {
        Knit::grid(n, n, false, &Tile::of(pattern), spacing, spacing, |w, c| {
            Vec3::new(w as f64 * spacing * sx, c as f64 * spacing * sy, 0.0)
        })
    }

    #[test]
    fn density_counts_the_real_stitches_whatever_the_grid() {
        // 1 mm stitches: 100 per cm² relaxed, on a grid of the stitches or of 2 mm cells (four
        // stitches each); stretched ×2 one way, half as many.
        let real = fabric([0.001, 0.001]);
        for spacing in [0.001, 0.002] {
            for d in stitch_density(&real, &stretch(&flat(Pattern::Plain, 5, spacing, 1.0, 1.0))) {
                assert!((d - 100.0).abs() < 1e-9, "{spacing}: {d}");
            }
            for d in stitch_density(&real, &stretch(&flat(Pattern::Plain, 5, spacing, 2.0, 1.0))) {
                assert!((d - 50.0).abs() < 1e-9, "{spacing}: {d}");
            }
        }
    }

    #[test]
    fn a_heel_pockets_short_rows_add_stitches_to_their_wales() {
        // A flat 4×3 grid of the real stitch, 2 mm across a wale and 1 mm along it, with one
        // short row each way over wales 1 and 2, laid between courses 0 and 1: those wales hold
        // four stitches' length of fabric where the others hold two, so twice the stitches.
        let (a, b) = (0.002, 0.001);
        let tile = Tile::of(Pattern::Plain);
        let at = |w: usize, c: f64| Vec3::new(w as f64 * a, c * b, 0.0);
        let knit = Knit::grid(4, 3, false, &tile, a, b, |w, c| at(w, c as f64))
            .with_toe_seam(b)
            .with_short_rows(0, vec![0, 1, 1, 0], &tile, a, b, at);
        let density = stitch_density(&fabric([a, b]), &stretch(&knit));
        let relaxed = M2_PER_CM2 / (a * b);
        for c in 0..3 {
            let plain = density[knit.point(0, c).index()];
            assert!(
                (plain - relaxed).abs() < 1e-9 * relaxed,
                "{plain} vs {relaxed}"
            );
            let pocket = density[knit.point(1, c).index()];
            assert!(
                (pocket - 2.0 * relaxed).abs() < 1e-9 * relaxed,
                "{pocket} vs 2 × {relaxed}"
            );
        }
        let first_short = PointId(knit.grid_len() as u32);
        assert!((density[first_short.index()] - 2.0 * relaxed).abs() < 1e-9 * relaxed);
    }

    #[test]
    fn stretch_is_one_at_rest_and_follows_each_direction() {
        let (course, wale) = stretch(&flat(Pattern::Plain, 6, 0.0005, 1.0, 1.0));
        assert!(course.iter().chain(&wale).all(|&s| (s - 1.0).abs() < 1e-12));
        let (course, wale) = stretch(&flat(Pattern::Plain, 6, 0.0005, 1.5, 1.2));
        assert!(course.iter().all(|&s| (s - 1.5).abs() < 1e-12));
        assert!(wale.iter().all(|&s| (s - 1.2).abs() < 1e-12));
    }

    #[test]
    fn stretch_reads_the_fabric_not_a_zigzag_of_alternate_courses() {
        // Every other course pushed sideways by half a stitch, as the real stitches' nylon
        // courses zigzag between the support courses: its springs are longer, the fabric is not.
        let s = 0.0005;
        let knit = Knit::grid(
            40,
            40,
            false,
            &Tile::of(Pattern::Alternating),
            s,
            s,
            |w, c| {
                let zig = if c % 2 == 1 && w % 2 == 1 {
                    0.5 * s
                } else {
                    0.0
                };
                Vec3::new(w as f64 * s, c as f64 * s + zig, 0.0)
            },
        );
        let (course, _) = stretch(&knit);
        let middle = knit.point(20, 21).index();
        assert!((course[middle] - 1.0).abs() < 1e-12, "{}", course[middle]);
    }

    #[test]
    fn stretch_around_a_ring_is_its_arc_not_its_chords() {
        // 60 points on a ring of 3 cm: each spring's rest is the arc it spans, so stretch 1.
        let (n, r) = (60, 0.03);
        let step = std::f64::consts::TAU * r / n as f64;
        let knit = Knit::grid(
            n,
            3,
            true,
            &Tile::of(Pattern::Plain),
            step,
            0.001,
            |w, c| {
                let t = std::f64::consts::TAU * w as f64 / n as f64;
                Vec3::new(r * t.cos(), c as f64 * 0.001, r * t.sin())
            },
        );
        let (course, _) = stretch(&knit);
        assert!(
            course.iter().all(|&s| (s - 1.0).abs() < 1e-9),
            "{:?}",
            &course[..3]
        );
    }

    /// A loop's in-plane length by a fine polyline along Choi & Lo's curve, the stitch stretched
    /// `[s_c, s_w]`: the hand calculation the quadrature is checked against.
    fn polyline_length(shape: &crate::post::loops::LoopShape, [sx, sy]: [f64; 2]) -> f64 {
        let n = 20_000;
        let at = |k: usize| {
            let p = shape.loop_m(2.0 * k as f64 / n as f64);
            nalgebra::Vector2::new(sx * p.x, sy * p.y)
        };
        (0..n).map(|k| (at(k + 1) - at(k)).norm()).sum()
    }

    #[test]
    fn coverage_of_a_stretched_stitch_is_the_hand_calculation() {
        // Plain nylon of 20 den (49.9 µm) in 0.5 mm × 0.74 mm stitches, stretched twice around:
        // a loop of length L hides d L of the 1.0 × 0.74 mm stitch, overlaps taken as random.
        let real = fabric([0.0005, 0.00074]);
        let d = yarn_diameter_m(20.0);
        let shape = crate::post::loops::LoopShape::of(0.0005, 0.00074, d);
        let hand = 1.0 - (-d * polyline_length(&shape, [2.0, 1.0]) / (0.001 * 0.00074)).exp();
        // About a quarter of the skin: sheer.
        assert!((0.15..0.3).contains(&hand), "{hand}");
        // On a grid of the real stitch and on a coarser one alike.
        for spacing in [0.0005, 0.002] {
            let knit = Knit::grid(
                6,
                6,
                false,
                &Tile::of(Pattern::Plain),
                spacing,
                spacing * 1.48,
                |w, c| Vec3::new(w as f64 * spacing * 2.0, c as f64 * spacing * 1.48, 0.0),
            );
            for c in coverage(&knit, &real, &stretch(&knit)) {
                assert!((c - hand).abs() < 1e-6, "{c} vs {hand}");
            }
        }
        // Yarn far wider than the stitch hides all but nothing of the skin, never more.
        let rope = Fabric {
            yarn_diameter_m: [0.002; 3],
            ..real
        };
        let knit = flat(Pattern::Plain, 6, 0.0005, 1.0, 1.0);
        assert!(coverage(&knit, &rope, &stretch(&knit))
            .iter()
            .all(|&c| c > 0.999 && c <= 1.0));
    }

    #[test]
    fn coverage_reads_both_yarns_of_an_alternating_knit_at_every_point() {
        // Half the courses are 40 den: half the stitches are its loops.
        let real = fabric([0.0005, 0.0005]);
        let knit = flat(Pattern::Alternating, 6, 0.0005, 1.0, 1.0);
        let yarn_area: f64 = [20.0, 40.0]
            .iter()
            .map(|&denier| {
                let d = yarn_diameter_m(denier);
                let shape = crate::post::loops::LoopShape::of(0.0005, 0.0005, d);
                0.5 * d * polyline_length(&shape, [1.0, 1.0])
            })
            .sum();
        let expected = 1.0 - (-yarn_area / (0.0005 * 0.0005)).exp();
        for c in coverage(&knit, &real, &stretch(&knit)) {
            assert!((c - expected).abs() < 1e-6, "{c} vs {expected}");
        }
    }

    /// A tube of `wales` × `courses` on a cylinder of `radius`, its rings stretched by
    /// `stretch` over their rest length, its wales at rest.
    fn cylinder(wales: usize, courses: usize, radius: f64, stretch: f64) -> Knit {
        let around = std::f64::consts::TAU * radius / wales as f64;
        let along = 0.002;
        Knit::grid(
            wales,
            courses,
            true,
            &Tile::of(Pattern::Plain),
            around / stretch,
            along,
            |w, c| {
                let t = std::f64::consts::TAU * w as f64 / wales as f64;
                Vec3::new(radius * t.cos(), c as f64 * along, radius * t.sin())
            },
        )
    }

    #[test]
    fn pressure_on_a_cylinder_is_laplaces_tension_over_radius() {
        // A ring stretched by half around a 4 cm leg: T = k a / b · 0.5, P = T / r.
        let (radius, real) = (0.04, fabric([0.0005, 0.0005]));
        let terms = ForceTerms {
            stiffness: [1.0; 3],
            connection_factor: None,
        };
        for wales in [60, 240] {
            let knit = cylinder(wales, 30, radius, 1.5);
            let [around, along] = tension(&knit, &real, &terms, &stretch(&knit));
            let t = real.membrane_n_per_m()[0] * 0.5;
            for (i, &ti) in around.iter().enumerate() {
                assert!((ti - t).abs() < 1e-6 * t, "{wales}: point {i}: {ti} vs {t}");
            }
            assert!(
                along.iter().all(|&t| t.abs() < 1e-9),
                "no tension along a relaxed wale"
            );
            let p = pressure(&knit, &[around, along]);
            let expected = t / radius / PA_PER_MMHG;
            // Away from the end courses, whose curvature along is not measured.
            for c in 5..25 {
                let got = p[knit.point(7, c).index()];
                assert!(
                    (got - expected).abs() < 1e-3 * expected,
                    "{wales}: {got} vs {expected}"
                );
            }
        }
    }

    #[test]
    fn a_slack_tube_presses_nothing_and_carries_no_tension() {
        let knit = cylinder(60, 10, 0.04, 0.8);
        let terms = ForceTerms {
            stiffness: [1.0; 3],
            connection_factor: None,
        };
        let t = tension(&knit, &fabric([0.0005, 0.0005]), &terms, &stretch(&knit));
        assert!(t[0].iter().all(|&v| v == 0.0));
        assert!(pressure(&knit, &t).iter().all(|&v| v == 0.0));
    }

    #[test]
    fn transfer_is_zero_far_from_yarn_and_exact_for_a_constant_field() {
        let points = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.001, 0.0, 0.0)];
        let values = vec![7.0, 7.0];
        let leg = vec![Point3::new(0.0005, 0.0, 0.0), Point3::new(1.0, 0.0, 0.0)];
        let out = transfer_to_leg(&points, &[&values], &leg, 0.002);
        assert!((out[0][0] - 7.0).abs() < 1e-12);
        assert_eq!(out[0][1], 0.0);
    }
}
