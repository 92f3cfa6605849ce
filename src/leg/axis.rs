//! The stocking's axis: two points, bottom (ankle end) and top (thigh end), between which the
//! tube is stretched (paper §6.2). Given by the scene or the command line, or placed on the
//! leg's landmarks ([`super::landmarks`]) by `tube.bottom` and `tube.top`.
//!
//! An axis is only a stocking's if the leg goes around it: [`leaves_mesh`] finds where it does
//! not (an axis typed with a wrong coordinate, one between two legs), so such a fit is refused
//! rather than fitted onto air.

use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

use super::{slice, Leg};

/// Where an axis came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AxisSource {
    /// `leg.axis` in the scene.
    Scene,
    /// `--axis` on the command line.
    CommandLine,
    /// Placed on the leg's landmarks.
    Landmarks,
}

impl AxisSource {
    /// Who placed the axis, as a message names it: the flag or field that gave it (`--axis`,
    /// `leg.axis`), or "the axis placed on the landmarks".
    pub fn describe(self) -> &'static str {
        match self {
            AxisSource::CommandLine => "--axis",
            AxisSource::Scene => "leg.axis",
            AxisSource::Landmarks => "the axis placed on the landmarks",
        }
    }
}

/// The stocking's axis, world space (metres, Y up).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Axis {
    /// Bottom point (ankle end).
    pub bottom: [f64; 3],
    /// Top point (thigh end).
    pub top: [f64; 3],
    /// Where it came from.
    pub source: AxisSource,
}

impl Axis {
    /// Bottom as a point.
    pub fn bottom(&self) -> Point3<f64> {
        Point3::from(self.bottom)
    }

    /// Top as a point.
    pub fn top(&self) -> Point3<f64> {
        Point3::from(self.top)
    }

    /// Distance from bottom to top, metres.
    pub fn length(&self) -> f64 {
        (self.top() - self.bottom()).norm()
    }

    /// Unit vector from bottom to top.
    pub fn direction(&self) -> Vector3<f64> {
        (self.top() - self.bottom()).normalize()
    }
}

/// Where along `axis` (a fraction of its length, of 0.1, 0.5 and 0.9) no loop of the mesh's
/// cross-section goes around it, if anywhere: an axis that leaves the mesh is not a leg's (it
/// misses the leg, or runs between two legs), and a tube around it would not be a stocking.
pub fn leaves_mesh(leg: &Leg, axis: &Axis) -> Option<f64> {
    let fractions = [0.1, 0.5, 0.9];
    let heights = fractions.map(|f| f * axis.length());
    let loops = slice::enclosing_radii(
        &leg.positions,
        &leg.triangles,
        &axis.bottom(),
        &axis.direction(),
        &heights,
    );
    fractions
        .into_iter()
        .zip(loops)
        .find_map(|(f, around)| around.is_none().then_some(f))
}
