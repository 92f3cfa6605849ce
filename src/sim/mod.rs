//! Simulation: force kernels (pure functions), one force evaluation every solver shares, and the
//! solvers that loop over it: the paper's explicit relaxation (the reference) and the fast
//! multilevel one.

pub mod accelerated;
pub mod contact;
pub mod evaluation;
pub mod forces;
pub mod multilevel;
#[cfg(test)]
mod properties;
pub mod relax;

pub use accelerated::{relax_accelerated, LevelStats};
pub use multilevel::{relax_multilevel, Levels, MultilevelStats};
pub use relax::{
    relax, relax_constrained, stability_limit, Constraints, ForceTerms, RelaxObserver, RelaxStats,
    Unconstrained,
};
