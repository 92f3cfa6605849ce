//! Per-point fields of a fitted knit, in the real stocking's units whatever the grid
//! ([`Fabric`]: each grid cell stands for a block of real stitches). What
//! [`crate::post::transfer`] carries to the leg's vertices ([`crate::post::measure_fields`] does
//! both).
//!
//! * **Stitch density** at a yarn point: real stitches per cm² of fabric, the textile measure
//!   (courses per cm × wales per cm): the relaxed stitch's `1 / (a b)` over the stretch both
//!   ways. Per cm² of fabric, not of skin: where the fabric wrinkles, how finely a grid
//!   resolves the folds would otherwise set it. The heel pocket's short rows lengthen its wales'
//!   fabric, so they count as more stitches there.
//! * **Stretch** at a yarn point, along the course and along the wale: the fitted fabric's length
//!   over its relaxed length there (1 relaxed, 1.5 stretched by half), measured over
//!   [`MEASURE_SPAN_M`] of relaxed fabric either way on every grid (fractional spans,
//!   interpolated), along the wale on over the toe seam (one real course of fabric on every
//!   grid, a fraction of a coarse grid's step), and cut back at the seam's folds to the
//!   point's own side (see [`stretch`]).
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
//! * **Pressure** on the skin, mmHg, by Laplace's law for a membrane: `P = Σ : κ`, the
//!   fabric's stress tensor (`T_c t_c⊗t_c + T_w t_w⊗t_w`, see [`stress`]) against the skin's
//!   curvature tensor ([`SkinCurvature`], fitted over [`MEASURE_SPAN_M`]); around a leg, the
//!   course tension over its radius. The skin's curvature, not the fitted fabric's: the skin's is
//!   the same whatever the grid, and a grid's chords and folds are not. Where the skin curves in
//!   (a hollow the fabric bridges) it presses nothing: 0; off the skin (beyond the toes, over a
//!   toe's cleft) 0 too. The skin is the one the fabric rests on, the toes boxed. Only a tube
//!   has it.
//! * **On the leg**: carried to the leg's vertices by one 16 mm kernel on every grid, pressure
//!   pressed on the skin's curvature at the vertex itself ([`crate::post::transfer`]).

use nalgebra::{Matrix3, Point3};
use rayon::prelude::*;

use crate::base::{Direction, PerDirection, Vec3};
use crate::knit::fabric::PA_PER_MMHG;
use crate::knit::{Fabric, Knit, PointId};
use crate::leg::SkinCurvature;
use crate::post::loops::loop_shapes;
use crate::sim::ForceTerms;

/// Square metres per square centimetre.
const M2_PER_CM2: f64 = 1e-4;
/// Length of relaxed fabric, metres, over which stretch is measured each way from a point (and
/// the radius the skin's curvature is fitted over): about one cell of the coarsest grid a fit is
/// run at (100 courses along a whole stocking), so that every grid and the real stitches see the
/// same fabric; an arc through the ends and the point keeps a ring's curve (a fitted ankle is
/// some 35 mm around its centre).
pub const MEASURE_SPAN_M: f64 = 0.008;

/// How much further than the yarn's own offset skin may lie from the fabric and still be pressed
/// by it, metres: the fit leaves the fabric on the skin to well under a millimetre; a toe's
/// cleft under the fabric's bridge lies further.
pub const PRESSED_WITHIN_M: f64 = 0.002;

/// A value per direction at every point of a knit: `course[i]`, `wale[i]` of point `i`.
pub type PerPoint = PerDirection<Vec<f64>>;

/// Real stitches per cm² of fabric at every point, from its `stretch` (see module docs).
pub fn stitch_density(fabric: &Fabric, PerDirection { course, wale }: &PerPoint) -> Vec<f64> {
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

/// Stretch along the course and along the wale at every point (see module docs): what density,
/// coverage and tension are computed from: the arc through the fabric [`MEASURE_SPAN_M`] of relaxed fabric either way and the
/// point itself, over that rest length (fractional spans, interpolated). Along the wale the
/// span follows the wale through the heel pocket's short rows and on over the toe seam; around,
/// a short row's point has only its own springs. Where the span folds back on itself (the toe
/// seam's folds) it is shortened to the part that does not. A point with no neighbour in a
/// direction gets 1 there.
pub fn stretch(knit: &Knit) -> PerPoint {
    let spans = Spans::of(knit);
    let [rest_course, rest_wale] = knit.grid_rest_m().to_array();
    let [reach_course, reach_wale] = spans.reach;
    let ratio = |rest: f64| move |ends: &Ends| ends.arc_length() / (rest * ends.steps);
    let course = (0..knit.len())
        .map(|i| {
            let p = PointId(i as u32);
            if i >= knit.grid_len() {
                return local_spacing(knit, p).stretch(0);
            }
            let (w, c) = knit.grid_coords(p);
            let line = Spans::around(knit, w, c);
            match rest_course > 0.0 {
                true => spans.measure_to_folds(reach_course, line, ratio(rest_course)),
                false => None,
            }
            .unwrap_or(1.0)
        })
        .collect();
    let mut wale = vec![1.0; knit.len()];
    if rest_wale > 0.0 {
        Spans::along_every_wale(knit, |p, line| {
            let reach = line.reach.unwrap_or(reach_wale);
            let ratio = |ends: &Ends| match line.relaxed {
                Some(relaxed) => ends.arc_length() / relaxed(ends),
                None => ratio(rest_wale)(ends),
            };
            if let Some(s) = spans.measure_to_folds(reach, line.at, ratio) {
                wale[p.index()] = s;
            }
        });
    }
    PerDirection { course, wale }
}

/// The fabric either side of a point along one direction, at whole grid steps: its ends,
/// `steps` grid steps of relaxed fabric apart in all.
#[derive(Clone, Copy, Debug)]
struct Ends {
    before: Vec3,
    here: Vec3,
    after: Vec3,
    /// Whole steps back to `before` and on to `after`.
    back: f64,
    on: f64,
    steps: f64,
}

impl Ends {
    /// Length of the circular arc through the ends and the point (see [`arc_length`]).
    fn arc_length(&self) -> f64 {
        arc_length(self.before, self.here, self.after)
    }
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

/// How far either way of a point its fabric is measured: [`MEASURE_SPAN_M`] of relaxed fabric,
/// in grid steps, fractional, so that every grid measures the same fabric (a span of whole
/// steps would be 10 mm on one grid and 7 on another, and a sharp curve such as the toe's
/// would read differently on each): a measure is taken over the whole steps either side of
/// the reach and interpolated. A knit of single stitches (the patch), whose alternate courses
/// are different yarns, is measured between points of the same parity.
struct Spans {
    reach: [f64; 2],
    parity: usize,
    /// True for a knit closed by a toe seam, the only one that folds.
    folding: bool,
}

impl Spans {
    fn of(knit: &Knit) -> Spans {
        let parity = if knit.yarn_blend.is_some() { 1 } else { 2 };
        let reach = knit.grid_rest_m().to_array().map(|rest| {
            let steps = if rest > 0.0 {
                MEASURE_SPAN_M / rest
            } else {
                1.0
            };
            steps.max(parity as f64)
        });
        Spans {
            reach,
            parity,
            folding: knit.has_toe_seam(),
        }
    }

    /// `measure` of the fabric `reach` steps either way of a point along a line of points,
    /// `at(j)` the point `j` steps from it (`None` past the line's end, where the span stops at
    /// the last point there is). On a knit with a toe seam, where the line folds back within
    /// reach, the span stops short of the fold on that side, so that a point beside a fold is
    /// measured over the fabric on its own side, as much on every grid. `None` for a point
    /// alone on its line.
    fn measure_to_folds(
        &self,
        reach: f64,
        at: impl Fn(isize) -> Option<Vec3>,
        measure: impl Fn(&Ends) -> f64,
    ) -> Option<f64> {
        let (k, t) = self.whole_steps(reach);
        let outer = k + self.parity;
        // Only a toe seam folds a knit; elsewhere the span runs its full reach.
        let [back, on] = match self.folding {
            true => Spans::folds(&at, outer)?,
            false => [outer; 2],
        };
        if back.min(on) < outer {
            return Spans::ends(&at, k.min(back), k.min(on)).map(|e| measure(&e));
        }
        // Interpolated between the whole steps either side of the reach (the inner alone where
        // the line has no outer).
        let inner = measure(&Spans::ends(&at, k, k)?);
        Some(match Spans::ends(&at, outer, outer) {
            Some(e) if t > 0.0 => inner * (1.0 - t) + measure(&e) * t,
            _ => inner,
        })
    }

    /// The whole steps below `reach` (a multiple of the parity, at least one) and how far
    /// `reach` lies from them toward the next, 0–1.
    fn whole_steps(&self, reach: f64) -> (usize, f64) {
        let p = self.parity as f64;
        let k = ((reach / p).floor() * p).max(p);
        (k as usize, ((reach - k) / p).clamp(0.0, 1.0))
    }

    /// How many steps either way (`[back, on]`, up to `k`) the line runs from the point before
    /// it folds back: before a step turns a right angle or more from the point's own direction
    /// (the chord through its neighbours; step by step, a grid's small wrinkles would add up
    /// to a fold). A point at a fold's apex (its two steps a right angle or more apart) is
    /// measured on its back side alone. A line's end is not a fold: `k` there. `None` for a
    /// point alone on its line.
    fn folds(at: &impl Fn(isize) -> Option<Vec3>, k: usize) -> Option<[usize; 2]> {
        let here = at(0)?;
        let extent = |sign: isize, heading: Vec3| {
            let mut last = here;
            for j in 1..=k {
                let Some(next) = at(sign * j as isize) else {
                    return k;
                };
                if (next - last).dot(&heading) <= 0.0 {
                    return j - 1;
                }
                last = next;
            }
            k
        };
        let apex = |a: Vec3, b: Vec3| (here - a).dot(&(b - here)) <= 0.0;
        Some(match (at(-1), at(1)) {
            (Some(a), Some(b)) if apex(a, b) => [extent(-1, a - here), 0],
            (Some(a), Some(b)) => [extent(-1, a - b), extent(1, b - a)],
            (Some(a), None) => [extent(-1, a - here), k],
            (None, Some(b)) => [k, extent(1, b - here)],
            (None, None) => return None,
        })
    }

    /// The fabric `back` and `on` whole steps either way along the line `at` (see
    /// [`Spans::measure_to_folds`]), stopping at its ends; `None` where that leaves no step.
    fn ends(at: &impl Fn(isize) -> Option<Vec3>, back: usize, on: usize) -> Option<Ends> {
        let here = at(0)?;
        let side = |sign: isize, k: usize| {
            (1..=k as isize)
                .rev()
                .find_map(|j| at(sign * j).map(|x| (x, j as f64)))
                .unwrap_or((here, 0.0))
        };
        let ((before, back), (after, on)) = (side(-1, back), side(1, on));
        (back + on > 0.0).then_some(Ends {
            before,
            here,
            after,
            back,
            on,
            steps: back + on,
        })
    }

    /// The line round the course of grid point `(w, c)` (see [`Spans::measure_to_folds`]): round a
    /// tube's ring (half of it at most either way), stopping at a patch's edges.
    fn around(knit: &Knit, w: usize, c: usize) -> impl Fn(isize) -> Option<Vec3> + '_ {
        let wales = knit.wales as isize;
        let closed = knit.closed_courses && knit.wales >= 3;
        let half = (wales - 1) / 2;
        move |j| {
            let at = w as isize + j;
            let wale = if closed {
                (j.abs() <= half).then(|| at.rem_euclid(wales))
            } else {
                (0..wales).contains(&at).then_some(at)
            };
            wale.map(|wale| knit.particles.x[knit.point(wale as usize, c).index()])
        }
    }

    /// Calls `f(point, line)` for every point of every wale, `line` its line along the wale
    /// (see [`Spans::measure_to_folds`]): through the heel pocket's short rows, and on over the
    /// toe seam along the facing wale, in steps of relaxed fabric: the seam is a fraction of the
    /// last interval (one real course; [`Knit::toe_seam_steps`] of one on an even grid), so past
    /// it the span's ends lie on the chords between the facing wale's points. On a graded grid
    /// the line also gives each point its reach in steps and the relaxed fabric between a
    /// span's ends.
    fn along_every_wale(knit: &Knit, mut f: impl FnMut(PointId, &WaleLine)) {
        let graded = knit.is_graded();
        let last = knit.courses.saturating_sub(2);
        let seam = match graded {
            true => knit.toe_seam_steps() * knit.grid_rest_m().wale / knit.course_interval(last),
            false => knit.toe_seam_steps(),
        };
        for w in 0..knit.wales {
            let path = knit.wale_path_over_toe(w);
            let own = knit.wale_chain(w).len();
            // Relaxed fabric to each point of the path, on a graded grid (over the seam, back
            // along the facing wale).
            let places: Vec<f64> = match graded {
                true => {
                    let mut places = knit.wale_chain_places(w);
                    let end = places.last().copied().unwrap_or(0.0);
                    if let Some(facing) = knit.toe_seam_partner(w) {
                        let theirs = knit.wale_chain_places(facing);
                        let total = theirs.last().copied().unwrap_or(0.0);
                        let seam_m = seam * knit.course_interval(last);
                        places.extend(theirs.iter().rev().map(|p| end + seam_m + total - p));
                    }
                    places
                }
                false => Vec::new(),
            };
            let x = |k: usize| path.get(k).map(|q| knit.particles.x[q.index()]);
            let between = |k: usize, t: f64| match t > 1e-9 {
                true => Some(x(k)? + (x(k + 1)? - x(k)?) * t),
                false => x(k),
            };
            // The place on the path `i` steps from the point `j`: a path index and the
            // fraction on to the next. The toe seam is a fraction of a grid step of relaxed
            // fabric (one on the real stitches): past it, the facing wale's points fall between
            // whole steps from here.
            let place = |j: usize, i: isize| -> Option<(usize, f64)> {
                let target = usize::try_from(j as isize + i).ok()?;
                if target < own {
                    return Some((target, 0.0));
                }
                let past_last = (target + 1 - own) as f64;
                if past_last < seam {
                    return Some((own - 1, past_last / seam));
                }
                let on = past_last - seam;
                Some((own + on.floor() as usize, on.fract()))
            };
            let relaxed_at = |(k, t): (usize, f64)| match t > 1e-9 {
                true => Some(places.get(k)? + (places.get(k + 1)? - places.get(k)?) * t),
                false => places.get(k).copied(),
            };
            for (j, &p) in path.iter().take(own).enumerate() {
                let at = |i: isize| place(j, i).and_then(|(k, t)| between(k, t));
                // The ends lie on the path, so their places are known; the first interval's
                // steps would do otherwise.
                let relaxed = |ends: &Ends| {
                    let span = |i: f64| place(j, i as isize).and_then(relaxed_at);
                    match (span(-ends.back), span(ends.on)) {
                        (Some(a), Some(b)) => b - a,
                        _ => ends.steps * knit.grid_rest_m().wale,
                    }
                };
                // A point's step: the mean of its intervals along its own wale.
                let step = match graded {
                    true => {
                        let (lo, hi) = (j.saturating_sub(1), (j + 1).min(own - 1));
                        (places[hi] - places[lo]) / (hi - lo).max(1) as f64
                    }
                    false => 0.0,
                };
                let line = WaleLine {
                    at: &at,
                    relaxed: graded.then_some(&relaxed as &dyn Fn(&Ends) -> f64),
                    reach: (graded && step > 0.0).then(|| (MEASURE_SPAN_M / step).max(1.0)),
                };
                f(p, &line);
            }
        }
    }
}

/// One point's line along its wale ([`Spans::along_every_wale`]).
struct WaleLine<'a> {
    /// The fabric `i` whole steps on from the point (back where negative), `None` past the
    /// line's ends.
    at: &'a dyn Fn(isize) -> Option<Vec3>,
    /// On a graded grid, the relaxed fabric between a span's ends, metres (on an even grid,
    /// its steps times the grid's rest).
    relaxed: Option<&'a dyn Fn(&Ends) -> f64>,
    /// On a graded grid, [`MEASURE_SPAN_M`] in this point's steps (on an even grid, the grid's).
    reach: Option<f64>,
}

/// Coverage at every point (see module docs), from the real yarns' loops: each stitch's loop
/// ([`LoopShape`](crate::post::loops::LoopShape), stretched with its stitch) hides its in-plane
/// length times its yarn's diameter, over the stitch's fitted area, the loops' overlaps taken
/// as random. An alternating pattern's
/// stitches are of either yarn by their courses' shares, so it reads the fabric, not a grid
/// course.
pub fn coverage(
    knit: &Knit,
    fabric: &Fabric,
    PerDirection {
        course: stretch_course,
        wale: stretch_wale,
    }: &PerPoint,
) -> Vec<f64> {
    let course_shares = knit.yarn_shares().course;
    let lengths = loop_shapes(fabric).map(|shape| shape.in_plane_length());
    let [w, c] = fabric.stitch_m.to_array();
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
    PerDirection { course, wale }: &PerPoint,
) -> PerPoint {
    let membrane = fabric.membrane_n_per_m().to_array();
    // The fabric's membrane, whatever yarn a point lies on: the grid's yarns blended.
    let shares = knit.yarn_shares();
    let stiffness = [Direction::Course, Direction::Wale].map(|d| terms.blended(shares[d], d));
    let of = |d: usize, along: &[f64], across: &[f64]| -> Vec<f64> {
        along
            .iter()
            .zip(across)
            .map(|(&s, &other)| stiffness[d] * membrane[d] * (s - 1.0).max(0.0) / other)
            .collect()
    };
    PerDirection::new(of(0, course, wale), of(1, wale, course))
}

/// The fabric's membrane stress at every point of a tube, N/m, a tensor on its tangent plane:
/// `T_course t_course⊗t_course + T_wale t_wale⊗t_wale` with `t` the unit tangents over the whole
/// steps within [`MEASURE_SPAN_M`]; zero for a knit whose courses do not close (a patch), which
/// presses on nothing.
pub fn stress(
    knit: &Knit,
    PerDirection {
        course: around,
        wale: along,
    }: &PerPoint,
) -> Vec<Matrix3<f64>> {
    let mut out = vec![Matrix3::zeros(); knit.len()];
    if !knit.closed_courses || knit.wales < 3 || knit.courses < 3 {
        return out;
    }
    let spans = Spans::of(knit);
    let tangent = |reach: f64, line: &dyn Fn(isize) -> Option<Vec3>| {
        let k = spans.whole_steps(reach).0;
        Spans::ends(&line, k, k)
            .and_then(|e| (e.after - e.before).try_normalize(1e-30))
            .unwrap_or_else(Vec3::zeros)
    };
    let [reach_course, reach_wale] = spans.reach;
    for (i, slot) in out.iter_mut().enumerate().take(knit.grid_len()) {
        let (w, c) = knit.grid_coords(PointId(i as u32));
        let t = tangent(reach_course, &Spans::around(knit, w, c));
        *slot = t * t.transpose() * around[i];
    }
    Spans::along_every_wale(knit, |p, line| {
        let t = tangent(line.reach.unwrap_or(reach_wale), line.at);
        if let Some(slot) = out.get_mut(p.index()) {
            *slot += t * t.transpose() * along[p.index()];
        }
    });
    // A short row's point takes the grid point below it on its wale.
    for i in knit.grid_len()..knit.len() {
        let [w, c] = knit.fabric_coords(PointId(i as u32));
        out[i] = out[knit.point(w as usize, c.floor() as usize).index()];
    }
    out
}

/// Pressure at every point, mmHg (see module docs): Laplace's law against the skin within
/// `offset` + [`PRESSED_WITHIN_M`] of it (`offset`: the yarn's centre line's distance from the
/// skin at rest); 0 off the skin.
pub fn pressure(
    knit: &Knit,
    stress: &[Matrix3<f64>],
    skin: &SkinCurvature,
    offset: f64,
) -> Vec<f64> {
    knit.particles
        .x
        .par_iter()
        .zip(stress)
        .map(|(x, stress)| pressed(skin, &Point3::from(*x), offset, stress))
        .collect()
}

/// Laplace's law for a membrane at `stress` on the skin within `offset` +
/// [`PRESSED_WITHIN_M`] of `at`, mmHg: `P = Σ : κ`, the stress contracted with the skin's
/// curvature tensor; 0 where that is negative (a hollow the fabric bridges) or off the skin.
pub(crate) fn pressed(
    skin: &SkinCurvature,
    at: &Point3<f64>,
    offset: f64,
    stress: &Matrix3<f64>,
) -> f64 {
    if *stress == Matrix3::zeros() {
        return 0.0;
    }
    skin.near(at, offset + PRESSED_WITHIN_M)
        .map_or(0.0, |curvature| {
            stress.component_mul(&curvature).sum().max(0.0) / PA_PER_MMHG
        })
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
    /// The membrane stress, N/m (see [`stress`]): what pressure is computed from, and how it
    /// reaches the leg; not written.
    pub stress: Vec<Matrix3<f64>>,
}

impl KnitFields {
    /// Every field at every point of `knit`, for the real stocking `fabric` with the stiffness
    /// of `terms`, pressing on `skin` where within `offset` of it (see [`pressure`]).
    pub fn measure(
        knit: &Knit,
        fabric: &Fabric,
        terms: &ForceTerms,
        skin: &SkinCurvature,
        offset: f64,
    ) -> KnitFields {
        let stretch = stretch(knit);
        let tension = tension(knit, fabric, terms, &stretch);
        let stress = stress(knit, &tension);
        let pressure = pressure(knit, &stress, skin, offset);
        let around = tension.course;
        let stitch_density = stitch_density(fabric, &stretch);
        let coverage = coverage(knit, fabric, &stretch);
        let PerDirection {
            course: stretch_course,
            wale: stretch_wale,
        } = stretch;
        KnitFields {
            stitch_density,
            stretch_course,
            stretch_wale,
            coverage,
            tension: around,
            pressure,
            stress,
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
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::knit::nylon::yarn_diameter_m;
    use crate::knit::{Pattern, Tile};
    use crate::leg::{Collider, ContactMethod, Leg};

    /// A stocking of `stitch_m` stitches in 20-den nylon and 40-den support yarn.
    fn fabric(stitch_m: [f64; 2]) -> Fabric {
        Fabric {
            needles: 400.0,
            stitch_m: stitch_m.into(),
            yarn_diameter_m: [yarn_diameter_m(20.0), yarn_diameter_m(40.0), 0.0],
            loop_stiffness_n_per_m: 5.0,
        }
    }

    /// A flat `n × n` grid at `spacing` metres, stretched by `sx` along the course and `sy`
    /// along the wale.
    pub(crate) fn flat(pattern: Pattern, n: usize, spacing: f64, sx: f64, sy: f64) -> Knit {
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

    /// A flat 4×3 grid of the real stitch, `a` across a wale and `b` along it, with one short
    /// row each way over wales 1 and 2, laid between courses 0 and 1.
    pub(crate) fn pocket_knit(a: f64, b: f64) -> Knit {
        let tile = Tile::of(Pattern::Plain);
        let at = |w: usize, c: f64| Vec3::new(w as f64 * a, c * b, 0.0);
        Knit::grid(4, 3, false, &tile, a, b, |w, c| at(w, c as f64)).with_short_rows(
            0,
            vec![0, 1, 1, 0],
            &tile,
            a,
            b,
            at,
        )
    }

    #[test]
    fn a_heel_pockets_short_rows_add_stitches_to_their_wales() {
        // Wales 1 and 2 of the pocket knit hold four stitches' length of fabric where the
        // others hold two, so twice the stitches.
        let (a, b) = (0.002, 0.001);
        let knit = pocket_knit(a, b);
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
    fn a_toe_seams_folds_are_measured_on_each_points_own_side() {
        // A tube of 12 wales laid flat as hosiery is at the toe: each ring a slit, wales 1–5 on
        // top and 7–11 underneath, the seam's length apart, wales 0 and 6 the folds between
        // them; the toe seam closes the last course. Every spring is at its rest length, so the
        // fabric is unstretched: the wales' spans run over the seam and the courses' round the
        // folds, each cut back to the point's own side of a fold (a span over a fold reads
        // 0.5–1.4 here). The seam is one course spacing, as on the real stitches, or a fraction
        // of one, as on a grid coarser than them: the spans past it then fall between points.
        let (n, courses, a, b) = (12, 20, 0.001_f64, 0.001);
        for seam in [b, 0.3 * b] {
            let h = seam / 2.0;
            let fold = (a * a - h * h).sqrt();
            let at = |w: usize, c: usize| {
                let (x, z) = match w {
                    0 => (a - fold, 0.0),
                    6 => (5.0 * a + fold, 0.0),
                    1..=5 => (w as f64 * a, h),
                    _ => ((n - w) as f64 * a, -h),
                };
                Vec3::new(x, c as f64 * b, z)
            };
            let knit = Knit::grid(n, courses, true, &Tile::of(Pattern::Plain), a, b, at)
                .with_toe_seam(seam);
            assert!((knit.toe_seam_steps() - seam / b).abs() < 1e-12);
            let PerDirection { course, wale } = stretch(&knit);
            for c in 0..courses {
                for w in 0..n {
                    let i = knit.point(w, c).index();
                    assert!(
                        (wale[i] - 1.0).abs() < 1e-9,
                        "seam {seam}, wale {w}, course {c}: {}",
                        wale[i]
                    );
                    // The corners of a slit are not arcs: within 3 % there.
                    assert!(
                        (course[i] - 1.0).abs() < 0.03,
                        "seam {seam}, wale {w}, course {c}: {}",
                        course[i]
                    );
                }
            }
        }
    }

    #[test]
    fn stretch_is_one_at_rest_and_follows_each_direction() {
        let PerDirection { course, wale } = stretch(&flat(Pattern::Plain, 6, 0.0005, 1.0, 1.0));
        assert!(course.iter().chain(&wale).all(|&s| (s - 1.0).abs() < 1e-12));
        let PerDirection { course, wale } = stretch(&flat(Pattern::Plain, 6, 0.0005, 1.5, 1.2));
        assert!(course.iter().all(|&s| (s - 1.5).abs() < 1e-12));
        assert!(wale.iter().all(|&s| (s - 1.2).abs() < 1e-12));
    }

    #[test]
    fn a_graded_grid_reads_the_stretch_of_its_fabric() {
        // A tube whose courses crowd towards one end (cells of 4, then down to 1 mm), stretched
        // by 1.3 around and 1.6 along: every point reads that, over the same 8 mm of relaxed
        // fabric as an even grid's, whatever its cells.
        let mut intervals = vec![0.004; 20];
        intervals.extend([0.003, 0.002, 0.0015]);
        intervals.extend(vec![0.001; 15]);
        let places = crate::knit::model::places_along(&intervals);
        let (wales, radius, [around, along]) = (40, 0.03, [1.3, 1.6]);
        let knit = Knit::grid(
            wales,
            places.len(),
            true,
            &Tile::of(Pattern::Plain),
            std::f64::consts::TAU * radius / wales as f64 / around,
            intervals[0],
            |w, c| {
                let t = std::f64::consts::TAU * w as f64 / wales as f64;
                Vec3::new(radius * t.cos(), places[c] * along, radius * t.sin())
            },
        )
        .with_course_intervals(&intervals);
        assert!(knit.is_graded());
        let PerDirection { course, wale } = stretch(&knit);
        for (i, (&sc, &sw)) in course.iter().zip(&wale).enumerate() {
            assert!((sc - around).abs() < 2e-3, "point {i}: around {sc}");
            assert!((sw - along).abs() < 1e-9, "point {i}: along {sw}");
        }
        // Each grid cell counts as its interval's share of an even one's.
        let cells: f64 = knit.faces().iter().map(|f| f.stitches).sum();
        let want = wales as f64 * places[places.len() - 1] / intervals[0];
        assert!((cells - want).abs() < 1e-9 * want, "{cells} vs {want}");
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
        let course = stretch(&knit).course;
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
        let course = stretch(&knit).course;
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

    #[test]
    fn the_coverage_attribute_is_what_the_loops_hide_seen_along_the_normal() {
        // The loops seen along the normal, each segment a strip of its yarn's diameter, rastered
        // at 100 px per stitch width over 4 × 4 stitches in the middle of a 12 × 12 patch,
        // relaxed and stretched as on a leg (ankle to thigh), against `coverage`. The stitch is
        // the default stocking's: 0.5 mm between wales, 0.74 mm between courses.
        const W: f64 = 0.0005;
        const C: f64 = 0.00074;
        for pattern in [Pattern::Plain, Pattern::Alternating] {
            for [sx, sy] in [[1.0, 1.0], [1.3, 1.3], [2.0, 1.5]] {
                let fabric = Fabric {
                    yarn_diameter_m: [20.0, 40.0, 20.0].map(yarn_diameter_m),
                    ..fabric([W, C])
                };
                let knit = Knit::grid(12, 12, false, &Tile::of(pattern), W, C, |w, c| {
                    Vec3::new(w as f64 * W * sx, c as f64 * C * sy, 0.0)
                });
                let geometry = crate::post::loops::loops(&knit, &fabric);
                let point = |i: usize| Vec3::from(geometry.positions[i]);
                let px = W * sx / 100.0;
                let (x0, y0) = (4.0 * W * sx, 4.0 * C * sy);
                let (nx, ny) = (400usize, (400.0 * C * sy / (W * sx)) as usize);
                let mut covered = vec![false; nx * ny];
                for s in &geometry.segments {
                    let d = fabric.yarn_diameter_m[s.yarn.index() as usize];
                    let (a, b) = (point(s.a as usize).xy(), point(s.b as usize).xy());
                    let pixel = |v: f64, origin: f64, n: usize| {
                        ((v - origin) / px).floor().clamp(0.0, n as f64) as usize
                    };
                    let (i0, i1) = (
                        pixel(a.x.min(b.x) - d, x0, nx),
                        pixel(a.x.max(b.x) + d, x0, nx),
                    );
                    let (j0, j1) = (
                        pixel(a.y.min(b.y) - d, y0, ny),
                        pixel(a.y.max(b.y) + d, y0, ny),
                    );
                    for j in j0..(j1 + 1).min(ny) {
                        for i in i0..(i1 + 1).min(nx) {
                            let centre = nalgebra::Vector2::new(
                                x0 + (i as f64 + 0.5) * px,
                                y0 + (j as f64 + 0.5) * px,
                            );
                            let h = ((centre - a).dot(&(b - a))
                                / (b - a).norm_squared().max(1e-300))
                            .clamp(0.0, 1.0);
                            if (centre - a - (b - a) * h).norm() <= 0.5 * d {
                                covered[j * nx + i] = true;
                            }
                        }
                    }
                }
                let raster = covered.iter().filter(|&&c| c).count() as f64 / covered.len() as f64;
                let formula = coverage(&knit, &fabric, &stretch(&knit))[knit.point(6, 6).index()];
                eprintln!(
                    "{pattern:?} stretched {sx} × {sy}: loop raster coverage {raster:.4}, \
                     attribute {formula:.4}"
                );
                // The polyline cuts the curve's corners and crossings are not random: a few
                // hundredths either way, far inside the preview's 0.1.
                assert!(
                    (raster - formula).abs() < 0.03,
                    "{pattern:?} {sx} × {sy}: raster {raster} vs attribute {formula}"
                );
            }
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

    /// The skin of a round leg of `radius` (96 sides), 10 cm up from y = 0.
    pub(crate) fn round_skin(radius: f64) -> Collider {
        Collider::new(&Leg::round(radius, 0.1, 96, 20), ContactMethod::Bvh).unwrap()
    }

    #[test]
    fn pressure_on_a_cylinder_is_laplaces_tension_over_radius() {
        // A ring stretched by half around a 4 cm leg: T = k a / b · 0.5, P = T / r.
        let (radius, real) = (0.04, fabric([0.0005, 0.0005]));
        let terms = ForceTerms {
            stiffness: [1.0; 3],
            connection_factor: None,
        };
        let surface = round_skin(radius);
        let skin = SkinCurvature::of(&surface, MEASURE_SPAN_M);
        for wales in [60, 240] {
            let knit = cylinder(wales, 30, radius, 1.5);
            let PerDirection {
                course: around,
                wale: along,
            } = tension(&knit, &real, &terms, &stretch(&knit));
            let t = real.membrane_n_per_m().course * 0.5;
            for (i, &ti) in around.iter().enumerate() {
                assert!((ti - t).abs() < 1e-6 * t, "{wales}: point {i}: {ti} vs {t}");
            }
            assert!(
                along.iter().all(|&t| t.abs() < 1e-9),
                "no tension along a relaxed wale"
            );
            let tension = PerDirection::new(around, along);
            let p = pressure(&knit, &stress(&knit, &tension), &skin, 0.0);
            let expected = t / radius / PA_PER_MMHG;
            // The same on every point, the end courses too: the skin's curvature (its quadric
            // fit reads the round ~1 % tight), not the fabric's, which its ends cannot measure.
            for (i, &got) in p.iter().enumerate() {
                assert!(
                    (got - expected).abs() < 0.02 * expected,
                    "{wales}: point {i}: {got} vs {expected}"
                );
            }
        }
    }

    #[test]
    fn a_slack_tube_or_one_off_the_skin_presses_nothing() {
        let terms = ForceTerms {
            stiffness: [1.0; 3],
            connection_factor: None,
        };
        let real = fabric([0.0005, 0.0005]);
        let surface = round_skin(0.04);
        let skin = SkinCurvature::of(&surface, MEASURE_SPAN_M);
        let slack = cylinder(60, 10, 0.04, 0.8);
        let t = tension(&slack, &real, &terms, &stretch(&slack));
        assert!(t.course.iter().all(|&v| v == 0.0));
        let p = pressure(&slack, &stress(&slack, &t), &skin, 0.0);
        assert!(p.iter().all(|&v| v == 0.0));
        // Stretched, but 5 mm clear of the skin: bridging, not pressing.
        let clear = cylinder(60, 10, 0.045, 1.5);
        let t = tension(&clear, &real, &terms, &stretch(&clear));
        assert!(t.course.iter().all(|&v| v > 0.0));
        let p = pressure(&clear, &stress(&clear, &t), &skin, 0.0);
        assert!(p.iter().all(|&v| v == 0.0));
        // Within the yarn's offset of it, pressing.
        let p = pressure(&clear, &stress(&clear, &t), &skin, 0.004);
        assert!(p.iter().all(|&v| v > 0.0));
    }
}
