//! Post-processing of a relaxed knit: stitch measurements, per-point fields and their transfer
//! to the leg, the stretch by part of the leg, the penetration fix of the yarn polylines, and
//! the surfaces the files show.

pub mod fields;
pub mod lattice;
pub mod loops;
pub mod penetration;
pub mod regions;
pub mod stitches;
pub mod surfaces;
pub mod transfer;

pub use stitches::{anisotropy, measure_stitches, StitchStats};
