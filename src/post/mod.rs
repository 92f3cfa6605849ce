//! Post-processing of a relaxed knit: stitch measurements, per-point fields and their transfer
//! to the leg, and the penetration fix of the yarn polylines.

pub mod fields;
pub mod penetration;
pub mod stitches;

pub use stitches::{anisotropy, measure_stitches, StitchStats};
