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

use crate::knit::{Fabric, Knit};
use crate::leg::{Leg, SkinCurvature};
use crate::sim::ForceTerms;
use fields::KnitFields;
use transfer::{carry_to_leg, OpenEnd};

/// Per-point stitch fields of `knit` ([`fields`]) and their transfer to the leg's vertices
/// ([`transfer`]), pressing on `skin` (the surface the fabric rests on, `offset` from it: see
/// [`fields::pressure`]).
pub fn measure_fields(
    knit: &Knit,
    leg: &Leg,
    skin: &SkinCurvature,
    offset: f64,
    fabric: &Fabric,
    terms: &ForceTerms,
) -> (KnitFields, KnitFields) {
    let per_point = KnitFields::measure(knit, fabric, terms, skin, offset);
    let ends = OpenEnd::of_tube(knit);
    let on_leg = carry_to_leg(knit, &per_point, &leg.positions, skin, &ends);
    (per_point, on_leg)
}
