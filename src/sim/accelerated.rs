//! The fast solver's iteration on one grid: a Jacobi-preconditioned heavy-ball (momentum)
//! iteration with adaptive restart, after Polyak (1964) for the momentum, Nesterov's `k/(k+3)`
//! schedule for its weight, and O'Donoghue & Candès, "Adaptive restart for accelerated gradient
//! schemes" (2015), for the restart.
//!
//! Each iteration, with `F` the unheld net force (eq. 1 + eq. 2, less what contact and the held
//! end rings hold) and `m_i` point `i`'s Gershgorin bound on the stiffness
//! (`evaluation::Workspace::stiffness_bound`):
//!
//! ```text
//! if Σ F·v < 0, or Σ_unsettled F·v < 0 for 12 iterations in a row:  v ← 0, k ← 0   (restart)
//! v_i ← β_k v_i + s · F_i / m_i,  β_k = k / (k + 3)
//! x_i ← constrain(x_i + v_i);  v_i ← the move actually made
//! ```
//!
//! **Why this method.** The fit is a static problem: only the rest state matters, not the path
//! (the paper's damped dynamics is one way to reach it). Dividing by `m_i` makes every point's
//! largest mode stiffness at most 1, so one step size `s` suits nylon and the 10× stiffer support
//! yarn alike; the paper's fixed step must suit the stiffest spring and crawls on the soft ones.
//! Momentum turns the `O(N²)` iterations plain relaxation needs on smooth, grid-wide error into
//! `O(N)`; the restart takes the momentum away whenever it overshoots, which needs no estimate
//! of the spectrum (Chebyshev does) and no energy (FIRE and line searches do). That matters
//! here, because the connection force of eq. (2) is not the gradient of any energy: the power
//! `F·v` is defined for any force, so eq. (2) enters like every other force, evaluated at the
//! current positions (lagged by nothing). Its iterations still grow with the grid size;
//! [`super::multilevel`] starts it from a coarser grid's rest state to cut how many it needs.
//!
//! Contact and the held end rings act through [`Constraints`] as for the paper's solver: the move
//! is limited, and the momentum carries only the move that was allowed. The step itself leaves out
//! the force the skin holds, so a resting point is not pushed into the skin and taken back each
//! iteration (docs/decisions/0010).
//!
//! **The stall test.** The power `Σ F·v` is taken over the whole grid, and late in a fit most of
//! the grid can still be coasting forward while a few hundred points (just off the skin at the
//! top of the inner thigh) oscillate with the momentum weight near 1. So the iteration also
//! watches the *unsettled* points, those whose force step (below) is above the tolerance: when
//! their power, taken together, has been negative for 12 iterations in a row, the momentum
//! restarts as it does for the grid (why 12: docs/decisions/0047).
//!
//! **The futility watch.** Two windows of 100 iterations in a row with restarts on 80 % of them
//! and no 10 % gain on the best residual (a tube that cannot pass a foot), or ten with a quarter
//! restarted and no gain, stop it, saying where ([`OutOfBalance`]; decisions/0049).
//!
//! **Convergence.** The relative residual is the paper solver's (RMS unheld net force over RMS
//! spring force); with it the *force step*, `s |F_i| / m_i` over the shortest rest length (the
//! largest move the unheld force alone would make), must be below the tolerance, so one point far
//! from balance cannot hide in the RMS. The last iteration's largest move is reported but does not
//! decide: with momentum it includes coasting along near-free slides of the tube around a smooth
//! leg, which change neither the forces nor the density (docs/decisions/0011). With [`Polish`] a
//! level goes on past the tolerance towards a tighter residual, best effort.

use std::time::Instant;

use super::evaluation::{
    evaluate, evaluate_and_step, residual_of, rest_force_floor, shortest_rest, unheld_forces,
    MomentumStep, Workspace,
};
use super::{Constraints, ForceTerms, RelaxObserver};
use crate::base::GridSize;
use crate::error::{Error, Result};
use crate::knit::Knit;

/// Step size `s`, as a fraction of the largest step the Gershgorin bound allows without momentum
/// (2). Below 2 by a margin, as the bound is only an estimate where springs change length fast.
const STEP: f64 = 1.5;
/// A residual this many times its starting value means the iteration is running away.
const RUNAWAY_GROWTH: f64 = 1e6;
/// The stall test: after this many iterations in a row in which the unsettled points, together,
/// moved against their force, the momentum is restarted (module docs).
const STALL_ITERATIONS: usize = 12;

/// The futility watch looks at the iterations in windows of this many.
const WATCH_WINDOW: usize = 100;
/// A window is futile when the momentum restarted on at least this fraction of its
/// iterations...
const FUTILE_RESTARTS: f64 = 0.8;
/// ...and its best residual is not below this fraction of the best before it.
const FUTILE_PROGRESS: f64 = 0.9;
/// This many futile windows in a row stop the iteration: it is not going anywhere.
const FUTILE_WINDOWS: usize = 2;
/// Nor is one whose best residual has not gained [`FUTILE_PROGRESS`] over this many windows
/// while restarting on [`STAGNANT_RESTARTS`] of its iterations (a ring's corners chattering on a
/// knee); a fit converging slowly to a tight tolerance restarts far less often.
const STAGNANT_WINDOWS: usize = 10;
/// See [`STAGNANT_WINDOWS`].
const STAGNANT_RESTARTS: f64 = 0.25;

/// The futility watch (module docs): restarts and the best residual, window by window.
#[derive(Clone, Debug)]
struct FutilityWatch {
    iterations: usize,
    restarts: usize,
    best_before: f64,
    best_in: f64,
    futile_windows: usize,
    /// The best residual before each of the last [`STAGNANT_WINDOWS`] windows and the restarts
    /// in it, oldest first.
    history: std::collections::VecDeque<(f64, usize)>,
}

impl Default for FutilityWatch {
    fn default() -> Self {
        FutilityWatch {
            iterations: 0,
            restarts: 0,
            best_before: f64::INFINITY,
            best_in: f64::INFINITY,
            futile_windows: 0,
            history: std::collections::VecDeque::with_capacity(STAGNANT_WINDOWS + 1),
        }
    }
}

impl FutilityWatch {
    /// Takes one iteration's residual and whether it restarted; true once the iteration has
    /// been futile for [`FUTILE_WINDOWS`] windows in a row.
    fn observe(&mut self, residual: f64, restarted: bool) -> bool {
        self.iterations += 1;
        self.restarts += usize::from(restarted);
        self.best_in = self.best_in.min(residual);
        if self.iterations < WATCH_WINDOW {
            return false;
        }
        let futile = self.restarts as f64 >= FUTILE_RESTARTS * WATCH_WINDOW as f64
            && self.best_in >= FUTILE_PROGRESS * self.best_before;
        self.futile_windows = if futile { self.futile_windows + 1 } else { 0 };
        self.history.push_back((self.best_before, self.restarts));
        if self.history.len() > STAGNANT_WINDOWS {
            self.history.pop_front();
        }
        self.best_before = self.best_before.min(self.best_in);
        (self.iterations, self.restarts, self.best_in) = (0, 0, f64::INFINITY);
        let restarts: usize = self.history.iter().map(|&(_, r)| r).sum();
        let stagnant = self.history.len() == STAGNANT_WINDOWS
            && self.best_before >= FUTILE_PROGRESS * self.history[0].0
            && restarts as f64 >= STAGNANT_RESTARTS * (STAGNANT_WINDOWS * WATCH_WINDOW) as f64;
        self.futile_windows >= FUTILE_WINDOWS || stagnant
    }
}

/// Where a level stopped short of balance (as futile, or at its iteration cap): the courses
/// still out of balance and the worst point.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutOfBalance {
    /// Lowest and highest course (0 = the first knitted: a stocking's top, an open tube's bottom
    /// end) whose force step is above the tolerance; the worst point's alone where none is.
    pub courses: [usize; 2],
    /// The point with the largest force step, world space.
    pub worst_point: [f64; 3],
    /// Its force step (over the shortest rest length).
    pub worst_force_step: f64,
}

/// Why the momentum restarts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Restart {
    /// The grid as a whole moved against the force.
    Power,
    /// The unsettled points did, [`STALL_ITERATIONS`] times in a row.
    Stall,
}

/// The restart rules, with the stall test's count of iterations in a row in which the unsettled
/// points moved against their force.
#[derive(Clone, Copy, Debug, Default)]
struct RestartRules {
    stalling: usize,
}

impl RestartRules {
    /// Takes one iteration's power of the grid and of its unsettled points; says whether the
    /// momentum restarts, and why (a grid power below 0 decides first).
    fn observe(&mut self, power: f64, unsettled_power: f64) -> Option<Restart> {
        self.stalling = if unsettled_power < 0.0 {
            self.stalling + 1
        } else {
            0
        };
        let restart = if power < 0.0 {
            Some(Restart::Power)
        } else if self.stalling >= STALL_ITERATIONS {
            Some(Restart::Stall)
        } else {
            None
        };
        if restart.is_some() {
            self.stalling = 0;
        }
        restart
    }
}

/// Best-effort iterations after a level has met its tolerance (the multilevel solver's finest
/// level). From the first iteration whose residual and force step are below the tolerance, the
/// level goes on until its residual is below [`Polish::residual`] with the force step still
/// below the tolerance, or [`Polish::max_iterations`] more iterations have passed, or a window
/// of 3,000 iterations has not bettered its best residual by 10 %, or the futility
/// watch fires (no stall then), or the level's own cap is reached, or the state stops being
/// finite or runs away. It has converged whichever: where it stops in a state that no longer
/// meets the tolerance, or is further from rest than the state that first met it (momentum
/// can take the residual back up), it hands back that first state, and its figures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Polish {
    /// The relative residual to go on to; the force step need only stay below the tolerance.
    pub residual: f64,
    /// Iterations after the tolerance was first met, at most (the level's own cap still holds).
    pub max_iterations: usize,
}

/// Polishing stops when its best residual has not gained [`FUTILE_PROGRESS`] over a window of
/// this many iterations: a few points trading places at a knee can hold the residual at
/// 5e-4–6e-3 for ever (makehuman_hips_heavy 100×100), and the futility watch, which needs a
/// quarter of the iterations restarted, does not see them (docs/decisions/0067). Shorter
/// windows cut short plateaus that end (makehuman_hips_heavy 100×187: over 1,000 iterations).
const POLISH_WINDOW: usize = 3000;

/// The state that first met the tolerance, kept while polishing, and how polishing gains.
struct Met {
    iteration: usize,
    x: Vec<crate::base::Vec3>,
    residual: f64,
    force_step: f64,
    max_move: f64,
    /// The best residual since, and the best when the current [`POLISH_WINDOW`] began.
    best: f64,
    window_best: f64,
}

impl Met {
    /// Takes a polishing iteration's residual; false once a whole window has not gained.
    fn gaining(&mut self, iteration: usize, residual: f64) -> bool {
        self.best = self.best.min(residual);
        let since = iteration - self.iteration;
        if since == 0 || !since.is_multiple_of(POLISH_WINDOW) {
            return true;
        }
        let gained = self.best < FUTILE_PROGRESS * self.window_best;
        self.window_best = self.best;
        gained
    }
}

/// What the iteration on one grid did.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LevelStats {
    /// Points around the grid.
    pub wales: usize,
    /// Rings along the grid.
    pub courses: usize,
    /// Iterations taken.
    pub iterations: usize,
    /// Of those, the iterations after the tolerance was first met, polishing towards a tighter
    /// residual ([`Polish`]); 0 without polishing.
    pub polish_iterations: usize,
    /// Times the momentum was restarted.
    pub restarts: usize,
    /// Of those, the restarts the stall test made (module docs).
    pub stall_restarts: usize,
    /// Relative residual when the level started (after interpolation from the coarser grid).
    pub start_residual: f64,
    /// Final relative residual.
    pub residual: f64,
    /// Final force step: the largest move the unheld force alone would make in one step,
    /// `s |F_i| / m_i`, over the shortest rest length (the max-norm companion of the residual).
    pub force_step: f64,
    /// The largest move of the last iteration (force and momentum), over the shortest rest
    /// length.
    pub max_move: f64,
    /// True when both went below the tolerance (a polished level: at the iteration that first
    /// met it, and in the state handed back).
    pub converged: bool,
    /// Where the iteration stopped early because it was going nowhere (module docs); `null`
    /// when it did not.
    pub stall: Option<OutOfBalance>,
    /// Where the level was still unsettled when it reached its iteration cap: the courses whose
    /// force step was above the tolerance, and the worst point; `null` when it converged or
    /// stalled. A run that ends unconverged says where, so that its user can tell a slow
    /// corner (raise the cap) from a whole grid out of balance.
    pub unsettled: Option<OutOfBalance>,
    /// Wall-clock seconds the level took.
    pub seconds: f64,
}

impl LevelStats {
    /// The level's grid.
    pub fn grid(&self) -> GridSize {
        GridSize::new(self.wales, self.courses)
    }
}

/// Relaxes `knit` in place on its own grid until the residual and the force step are below
/// `tolerance`, or `max_iterations` is reached. With `polish`, a level that meets the tolerance
/// goes on towards `polish.residual` ([`Polish`]) and converges whatever that reaches.
/// `first_step` numbers the observer's steps (levels of a multilevel solve count on from each
/// other).
///
/// Errors: [`Error::SolverDiverged`] when a value stops being finite or the residual runs away.
#[allow(clippy::too_many_arguments)]
pub fn relax_accelerated(
    knit: &mut Knit,
    terms: &ForceTerms,
    tolerance: f64,
    max_iterations: usize,
    polish: Option<Polish>,
    constraints: &mut dyn Constraints,
    observer: &mut dyn RelaxObserver,
    first_step: usize,
) -> Result<LevelStats> {
    let started = Instant::now();
    let shortest_rest = shortest_rest(knit);
    let force_floor = rest_force_floor(knit, terms);
    let mut ws = Workspace::new(knit);
    // Where each point was before the last iteration: its velocity is the last move, `x − from`
    // (the move the constraints allowed), so no velocity is stored.
    let mut from = knit.particles.x.clone();
    let mut since_restart = 0usize;
    let (mut restarts, mut stall_restarts) = (0, 0);
    let mut rules = RestartRules::default();
    let mut watch = FutilityWatch::default();
    let mut stall = None;
    // A point whose force step is above the tolerance is unsettled.
    let unsettled_above = tolerance * shortest_rest / STEP;
    let mut start_residual = None;
    // Polishing: the state that first met the tolerance.
    let mut met: Option<Met> = None;
    let mut iteration = 0;
    loop {
        // The step is taken with the momentum of no restart, in the same pass; the rare
        // iteration that restarts takes it again.
        let beta = since_restart as f64 / (since_restart as f64 + 3.0);
        let momentum = MomentumStep {
            beta,
            step: STEP,
            unsettled_above,
        };
        let (eval, sums) =
            evaluate_and_step(knit, terms, &mut ws, &*constraints, &mut from, momentum);
        let residual = residual_of(knit, &sums, eval.spring_force_sq, force_floor);
        let force_step = STEP * sums.max_step() / shortest_rest;
        let max_move = sums.max_move() / shortest_rest;
        observer.on_step(first_step + iteration, residual);
        let start = *start_residual.get_or_insert(residual);
        let diverged = |what: String| Error::SolverDiverged {
            grid: format!("{}×{}", knit.wales, knit.courses),
            iteration,
            what,
        };
        let finite = residual.is_finite() && force_step.is_finite() && f64::is_finite(max_move);
        let runaway = residual > RUNAWAY_GROWTH * start.max(tolerance);
        // While polishing, a state that met the tolerance is held: it is handed back instead.
        if met.is_none() && !finite {
            return Err(diverged("a position or force stopped being finite".into()));
        }
        if met.is_none() && runaway {
            return Err(diverged(format!(
                "the residual grew from {start:.3e} to {residual:.3e}"
            )));
        }
        let converged = finite && residual < tolerance && force_step < tolerance;
        if let Some(polish) = polish {
            if converged && met.is_none() {
                met = Some(Met {
                    iteration,
                    x: knit.particles.x.clone(),
                    residual,
                    force_step,
                    max_move,
                    best: residual,
                    window_best: residual,
                });
            }
            if let Some(met) = &mut met {
                let polished = residual < polish.residual && force_step < tolerance;
                let spent = iteration - met.iteration >= polish.max_iterations
                    || !met.gaining(iteration, residual);
                let lost = !finite || runaway;
                if polished || spent || lost || iteration >= max_iterations || stall.is_some() {
                    // Best effort: a state that no longer meets the tolerance, or is further
                    // from rest than the one that first did, goes back to that one; a watch
                    // that fired while polishing is no stall.
                    let (residual, force_step, max_move) = if converged && residual <= met.residual
                    {
                        (residual, force_step, max_move)
                    } else {
                        knit.particles.x.clone_from(&met.x);
                        (met.residual, met.force_step, met.max_move)
                    };
                    return Ok(LevelStats {
                        wales: knit.wales,
                        courses: knit.courses,
                        iterations: iteration,
                        polish_iterations: iteration - met.iteration,
                        restarts,
                        stall_restarts,
                        start_residual: start,
                        residual,
                        force_step,
                        max_move,
                        converged: true,
                        stall: None,
                        unsettled: None,
                        seconds: started.elapsed().as_secs_f64(),
                    });
                }
            }
        }
        if met.is_none() && (converged || iteration >= max_iterations || stall.is_some()) {
            // A level that converged on the iteration after the watch fired is no stall.
            let stall = stall.filter(|_| !converged);
            let unsettled = (!converged && stall.is_none())
                .then(|| out_of_balance(knit, terms, &mut ws, &*constraints, tolerance));
            return Ok(LevelStats {
                wales: knit.wales,
                courses: knit.courses,
                iterations: iteration,
                polish_iterations: 0,
                restarts,
                stall_restarts,
                start_residual: start,
                residual,
                force_step,
                max_move,
                converged,
                stall,
                unsettled,
                seconds: started.elapsed().as_secs_f64(),
            });
        }

        let restart = rules.observe(sums.power, sums.unsettled_power);
        if watch.observe(residual, restart.is_some()) {
            stall = Some(out_of_balance(
                knit,
                terms,
                &mut ws,
                &*constraints,
                tolerance,
            ));
        }
        if let Some(why) = restart {
            since_restart = 0;
            restarts += 1;
            stall_restarts += usize::from(why == Restart::Stall);
            from.clone_from(&knit.particles.x);
            let still = MomentumStep {
                beta: 0.0,
                ..momentum
            };
            evaluate_and_step(knit, terms, &mut ws, &*constraints, &mut from, still);
        }
        // `from` holds the new positions: swap, so that it holds where each point was.
        std::mem::swap(&mut knit.particles.x, &mut from);
        let p = &mut knit.particles;
        constraints.constrain(&from, &mut p.x, &p.inv_mass);
        since_restart += 1;
        iteration += 1;
    }
}

/// The courses whose force step is above `tolerance`, and the worst point.
fn out_of_balance(
    knit: &Knit,
    terms: &ForceTerms,
    ws: &mut Workspace,
    constraints: &dyn Constraints,
    tolerance: f64,
) -> OutOfBalance {
    evaluate(knit, terms, ws);
    unheld_forces(knit, ws, constraints);
    let shortest = shortest_rest(knit);
    let step = |i: usize| {
        let bound = ws.stiffness_bound[i];
        if bound > 0.0 {
            STEP * ws.unheld[i].norm() / bound / shortest
        } else {
            0.0
        }
    };
    let (mut courses, mut worst) = ([usize::MAX, 0], (0, 0.0));
    for i in 0..knit.len() {
        let s = step(i);
        if s > tolerance {
            let c = course_of(knit, i);
            courses = [courses[0].min(c), courses[1].max(c)];
        }
        if s > worst.1 {
            worst = (i, s);
        }
    }
    if courses[0] == usize::MAX {
        // No point is above the tolerance (only the residual is): the worst one says where.
        let c = course_of(knit, worst.0);
        courses = [c, c];
    }
    OutOfBalance {
        courses,
        worst_point: knit.particles.x[worst.0].into(),
        worst_force_step: worst.1,
    }
}

/// The grid course at or below point `i` (a short row's point: the course it was knitted above).
fn course_of(knit: &Knit, i: usize) -> usize {
    knit.fabric_coords(crate::knit::PointId(i as u32))[1] as usize
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::Vec3;
    use crate::knit::{Pattern, Tile};
    use crate::sim::Unconstrained;

    /// A 6×9 tube at rest (rest lengths 1, its first ring pinned) but for course `pulled`,
    /// whose points are pulled 0.3 outwards.
    fn tube_pulled_at(pulled: usize) -> Knit {
        let (wales, courses) = (6, 9);
        // Chords of rest length 1 around.
        let radius = 0.5 / (std::f64::consts::PI / wales as f64).sin();
        let mut knit = Knit::grid(
            wales,
            courses,
            true,
            &Tile::of(Pattern::Alternating),
            1.0,
            1.0,
            |w, c| {
                let t = std::f64::consts::TAU * w as f64 / wales as f64;
                let r = radius + if c == pulled { 0.3 } else { 0.0 };
                Vec3::new(r * t.cos(), c as f64, r * t.sin())
            },
        );
        for w in 0..wales {
            let i = knit.point(w, 0).index();
            knit.particles.inv_mass[i] = 0.0;
        }
        knit
    }

    #[test]
    fn a_level_that_runs_out_of_iterations_says_where_it_had_not_settled() {
        let terms = ForceTerms {
            stiffness: [1.0; 3],
            connection_factor: None,
        };
        let mut knit = tube_pulled_at(6);
        let relax = |knit: &mut Knit, tolerance, cap| {
            relax_accelerated(
                knit,
                &terms,
                tolerance,
                cap,
                None,
                &mut Unconstrained,
                &mut (),
                0,
            )
            .unwrap()
        };
        let capped = relax(&mut knit, 1e-3, 2);
        assert!(!capped.converged && capped.stall.is_none());
        let at = capped.unsettled.expect("a capped level says where");
        // The pulled course and its neighbours, not the pinned ring; worst on the pulled one.
        assert!(at.courses[0] >= 4 && at.courses[1] <= 8, "{at:?}");
        assert!((at.worst_point[1] - 6.0).abs() < 0.5, "{at:?}");
        assert!(at.worst_force_step > 1e-3);
        // Of the state handed back.
        assert_eq!(at.worst_force_step, capped.force_step);
        let settled = relax(&mut knit, 1e-3, 100_000);
        assert!(settled.converged, "{settled:?}");
        assert_eq!(settled.unsettled, None);
        // Without polishing a level stops at the first iteration that meets the tolerance.
        assert_eq!(settled.polish_iterations, 0);
        assert!(settled.residual > 1e-4, "{settled:?}");
    }

    #[test]
    fn polishing_stops_after_a_window_without_a_tenth_gained() {
        let met = |residual: f64| Met {
            iteration: 10,
            x: Vec::new(),
            residual,
            force_step: 0.0,
            max_move: 0.0,
            best: residual,
            window_best: residual,
        };
        // Stuck, trading places around 6e-4: the first whole window ends it.
        let mut stuck = met(6e-4);
        let end = 10 + POLISH_WINDOW;
        assert!((11..end).all(|i| stuck.gaining(i, 6e-4 * (1.0 + 0.1 * (i % 2) as f64))));
        assert!(!stuck.gaining(end, 6e-4));
        // Falling by a tenth a window, not more: it goes on as long as it falls.
        let mut falling = met(1e-3);
        for window in 1..=3 {
            let i = 10 + window * POLISH_WINDOW;
            assert!(falling.gaining(i - 1, 1e-3 * 0.85f64.powi(window as i32)));
            assert!(
                falling.gaining(i, 1e-3 * 0.85f64.powi(window as i32)),
                "window {window}"
            );
        }
        assert!(!falling.gaining(10 + 4 * POLISH_WINDOW, 1e-3 * 0.86f64.powi(3)));
    }

    /// Records the residual of every iteration.
    struct Residuals(Vec<f64>);

    impl RelaxObserver for Residuals {
        fn on_step(&mut self, _step: usize, residual: f64) {
            self.0.push(residual);
        }
    }

    /// [`tube_pulled_at`] course 6, relaxed; its stats, knit and every iteration's residual.
    fn relaxed_tube(
        tolerance: f64,
        max_iterations: usize,
        polish: Option<Polish>,
    ) -> (LevelStats, Knit, Vec<f64>) {
        let terms = ForceTerms {
            stiffness: [1.0; 3],
            connection_factor: None,
        };
        let mut knit = tube_pulled_at(6);
        let mut residuals = Residuals(Vec::new());
        let stats = relax_accelerated(
            &mut knit,
            &terms,
            tolerance,
            max_iterations,
            polish,
            &mut Unconstrained,
            &mut residuals,
            0,
        )
        .unwrap();
        (stats, knit, residuals.0)
    }

    /// The figures of a level but its time.
    fn untimed(stats: &LevelStats) -> LevelStats {
        LevelStats {
            seconds: 0.0,
            ..stats.clone()
        }
    }

    #[test]
    fn a_polished_level_goes_on_from_where_it_met_the_tolerance_to_the_polish_residual() {
        let (plain, plain_knit, _) = relaxed_tube(1e-3, 100_000, None);
        assert!(plain.converged && plain.residual > 1e-4, "{plain:?}");
        let polish = Polish {
            residual: 1e-4,
            max_iterations: 10_000,
        };
        let (polished, knit, _) = relaxed_tube(1e-3, 100_000, Some(polish));
        assert!(polished.converged, "{polished:?}");
        assert!(
            polished.residual < 1e-4 && polished.force_step < 1e-3,
            "{polished:?}"
        );
        assert!(polished.iterations > plain.iterations, "{polished:?}");
        // Counted from the iteration the plain level stopped at.
        assert!(polished.polish_iterations > 0);
        assert_eq!(
            polished.iterations - polished.polish_iterations,
            plain.iterations
        );
        assert_eq!((polished.stall, polished.unsettled), (None, None));
        assert_ne!(knit.particles.x, plain_knit.particles.x);
        // The level's own cap ends the polishing too, converged.
        let capped_at = plain.iterations + 2;
        let (capped, _, _) = relaxed_tube(1e-3, capped_at, Some(polish));
        assert!(capped.converged && capped.unsettled.is_none(), "{capped:?}");
        assert_eq!(
            (capped.iterations, capped.polish_iterations),
            (capped_at, 2)
        );
    }

    #[test]
    fn a_polish_budget_spent_hands_back_the_state_that_first_met_the_tolerance() {
        // No budget: the plain level's state and figures.
        let (plain, plain_knit, _) = relaxed_tube(1e-3, 100_000, None);
        let none = Polish {
            residual: 1e-9,
            max_iterations: 0,
        };
        let (polished, knit, _) = relaxed_tube(1e-3, 100_000, Some(none));
        assert_eq!(untimed(&polished), untimed(&plain));
        assert_eq!(knit.particles.x, plain_knit.particles.x);

        // An iteration that first meets a tolerance and whose next one is above it again
        // (momentum): a budget of one iteration ends above the tolerance, so the level goes back.
        let (_, _, residuals) = relaxed_tube(1e-9, 100_000, None);
        let mut best_before = f64::INFINITY;
        let mut bump = None;
        for (k, pair) in residuals.windows(2).enumerate() {
            if pair[0] < 0.5 && pair[0] < best_before && pair[1] > pair[0] {
                bump = Some((k, (pair[0] + pair[1].min(best_before)) / 2.0));
                break;
            }
            best_before = best_before.min(pair[0]);
        }
        let (met_at, tolerance) = bump.expect("the momentum takes the residual back up somewhere");
        let (plain, plain_knit, _) = relaxed_tube(tolerance, 100_000, None);
        assert_eq!(plain.iterations, met_at, "{plain:?}");
        let one = Polish {
            residual: 1e-9,
            max_iterations: 1,
        };
        let (polished, knit, residuals) = relaxed_tube(tolerance, 100_000, Some(one));
        assert!(residuals[met_at + 1] >= tolerance, "{residuals:?}");
        assert!(polished.converged, "{polished:?}");
        assert_eq!(
            (polished.iterations, polished.polish_iterations),
            (met_at + 1, 1)
        );
        let back = LevelStats {
            iterations: plain.iterations,
            polish_iterations: 0,
            restarts: plain.restarts,
            stall_restarts: plain.stall_restarts,
            ..untimed(&polished)
        };
        assert_eq!(back, untimed(&plain));
        assert_eq!(knit.particles.x, plain_knit.particles.x);
    }

    #[test]
    fn a_futile_watch_while_polishing_is_no_stall() {
        // Relaxed without polishing to 1e-9, the tube's residual floors near 1e-6 and the watch
        // stops it as going nowhere.
        let (futile, _, _) = relaxed_tube(1e-9, 100_000, None);
        assert!(futile.stall.is_some() && !futile.converged, "{futile:?}");
        let polish = Polish {
            residual: 1e-9,
            max_iterations: 100_000,
        };
        let (polished, _, _) = relaxed_tube(1e-3, 100_000, Some(polish));
        assert!(polished.converged, "{polished:?}");
        assert_eq!((polished.stall, polished.unsettled), (None, None));
        assert_eq!(polished.iterations, futile.iterations);
        assert!(
            polished.residual < 1e-3 && polished.residual > 1e-9,
            "{polished:?}"
        );
    }

    #[test]
    fn the_stall_test_restarts_on_the_twelfth_negative_unsettled_power_in_a_row() {
        assert_eq!(STALL_ITERATIONS, 12, "the module docs measure 12");
        let mut rules = RestartRules::default();
        for _ in 1..STALL_ITERATIONS {
            assert_eq!(rules.observe(1.0, -1.0), None);
        }
        assert_eq!(rules.observe(1.0, -1.0), Some(Restart::Stall));
        // The count starts again after a restart.
        assert_eq!(rules.observe(1.0, -1.0), None);
    }

    #[test]
    fn a_settled_or_forward_iteration_breaks_the_run() {
        for breaker in [0.0, 1e-12] {
            let mut rules = RestartRules::default();
            for _ in 1..STALL_ITERATIONS {
                assert_eq!(rules.observe(1.0, -1.0), None);
            }
            // No unsettled point (power 0), or the unsettled points moving with their force.
            assert_eq!(rules.observe(1.0, breaker), None);
            assert_eq!(rules.observe(1.0, -1.0), None);
        }
    }

    #[test]
    fn the_watch_stops_only_after_windows_of_restarts_without_progress() {
        let mut watch = FutilityWatch::default();
        // Restarting every iteration while the residual falls steadily is progress.
        let mut residual = 1.0;
        for _ in 0..10 * WATCH_WINDOW {
            residual *= 0.998;
            assert!(!watch.observe(residual, true));
        }
        // A residual gaining 2 % a window with rare restarts is a slow fit, not a futile one.
        for k in 0..30 * WATCH_WINDOW {
            if k % WATCH_WINDOW == 0 {
                residual *= 0.98;
            }
            assert!(!watch.observe(residual, k % 20 == 0));
        }
        // A flat residual restarted on every iteration: stopped at the end of the second
        // window in a row.
        let stopped = (1..=10 * WATCH_WINDOW).find(|_| watch.observe(residual, true));
        assert_eq!(stopped, Some(FUTILE_WINDOWS * WATCH_WINDOW));
        // A flat residual with rare restarts: a slow fit near its tolerance, left to run.
        let mut watch = FutilityWatch::default();
        assert!((1..=30 * WATCH_WINDOW).all(|k| !watch.observe(residual, k % 20 == 0)));
        // A flat residual restarted on every second iteration: stopped after ten windows
        // without a 10 % gain on the first one's best.
        let mut watch = FutilityWatch::default();
        let stopped = (1..=20 * WATCH_WINDOW).find(|k| watch.observe(residual, k % 2 == 0));
        assert_eq!(stopped, Some((STAGNANT_WINDOWS + 1) * WATCH_WINDOW));
    }

    #[test]
    fn the_grid_power_decides_first_and_resets_the_stall_count() {
        let mut rules = RestartRules::default();
        for _ in 1..STALL_ITERATIONS {
            rules.observe(1.0, -1.0);
        }
        // Both rules would fire: the grid's power names the restart.
        assert_eq!(rules.observe(-1.0, -1.0), Some(Restart::Power));
        for _ in 1..STALL_ITERATIONS {
            assert_eq!(rules.observe(1.0, -1.0), None);
        }
        assert_eq!(rules.observe(1.0, -1.0), Some(Restart::Stall));
        assert_eq!(rules.observe(-1.0, 1.0), Some(Restart::Power));
    }
}
