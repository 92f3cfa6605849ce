//! The paper's relaxation (Sakaguchi & Miyata §5): explicit steps of size `t` with a velocity
//! damper, repeated until the knit stops moving.
//!
//! Each step is semi-implicit Euler, `v ← (v + t·F/m)·exp(−damping·t)`, `x ← x + t·v`, on the
//! free points (inverse mass > 0); pinned points do not move.
//!
//! **Convergence**, defined so that it means the same at any size and unit:
//! `residual = RMS |net force| over free points / RMS |spring force| over all springs`, and
//! `max_move = largest |v|·t over free points / shortest rest length`. The run has converged when
//! both are below the tolerance.
//!
//! **Stability.** Explicit integration of a spring network is stable only for
//! `t ≤ 2/√λ_max`, λ_max the largest eigenvalue of the mass-weighted stiffness. We bound λ_max
//! per point by Gershgorin's theorem (sum of `2·c1` over its springs, with the geometric
//! stiffness of stretched or compressed springs and the connection terms included), which gives
//! a limit that is safe and within a factor ~√2 of the true one on a grid. A step above it is
//! split into equal sub-steps, or refused, as the scene says. As a second line of defence the
//! total energy (springs + motion) is watched: if it grows a thousandfold over its start, or any
//! value stops being finite, the run stops with [`Error::Diverged`] before anything is written.
//!
//! Every sum is taken in fixed-size chunks in a fixed order, so results are bit-identical
//! whatever the number of threads.

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::knit::{Knit, Vec3};
use crate::scene::{OnUnstable, SolverSettings};

/// Points or springs per parallel chunk. Fixed, so that sums do not depend on the thread count.
const CHUNK: usize = 4096;
/// A strain this small is rest: it sets the floor of the residual's denominator.
const REST_STRAIN: f64 = 1e-9;
/// Energy growth over the starting energy that counts as divergence.
const DIVERGENCE_ENERGY_GROWTH: f64 = 1e3;

/// Which force terms run, with their coefficients. Built by the plan from the scene's effects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForceTerms {
    /// Spring stiffness c1 per yarn kind (indexed by `YarnKind::index()`). Equal entries when the
    /// scene does not ask for `alternating_yarns`.
    pub stiffness: [f64; 2],
    /// Connection factor c2 of eq. (2), or `None` when `yarn_connection` is off.
    pub connection_factor: Option<f64>,
}

/// What a relaxation did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RelaxStats {
    /// Full steps of size `time_step` taken.
    pub steps: usize,
    /// Sub-steps per step (1 when the time step is below the stability limit).
    pub substeps_per_step: usize,
    /// The explicit stability limit on the time step for this knit, solver time units.
    pub time_step_limit: f64,
    /// Final relative residual (see module docs).
    pub residual: f64,
    /// Final largest move per step relative to the shortest rest length.
    pub max_move: f64,
    /// True when both residual and max_move went below the tolerance.
    pub converged: bool,
}

/// Limits on where points may go, applied after each sub-step's unconstrained update (the
/// paper's "modified move", §6.2), and the forces those limits hold.
pub trait Constraints: Sync {
    /// Moves each free point from `from[i]` towards `x[i]` as far as the constraints allow,
    /// writing the allowed position into `x[i]`.
    fn constrain(&mut self, from: &[Vec3], x: &mut [Vec3], inv_mass: &[f64]);
    /// The part of the force `f` on point `i` that the constraints do not hold (a contact's
    /// reaction and a locked direction removed), so the residual measures only what can still
    /// move points.
    fn unheld_force(&self, i: usize, f: &Vec3) -> Vec3;
}

/// No constraints: points go wherever the forces take them.
pub struct Unconstrained;

impl Constraints for Unconstrained {
    fn constrain(&mut self, _from: &[Vec3], _x: &mut [Vec3], _inv_mass: &[f64]) {}
    fn unheld_force(&self, _i: usize, f: &Vec3) -> Vec3 {
        *f
    }
}

/// Told about each step, e.g. to drive a progress bar. The library itself prints nothing.
pub trait RelaxObserver {
    /// Called after each residual evaluation, with the step number and the residual.
    fn on_step(&mut self, step: usize, residual: f64);
}

impl RelaxObserver for () {
    fn on_step(&mut self, _step: usize, _residual: f64) {}
}

/// Per-spring state of one force evaluation.
#[derive(Clone, Copy, Debug, Default)]
struct SpringState {
    /// Signed spring force magnitude `c1 (|x_b − x_a| − l)`: positive in tension.
    tension: f64,
    /// Unit vector from end `a` to end `b` (zero when they coincide).
    unit_ab: Vec3,
}

/// Scratch space for force evaluations, reused across steps.
struct Workspace {
    springs: Vec<SpringState>,
    force: Vec<Vec3>,
}

/// Sums of one force evaluation.
struct Evaluation {
    /// Σ over springs of (spring force magnitude)².
    spring_force_sq: f64,
    /// Σ over springs of ½ c1 (|x_b − x_a| − l)².
    potential_energy: f64,
}

/// The explicit stability limit on the time step for `knit` under `terms` (see module docs).
/// Infinite when no point is free.
pub fn stability_limit(knit: &Knit, terms: &ForceTerms) -> f64 {
    let x = &knit.particles.x;
    let c1 = |s: u32| terms.stiffness[knit.springs[s as usize].yarn.index() as usize];
    let mut lambda_max: f64 = 0.0;
    for i in 0..knit.len() {
        let p = crate::knit::PointId(i as u32);
        let inv_mass = knit.particles.inv_mass[i];
        if inv_mass == 0.0 {
            continue;
        }
        let mut lambda = 0.0;
        for inc in knit.incident(p) {
            let s = &knit.springs[inc.spring as usize];
            let len = (x[s.b.index()] - x[s.a.index()]).norm();
            // Geometric stiffness across a spring is c1 (1 − l/len): larger than c1 only when
            // the spring is compressed below half its length.
            let geometric = if len > 0.0 {
                (1.0 - s.rest / len).abs()
            } else {
                1.0
            };
            lambda += 2.0 * c1(inc.spring) * geometric.max(1.0);
        }
        if let Some(c2) = terms.connection_factor {
            for conn in knit.connections(p) {
                lambda += 2.0 * c2 * c1(conn.spring);
            }
        }
        lambda_max = lambda_max.max(lambda * inv_mass);
    }
    if lambda_max > 0.0 {
        2.0 / lambda_max.sqrt()
    } else {
        f64::INFINITY
    }
}

/// Relaxes `knit` in place until it converges, reaches `settings.max_steps`, or diverges.
///
/// Errors: [`Error::TimeStepTooLarge`] when the step is above the stability limit and
/// `on_unstable` is `error`; [`Error::Diverged`] when the energy watchdog fires.
pub fn relax(
    knit: &mut Knit,
    terms: &ForceTerms,
    settings: &SolverSettings,
    observer: &mut dyn RelaxObserver,
) -> Result<RelaxStats> {
    relax_constrained(knit, terms, settings, &mut Unconstrained, observer)
}

/// [`relax`] with `constraints` applied after every sub-step.
pub fn relax_constrained(
    knit: &mut Knit,
    terms: &ForceTerms,
    settings: &SolverSettings,
    constraints: &mut dyn Constraints,
    observer: &mut dyn RelaxObserver,
) -> Result<RelaxStats> {
    let limit = stability_limit(knit, terms);
    let substeps = substeps_for(settings, limit, terms)?;
    let h = settings.time_step / substeps as f64;
    let decay = (-settings.damping * h).exp();
    let shortest_rest = knit
        .springs
        .iter()
        .map(|s| s.rest)
        .fold(f64::INFINITY, f64::min);
    let softest = terms
        .stiffness
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let force_floor = REST_STRAIN * softest * shortest_rest;
    // Energy of a strain of 1e-6 on every spring: below this, growth is rounding, not divergence.
    let energy_floor: f64 = knit
        .springs
        .iter()
        .map(|s| 0.5 * terms.stiffness[s.yarn.index() as usize] * (1e-6 * s.rest).powi(2))
        .sum();

    let mut ws = Workspace {
        springs: vec![SpringState::default(); knit.springs.len()],
        force: vec![Vec3::zeros(); knit.len()],
    };
    let mut start_energy = None;
    let mut step = 0;
    let mut from = Vec::new();
    loop {
        let eval = evaluate(knit, terms, &mut ws);
        let residual = relative_residual(
            knit,
            &ws.force,
            &*constraints,
            eval.spring_force_sq,
            force_floor,
        );
        let (max_speed, kinetic_energy) = motion(knit);
        let max_move = max_speed * settings.time_step / shortest_rest;
        let energy = eval.potential_energy + kinetic_energy;
        let start = *start_energy.get_or_insert(energy);
        observer.on_step(step, residual);

        let diverged = |what: String| Error::Diverged {
            step,
            what,
            time_step: settings.time_step,
            limit,
        };
        if !(residual.is_finite() && energy.is_finite() && max_move.is_finite()) {
            return Err(diverged(
                "a position, velocity or force stopped being finite".into(),
            ));
        }
        if energy > DIVERGENCE_ENERGY_GROWTH * start + energy_floor {
            return Err(diverged(format!(
                "energy grew from {start:.3e} to {energy:.3e}"
            )));
        }
        let converged = residual < settings.tolerance && max_move < settings.tolerance;
        if converged || step >= settings.max_steps {
            return Ok(RelaxStats {
                steps: step,
                substeps_per_step: substeps,
                time_step_limit: limit,
                residual,
                max_move,
                converged,
            });
        }
        for sub in 0..substeps {
            if sub > 0 {
                evaluate(knit, terms, &mut ws);
            }
            from.clone_from(&knit.particles.x);
            integrate(knit, &ws.force, h, decay);
            let p = &mut knit.particles;
            constraints.constrain(&from, &mut p.x, &p.inv_mass);
            // Where a constraint changed the move, the velocity is the move that was allowed.
            for (((x, v), from), &inv_mass) in p.x.iter().zip(&mut p.v).zip(&from).zip(&p.inv_mass)
            {
                if inv_mass > 0.0 && *x != from + *v * h {
                    *v = (x - from) / h;
                }
            }
        }
        step += 1;
    }
}

/// How many sub-steps a step needs to stay below the stability limit, or the error the scene
/// asked for.
fn substeps_for(settings: &SolverSettings, limit: f64, terms: &ForceTerms) -> Result<usize> {
    let t = settings.time_step;
    if t <= limit {
        return Ok(1);
    }
    match settings.on_unstable {
        OnUnstable::Substep => Ok((t / limit).ceil() as usize),
        OnUnstable::Ignore => Ok(1),
        OnUnstable::Error => Err(Error::TimeStepTooLarge {
            time_step: t,
            limit,
            stiffest: terms.stiffness.iter().copied().fold(0.0, f64::max),
        }),
    }
}

/// Computes spring states and the net force on every point; returns the sums the convergence
/// test and the watchdog need.
fn evaluate(knit: &Knit, terms: &ForceTerms, ws: &mut Workspace) -> Evaluation {
    let x = &knit.particles.x;
    let springs = &knit.springs;
    let partial: Vec<(f64, f64)> = ws
        .springs
        .par_chunks_mut(CHUNK)
        .enumerate()
        .map(|(chunk, states)| {
            let (mut force_sq, mut energy) = (0.0, 0.0);
            for (k, state) in states.iter_mut().enumerate() {
                let s = &springs[chunk * CHUNK + k];
                let c1 = terms.stiffness[s.yarn.index() as usize];
                let d = x[s.b.index()] - x[s.a.index()];
                let len = d.norm();
                let stretch = len - s.rest;
                state.tension = c1 * stretch;
                state.unit_ab = if len > 0.0 { d / len } else { Vec3::zeros() };
                force_sq += state.tension * state.tension;
                energy += 0.5 * c1 * stretch * stretch;
            }
            (force_sq, energy)
        })
        .collect();
    let states = &ws.springs;
    ws.force
        .par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(chunk, forces)| {
            for (k, f) in forces.iter_mut().enumerate() {
                let p = crate::knit::PointId((chunk * CHUNK + k) as u32);
                *f = net_force(knit, terms, states, p);
            }
        });
    let (spring_force_sq, potential_energy) = partial
        .iter()
        .fold((0.0, 0.0), |(a, b), (c, d)| (a + c, b + d));
    Evaluation {
        spring_force_sq,
        potential_energy,
    }
}

/// Net force on point `p`: eq. (1) over its springs, plus eq. (2) over its connection terms when
/// the yarn connection runs. Summed in the knit's fixed incident order.
fn net_force(
    knit: &Knit,
    terms: &ForceTerms,
    states: &[SpringState],
    p: crate::knit::PointId,
) -> Vec3 {
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
    for inc in knit.incident(p) {
        // Tension pulls p along the spring, compression pushes it back: eq. (1).
        f += away(inc.spring, inc.at_a) * states[inc.spring as usize].tension;
    }
    if let Some(c2) = terms.connection_factor {
        for conn in knit.connections(p) {
            let tension = states[conn.spring as usize].tension.max(0.0);
            // Drawn towards the middle point j, along spring i–j (sign: see forces.rs).
            f += away(conn.from, conn.from_at_a) * (c2 * tension);
        }
    }
    f
}

/// RMS net force on free points over RMS spring force. Spring forces below that of a strain of
/// [`REST_STRAIN`] on the softest spring count as that floor: such a knit is at rest, and both
/// sums are rounding noise whose ratio means nothing.
fn relative_residual(
    knit: &Knit,
    force: &[Vec3],
    constraints: &dyn Constraints,
    spring_force_sq: f64,
    force_floor: f64,
) -> f64 {
    let inv_mass = &knit.particles.inv_mass;
    let partial: Vec<(f64, usize)> = force
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(chunk, f)| {
            let mut sum = (0.0, 0usize);
            for (k, f) in f.iter().enumerate() {
                let i = chunk * CHUNK + k;
                if inv_mass[i] > 0.0 {
                    sum.0 += constraints.unheld_force(i, f).norm_squared();
                    sum.1 += 1;
                }
            }
            sum
        })
        .collect();
    let (sum_sq, free) = partial
        .iter()
        .fold((0.0, 0), |(a, n), (b, k)| (a + b, n + k));
    if free == 0 {
        return 0.0;
    }
    let rms_net = (sum_sq / free as f64).sqrt();
    let rms_spring = (spring_force_sq / knit.springs.len().max(1) as f64).sqrt();
    rms_net / rms_spring.max(force_floor)
}

/// Largest speed and kinetic energy over free points.
fn motion(knit: &Knit) -> (f64, f64) {
    let p = &knit.particles;
    p.v.iter().zip(&p.inv_mass).filter(|(_, &m)| m > 0.0).fold(
        (0.0f64, 0.0),
        |(max, ke), (v, m)| {
            let speed_sq = v.norm_squared();
            (max.max(speed_sq.sqrt()), ke + 0.5 * speed_sq / m)
        },
    )
}

/// One semi-implicit Euler step with the velocity damper, on free points.
fn integrate(knit: &mut Knit, force: &[Vec3], h: f64, decay: f64) {
    let p = &mut knit.particles;
    p.x.par_chunks_mut(CHUNK)
        .zip(p.v.par_chunks_mut(CHUNK))
        .zip(p.inv_mass.par_chunks(CHUNK))
        .zip(force.par_chunks(CHUNK))
        .for_each(|(((x, v), inv_mass), f)| {
            for k in 0..x.len() {
                if inv_mass[k] > 0.0 {
                    v[k] = (v[k] + f[k] * (h * inv_mass[k])) * decay;
                    x[k] += v[k] * h;
                }
            }
        });
}
