//! One evaluation of the knit's forces, shared by every solver: the spring states of eq. (1), the
//! net force on each point with the connection terms of eq. (2), a per-point bound on the
//! stiffness (Gershgorin), and the relative residual that says how far from rest the knit is.
//!
//! Every sum is taken in fixed-size chunks in a fixed order, so results are bit-identical
//! whatever the number of threads.

use rayon::prelude::*;

use super::Constraints;
use crate::knit::{Direction, Knit, PointId, Vec3, YarnKind};

/// Points or springs per parallel chunk. Fixed, so that sums do not depend on the thread count.
pub(crate) const CHUNK: usize = 4096;
/// A strain this small is rest: it sets the floor of the residual's denominator.
const REST_STRAIN: f64 = 1e-9;

/// Which force terms run, with their coefficients. Built by the plan from the scene's effects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForceTerms {
    /// Spring stiffness c1 per yarn kind (indexed by `YarnKind::index()`). Equal entries when the
    /// scene does not ask for `alternating_yarns`.
    pub stiffness: [f64; 2],
    /// Connection factor c2 of eq. (2), or `None` when `yarn_connection` is off.
    pub connection_factor: Option<f64>,
}

impl ForceTerms {
    /// c1 of a spring of the knit: its yarn's stiffness, times the knit's factor for its
    /// direction ([`Knit::stiffness_scale`]).
    pub(crate) fn c1(&self, knit: &Knit, spring: u32) -> f64 {
        let s = &knit.springs[spring as usize];
        self.c1_of(knit, s.yarn, s.direction)
    }

    /// c1 of a spring of `yarn` along `direction` in the knit.
    pub(crate) fn c1_of(&self, knit: &Knit, yarn: YarnKind, direction: Direction) -> f64 {
        self.stiffness[yarn.index() as usize] * knit.stiffness_scale[direction.index()]
    }
}

/// Gershgorin contribution of one spring to the stiffness bound of each of its ends: `2 c1`
/// scaled by the spring's geometric stiffness `|1 − l/len|` where that exceeds 1 (a spring
/// compressed below half its rest length is stiffer across than along).
pub(crate) fn spring_stiffness_bound(c1: f64, rest: f64, len: f64) -> f64 {
    let geometric = if len > 0.0 {
        (1.0 - rest / len).abs()
    } else {
        1.0
    };
    2.0 * c1 * geometric.max(1.0)
}

/// Gershgorin contribution of one connection term (eq. 2) to the bound of the point `i` it acts
/// on: `2 c2 c1` from the tension of `j–k` changing as `j` and `k` move, plus `2 c2 T / |x_i −
/// x_j|` from its direction `i → j` turning as `i` and `j` move (none when they coincide: the
/// force is zero there). Without the turning part a strained knit with a large c2 can have
/// steps divided by the bound overshoot (`sim::properties`).
pub(crate) fn connection_stiffness_bound(c2: f64, c1: f64, tension: f64, len_ij: f64) -> f64 {
    let turning = if len_ij > 0.0 { tension / len_ij } else { 0.0 };
    2.0 * c2 * (c1 + turning)
}

/// Per-spring state of one force evaluation.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SpringState {
    /// Signed spring force magnitude `c1 (|x_b − x_a| − l)`: positive in tension.
    pub tension: f64,
    /// Unit vector from end `a` to end `b` (zero when they coincide).
    pub unit_ab: Vec3,
    /// Length `|x_b − x_a|`, metres.
    pub len: f64,
    /// [`spring_stiffness_bound`] of this spring.
    pub stiffness_bound: f64,
}

/// Scratch space and results of force evaluations, reused across iterations.
pub(crate) struct Workspace {
    /// Per spring.
    pub springs: Vec<SpringState>,
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
            springs: vec![SpringState::default(); knit.springs.len()],
            force: vec![Vec3::zeros(); knit.len()],
            stiffness_bound: vec![0.0; knit.len()],
            unheld: vec![Vec3::zeros(); knit.len()],
        }
    }
}

/// Sums of one force evaluation.
pub(crate) struct Evaluation {
    /// Σ over springs of (spring force magnitude)².
    pub spring_force_sq: f64,
    /// Σ over springs of ½ c1 (|x_b − x_a| − l)².
    pub potential_energy: f64,
}

/// Computes spring states, the net force and the stiffness bound of every point; returns the
/// sums the convergence test and the watchdog need.
pub(crate) fn evaluate(knit: &Knit, terms: &ForceTerms, ws: &mut Workspace) -> Evaluation {
    let eval = spring_states(knit, terms, &mut ws.springs);
    let states = &ws.springs;
    ws.force
        .par_chunks_mut(CHUNK)
        .zip(ws.stiffness_bound.par_chunks_mut(CHUNK))
        .enumerate()
        .for_each(|(chunk, (forces, bounds))| {
            for (k, (f, bound)) in forces.iter_mut().zip(bounds.iter_mut()).enumerate() {
                let p = PointId((chunk * CHUNK + k) as u32);
                (*f, *bound) = net_force(knit, terms, states, p);
            }
        });
    eval
}

/// [`evaluate`] and [`unheld_forces`] in one pass over the points, for the fast solver, whose
/// every iteration needs both: fills the spring states, `ws.stiffness_bound` and `ws.unheld`
/// (not `ws.force`, which it leaves as it was). The motion sums are taken over the last move,
/// `x − from`. Each point's figures are those of the two functions, summed in the same chunks,
/// so the results are bit-identical to calling them in turn; what is saved is a pass that
/// reads every force back from memory.
pub(crate) fn evaluate_unheld(
    knit: &Knit,
    terms: &ForceTerms,
    ws: &mut Workspace,
    constraints: &dyn Constraints,
    from: &[Vec3],
) -> (Evaluation, UnheldSums) {
    let eval = spring_states(knit, terms, &mut ws.springs);
    let states = &ws.springs;
    let (x, inv_mass) = (&knit.particles.x, &knit.particles.inv_mass);
    let partial: Vec<UnheldSums> = ws
        .unheld
        .par_chunks_mut(CHUNK)
        .zip(ws.stiffness_bound.par_chunks_mut(CHUNK))
        .enumerate()
        .map(|(chunk, (unheld, bounds))| {
            let mut sums = UnheldSums::default();
            for (k, (u, bound)) in unheld.iter_mut().zip(bounds.iter_mut()).enumerate() {
                let i = chunk * CHUNK + k;
                let force;
                (force, *bound) = net_force(knit, terms, states, PointId(i as u32));
                let last_move = x[i] - from[i];
                *u = unheld_point(
                    constraints,
                    i,
                    &force,
                    *bound,
                    inv_mass[i],
                    Some(&last_move),
                    &mut sums,
                );
            }
            sums
        })
        .collect();
    (eval, UnheldSums::sum(&partial))
}

/// The spring states of eq. (1) for the current positions; returns their sums.
fn spring_states(knit: &Knit, terms: &ForceTerms, states: &mut [SpringState]) -> Evaluation {
    let x = &knit.particles.x;
    let springs = &knit.springs;
    let partial: Vec<(f64, f64)> = states
        .par_chunks_mut(CHUNK)
        .enumerate()
        .map(|(chunk, states)| {
            let (mut force_sq, mut energy) = (0.0, 0.0);
            for (k, state) in states.iter_mut().enumerate() {
                let spring = chunk * CHUNK + k;
                let s = &springs[spring];
                let c1 = terms.c1(knit, spring as u32);
                let d = x[s.b.index()] - x[s.a.index()];
                let len = d.norm();
                let stretch = len - s.rest;
                state.tension = c1 * stretch;
                state.unit_ab = if len > 0.0 { d / len } else { Vec3::zeros() };
                state.len = len;
                state.stiffness_bound = spring_stiffness_bound(c1, s.rest, len);
                force_sq += state.tension * state.tension;
                energy += 0.5 * c1 * stretch * stretch;
            }
            (force_sq, energy)
        })
        .collect();
    let (spring_force_sq, potential_energy) = partial
        .iter()
        .fold((0.0, 0.0), |(a, b), (c, d)| (a + c, b + d));
    Evaluation {
        spring_force_sq,
        potential_energy,
    }
}

/// Net force on point `p` and its stiffness bound: eq. (1) over its springs, plus eq. (2) over
/// its connection terms when the yarn connection runs. Summed in the knit's fixed incident order.
fn net_force(knit: &Knit, terms: &ForceTerms, states: &[SpringState], p: PointId) -> (Vec3, f64) {
    // Unit vector along spring `s`, pointing away from `p` (which is end `a` when `at_a`).
    let away = |s: u32, at_a: bool| {
        let unit = states[s as usize].unit_ab;
        if at_a {
            unit
        } else {
            -unit
        }
    };
    let mut f = Vec3::zeros();
    let mut bound = 0.0;
    for inc in knit.incident(p) {
        let state = &states[inc.spring as usize];
        // Tension pulls p along the spring, compression pushes it back: eq. (1).
        f += away(inc.spring, inc.at_a) * state.tension;
        bound += state.stiffness_bound;
    }
    if let Some(c2) = terms.connection_factor {
        for conn in knit.connections(p) {
            let tension = states[conn.spring as usize].tension.max(0.0);
            // Drawn towards the middle point j, along spring i–j (sign: see forces.rs).
            f += away(conn.from, conn.from_at_a) * (c2 * tension);
            let len_ij = states[conn.from as usize].len;
            let c1 = terms.c1_of(knit, conn.yarn, Direction::Course);
            bound += connection_stiffness_bound(c2, c1, tension, len_ij);
        }
    }
    (f, bound)
}

/// The residual's floor: the spring force of a strain of [`REST_STRAIN`] on the softest, shortest
/// spring.
pub(crate) fn rest_force_floor(knit: &Knit, terms: &ForceTerms) -> f64 {
    let min = |values: &[f64]| values.iter().copied().fold(f64::INFINITY, f64::min);
    let softest = min(&terms.stiffness) * min(&knit.stiffness_scale);
    REST_STRAIN * softest * shortest_rest(knit)
}

/// The shortest rest length of the knit's springs, metres.
pub(crate) fn shortest_rest(knit: &Knit) -> f64 {
    knit.springs
        .iter()
        .map(|s| s.rest)
        .fold(f64::INFINITY, f64::min)
}

/// Sums of the unheld forces of one evaluation (see [`unheld_forces`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct UnheldSums {
    /// Σ |unheld force|² over free points.
    pub sum_sq: f64,
    /// Free points.
    pub free: usize,
    /// Σ unheld force · (velocity or last move) over free points (0 without motion).
    pub power: f64,
    /// Largest `|unheld force| / stiffness bound` over free points, metres: how far one plain
    /// preconditioned step would move the worst point.
    pub max_step: f64,
    /// Largest last move over free points, metres (0 without motion).
    pub max_move: f64,
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
                max_step: a.max_step.max(b.max_step),
                max_move: a.max_move.max(b.max_move),
            })
    }
}

/// Point `i`'s unheld force (zero when pinned), added into `sums`; `motion` is the point's
/// velocity or last move, for the power and the largest move.
fn unheld_point(
    constraints: &dyn Constraints,
    i: usize,
    force: &Vec3,
    bound: f64,
    inv_mass: f64,
    motion: Option<&Vec3>,
    sums: &mut UnheldSums,
) -> Vec3 {
    if inv_mass == 0.0 {
        return Vec3::zeros();
    }
    let u = constraints.unheld_force(i, force);
    sums.sum_sq += u.norm_squared();
    sums.free += 1;
    if let Some(v) = motion {
        sums.power += u.dot(v);
        sums.max_move = sums.max_move.max(v.norm());
    }
    if bound > 0.0 {
        sums.max_step = sums.max_step.max(u.norm() / bound);
    }
    u
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
                *u = unheld_point(
                    constraints,
                    i,
                    &force[i],
                    bound[i],
                    inv_mass[i],
                    None,
                    &mut sums,
                );
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
    let rms_spring = (spring_force_sq / knit.springs.len().max(1) as f64).sqrt();
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
