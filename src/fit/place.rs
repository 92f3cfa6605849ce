//! Where the stocking goes on a leg: the leg's landmarks ([`crate::leg::landmarks`]), the
//! stocking's axis, given or placed on them by `tube.bottom` and `tube.top`
//! ([`crate::knit::tube::tube_axis`]), and for a stocking to the toe its path down the leg,
//! around the heel and along the foot ([`crate::knit::path`]). The stages
//! [`Stage::FindLandmarks`] and [`Stage::FindAxis`] of a fit; `knitfit plan` runs the same, so a
//! plan shows what the fit will dress or refuses what it will refuse.
//!
//! An axis is only a stocking's if the leg goes around it ([`leaves_mesh`]): one typed with a
//! wrong coordinate, or between two legs, is refused rather than fitted onto air.

use nalgebra::{Point3, Vector3};

use crate::base::settings::Invalid;
use crate::error::{Error, Result};
use crate::knit::path::{path_to_toe, TubePath};
use crate::knit::tube::{tube_axis, Centreline};
use crate::knit::{TubeBottom, TubeSettings};
use crate::leg::{
    find_landmarks, leaves_mesh, Axis, AxisSource, Landmarks, Leg, LegAxis, NoLandmarks, Side,
    UpFrom,
};
use crate::stage::{timed, Stage, StageTimes};

/// What the place stage reads of the scene: the leg's `axis` (if given, and who gave it) and its
/// `side`; the rest is the tube's (`tube.bottom`, `tube.top`, and its grid, which a stocking to
/// the toe must not be too coarse for).
#[derive(Clone, Debug, PartialEq)]
pub struct PlaceSettings {
    /// `leg.axis`, in the leg file's coordinates, and whether the scene or `--axis` set it;
    /// `None` places the stocking on the leg's landmarks.
    pub axis: Option<(LegAxis, AxisSource)>,
    /// `leg.side`: which leg to dress where the file holds both.
    pub side: Side,
}

/// Where a fit's stocking goes: the landmarks it was placed on, its axis, and for a stocking to
/// the toe its path over the foot.
#[derive(Clone, Debug)]
pub struct Placement {
    /// The leg's landmarks (none where the scene gives the axis).
    pub landmarks: Option<Landmarks>,
    /// The stocking's axis (to the toe: its leg part, from the ankle up).
    pub axis: Axis,
    /// The path of a stocking to the toe.
    pub path: Option<TubePath>,
    /// The stocking's centreline, from course 0 to the last course: the path's, or the axis.
    pub centreline: Centreline,
    /// Which leg was dressed (`leg.side`; a file with one leg has it dressed whatever its side).
    pub side: Side,
}

impl Placement {
    /// The direction the held end ring(s) may not move along: the path's at the welt, or the
    /// axis's.
    pub fn lock_axis(&self) -> Vector3<f64> {
        match &self.path {
            Some(path) => path.stations[0].t,
            None => self.axis.direction(),
        }
    }
}

/// Finds the landmarks of `leg` where `place` gives no axis, places the stocking's axis, and
/// for a stocking to the toe its path; timed as [`Stage::FindLandmarks`] and
/// [`Stage::FindAxis`] in `times`.
///
/// Errors: [`Error::Leg`] when the landmarks cannot be found, the axis cannot be placed on them,
/// the leg does not go around it, or the stocking cannot be taken to the toe;
/// [`Error::Settings`] for a grid too coarse for a stocking to the toe, or one to the toe on a
/// given axis.
pub fn place(
    leg: &Leg,
    place: &PlaceSettings,
    tube: &TubeSettings,
    times: &mut dyn StageTimes,
) -> Result<Placement> {
    let landmarks = match place.axis {
        Some(_) => None,
        None => Some(timed(times, Stage::FindLandmarks, || {
            find_landmarks(
                &leg.positions,
                &leg.triangles,
                leg.up,
                place.side,
                leg.rig.as_ref(),
            )
            .map_err(|no| {
                // Read only where up is in doubt: turning it over is advice only if that way
                // up shows a leg.
                let leg_the_other_way = no.up_in_doubt
                    && find_landmarks(
                        &leg.positions,
                        &leg.triangles,
                        -leg.up,
                        place.side,
                        leg.rig.as_ref(),
                    )
                    .is_ok();
                Error::Leg {
                    path: leg.path.clone(),
                    message: format!(
                        "cannot find the leg's landmarks: {}",
                        advised(&no, leg, leg_the_other_way)
                    ),
                }
            })
        })?),
    };
    let (axis, path) = timed(times, Stage::FindAxis, || -> Result<_> {
        let axis = choose_axis(leg, place, tube, landmarks.as_ref())?;
        let path = match (tube.bottom, &landmarks) {
            (Some(TubeBottom::Ankle), _) => None,
            // A given axis is a straight tube's (a scene's validation refuses this too).
            (Some(TubeBottom::Toe), None) => return Err(Error::Settings(toe_on_a_given_axis())),
            (None, None) => None,
            // Absent: to the toe where the leg has a foot.
            (None, Some(l)) if l.foot.is_none() => None,
            (_, Some(l)) => Some(stocking_path(leg, tube, l)?),
        };
        Ok((axis, path))
    })?;
    let centreline = match &path {
        Some(path) => Centreline::of_path(path),
        None => Centreline::straight(&axis),
    };
    Ok(Placement {
        landmarks,
        axis,
        path,
        centreline,
        side: place.side,
    })
}

/// What was seen instead of a leg, and where up is in doubt, the way out that fits how up was
/// chosen ([`Leg::up_chosen`]): an up `auto` chose can be overruled by naming the file's axis;
/// a given one can be left to the anatomy. Never the advice to do what the user already did,
/// nor to turn up over where `leg_the_other_way` says that shows no leg either (a kneeling
/// body: its hands read as feet one way up, its shins lying on the floor the other).
fn advised(no: &NoLandmarks, leg: &Leg, leg_the_other_way: bool) -> String {
    if !no.up_in_doubt {
        return no.seen.clone();
    }
    if !leg_the_other_way {
        return format!(
            "{}; nor does the other way up show a leg: a character that kneels, sits or lies \
             is read only with its rig (export it with its skin, or fit it standing); else give \
             the part to dress with --axis",
            no.seen
        );
    }
    match leg.up_from {
        UpFrom::Anatomy | UpFrom::Convention => format!(
            "{}: up may be the wrong way (leg.up_axis {}): if the file's up is another axis, \
             name it with leg.up_axis (--up-axis)",
            no.seen,
            leg.up_chosen()
        ),
        UpFrom::Given => format!(
            "{}: up may be the wrong way; leg.up_axis (--up-axis) gives it as the file's {}: \
             give the file's real up axis, or \"auto\" to find it from the anatomy",
            no.seen,
            leg.up_axis.name()
        ),
    }
}

/// The axis from `place` (converted from file coordinates), or placed on the landmarks by
/// `tube.bottom` and `tube.top`; refused where the leg does not go around it.
fn choose_axis(
    leg: &Leg,
    place: &PlaceSettings,
    tube: &TubeSettings,
    landmarks: Option<&Landmarks>,
) -> Result<Axis> {
    let fail = |message: String| Error::Leg {
        path: leg.path.clone(),
        message,
    };
    let axis = match (&place.axis, landmarks) {
        (Some((given, source)), _) => {
            let bottom = leg.world_from_file(&Point3::from(given.bottom));
            let top = leg.world_from_file(&Point3::from(given.top));
            Axis {
                bottom: bottom.coords.into(),
                top: top.coords.into(),
                source: *source,
            }
        }
        (None, Some(landmarks)) => {
            let bottom = tube.bottom.unwrap_or(TubeBottom::Ankle);
            tube_axis(landmarks, bottom, tube.top).map_err(fail)?
        }
        (None, None) => unreachable!("landmarks are found whenever no axis is given"),
    };
    if let Some(at) = leaves_mesh(leg, &axis) {
        // A given axis is the user's to check; one placed on the landmarks is straight from
        // ankle to thigh, and leaves a leg that bends between them.
        let why = match axis.source {
            AxisSource::Landmarks => "the leg bends between its ankle and its thigh more than a \
                 straight stocking allows, and was not straightened from its sections (they show \
                 no knee or ankle to straighten it at): fit it standing straight, \
                 export it with a rig that poses it, or give the part to dress with --axis \
                 (knitfit plan prints the landmarks)"
                .to_string(),
            _ => format!(
                "it misses the leg, or runs between two legs; check its coordinates (file \
                 units, {} up)",
                leg.up_axis.name()
            ),
        };
        return Err(fail(format!(
            "{} runs outside the leg {:.0}% of the way from its bottom end to its top: {why}",
            axis.source.describe(),
            100.0 * at,
        )));
    }
    Ok(axis)
}

/// The path of a stocking to the toe on `landmarks`, its top where `tube.top` puts it.
fn stocking_path(leg: &Leg, tube: &TubeSettings, landmarks: &Landmarks) -> Result<TubePath> {
    let fail = |message: String| Error::Leg {
        path: leg.path.clone(),
        message: format!(
            "cannot take the stocking to the toe: {message}; or set tube.bottom to \"ankle\" \
             (--bottom ankle) for a stocking that ends there"
        ),
    };
    tube.check_to_the_toe()
        .map_err(|invalid| Error::Settings(invalid.within("tube")))?;
    let axis = tube_axis(landmarks, TubeBottom::Toe, tube.top).map_err(fail)?;
    let top_s = axis.top().coords.dot(&Vector3::from(landmarks.up));
    path_to_toe(landmarks, top_s, &leg.positions, &leg.triangles).map_err(fail)
}

/// The refusal of a stocking to the toe on a given axis: a straight tube cannot follow the
/// foot. The scene's validation and [`place`] both refuse it.
pub fn toe_on_a_given_axis() -> Invalid {
    Invalid::new(
        "tube.bottom",
        "\"toe\" follows the leg's landmarks, but leg.axis gives a straight tube; set \
         tube.bottom to \"ankle\", or leave leg.axis out",
    )
    .with(&["leg.axis"])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::leg::UpAxis;

    #[test]
    fn the_advice_on_up_is_the_way_out_the_user_has_not_taken() {
        let mut leg = Leg::from_world("leg.glb".into(), &[], &[]);
        let upside_down = NoLandmarks {
            seen: "the leg found narrows upwards".into(),
            up_in_doubt: true,
        };
        // Up found from the anatomy: name the file's own up axis, not "auto" again.
        leg.up_axis = UpAxis::PosZ;
        leg.up_from = UpFrom::Anatomy;
        let found = advised(&upside_down, &leg, true);
        assert!(
            found.starts_with("the leg found narrows upwards: "),
            "{found}"
        );
        assert!(
            found.contains("now \"auto\", which found +z from the anatomy"),
            "{found}"
        );
        assert!(!found.contains("or \"auto\""), "{found}");
        // Up given: leaving it to the anatomy is a way out.
        leg.up_axis = UpAxis::NegY;
        leg.up_from = UpFrom::Given;
        let given = advised(&upside_down, &leg, true);
        assert!(given.contains("gives it as the file's -y"), "{given}");
        assert!(
            given.contains("\"auto\" to find it from the anatomy"),
            "{given}"
        );
        // Up taken by glTF's convention, the shape not clear: name the file's axis; "auto"
        // is what gave it.
        leg.up_axis = UpAxis::PosY;
        leg.up_from = UpFrom::Convention;
        let convention = advised(&upside_down, &leg, true);
        assert!(
            convention.contains("which took +y, glTF's convention"),
            "{convention}"
        );
        assert!(
            convention.contains("name it with leg.up_axis"),
            "{convention}"
        );
        assert!(!convention.contains("or \"auto\""), "{convention}");
        // Where the other way up shows no leg either, turning it over is no way out.
        let neither = advised(&upside_down, &leg, false);
        assert!(
            neither.contains("nor does the other way up show a leg"),
            "{neither}"
        );
        assert!(!neither.contains("up may be the wrong way"), "{neither}");
        // What does not put up in doubt is said as seen.
        let other = NoLandmarks::from("no closed cross-section");
        assert_eq!(advised(&other, &leg, true), "no closed cross-section");
    }
}
