//! Simulation: force kernels (pure functions), one force evaluation every solver shares, and the
//! solvers that loop over it: the paper's explicit relaxation (the reference) and the fast
//! multilevel one.
//!
//! What every solver shares lives here, at the root: the force terms a plan switches on
//! ([`ForceTerms`]), the constraints a fit adds ([`Constraints`]: contact with the leg, held end
//! rings) and the observer a progress display listens through ([`RelaxObserver`]).

pub mod accelerated;
pub mod contact;
pub mod evaluation;
pub mod forces;
pub mod multilevel;
pub mod relax;
pub mod settings;
pub mod stall;

pub use accelerated::{relax_accelerated, LevelStats, Polish};
pub use multilevel::{relax_multilevel, Levels, MultilevelStats};
pub use relax::{relax, relax_constrained, stability_limit, RelaxStats};
pub use settings::{ContactSettings, OnUnstable, SolverMethod, SolverSettings};

use crate::base::{Direction, PerYarn, Vec3, YarnKind};
use crate::knit::Knit;

/// Which force terms run, with their coefficients. Built by the plan from the scene's effects.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ForceTerms {
    /// Spring stiffness c1 per yarn kind (indexed by `YarnKind::index()`). Equal entries when the
    /// scene does not ask for `alternating_yarns`.
    pub stiffness: PerYarn<f64>,
    /// Connection factor c2 of eq. (2), or `None` when `yarn_connection` is off.
    pub connection_factor: Option<f64>,
}

impl ForceTerms {
    /// c1 of a spring of the knit: its yarn's stiffness, times the knit's factor for its
    /// direction ([`Knit::stiffness_scale`]) and its row's on a graded grid
    /// ([`Knit::spring_factor`]).
    pub fn c1(&self, knit: &Knit, spring: u32) -> f64 {
        let s = &knit.springs[spring as usize];
        self.c1_of(knit, s.yarn, s.direction) * knit.spring_factor(spring as usize)
    }

    /// c1 of a spring of `yarn` along `direction` in the knit: its yarn's, or where the knit's
    /// cells stand for blocks of stitches, the blend's ([`ForceTerms::blended`]).
    pub(crate) fn c1_of(&self, knit: &Knit, yarn: YarnKind, direction: Direction) -> f64 {
        let stiffness = match &knit.yarn_blend {
            Some(shares) => self.blended(shares[direction], direction),
            None => self.stiffness[yarn.index() as usize],
        };
        let seam = match yarn {
            YarnKind::Seam => 1.0 / knit.toe_seam_steps(),
            _ => 1.0,
        };
        stiffness * knit.stiffness_scale[direction] * seam
    }

    /// The stiffness of yarns mixed in `shares` along `direction`: courses lie side by side, so
    /// along the course their stiffness adds (the mean); a wale's loop legs follow one another,
    /// alternating yarns, so along the wale their compliance adds (the harmonic mean).
    pub fn blended(&self, shares: PerYarn<f64>, direction: Direction) -> f64 {
        let pairs = shares.iter().zip(&self.stiffness).filter(|(&f, _)| f > 0.0);
        match direction {
            Direction::Course => pairs.map(|(f, k)| f * k).sum(),
            Direction::Wale => 1.0 / pairs.map(|(f, k)| f / k).sum::<f64>(),
        }
    }
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
    /// [`Constraints::unheld_force`] of the points `first..first + forces.len()`, in place: the
    /// force pass asks once per row of the grid rather than once per point. Pinned points may be
    /// among them; the caller ignores what they get.
    fn unheld_forces_from(&self, first: usize, forces: &mut [Vec3]) {
        for (k, f) in forces.iter_mut().enumerate() {
            *f = self.unheld_force(first + k, f);
        }
    }
    /// Puts every free point where the constraints allow it to rest, with no move to follow:
    /// for a start from positions that were not reached by constrained moves (interpolated from
    /// a coarser grid, say), which may break the constraints. Default: nothing to do.
    fn settle(&mut self, _x: &mut [Vec3], _inv_mass: &[f64]) {}
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::PerDirection;
    use crate::knit::pattern::{Pattern, Tile};

    #[test]
    fn a_graded_grids_springs_are_the_same_fabric_per_strain() {
        // Courses 1, 0.5 and 0.25 apart: stretched by a strain along the wales, every wale
        // spring pulls the same (shorter yarn, stiffer); stretched around, every ring pulls in
        // proportion to the fabric it stands for (half its intervals either side).
        let intervals = [1.0, 1.0, 0.5, 0.25, 0.25];
        let knit = Knit::grid(
            8,
            6,
            true,
            &Tile::of(Pattern::Alternating),
            1.0,
            1.0,
            |w, c| Vec3::new(w as f64, c as f64, 0.0),
        )
        .with_course_intervals(&intervals)
        .with_stitch_shape(PerDirection::new(1.0, 1.0));
        let terms = ForceTerms {
            stiffness: [1.0, 10.0, 10.0],
            connection_factor: None,
        };
        let strain = 0.1;
        let fabric: Vec<f64> = (0..6)
            .map(|c| match c {
                0 => intervals[0],
                5 => intervals[4],
                _ => 0.5 * (intervals[c - 1] + intervals[c]),
            })
            .collect();
        for (i, s) in knit.springs.iter().enumerate() {
            let pull = terms.c1(&knit, i as u32) * strain * s.rest;
            let (_, c) = knit.grid_coords(s.a);
            let c1 = terms.c1_of(&knit, s.yarn, s.direction);
            let want = match s.direction {
                Direction::Wale => c1 * strain * intervals[0],
                Direction::Course => c1 * strain * s.rest * fabric[c] / intervals[0],
            };
            assert!(
                (pull - want).abs() < 1e-12 * want,
                "spring {i}: {pull} vs {want}"
            );
            if s.direction == Direction::Wale {
                assert_eq!(s.rest, intervals[c]);
            }
        }
        // An even grid's factors are exactly 1.
        let even = tube_of(1.0);
        assert!(!even.is_graded());
        assert!((0..even.springs.len()).all(|i| even.spring_factor(i) == 1.0));
    }

    fn tube_of(rest: f64) -> Knit {
        Knit::grid(
            8,
            4,
            true,
            &Tile::of(Pattern::Alternating),
            rest,
            rest,
            |w, c| Vec3::new(w as f64, c as f64, 0.0),
        )
    }

    #[test]
    fn a_toe_seam_shorter_than_a_step_is_the_same_fabric_per_strain() {
        // Wale springs resting at 1 and a seam resting at 0.2 (one real course on a grid five
        // times coarser): the seam is a fifth of a step, and its springs five times as stiff,
        // so that stretched by the same strain they pull as a wale spring does.
        let tube = || {
            Knit::grid(
                8,
                4,
                true,
                &Tile::of(Pattern::Alternating),
                1.0,
                1.0,
                |w, c| Vec3::new(w as f64, c as f64, 0.0),
            )
            .with_stitch_shape(PerDirection::new(1.0, 1.0))
        };
        let knit = tube().with_toe_seam(0.2);
        assert!((knit.toe_seam_steps() - 0.2).abs() < 1e-12);
        let terms = ForceTerms {
            stiffness: [1.0, 10.0, 10.0],
            connection_factor: None,
        };
        let wale = terms.c1_of(&knit, YarnKind::Nylon, Direction::Wale);
        let seam = terms.c1_of(&knit, YarnKind::Seam, Direction::Wale);
        assert!((seam * 0.2 - wale).abs() < 1e-12 * wale);
        // Without a seam, or with one a step long, nothing changes.
        assert_eq!(tube().toe_seam_steps(), 1.0);
        let whole = tube().with_toe_seam(1.0);
        assert_eq!(terms.c1_of(&whole, YarnKind::Seam, Direction::Wale), wale);
    }
}
