//! Simulation: force kernels (pure functions) and the solvers that loop over them.

pub mod forces;
pub mod relax;

pub use relax::{relax, stability_limit, ForceTerms, RelaxObserver, RelaxStats};
