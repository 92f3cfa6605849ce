//! One evaluation of the knit's forces, shared by every solver: the spring states of eq. (1), the
//! net force on each point with the connection terms of eq. (2), a per-point bound on the
//! stiffness (Gershgorin), and the relative residual that says how far from rest the knit is.
//!
//! The pass walks the grid row by row (`force_pass`): a row's springs are computed into small
//! buffers just before its points read them, with one division each, and the constraints are
//! asked for a whole row's unheld forces at once, so each spring is read where it is needed and
//! divided once (docs/decisions/0028).
//!
//! Every sum is taken in chunks fixed by the grid alone, in a fixed order, so results are
//! bit-identical whatever the number of threads.

use rayon::prelude::*;

use super::{Constraints, ForceTerms};
use crate::base::{Direction, Vec3, YarnKind};
use crate::knit::Knit;

/// Points per parallel chunk (the force pass takes whole rows of about this many). Fixed, so that
/// sums do not depend on the thread count.
pub(crate) const CHUNK: usize = 4096;
/// A strain this small is rest: it sets the floor of the residual's denominator.
const REST_STRAIN: f64 = 1e-9;

/// Gershgorin contribution of one spring to the stiffness bound of each of its ends: `2 c1`
/// scaled by the spring's geometric stiffness `|1 − l/len|` where that exceeds 1 (a spring
/// compressed below half its rest length is stiffer across than along).
/// `inv_len` is `1 / len`, 0 for coincident ends (which gives the factor 1).
pub fn spring_stiffness_bound(c1: f64, rest: f64, inv_len: f64) -> f64 {
    2.0 * c1 * (1.0 - rest * inv_len).abs().max(1.0)
}

/// Gershgorin contribution of one connection term (eq. 2) to the bound of the point `i` it acts
/// on: `2 c2 c1` from the tension of `j–k` changing as `j` and `k` move, plus `2 c2 T / |x_i −
/// x_j|` from its direction `i → j` turning as `i` and `j` move (none when they coincide: the
/// force is zero there, and `inv_len_ij`, `1 / |x_i − x_j|`, is 0). Without the turning part a
/// strained knit with a large c2 can have steps divided by the bound overshoot
/// (`tests/integration/evaluation.rs`).
pub fn connection_stiffness_bound(c2: f64, c1: f64, tension: f64, inv_len_ij: f64) -> f64 {
    2.0 * c2 * (c1 + tension * inv_len_ij)
}

/// Per-spring state of one force evaluation.
#[derive(Clone, Copy, Debug, Default)]
struct SpringState {
    /// Signed spring force magnitude `c1 (|x_b − x_a| − l)`: positive in tension.
    tension: f64,
    /// Unit vector from end `a` to end `b` (zero when they coincide).
    unit_ab: Vec3,
    /// Length `|x_b − x_a|`, metres.
    len: f64,
    /// `1 / len`, or 0 when the ends coincide. Divisions are the pass's costliest arithmetic:
    /// this is the spring's only one.
    inv_len: f64,
    /// The spring's c1.
    c1: f64,
    /// [`spring_stiffness_bound`] of this spring.
    stiffness_bound: f64,
}

impl SpringState {
    /// The state of a spring of rest length `rest` and stiffness `c1` from `a` to `b`.
    #[inline(always)]
    fn between(a: &Vec3, b: &Vec3, rest: f64, c1: f64) -> SpringState {
        let d = b - a;
        let len = d.norm();
        let inv_len = if len > 0.0 { 1.0 / len } else { 0.0 };
        SpringState {
            tension: c1 * (len - rest),
            unit_ab: d * inv_len,
            len,
            inv_len,
            c1,
            stiffness_bound: spring_stiffness_bound(c1, rest, inv_len),
        }
    }

    /// Unit vector from the point the force acts on towards the spring's other end (the point is
    /// end `a` when `at_a`): a tension pulls the point along it.
    fn away(&self, at_a: bool) -> Vec3 {
        if at_a {
            self.unit_ab
        } else {
            -self.unit_ab
        }
    }
}

/// Scratch space and results of force evaluations, reused across iterations.
pub struct Workspace {
    /// Net force per point.
    pub force: Vec<Vec3>,
    /// Per point, a bound on the largest eigenvalue of the stiffness seen from that point
    /// (Gershgorin row sum): the sum of its springs' and connection terms' bounds.
    pub stiffness_bound: Vec<f64>,
    /// Per point, the part of the net force the constraints do not hold (contact reactions and
    /// locked directions removed; zero on pinned points): what can still move it.
    pub unheld: Vec<Vec3>,
}

impl Workspace {
    /// Space for `knit`.
    pub fn new(knit: &Knit) -> Workspace {
        Workspace {
            force: vec![Vec3::zeros(); knit.len()],
            stiffness_bound: vec![0.0; knit.len()],
            unheld: vec![Vec3::zeros(); knit.len()],
        }
    }
}

/// Sums of one force evaluation.
#[derive(Clone, Copy, Debug, Default)]
pub struct Evaluation {
    /// Σ over springs of (spring force magnitude)².
    pub spring_force_sq: f64,
    /// Σ over springs of ½ c1 (|x_b − x_a| − l)².
    pub potential_energy: f64,
}

impl Evaluation {
    /// Adds a spring of rest length `rest` in `state`.
    #[inline(always)]
    fn add(&mut self, state: &SpringState, rest: f64) {
        let stretch = state.len - rest;
        self.spring_force_sq += state.tension * state.tension;
        self.potential_energy += 0.5 * state.c1 * stretch * stretch;
    }
}

/// Computes the net force and the stiffness bound of every point into `ws.force` and
/// `ws.stiffness_bound`; returns the sums the convergence test and the watchdog need.
pub fn evaluate(knit: &Knit, terms: &ForceTerms, ws: &mut Workspace) -> Evaluation {
    let (eval, _) = force_pass(
        knit,
        terms,
        &mut ws.force,
        &mut ws.stiffness_bound,
        |_, forces, _, out, _: &mut ()| out.copy_from_slice(forces),
    );
    eval
}

/// One momentum step of the fast solver, as [`evaluate_and_step`] takes it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MomentumStep {
    /// Weight of the velocity (the last move).
    pub beta: f64,
    /// Step size, as a fraction of `unheld / bound`.
    pub step: f64,
    /// A point whose plain step `|unheld| / bound` is longer than this, metres, is *unsettled*:
    /// it still holds the force-step stop, and its power goes to
    /// [`UnheldSums::unsettled_power`] as well.
    pub unsettled_above: f64,
}

/// The fast solver's whole iteration but the constraints, in one pass over the points: the
/// evaluation, the unheld forces, and the momentum step
/// `next = x + beta (x − from) + step · unheld / bound` on free points with springs (others stay
/// at `x`), written over `from` as the point's velocity `x − from` is read. Returns the spring
/// sums and the unheld sums, taken over the velocity before the step, so the caller can still
/// decide on them (a restart redoes the step with no velocity). Fills `ws.stiffness_bound`, not
/// `ws.force` or `ws.unheld`.
///
/// One pass, so the step reads the point arrays the evaluation has just read
/// (docs/decisions/0030).
pub(crate) fn evaluate_and_step(
    knit: &Knit,
    terms: &ForceTerms,
    ws: &mut Workspace,
    constraints: &dyn Constraints,
    from: &mut [Vec3],
    momentum: MomentumStep,
) -> (Evaluation, UnheldSums) {
    let MomentumStep {
        beta,
        step,
        unsettled_above,
    } = momentum;
    let unsettled_above_sq = unsettled_above * unsettled_above;
    let (x, inv_mass) = (&knit.particles.x, &knit.particles.inv_mass);
    let (eval, partial) = force_pass(
        knit,
        terms,
        from,
        &mut ws.stiffness_bound,
        |first, forces, bounds, from, sums: &mut UnheldSums| {
            constraints.unheld_forces_from(first, forces);
            for (k, ((unheld, &bound), from)) in forces.iter().zip(bounds).zip(from).enumerate() {
                let x = &x[first + k];
                if inv_mass[first + k] == 0.0 {
                    *from = *x;
                    continue;
                }
                let inv_bound = if bound > 0.0 { 1.0 / bound } else { 0.0 };
                let velocity = x - *from;
                if sums.add(unheld, inv_bound, Some(&velocity)) > unsettled_above_sq {
                    sums.unsettled_power += unheld.dot(&velocity);
                }
                // A point with no springs (bound 0) stays where the constraints put it.
                *from = if bound > 0.0 {
                    x + (velocity * beta + (unheld * inv_bound) * step)
                } else {
                    *x
                };
            }
        },
    );
    (eval, UnheldSums::sum(&partial))
}

/// Whole rows of the grid per parallel chunk of the force pass: about [`CHUNK`] points (one row
/// where a row is longer), and no more than an eighth of the rows, so small grids still give
/// every thread work. A function of the grid alone, so the sums do not depend on the thread
/// count.
fn rows_per_chunk(knit: &Knit) -> usize {
    let by_size = (CHUNK / knit.wales.max(1)).max(1);
    by_size.min(knit.courses.div_ceil(8)).max(1)
}

/// The force pass every evaluation shares: the net force on each point (eq. 1 over its springs,
/// plus eq. 2 over its connection terms when the yarn connection runs) and its stiffness bound,
/// which goes to `bounds`. A row at a time, it calls `visit(first point, forces, bounds, out,
/// sums)` with the row's forces (which `visit` may change in place), bounds and share of `out`,
/// which `visit` fills, and its chunk's sums. Returns the spring sums and each chunk's sums, in
/// order.
///
/// It walks the grid row by row (the knit's springs are laid out that way, [`Knit::grid`]):
/// each row's course springs and the wale springs up to the next row are computed into small
/// buffers just before the row's points read them, so every spring is computed once and read
/// from cache, never stored for the whole knit. A chunk also computes the wale springs just
/// below its first row (the chunk before owns and sums them). Each point's force is what the
/// kernels of `forces.rs` summed over its lists ([`Knit::incident`], [`Knit::connections`])
/// give, to rounding (`tests/integration/evaluation.rs` checks it); only the neighbours'
/// places come from the grid layout.
fn force_pass<T: Send, S: Default + Send>(
    knit: &Knit,
    terms: &ForceTerms,
    out: &mut [T],
    bounds: &mut [f64],
    visit: impl Fn(usize, &mut [Vec3], &[f64], &mut [T], &mut S) + Sync,
) -> (Evaluation, Vec<S>) {
    let (wales, courses) = (knit.wales, knit.courses);
    let wraps = knit.closed_courses;
    let per_row = if wraps {
        wales
    } else {
        wales.saturating_sub(1)
    };
    let wale_start = courses * per_row;
    let x = &knit.particles.x;
    // c1 by direction (course, wale) and yarn, looked up once rather than per spring; a graded
    // grid's rows scale it ([`Knit::grid_spring_factors`]).
    let c1 = [Direction::Course, Direction::Wale]
        .map(|d| YarnKind::ALL.map(|yarn| terms.c1_of(knit, yarn, d)));
    let rows = rows_per_chunk(knit);
    let chunk_points = (rows * wales).max(1);
    // The shaping's springs (toe seam, short rows), computed once before the grid reads them.
    let shaping: Vec<SpringState> = knit.springs[knit.shaping_springs()]
        .iter()
        .map(|s| {
            let c1 = c1[s.direction.index()][s.yarn.index() as usize];
            SpringState::between(&x[s.a.index()], &x[s.b.index()], s.rest, c1)
        })
        .collect();
    let grid_len = knit.grid_len();
    let (out, out_extra) = out.split_at_mut(grid_len);
    let (bounds, bounds_extra) = bounds.split_at_mut(grid_len);
    let mut partial: Vec<(Evaluation, S)> = out
        .par_chunks_mut(chunk_points)
        .zip(bounds.par_chunks_mut(chunk_points))
        .enumerate()
        .map(|(chunk, (out, bounds))| {
            let mut eval = Evaluation::default();
            let mut sums = S::default();
            let first = chunk * rows;
            // The wale springs from row c up to row c + 1.
            let wale_row = |c: usize, row: &mut Vec<SpringState>, eval: Option<&mut Evaluation>| {
                row.clear();
                let (below, above) = (&x[c * wales..][..wales], &x[(c + 1) * wales..][..wales]);
                let springs = &knit.springs[wale_start + c * wales..][..wales];
                let factor = knit.grid_spring_factors(c)[1];
                row.extend(springs.iter().enumerate().map(|(w, s)| {
                    debug_assert_eq!(
                        (s.a.index(), s.b.index()),
                        (c * wales + w, (c + 1) * wales + w)
                    );
                    // A slot the short rows replaced carries nothing.
                    let c1 = if s.cut {
                        0.0
                    } else {
                        c1[1][s.yarn.index() as usize] * factor
                    };
                    SpringState::between(&below[w], &above[w], s.rest, c1)
                }));
                if let Some(eval) = eval {
                    for (state, s) in row.iter().zip(springs) {
                        eval.add(state, s.rest);
                    }
                }
            };
            let (mut course, mut below, mut above) = (Vec::new(), Vec::new(), Vec::new());
            let mut forces = vec![Vec3::zeros(); wales];
            if first > 0 {
                wale_row(first - 1, &mut below, None);
            }
            for (r, (out, bounds)) in out
                .chunks_mut(wales)
                .zip(bounds.chunks_mut(wales))
                .enumerate()
            {
                let c = first + r;
                let points = &x[c * wales..][..wales];
                let factor = knit.grid_spring_factors(c)[0];
                course.clear();
                course.extend(
                    knit.springs[c * per_row..][..per_row]
                        .iter()
                        .enumerate()
                        .map(|(w, s)| {
                            // The last spring of a closed ring goes back to its first point.
                            let next = if w + 1 < wales { w + 1 } else { 0 };
                            debug_assert_eq!(
                                (s.a.index(), s.b.index()),
                                (c * wales + w, c * wales + next)
                            );
                            let c1 = c1[0][s.yarn.index() as usize] * factor;
                            let state = SpringState::between(&points[w], &points[next], s.rest, c1);
                            eval.add(&state, s.rest);
                            state
                        }),
                );
                let has_above = c + 1 < courses;
                if has_above {
                    wale_row(c, &mut above, Some(&mut eval));
                }
                let row = RowSprings {
                    course: &course,
                    below: (c > 0).then_some(&below[..]),
                    above: has_above.then_some(&above[..]),
                    wales,
                    wraps,
                };
                for (w, (force, bound)) in forces.iter_mut().zip(bounds.iter_mut()).enumerate() {
                    (*force, *bound) = row.net_force(w, terms.connection_factor);
                }
                add_shaping_to_row(knit, &shaping, c, &mut forces, bounds);
                visit(c * wales, &mut forces, bounds, out, &mut sums);
                std::mem::swap(&mut below, &mut above);
            }
            (eval, sums)
        })
        .collect();
    // The short rows' points, after the grid's: every force on them from the lists.
    let mut eval = Evaluation::default();
    for (state, s) in shaping.iter().zip(&knit.springs[knit.shaping_springs()]) {
        eval.add(state, s.rest);
    }
    let mut sums = S::default();
    if !out_extra.is_empty() {
        let mut forces: Vec<Vec3> = Vec::with_capacity(out_extra.len());
        for (k, bound) in bounds_extra.iter_mut().enumerate() {
            let (f, b) = list_force(knit, &shaping, grid_len + k, terms.connection_factor);
            forces.push(f);
            *bound = b;
        }
        visit(grid_len, &mut forces, bounds_extra, out_extra, &mut sums);
    }
    partial.push((eval, sums));
    let eval = partial
        .iter()
        .fold(Evaluation::default(), |a, (b, _)| Evaluation {
            spring_force_sq: a.spring_force_sq + b.spring_force_sq,
            potential_energy: a.potential_energy + b.potential_energy,
        });
    (eval, partial.into_iter().map(|(_, s)| s).collect())
}

/// Adds to row `c`'s grid points the shaping springs that reach them (`shaping`: their states,
/// in the order of [`Knit::shaping_springs`]).
fn add_shaping_to_row(
    knit: &Knit,
    shaping: &[SpringState],
    c: usize,
    forces: &mut [Vec3],
    bounds: &mut [f64],
) {
    let shaped = knit.shaped_grid_points();
    if shaped.is_empty() {
        return;
    }
    let wales = knit.wales;
    let (first, end) = ((c * wales) as u32, ((c + 1) * wales) as u32);
    let from = shaped.partition_point(|&p| p < first);
    let first_shaping = knit.shaping_springs().start;
    for &p in shaped[from..].iter().take_while(|&&p| p < end) {
        let w = (p - first) as usize;
        for inc in knit.incident(crate::knit::PointId(p)) {
            let s = inc.spring as usize;
            if s >= first_shaping {
                let state = &shaping[s - first_shaping];
                let at_a = knit.springs[s].a.0 == p;
                forces[w] += state.away(at_a) * state.tension;
                bounds[w] += state.stiffness_bound;
            }
        }
    }
}

/// Net force and stiffness bound of a short row's point, from its lists: its springs (all of
/// them the shaping's, with states in `shaping`), then its connection terms.
fn list_force(
    knit: &Knit,
    shaping: &[SpringState],
    i: usize,
    connection_factor: Option<f64>,
) -> (Vec3, f64) {
    let first_shaping = knit.shaping_springs().start;
    let p = crate::knit::PointId(i as u32);
    let state_of = |s: u32| &shaping[s as usize - first_shaping];
    let mut f = Vec3::zeros();
    let mut bound = 0.0;
    for inc in knit.incident(p) {
        let state = state_of(inc.spring);
        let at_a = knit.springs[inc.spring as usize].a == p;
        f += state.away(at_a) * state.tension;
        bound += state.stiffness_bound;
    }
    if let Some(c2) = connection_factor {
        for conn in knit.connections(p) {
            // The spring i–j this term acts along: i's course spring to `via`.
            let from = knit
                .incident(p)
                .iter()
                .find(|inc| {
                    inc.other == conn.via
                        && knit.springs[inc.spring as usize].direction
                            == crate::base::Direction::Course
                })
                .expect("a connection runs through a course neighbour");
            let at_a = knit.springs[from.spring as usize].a == p;
            add_connection(
                c2,
                state_of(from.spring),
                at_a,
                state_of(conn.spring),
                &mut f,
                &mut bound,
            );
        }
    }
    (f, bound)
}

/// Eq. (2) on point `i`: the tension of `onward` (spring j–k) draws it towards the middle point j
/// along `from` (spring i–j, with `i` its end `a` when `at_a`); sign: see forces.rs.
#[inline]
fn add_connection(
    c2: f64,
    from: &SpringState,
    at_a: bool,
    onward: &SpringState,
    f: &mut Vec3,
    bound: &mut f64,
) {
    let tension = onward.tension.max(0.0);
    *f += from.away(at_a) * (c2 * tension);
    *bound += connection_stiffness_bound(c2, onward.c1, tension, from.inv_len);
}

/// The spring states one row of points reads: the row's course springs, and the wale springs
/// below and above it (none at the first and last row).
struct RowSprings<'a> {
    course: &'a [SpringState],
    below: Option<&'a [SpringState]>,
    above: Option<&'a [SpringState]>,
    /// Points in the row.
    wales: usize,
    wraps: bool,
}

impl RowSprings<'_> {
    /// The course spring `w + offset` of the row (around the ring when it wraps), if any.
    fn course_at(&self, w: usize, offset: isize) -> Option<&SpringState> {
        let n = self.course.len() as isize;
        let i = w as isize + offset;
        if self.wraps {
            self.course.get(i.rem_euclid(n.max(1)) as usize)
        } else if (0..n).contains(&i) {
            self.course.get(i as usize)
        } else {
            None
        }
    }

    /// Net force on the row's point `w` and its stiffness bound: its course springs (left, then
    /// right), its wale springs (below, then above), then its connection terms.
    #[inline]
    fn net_force(&self, w: usize, connection_factor: Option<f64>) -> (Vec3, f64) {
        let course = self.course;
        if w >= 2 && w + 2 < self.wales {
            // Away from the ring's ends (all but a few points) both course springs and both
            // onward springs are there: a path with nothing to look up (the general one below
            // made the whole fit 8% slower).
            let ends = [(&course[w - 1], false), (&course[w], true)];
            let onward = [&course[w - 2], &course[w + 1]];
            let mut f = Vec3::zeros();
            let mut bound = 0.0;
            for (state, at_a) in ends {
                // Tension pulls the point along the spring, compression pushes it back: eq. (1).
                f += state.away(at_a) * state.tension;
                bound += state.stiffness_bound;
            }
            self.add_wale(w, &mut f, &mut bound);
            if let Some(c2) = connection_factor {
                for ((from, at_a), onward) in ends.into_iter().zip(onward) {
                    add_connection(c2, from, at_a, onward, &mut f, &mut bound);
                }
            }
            return (f, bound);
        }
        // Each course spring with the point's end of it, and the onward spring j–k beyond it:
        // the spring to the left ends at `w` (end b), the one to the right starts there.
        let ends = [
            self.course_at(w, -1)
                .map(|s| (s, false, self.course_at(w, -2))),
            self.course_at(w, 0)
                .map(|s| (s, true, self.course_at(w, 1))),
        ];
        let mut f = Vec3::zeros();
        let mut bound = 0.0;
        for &(state, at_a, _) in ends.iter().flatten() {
            f += state.away(at_a) * state.tension;
            bound += state.stiffness_bound;
        }
        self.add_wale(w, &mut f, &mut bound);
        if let Some(c2) = connection_factor {
            for &(from, at_a, onward) in ends.iter().flatten() {
                if let Some(onward) = onward {
                    add_connection(c2, from, at_a, onward, &mut f, &mut bound);
                }
            }
        }
        (f, bound)
    }

    /// Adds the wale springs below and above point `w` (eq. 1).
    #[inline]
    fn add_wale(&self, w: usize, f: &mut Vec3, bound: &mut f64) {
        if let Some(below) = self.below {
            let state = &below[w];
            *f += state.away(false) * state.tension;
            *bound += state.stiffness_bound;
        }
        if let Some(above) = self.above {
            let state = &above[w];
            *f += state.away(true) * state.tension;
            *bound += state.stiffness_bound;
        }
    }
}

/// The residual's floor: the spring force of a strain of [`REST_STRAIN`] on the softest, shortest
/// spring.
pub(crate) fn rest_force_floor(knit: &Knit, terms: &ForceTerms) -> f64 {
    let min = |values: &[f64]| values.iter().copied().fold(f64::INFINITY, f64::min);
    let softest = min(&terms.stiffness) * min(&knit.stiffness_scale.to_array());
    REST_STRAIN * softest * shortest_rest(knit)
}

/// The shortest rest length of the knit's springs, metres.
pub(crate) fn shortest_rest(knit: &Knit) -> f64 {
    knit.yarn_springs()
        .map(|(_, s)| s.rest)
        .fold(f64::INFINITY, f64::min)
}

/// Sums of the unheld forces of one evaluation (see [`unheld_forces`], [`evaluate_and_step`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct UnheldSums {
    /// Σ |unheld force|² over free points.
    pub sum_sq: f64,
    /// Free points.
    pub free: usize,
    /// Σ unheld force · (velocity or last move) over free points (0 without motion).
    pub power: f64,
    /// Square of the largest `|unheld force| / stiffness bound` over free points (see
    /// [`UnheldSums::max_step`]): squares, so that no point needs a square root for it.
    max_step_sq: f64,
    /// Square of the largest last move over free points.
    max_move_sq: f64,
    /// [`UnheldSums::power`] over the unsettled points alone ([`MomentumStep::unsettled_above`];
    /// 0 without motion).
    pub unsettled_power: f64,
}

impl UnheldSums {
    /// The sums of all chunks, in their order.
    fn sum(partial: &[UnheldSums]) -> UnheldSums {
        partial
            .iter()
            .fold(UnheldSums::default(), |a, b| UnheldSums {
                sum_sq: a.sum_sq + b.sum_sq,
                free: a.free + b.free,
                power: a.power + b.power,
                max_step_sq: a.max_step_sq.max(b.max_step_sq),
                max_move_sq: a.max_move_sq.max(b.max_move_sq),
                unsettled_power: a.unsettled_power + b.unsettled_power,
            })
    }

    /// Largest `|unheld force| / stiffness bound` over free points, metres: how far one plain
    /// preconditioned step would move the worst point.
    pub fn max_step(&self) -> f64 {
        self.max_step_sq.sqrt()
    }

    /// Largest last move over free points, metres (0 without motion).
    pub fn max_move(&self) -> f64 {
        self.max_move_sq.sqrt()
    }

    /// Adds a free point's unheld force `u`, with 1 over its stiffness bound (0 where the bound
    /// is 0) and its velocity or last move, `motion`, for the power and the largest move.
    /// Returns the square of the point's plain step `|u| / bound`.
    #[inline(always)]
    fn add(&mut self, u: &Vec3, inv_bound: f64, motion: Option<&Vec3>) -> f64 {
        let u_sq = u.norm_squared();
        self.sum_sq += u_sq;
        self.free += 1;
        if let Some(v) = motion {
            let v_sq = v.norm_squared();
            self.power += u.dot(v);
            self.max_move_sq = self.max_move_sq.max(v_sq);
        }
        let step_sq = u_sq * (inv_bound * inv_bound);
        self.max_step_sq = self.max_step_sq.max(step_sq);
        step_sq
    }
}

/// Fills `ws.unheld` with the part of each free point's net force the constraints do not hold
/// (zero on pinned points), and returns its sums (no motion: the power and the largest move
/// are 0).
pub(crate) fn unheld_forces(
    knit: &Knit,
    ws: &mut Workspace,
    constraints: &dyn Constraints,
) -> UnheldSums {
    let inv_mass = &knit.particles.inv_mass;
    let (force, bound) = (&ws.force, &ws.stiffness_bound);
    let partial: Vec<UnheldSums> = ws
        .unheld
        .par_chunks_mut(CHUNK)
        .enumerate()
        .map(|(chunk, unheld)| {
            let mut sums = UnheldSums::default();
            for (k, u) in unheld.iter_mut().enumerate() {
                let i = chunk * CHUNK + k;
                *u = if inv_mass[i] == 0.0 {
                    Vec3::zeros()
                } else {
                    let unheld = constraints.unheld_force(i, &force[i]);
                    let inv_bound = if bound[i] > 0.0 { 1.0 / bound[i] } else { 0.0 };
                    sums.add(&unheld, inv_bound, None);
                    unheld
                };
            }
            sums
        })
        .collect();
    UnheldSums::sum(&partial)
}

/// The relative residual: RMS unheld force over free points over RMS spring force. Spring
/// forces below [`rest_force_floor`] count as that floor: such a knit is at rest, and both sums
/// are rounding noise whose ratio means nothing.
pub(crate) fn residual_of(
    knit: &Knit,
    sums: &UnheldSums,
    spring_force_sq: f64,
    force_floor: f64,
) -> f64 {
    if sums.free == 0 {
        return 0.0;
    }
    let rms_net = (sums.sum_sq / sums.free as f64).sqrt();
    let rms_spring = (spring_force_sq / knit.yarn_spring_count().max(1) as f64).sqrt();
    rms_net / rms_spring.max(force_floor)
}

/// [`unheld_forces`] then [`residual_of`].
pub(crate) fn relative_residual(
    knit: &Knit,
    ws: &mut Workspace,
    constraints: &dyn Constraints,
    spring_force_sq: f64,
    force_floor: f64,
) -> f64 {
    let sums = unheld_forces(knit, ws, constraints);
    residual_of(knit, &sums, spring_force_sq, force_floor)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::knit::{Pattern, Tile};
    use crate::sim::Unconstrained;

    /// A strained, uneven 6×9 tube (9 courses: two rows per parallel chunk) with its first ring
    /// pinned.
    fn tube() -> Knit {
        let (wales, courses) = (6, 9);
        let mut knit = Knit::grid(
            wales,
            courses,
            true,
            &Tile::of(Pattern::Alternating),
            0.8,
            0.9,
            |w, c| {
                let t = std::f64::consts::TAU * w as f64 / wales as f64;
                let wobble = 0.1 * ((3 * w + 5 * c) % 7) as f64;
                Vec3::new(t.cos() + wobble, c as f64 + 0.3 * wobble, t.sin())
            },
        );
        for w in 0..wales {
            let i = knit.point(w, 0).index();
            knit.particles.inv_mass[i] = 0.0;
        }
        knit
    }

    /// A velocity for every point, pinned ones included (the step must not use theirs).
    fn moved_from(knit: &Knit) -> Vec<Vec3> {
        let x = &knit.particles.x;
        (0..x.len())
            .map(|i| x[i] - Vec3::new(0.01, -0.02, 0.005) * (1 + i % 3) as f64)
            .collect()
    }

    #[test]
    fn the_fused_step_is_the_evaluation_followed_by_a_momentum_step() {
        let knit = tube();
        let terms = ForceTerms {
            stiffness: [1.0, 10.0, 1.0],
            connection_factor: Some(0.3),
        };
        let (beta, step) = (0.7, 1.5);
        let from = moved_from(&knit);
        let mut plain = Workspace::new(&knit);
        evaluate(&knit, &terms, &mut plain);
        let plain_step = |i: usize| plain.force[i].norm() / plain.stiffness_bound[i];
        // About half the free points are unsettled: the threshold lies halfway between two
        // neighbouring steps, so rounding cannot move a point across it.
        let mut steps: Vec<f64> = (0..knit.len())
            .filter(|&i| knit.particles.inv_mass[i] > 0.0)
            .map(plain_step)
            .collect();
        steps.sort_by(f64::total_cmp);
        let half = steps.len() / 2;
        assert!(steps[half - 1] < steps[half]);
        let unsettled_above = 0.5 * (steps[half - 1] + steps[half]);

        let mut next = from.clone();
        let mut ws = Workspace::new(&knit);
        let momentum = MomentumStep {
            beta,
            step,
            unsettled_above,
        };
        let (_, sums) =
            evaluate_and_step(&knit, &terms, &mut ws, &Unconstrained, &mut next, momentum);

        let (mut power, mut unsettled_power) = (0.0, 0.0);
        for i in 0..knit.len() {
            let x = knit.particles.x[i];
            let expected = if knit.particles.inv_mass[i] == 0.0 {
                x
            } else {
                let velocity = x - from[i];
                power += plain.force[i].dot(&velocity);
                if plain_step(i) > unsettled_above {
                    unsettled_power += plain.force[i].dot(&velocity);
                }
                x + velocity * beta + plain.force[i] / plain.stiffness_bound[i] * step
            };
            assert!(
                (next[i] - expected).norm() < 1e-12,
                "point {i}: {} against {}",
                next[i],
                expected
            );
        }
        assert!((sums.power - power).abs() < 1e-12 * power.abs().max(1.0));
        assert!(unsettled_power != 0.0 && unsettled_power != power);
        let tolerance = 1e-12 * unsettled_power.abs().max(1.0);
        assert!((sums.unsettled_power - unsettled_power).abs() < tolerance);
        assert_eq!(sums.free, knit.len() - knit.wales);
    }

    #[test]
    fn a_point_with_no_stiffness_does_not_coast_on_its_velocity() {
        let knit = tube();
        let terms = ForceTerms {
            stiffness: [0.0; 3],
            connection_factor: None,
        };
        let mut next = moved_from(&knit);
        let mut ws = Workspace::new(&knit);
        evaluate_and_step(
            &knit,
            &terms,
            &mut ws,
            &Unconstrained,
            &mut next,
            MomentumStep {
                beta: 0.9,
                step: 1.5,
                unsettled_above: 0.0,
            },
        );
        assert!(ws.stiffness_bound.iter().all(|&b| b == 0.0));
        assert_eq!(next, knit.particles.x);
    }
}
