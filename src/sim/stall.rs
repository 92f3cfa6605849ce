//! Where a fit stopped out of balance, in words, and what to change. The multilevel solver
//! ([`super::multilevel`]) stops a level that is going nowhere ([`LevelStats::stall`],
//! docs/decisions/0049) and marks where a level that ran out of steps had not settled
//! ([`LevelStats::unsettled`]); this reads those courses back onto the stocking and the leg
//! (how far along the stocking, near which landmark) and picks the advice that fits the cause.
//! Each message is one line: it reaches the user as the fit's error or in its report.

use std::borrow::Cow;

use nalgebra::{Point3, Vector3};

use super::accelerated::{LevelStats, OutOfBalance};
use crate::error::Error;
use crate::knit::tube::Centreline;
use crate::knit::Knit;
use crate::leg::{find_landmarks, Axis, AxisSource, Landmarks, Leg, Side};

/// The stocking a stalled or unsettled level belongs to: what places its courses on the leg.
pub struct StockingOnLeg<'a> {
    /// The leg, world space.
    pub leg: &'a Leg,
    /// Which leg was dressed (`leg.side`): where a given axis left the fit no landmarks, they
    /// are found on it to name places.
    pub side: Side,
    /// The stocking's axis, and who placed it.
    pub axis: &'a Axis,
    /// The stocking's centreline, from course 0 to the last course.
    pub centreline: &'a Centreline,
    /// The landmarks it was placed on, if it was.
    pub landmarks: Option<&'a Landmarks>,
    /// The relaxed stocking's circumference, metres.
    pub circumference_m: f64,
    /// The yarns' stiffness.
    pub yarn_stiffness: YarnStiffness,
}

/// The two yarns' stiffness (`yarns.nylon.stiffness`, `yarns.support.stiffness`): what the
/// advice of a stalled or bunched fit names.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct YarnStiffness {
    /// The nylon's.
    pub nylon: f64,
    /// The support yarn's.
    pub support: f64,
}

impl YarnStiffness {
    /// Support yarn's stiffness over nylon's.
    pub fn support_ratio(self) -> f64 {
        self.support / self.nylon
    }
}

impl StockingOnLeg<'_> {
    /// The landmarks, or where a given axis left the fit none, the leg's own: what names a
    /// place.
    fn named_landmarks(&self) -> Option<Cow<'_, Landmarks>> {
        match self.landmarks {
            Some(l) => Some(Cow::Borrowed(l)),
            None => find_landmarks(
                &self.leg.positions,
                &self.leg.triangles,
                self.leg.up,
                self.side,
                self.leg.rig.as_ref(),
            )
            .ok()
            .map(Cow::Owned),
        }
    }
}

/// Below this many points around, a grid's rings are polygons coarse enough to catch on a knee
/// (a heavy knee is about 40 cm around: 1.6 cm a side at 24).
const COARSE_GRID_WALES: usize = 40;

/// Where a level of `courses` courses has each along its fabric: the knit's relaxed places
/// where it is that level (a graded grid's courses crowd over the toe's tip), else evenly.
fn course_places(knit: &Knit, courses: usize) -> Vec<f64> {
    match knit.courses == courses && knit.is_graded() {
        true => knit.course_places(),
        false => (0..courses).map(|c| c as f64).collect(),
    }
}

/// Where on the stocking a level's courses stopped out of balance, in words.
struct PlaceInWords {
    /// The courses, and how far along the stocking they lie: "courses 140–148 of 150 (70–75 cm
    /// down the stocking from its top)".
    courses: String,
    /// The worst point's height and nearest landmark (", worst 2 cm above the sole, at the
    /// foot"); empty without landmarks.
    worst: String,
    /// True for a stocking to the toe (knitted from its welt down: course 0 is its top).
    to_the_toe: bool,
    /// True where the worst point is nearest the foot, or no landmark names it.
    at_foot: bool,
}

impl PlaceInWords {
    /// Where the courses of `at` lie on a stocking along `axis` and `centreline`, named by
    /// `landmarks`, a level's courses lying at `places` along its fabric.
    fn of(
        axis: &Axis,
        centreline: &Centreline,
        landmarks: Option<&Landmarks>,
        places: &[f64],
        at: &OutOfBalance,
    ) -> PlaceInWords {
        let courses = places.len();
        let total = places.last().copied().filter(|&p| p > 0.0).unwrap_or(1.0);
        let place = |c: usize| places.get(c).copied().unwrap_or(total);
        let [from, to] = at.courses.map(|c| place(c) / total * centreline.length());
        let to_the_toe = centreline.length() > axis.length() + 1e-9;
        let [first, last] = at.courses;
        let along = format!(
            "{} of {courses} ({:.0}–{:.0} cm {})",
            if first == last {
                format!("course {first}")
            } else {
                format!("courses {first}–{last}")
            },
            100.0 * from,
            100.0 * to,
            if to_the_toe {
                "down the stocking from its top"
            } else {
                "up the stocking from its bottom end"
            }
        );
        let Some(l) = landmarks else {
            return PlaceInWords {
                courses: along,
                worst: String::new(),
                to_the_toe,
                at_foot: true,
            };
        };
        let worst = Point3::from(at.worst_point);
        let up = Vector3::from(l.up);
        let height = worst.coords.dot(&up) - l.sole_s();
        let named = [
            ("the foot", l.sole_s()),
            ("the ankle", l.ankle.s),
            ("the knee", l.knee.s),
            ("the top of the thigh", l.thigh_top.s),
        ];
        let (name, _) = named
            .iter()
            .min_by(|a, b| {
                let d = |s: f64| (worst.coords.dot(&up) - s).abs();
                d(a.1).total_cmp(&d(b.1))
            })
            .expect("four landmarks");
        PlaceInWords {
            courses: along,
            worst: format!(
                ", worst {:.0} cm above the sole, at {name}",
                (100.0 * height).max(0.0)
            ),
            to_the_toe,
            at_foot: *name == "the foot",
        }
    }
}

/// Where a `level` that ran out of steps had not settled, in words, `at` the place of
/// `unsettled`: the courses whose force step was above the `tolerance`, and whether the residual
/// was within it (only those courses had not settled); or the grid as a whole, where no point
/// was above it and only the residual was.
fn unsettled_words(
    at: &PlaceInWords,
    unsettled: &OutOfBalance,
    level: &LevelStats,
    tolerance: f64,
) -> String {
    if unsettled.worst_force_step <= tolerance {
        return format!(
            "no course stood out: the residual over the whole grid, {:.1e}, was above the \
             tolerance",
            level.residual
        );
    }
    let residual = match level.residual < tolerance {
        true => format!(
            "; the residual, {:.1e}, was within the tolerance, their largest force step, {:.1e}, \
             was not",
            level.residual, unsettled.worst_force_step
        ),
        false => String::new(),
    };
    format!("{} had not settled{}{residual}", at.courses, at.worst)
}

impl StockingOnLeg<'_> {
    /// Where `level` of `knit` (the grid asked for) had not settled when it ran out of steps,
    /// `unsettled` the place the solver marked, with `tolerance` asked for.
    pub fn unsettled(
        &self,
        knit: &Knit,
        level: &LevelStats,
        unsettled: &OutOfBalance,
        tolerance: f64,
    ) -> String {
        let named = self.named_landmarks();
        let places = course_places(knit, level.courses);
        let at = PlaceInWords::of(
            self.axis,
            self.centreline,
            named.as_deref(),
            &places,
            unsettled,
        );
        unsettled_words(&at, unsettled, level, tolerance)
    }

    /// The error of a fit stopped as futile on `level` (whose knit, or the finer one it was to
    /// start, is `knit`): where along the stocking its courses are out of balance, near which
    /// landmark, and what to change.
    pub fn stalled(&self, knit: &Knit, level: &LevelStats) -> Error {
        self.stalled_at(level, &course_places(knit, level.courses))
    }

    /// [`StockingOnLeg::stalled`] of a level whose courses lie at `places` along its fabric.
    pub(crate) fn stalled_at(&self, level: &LevelStats, places: &[f64]) -> Error {
        let (leg, axis) = (self.leg, self.axis);
        let named = self.named_landmarks();
        let landmarks = named.as_deref();
        let stall = level.stall.expect("a stalled level says where");
        let at = PlaceInWords::of(axis, self.centreline, landmarks, places, &stall);
        let place = format!("{} are out of balance{}", at.courses, at.worst);
        let (to_the_toe, at_foot) = (at.to_the_toe, at.at_foot);
        let circumference = self.circumference_m;
        let advice = match (landmarks, axis.source) {
            (Some(l), _) if circumference < 0.5 * l.ankle.girth_m => format!(
                "The stocking is far too small for this leg: relaxed {circumference} m around, \
                 against an ankle of {:.3} m; raise tube.relaxed_circumference_m.",
                l.ankle.girth_m
            ),
            (Some(_), _) if to_the_toe && at_foot => {
                "The foot of the stocking cannot settle on this foot (look for debris or a broken \
                 surface there): end the stocking at the ankle (--bottom ankle), or try another grid \
                 (--resolution)."
                    .to_string()
            }
            (_, AxisSource::CommandLine | AxisSource::Scene) if at_foot => {
                let flag = axis.source.describe();
                let ankle = landmarks.map_or(String::new(), |l| {
                    let at = leg.file_from_world(&Point3::from(l.ankle.centre));
                    format!(
                        " (here about {:.3}, {:.3}, {:.3} in the file)",
                        at.x, at.y, at.z
                    )
                });
                format!(
                    "Check {flag}: a straight stocking cannot be pulled over a foot, so its bottom \
                     belongs at the ankle{ankle}; leave {flag} out and knitfit places the stocking on \
                     the leg's landmarks."
                )
            }
            (_, AxisSource::CommandLine | AxisSource::Scene) => format!(
                "Check {}: the stocking cannot settle around it here; leave it out and knitfit \
                 places the stocking on the leg's landmarks.",
                axis.source.describe()
            ),
            _ if self.yarn_stiffness.support >= 100.0 * self.yarn_stiffness.nylon => format!(
                "The support yarn ({}× nylon's) barely stretches: lower yarns.support.stiffness, or \
                 raise tube.relaxed_circumference_m (now {circumference} m).",
                self.yarn_stiffness.support_ratio()
            ),
            _ if level.wales < COARSE_GRID_WALES => format!(
                "The {} grid is coarse for this leg: its rings are polygons whose corners catch \
                 on it; give a finer grid (--resolution, tube.wales and tube.courses).",
                level.grid()
            ),
            _ => "The leg is too thin or bent here for the stocking: end it lower (tube.top), or \
                  raise tube.relaxed_circumference_m."
                .into(),
        };
        Error::Stalled {
            grid: level.grid().to_string(),
            iterations: level.iterations,
            seconds: level.seconds,
            residual: level.residual,
            place,
            advice,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_graded_grids_courses_are_placed_along_its_fabric_in_words() {
        // Courses crowding towards the end: the last three lie in the last 10 cm of a metre,
        // not the last 29 as their index would say.
        let axis = Axis {
            bottom: [0.0, 0.0, 0.0],
            top: [0.0, 1.0, 0.0],
            source: AxisSource::Scene,
        };
        let places = [0.0, 0.2, 0.4, 0.6, 0.8, 0.9, 0.95, 1.0];
        let at = OutOfBalance {
            courses: [5, 7],
            worst_point: [0.0, 0.9, 0.0],
            worst_force_step: 0.1,
        };
        let words = PlaceInWords::of(&axis, &Centreline::straight(&axis), None, &places, &at);
        assert_eq!(
            words.courses,
            "courses 5–7 of 8 (90–100 cm up the stocking from its bottom end)"
        );
    }

    #[test]
    fn a_grid_out_of_steps_says_which_courses_had_not_settled_and_whether_the_residual_did() {
        let at = PlaceInWords {
            courses: "courses 297–299 of 300 (73–74 cm down the stocking from its top)".into(),
            worst: ", worst 1 cm above the sole, at the foot".into(),
            to_the_toe: true,
            at_foot: true,
        };
        let unsettled = OutOfBalance {
            courses: [297, 299],
            worst_point: [0.0; 3],
            worst_force_step: 1.5e-3,
        };
        let level = |residual: f64| LevelStats {
            wales: 300,
            courses: 300,
            iterations: 15_000,
            polish_iterations: 0,
            restarts: 30,
            stall_restarts: 0,
            start_residual: 0.2,
            residual,
            force_step: 1.5e-3,
            max_move: 0.01,
            converged: false,
            stall: None,
            unsettled: Some(unsettled),
            seconds: 20.0,
        };
        let corner = unsettled_words(&at, &unsettled, &level(3.8e-5), 1e-4);
        assert_eq!(
            corner,
            "courses 297–299 of 300 (73–74 cm down the stocking from its top) had not settled, \
             worst 1 cm above the sole, at the foot; the residual, 3.8e-5, was within the \
             tolerance, their largest force step, 1.5e-3, was not"
        );
        let both = unsettled_words(&at, &unsettled, &level(2e-4), 1e-4);
        assert!(both.ends_with("at the foot"), "{both}");
        // No point above the tolerance: the grid as a whole, not the worst point's course.
        let calm = OutOfBalance {
            worst_force_step: 5e-5,
            ..unsettled
        };
        let whole = unsettled_words(&at, &calm, &level(2e-4), 1e-4);
        assert!(
            whole.starts_with("no course stood out") && !whole.contains("297"),
            "{whole}"
        );
    }
}
