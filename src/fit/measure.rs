//! What the fitted stocking measures, in the real stocking's units at any grid
//! ([`crate::post::fields`]): stitch density, coverage, stretch, tension and pressure on the
//! knit's points and carried to the leg's vertices (stage [`crate::stage::Stage::LegAttributes`]);
//! where the fabric lies slack; and its stretch over each part of the leg.

use crate::knit::path::PathPart;
use crate::knit::tube::part_at;
use crate::knit::Fabric;
use crate::leg::SkinCurvature;
use crate::post::fields::{self, KnitFields};
use crate::post::measure_fields;
use crate::post::regions::{regions, stretch_by_region, RegionStretch};
use crate::post::stitches::{slack, slack_details, SlackDetails};
use crate::sim::ForceTerms;

use super::SolvedFit;

/// A fitted knit's fields: per knit point, and carried to the leg's vertices (empty where not
/// measured).
#[derive(Clone, Debug, Default)]
pub struct Fields {
    /// Per knit point.
    pub on_knit: KnitFields,
    /// Per leg vertex (zero on skin the stocking does not cover).
    pub on_leg: KnitFields,
}

/// The fitted knit's fields as the real stocking `fabric`, with the stiffness of `terms`,
/// pressing on the skin it rests on ([`measure_fields`]).
pub fn fields(fit: &SolvedFit, fabric: &Fabric, terms: &ForceTerms) -> Fields {
    let skin = SkinCurvature::of(fit.rested_on(), fields::MEASURE_SPAN_M);
    let (on_knit, on_leg) = measure_fields(&fit.knit, &fit.leg, &skin, fit.offset, fabric, terms);
    Fields { on_knit, on_leg }
}

/// Where the fitted fabric lies slack (wale springs shorter than their rest), and on which part
/// of a stocking to the toe's path.
pub fn slack_of(fit: &SolvedFit) -> SlackDetails {
    let placement = &fit.placement;
    let along = fit.knit_as_placed();
    slack_details(along, &slack(&fit.knit), &placement.centreline, |s| {
        placement
            .path
            .as_ref()
            .map(|path| part_name(part_at(path, s)))
    })
}

/// The knit's stretch over each part of the leg (toe … thigh), each point weighed by the fabric
/// it stands for; none where the stocking was placed by a given axis (no landmarks name the
/// parts).
pub fn stretch_by_part(fit: &SolvedFit) -> Vec<RegionStretch> {
    let placement = &fit.placement;
    let Some(landmarks) = &placement.landmarks else {
        return Vec::new();
    };
    let knit = &fit.knit;
    let regions = regions(
        fit.knit_as_placed(),
        &placement.centreline,
        placement.path.as_ref(),
        landmarks,
    );
    let stretch = fields::stretch(knit);
    let shares = knit.point_fabric_shares();
    stretch_by_region(&regions, &stretch, shares.as_deref())
}

/// A part of the path as the report names it (`"heel"`).
fn part_name(part: PathPart) -> String {
    format!("{part:?}").to_lowercase()
}
