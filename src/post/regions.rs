//! The parts of the leg a fitted stocking covers (toe, foot, heel, ankle, calf, knee, thigh),
//! and how much the knit is stretched on each: what a hosiery designer reads off a fit.
//!
//! Each course is given a region by where it came to rest: its mean point's place along the
//! stocking's centreline names the part of the path (leg, heel fan, foot), and on the leg its
//! height against the landmarks (ankle band up to [`ANKLE_BAND_M`] above the heel's fan, knee
//! within [`KNEE_BAND_M`] of the knee); on the foot, the last [`TOE_LENGTH_M`] before the toe tip
//! is the toe. A short row's points take the region of the course they were knitted above.
//! Stretch is the knit's own (`_STRETCH_COURSE`, `_STRETCH_WALE`: length over rest length), so
//! it is the same fabric's at any grid size.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::base::PerDirection;
use crate::knit::path::{PathPart, TubePath};
use crate::knit::tube::{part_at, Centreline};
use crate::knit::{Knit, PointId};
use crate::leg::Landmarks;

/// Height of the ankle band above the heel's fan (or above an open tube's bottom), metres.
pub const ANKLE_BAND_M: f64 = 0.06;
/// Half the height of the knee band, metres.
pub const KNEE_BAND_M: f64 = 0.05;
/// Length of the toe before the toe tip, metres.
pub const TOE_LENGTH_M: f64 = 0.05;

/// A part of the leg.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Region {
    /// The last few centimetres of the foot.
    Toe,
    /// The foot from the heel to the toe.
    Foot,
    /// The heel and the instep: the fan of courses from the leg to the foot.
    Heel,
    /// Just above the heel.
    Ankle,
    /// From the ankle to the knee.
    Calf,
    /// Around the knee.
    Knee,
    /// Above the knee.
    Thigh,
}

impl Region {
    /// Every region, toe to thigh.
    pub const ALL: [Region; 7] = [
        Region::Toe,
        Region::Foot,
        Region::Heel,
        Region::Ankle,
        Region::Calf,
        Region::Knee,
        Region::Thigh,
    ];
}

/// The stretch of one region.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionStretch {
    /// The region.
    pub region: Region,
    /// Knit points in it.
    pub points: usize,
    /// Mean stretch along the course (around the leg): 1 at rest.
    pub course: f64,
    /// Mean stretch along the wale (along the leg).
    pub wale: f64,
    /// Mean of the two multiplied: how much larger each stitch's area is than knitted.
    pub area: f64,
    /// The largest area stretch in the region.
    pub max_area: f64,
}

/// The region of every point of `knit` (module docs).
pub fn regions(
    knit: &Knit,
    centreline: &Centreline,
    path: Option<&TubePath>,
    landmarks: &Landmarks,
) -> Vec<Region> {
    let up = Vector3::from(landmarks.up);
    let heel_top = path.map(|p| {
        let [start, _] = p.heel_range();
        p.frame_at(start).0.coords.dot(&up)
    });
    let ankle_top = heel_top.unwrap_or(landmarks.ankle.s) + ANKLE_BAND_M;
    let toe = landmarks
        .foot
        .map(|f| (Vector3::from(f.toe_tip), Vector3::from(f.direction)));
    let of_course: Vec<Region> = (0..knit.courses)
        .map(|c| {
            let ring = &knit.particles.x[c * knit.wales..(c + 1) * knit.wales];
            let mean = ring.iter().sum::<Vector3<f64>>() / knit.wales as f64;
            let part = path.map_or(PathPart::Leg, |p| part_at(p, centreline.along(&mean)));
            let height = mean.dot(&up);
            match part {
                PathPart::Foot => match toe {
                    Some((tip, forward)) if (tip - mean).dot(&forward) < TOE_LENGTH_M => {
                        Region::Toe
                    }
                    _ => Region::Foot,
                },
                PathPart::Heel => Region::Heel,
                PathPart::Leg if height < ankle_top => Region::Ankle,
                PathPart::Leg if height < landmarks.knee.s - KNEE_BAND_M => Region::Calf,
                PathPart::Leg if height < landmarks.knee.s + KNEE_BAND_M => Region::Knee,
                PathPart::Leg => Region::Thigh,
            }
        })
        .collect();
    (0..knit.len())
        .map(|i| {
            let course = knit.fabric_coords(PointId(i as u32))[1] as usize;
            of_course[course.min(knit.courses - 1)]
        })
        .collect()
}

/// Mean stretch of each region that has points, toe to thigh, from the per-point `stretch`
/// along the course and the wale.
pub fn stretch_by_region(
    regions: &[Region],
    stretch: &PerDirection<Vec<f64>>,
    fabric_shares: Option<&[f64]>,
) -> Vec<RegionStretch> {
    let (stretch_course, stretch_wale) = (&stretch.course, &stretch.wale);
    // Each point weighs the fabric it stands for (a graded grid's toe tip has more, smaller
    // cells); alike on an even grid.
    let share = |i: usize| fabric_shares.map_or(1.0, |s| s[i]);
    Region::ALL
        .iter()
        .filter_map(|&region| {
            let points: Vec<usize> = (0..regions.len())
                .filter(|&i| regions[i] == region)
                .collect();
            if points.is_empty() {
                return None;
            }
            let n: f64 = points.iter().map(|&i| share(i)).sum();
            let mean = |value: &dyn Fn(usize) -> f64| {
                points.iter().map(|&i| share(i) * value(i)).sum::<f64>() / n
            };
            let area = |i: usize| stretch_course[i] * stretch_wale[i];
            Some(RegionStretch {
                region,
                points: points.len(),
                course: mean(&|i| stretch_course[i]),
                wale: mean(&|i| stretch_wale[i]),
                area: mean(&area),
                max_area: points.iter().map(|&i| area(i)).fold(0.0, f64::max),
            })
        })
        .collect()
}
