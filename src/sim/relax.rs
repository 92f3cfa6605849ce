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

use super::evaluation::{
    evaluate, relative_residual, rest_force_floor, shortest_rest, Workspace, CHUNK,
};
use super::{Constraints, ForceTerms, RelaxObserver, Unconstrained};
use crate::base::Vec3;
use crate::error::{Error, Result};
use crate::knit::Knit;
use crate::sim::{OnUnstable, SolverSettings};

/// Energy growth over the starting energy that counts as divergence.
const DIVERGENCE_ENERGY_GROWTH: f64 = 1e3;

/// The most sub-steps one step may be split into: a time step further above the stability
/// limit is refused ([`Error::TooManySubsteps`]) rather than run for ever (`1e308` would be
/// `usize::MAX` sub-steps).
pub const MAX_SUBSTEPS_PER_STEP: usize = 10_000;

/// What a relaxation did.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
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

/// The explicit stability limit on the time step for `knit` under `terms` (see module docs).
/// Infinite when no point is free.
pub fn stability_limit(knit: &Knit, terms: &ForceTerms) -> f64 {
    // The bound of the force evaluation itself, so the limit and the solvers agree on it.
    let mut ws = Workspace::new(knit);
    evaluate(knit, terms, &mut ws);
    let lambda_max = ws
        .stiffness_bound
        .iter()
        .zip(&knit.particles.inv_mass)
        .map(|(bound, inv_mass)| bound * inv_mass)
        .fold(0.0, f64::max);
    if lambda_max > 0.0 {
        2.0 / lambda_max.sqrt()
    } else {
        f64::INFINITY
    }
}

/// Relaxes `knit` in place until it converges, reaches `settings.max_steps`, or diverges.
///
/// Errors: [`Error::TimeStepTooLarge`] when the step is above the stability limit and
/// `on_unstable` is `error`; [`Error::TooManySubsteps`] when sub-stepping it would take more
/// than [`MAX_SUBSTEPS_PER_STEP`] sub-steps; [`Error::Diverged`] when the energy watchdog fires.
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
    let shortest_rest = shortest_rest(knit);
    let force_floor = rest_force_floor(knit, terms);
    // Energy of a strain of 1e-6 on every spring: below this, growth is rounding, not divergence.
    let energy_floor: f64 = knit
        .yarn_springs()
        .map(|(i, s)| 0.5 * terms.c1(knit, i as u32) * (1e-6 * s.rest).powi(2))
        .sum();

    let mut ws = Workspace::new(knit);
    let mut start_energy = None;
    let mut step = 0;
    let mut from = Vec::new();
    loop {
        let eval = evaluate(knit, terms, &mut ws);
        let residual = relative_residual(
            knit,
            &mut ws,
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
    let stiffest = terms.stiffness.iter().copied().fold(0.0, f64::max);
    match settings.on_unstable {
        OnUnstable::Substep => {
            // Checked before the cast: `t / limit` can be any size (a limit of 0 makes it
            // infinite), and `as usize` would saturate it into a loop that never ends.
            let ratio = t / limit;
            if ratio.is_nan() || ratio > MAX_SUBSTEPS_PER_STEP as f64 {
                return Err(Error::TooManySubsteps {
                    time_step: t,
                    limit,
                    stiffest,
                    max_substeps: MAX_SUBSTEPS_PER_STEP,
                    most: limit * MAX_SUBSTEPS_PER_STEP as f64,
                });
            }
            Ok(ratio.ceil() as usize)
        }
        OnUnstable::Ignore => Ok(1),
        OnUnstable::Error => Err(Error::TimeStepTooLarge {
            time_step: t,
            limit,
            stiffest,
        }),
    }
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
