//! Stitch shape measurements on a relaxed grid knit, and the two ways a fitted stocking's courses
//! can fail to lie as knitted: slack and sliding.
//!
//! A stitch is a grid cell: points `(w, c)`, `(w+1, c)`, `(w, c+1)`, `(w+1, c+1)`. Its width is the
//! mean length of its two course edges, its height the mean length of its two wale edges, and its
//! aspect ratio width / height (1 for a square stitch at equal rest spacing).
//!
//! *Slack* is local surplus fabric: courses closer together than their rest spacing, where a
//! real stocking wrinkles (over the front of the ankle, where a tube has more fabric than the
//! skin). It is reported, per point and as a region, and never refused. *Sliding* is the fit
//! leaving its place: courses out of order along the stocking's centreline
//! ([`bunched_courses`]), refused beyond [`MAX_BUNCHED_FRACTION`].

use serde::{Deserialize, Serialize};

use crate::base::Direction;
use crate::error::{Error, Result};
use crate::knit::tube::Centreline;
use crate::knit::{Knit, PointId};

/// Summary of the stitch shapes of a knit. Lengths in metres.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StitchStats {
    /// Number of stitches (cells) measured.
    pub stitches: usize,
    /// Mean stitch width (along the course), metres.
    pub mean_width_m: f64,
    /// Mean stitch height (along the wale), metres.
    pub mean_height_m: f64,
    /// Mean aspect ratio width / height.
    pub mean_aspect: f64,
    /// Smallest aspect ratio.
    pub min_aspect: f64,
    /// Largest aspect ratio.
    pub max_aspect: f64,
    /// Coefficient of variation (std / mean) of stitch widths: 0 for a uniform stretch.
    pub width_variation: f64,
    /// Coefficient of variation of stitch heights.
    pub height_variation: f64,
    /// Every stitch's aspect ratio, sorted ascending (not serialised).
    #[serde(skip)]
    pub sorted_aspects: Vec<f64>,
}

/// Measures every cell of an open grid knit. Returns `None` for a knit with no cell.
pub fn measure_stitches(knit: &Knit) -> Option<StitchStats> {
    let x = &knit.particles.x;
    let at = |w: usize, c: usize| x[knit.point(w, c).index()];
    let mut widths = Vec::new();
    let mut heights = Vec::new();
    for c in 0..knit.courses.saturating_sub(1) {
        for w in 0..knit.wales.saturating_sub(1) {
            let width =
                ((at(w + 1, c) - at(w, c)).norm() + (at(w + 1, c + 1) - at(w, c + 1)).norm()) / 2.0;
            let height =
                ((at(w, c + 1) - at(w, c)).norm() + (at(w + 1, c + 1) - at(w + 1, c)).norm()) / 2.0;
            widths.push(width);
            heights.push(height);
        }
    }
    if widths.is_empty() {
        return None;
    }
    let mut aspects: Vec<f64> = widths.iter().zip(&heights).map(|(w, h)| w / h).collect();
    aspects.sort_by(f64::total_cmp);
    let n = widths.len() as f64;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / n;
    let variation = |v: &[f64]| {
        let m = mean(v);
        (v.iter().map(|a| (a - m).powi(2)).sum::<f64>() / n).sqrt() / m
    };
    Some(StitchStats {
        stitches: widths.len(),
        mean_width_m: mean(&widths),
        mean_height_m: mean(&heights),
        mean_aspect: mean(&aspects),
        min_aspect: aspects[0],
        max_aspect: aspects[aspects.len() - 1],
        width_variation: variation(&widths),
        height_variation: variation(&heights),
        sorted_aspects: aspects,
    })
}

/// Asymmetry between two patches stretched by the same factor, one along the course and one
/// along the wale: the RMS difference between the sorted log aspect ratios of the first and the
/// sorted log inverse aspect ratios of the second. A knit that responds alike in both directions
/// turns the wale-stretched patch into the transpose of the course-stretched one (for a square
/// patch), giving 0. Dimensionless; 0.01 is a 1% difference in stitch shape.
pub fn anisotropy(course_stretched: &StitchStats, wale_stretched: &StitchStats) -> f64 {
    let a = &course_stretched.sorted_aspects;
    // 1/aspect sorted ascending is aspect sorted descending.
    let b = wale_stretched.sorted_aspects.iter().rev();
    let n = a.len().min(wale_stretched.sorted_aspects.len()).max(1) as f64;
    let sum_sq: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x.ln() + y.ln()).powi(2))
        .sum();
    (sum_sq / n).sqrt()
}

/// Courses of a fitted tube that bunched: those whose mean position along `centreline` is not
/// beyond every course before them (the courses slid along the leg past each
/// other). Returns how many, and the first.
///
/// A yarn too tight for the leg slides down it towards the ankle, where it is thinnest, and
/// most of the stocking piles up there. A stocking that fits keeps its courses in order, except
/// at most a small fold just above a slack ankle: on a frictionless leg, the rings' own tension
/// pushes the lower courses down onto the held bottom ring, and where the wales are slack they
/// fold (at 400×1600 on the MakeHuman leg, 3% of the courses; see [`MAX_BUNCHED_FRACTION`]).
pub fn bunched_courses(knit: &Knit, centreline: &Centreline) -> (usize, Option<usize>) {
    let mut furthest = f64::NEG_INFINITY;
    let (mut count, mut first) = (0, None);
    for c in 0..knit.courses {
        let h = centreline.course_along(knit, c);
        if h <= furthest {
            count += 1;
            first.get_or_insert(c);
        }
        furthest = furthest.max(h);
    }
    (count, first)
}

/// How many of `knit`'s courses came to rest below a course before them; refused as
/// [`Error::Bunched`] above [`MAX_BUNCHED_FRACTION`] of them.
pub fn refuse_bunched(
    knit: &Knit,
    centreline: &Centreline,
    circumference_m: f64,
    support_ratio: f64,
) -> Result<usize> {
    let (bunched, first) = bunched_courses(knit, centreline);
    match first.filter(|_| bunched as f64 > MAX_BUNCHED_FRACTION * knit.courses as f64) {
        Some(course) => Err(Error::Bunched {
            course,
            bunched,
            courses: knit.courses,
            place: {
                // Where the courses from the first out of order on came to rest.
                let along: Vec<f64> = (course..knit.courses)
                    .map(|c| centreline.course_along(knit, c))
                    .collect();
                let lo = along.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = along.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                format!(
                    "gathered {:.0}–{:.0} cm along the stocking from its {} end",
                    100.0 * lo.max(0.0),
                    100.0 * hi.max(0.0),
                    if knit.has_toe_seam() { "top" } else { "bottom" }
                )
            },
            ratio: support_ratio,
            circumference_m,
        }),
        None => Ok(bunched),
    }
}

/// The largest fraction of a fit's courses that may be out of order ([`bunched_courses`])
/// before the fit is refused as bunched.
pub const MAX_BUNCHED_FRACTION: f64 = 0.1;

/// A point whose wales are shorter than their rest length by more than this fraction is slack.
pub const SLACK_THRESHOLD: f64 = 0.1;

/// Per point, its slack: how much shorter than their rest length its wale springs are, as a
/// fraction (0 where they are at rest or stretched, 0.3 where the courses are 30% closer than
/// knitted). The `slack` attribute: where the stocking would wrinkle.
pub fn slack(knit: &Knit) -> Vec<f64> {
    let x = &knit.particles.x;
    (0..knit.len())
        .map(|i| {
            let (mut length, mut rest) = (0.0, 0.0);
            for inc in knit.incident(PointId(i as u32)) {
                let s = &knit.springs[inc.spring as usize];
                if s.direction == Direction::Wale {
                    length += (x[s.b.index()] - x[s.a.index()]).norm();
                    rest += s.rest;
                }
            }
            if rest > 0.0 {
                (1.0 - length / rest).max(0.0)
            } else {
                0.0
            }
        })
        .collect()
}

/// Where a fitted stocking is slack (see [`slack`]), for the report.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SlackDetails {
    /// Points slacker than [`SLACK_THRESHOLD`], as a fraction of all points.
    pub fraction_of_points: f64,
    /// The largest slack.
    pub max: f64,
    /// Where the slack points lie along the stocking's centreline, metres from its start
    /// (`None` where no point is slack).
    pub along_m: Option<[f64; 2]>,
    /// The parts of the leg they lie on (`leg`, `heel`, `foot`), where the stocking follows a
    /// path over the foot.
    pub parts: Vec<String>,
}

/// [`SlackDetails`] of `knit` from its per-point `slack`, placed along `centreline`; `part`
/// names the part of the leg at a distance along it, where known.
pub fn slack_details(
    knit: &Knit,
    slack: &[f64],
    centreline: &Centreline,
    part: impl Fn(f64) -> Option<String>,
) -> SlackDetails {
    let slack_points: Vec<usize> = (0..knit.len())
        .filter(|&i| slack[i] > SLACK_THRESHOLD)
        .collect();
    let mut parts: Vec<String> = Vec::new();
    let mut range = [f64::INFINITY, f64::NEG_INFINITY];
    for &i in &slack_points {
        let s = centreline.along(&knit.particles.x[i]);
        range = [range[0].min(s), range[1].max(s)];
        if let Some(name) = part(s) {
            if !parts.contains(&name) {
                parts.push(name);
            }
        }
    }
    SlackDetails {
        fraction_of_points: slack_points.len() as f64 / knit.len().max(1) as f64,
        max: slack.iter().copied().fold(0.0, f64::max),
        along_m: (!slack_points.is_empty()).then_some(range),
        parts,
    }
}
