//! Post-processing of a relaxed knit: measurements now; penetration fix and per-vertex
//! attributes when fitting exists.

pub mod fields;
pub mod stitches;

pub use stitches::{anisotropy, measure_stitches, StitchStats};
