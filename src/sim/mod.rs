//! Simulation: force kernels (pure functions) and the solvers that loop over them.

pub mod contact;
pub mod forces;
pub mod relax;

pub use relax::{
    relax, relax_constrained, stability_limit, Constraints, ForceTerms, RelaxObserver, RelaxStats,
    Unconstrained,
};
