//! A leg posed without its rig (a baked pose: a stride, a bent knee, a pointed foot) read through
//! its own joints: the geometry's rest pose, standing straight, where the stocking is fitted
//! before it is carried into the pose as a rigged leg's is ([`crate::fit::pose`]).
//!
//! Method, one bone at a time:
//! - **Knee**: the landmarks' sections, taken along up, still go around a leg that leans or
//!   bends moderately, and their centres trace its centreline. The knee is the centre that best
//!   splits them into a shin's line and a thigh's (least squares), 30–70 % of the way up.
//! - **Ankle**: the landmarks'. Where it is in doubt (thinner than a standing leg's, or under
//!   [`LOWEST_ANKLE_M`] above the sole: a foot pointed down, cut through its toes), the leg is
//!   followed down from its thigh by sections square to its own centreline
//!   ([`super::centreline`]); their narrowest above the heel is the ankle where it lies
//!   [`POINTED_ANKLE_RISE_M`] or more higher, or where the landmarks' is thinner than a standing
//!   leg's (a mannequin's ball joint), in the lowest third of the leg, and the knee is then
//!   read from those sections. An ankle found over [`HIGHEST_STANDING_ANKLE_M`] above the
//!   lowest point with no foot reaching out from it has its foot hanging under it, pointed.
//! - **Turns**: the thigh about the top of the thigh to stand along up (a lone leg's, whose up
//!   its own bent shape tilts, is left as it leans, and the straight leg's up found again); the
//!   shin about the knee to continue it (each the least turn between the two directions); the
//!   foot up about the ankle's hinge (square to the plane of the ankle, toe tip and back of the
//!   heel, which pointing keeps) until its heel and ball stand level, where that takes
//!   [`BENT_DEG`] or more (any turn, for an ankle the shin's own sections put higher or a foot
//!   hanging; none where the ball is not below the heel as posed, or no foot is found).
//! - **Blend**: each vertex of the leg (below the top of the thigh: the piece at the ankle and
//!   the pieces along the limb that touch it, a mannequin's foot, shin, knee ball and thigh;
//!   not the other leg) moves by its bones' turns blended as linear blend skinning blends them,
//!   weighted by smoothsteps across a band at each joint (the ankle's placed at rest, as a rig's
//!   weights are painted, so a pointed foot's raised heel is the foot's); the rest of the body
//!   stays. The matrix back to the pose is each vertex's blend inverted, so carrying the rest
//!   mesh by it gives the file's mesh exactly.
//!
//! Contract: `None` where the leg is standing straight enough (the axis from the ankle to the top
//! of the thigh stays inside it, and the knee, the thigh and a pointed foot bend less than
//! [`BENT_DEG`]), or where its joints cannot be trusted: its landmarks not found as posed, an
//! ankle thinner than a standing leg's (a section through a pointed foot's toes) that the shin's
//! own sections do not place, no knee where a knee can be, a foot found so that no turn up to
//! [`MAX_FOOT_TURN_DEG`] stands flat, the straightened leg not read as standing around its
//! straight axis, or not as long as the posed one along its bones (and where no triangle lies
//! below the thigh top, or a vertex's blend cannot be inverted). The fit then reads the leg as it
//! is and says what it saw. An error instead where the shin's own sections put the ankle
//! [`POINTED_ANKLE_RISE_M`] or more above the one sections along up found, or the foot hangs
//! (it points down), and the foot cannot be levelled or the straightened leg is not read as
//! standing: read as posed, its stocking would end in the foot, toes bare.

use nalgebra::{Matrix4, Point3, Rotation3, Translation3, Unit, Vector3};
use serde::Serialize;

use super::centreline::{Skin, Station};
use super::landmarks::{anatomical_up, find_landmarks, BodyUp, Landmarks, MIN_STANDING_GIRTH_M};
use super::solid::{touching_groups, triangle_pieces};
use super::UpFrom;
use super::{leaves_mesh, Axis, AxisSource, Leg, RestPose, Side};

/// A leg whose thigh leans off up, or whose knee bends, more than this, degrees, is fitted
/// straightened: a straight stocking pulled onto it would bunch on one side.
pub const BENT_DEG: f64 = 20.0;
/// The shin's share of the leg from the ankle to the top of the thigh where a knee can be: an
/// adult's is about half. A bend's apex outside it is not a knee (a pointed foot's sections).
const KNEE_SHARE: std::ops::RangeInclusive<f64> = 0.3..=0.7;
/// How far the straightened leg's length from its ankle to the top of its thigh may differ from
/// the posed one's along its bones, as a fraction.
const SAME_LENGTH: f64 = 0.1;
/// Half the band across the knee over which a vertex's weight goes from the thigh to the shin,
/// as a fraction of the knee's radius.
const KNEE_BAND: f64 = 1.0;
/// The narrowest a joint's band may be, metres: a section of no girth does not make the
/// weights 0/0.
const MIN_JOINT_BAND_M: f64 = 0.01;
/// The band below the top of the thigh over which the leg's weight goes from the body's to the
/// thigh's, metres.
const HIP_BAND_M: f64 = 0.08;
/// An ankle the sections along up found lower than this above the sole, metres, may be a
/// section through a pointed foot: a standing adult's narrowest ankle is 7–12 cm up.
pub const LOWEST_ANKLE_M: f64 = 0.05;
/// The shin's own sections put the ankle this much higher than the sections along up did,
/// metres, where those cut a pointed foot: a standing leg's two ankles are within a centimetre
/// or two.
pub const POINTED_ANKLE_RISE_M: f64 = 0.04;
/// The highest a standing leg's ankle lies above its lowest point, metres (an adult's, 7–15 cm):
/// one higher, with no foot reaching out below it, has its foot pointed down under it.
pub const HIGHEST_STANDING_ANKLE_M: f64 = 0.2;
/// An ankle lies in this lowest share of the leg from the sole to the top of the thigh, as the
/// landmarks look for it.
const ANKLE_SHARE: f64 = 1.0 / 3.0;
/// The leg is followed down from the top of its thigh towards the centre of its section this
/// far below, metres.
const START_DROP_M: f64 = 0.15;
/// The shin's ankle is looked for in this lower share of the way followed.
const SHIN_ANKLE_SHARE: f64 = 0.4;
/// The shortest way followed down the leg from the top of its thigh that can reach its ankle,
/// metres: more than a thigh.
const MIN_SHIN_TRACK_M: f64 = 0.3;
/// A foot's ball: its vertices over this share of the way forward from the ankle to the toe
/// tip; its heel: those under [`HEEL_SHARE`] of it (the heel's sole is under the ankle, not
/// behind it).
const BALL_SHARE: f64 = 0.6;
/// See [`BALL_SHARE`].
const HEEL_SHARE: f64 = 0.3;
/// The furthest a pointed foot is turned back up, degrees: a dancer's, on point, is about 90
/// (the ankle's 50 and the foot's arch), which the levelling reads a few degrees over.
pub const MAX_FOOT_TURN_DEG: f64 = 100.0;
/// Turns tried for a pointed foot, evenly from 0 to [`MAX_FOOT_TURN_DEG`], before the level
/// one is narrowed down between two of them.
const FOOT_TURNS_TRIED: usize = 40;
/// A foot's heel lies at least this many of the ankle's radii off the line from the ankle to
/// its toe tip (an adult's, 3 or more; a tube's, under 1).
const FOOT_DEPTH: f64 = 2.0;

/// How the geometry's joints straightened a leg (`report.json`'s `details.pose.bend`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bend {
    /// The knee's bend: the angle between the shin and the thigh's line, degrees.
    pub knee_deg: f64,
    /// The thigh's lean off up, degrees.
    pub thigh_deg: f64,
    /// How far a pointed foot was turned back up about the ankle to stand flat, degrees; 0
    /// where the foot was not turned (and in reports written before the foot was turned).
    #[serde(default)]
    pub foot_deg: f64,
    /// The ankle as posed, world space: its section's centre.
    pub ankle: [f64; 3],
    /// The knee as posed: the section centre the leg was straightened about.
    pub knee: [f64; 3],
    /// The top of the thigh as posed: its section's centre.
    pub thigh_top: [f64; 3],
}

impl Bend {
    /// The straight axis from the ankle to the top of the thigh.
    fn straight_axis(&self) -> Axis {
        Axis {
            bottom: self.ankle,
            top: self.thigh_top,
            source: AxisSource::Landmarks,
        }
    }
}

/// The leg on `side` straightened to stand along up (module docs), with the matrices back to
/// the pose; `None` where it stands straight enough or cannot be read.
///
/// Errors: a foot seen pointed down (the shin's own sections put its ankle
/// [`POINTED_ANKLE_RISE_M`] or more above where sections along up cut the foot, or it hangs
/// under an ankle over [`HIGHEST_STANDING_ANKLE_M`] up) that is not turned back to stand: read
/// as posed, its stocking would end in the foot, open, with the toes bare. The message says
/// what was seen and what to do.
pub fn straightened(leg: &Leg, side: Side) -> Result<Option<(RestPose, Bend)>, String> {
    let up = leg.up;
    let Ok(landmarks) = find_landmarks(&leg.positions, &leg.triangles, up, side, leg.rig.as_ref())
    else {
        return Ok(None);
    };
    // A foot pointed down is cut through its toes by sections along up, which then put the
    // ankle in the foot (thinner than any standing ankle, or lower): the shin's own sections
    // find it where it is. A standing leg's ankle is not followed for: it costs a section of
    // the whole mesh every centimetre.
    let sole_s = landmarks.sole_s();
    let in_doubt = landmarks.ankle.girth_m < MIN_STANDING_GIRTH_M
        || landmarks.ankle.s - sole_s < LOWEST_ANKLE_M;
    let shin = if in_doubt {
        shin_sections(leg, &landmarks)
    } else {
        None
    };
    let rise = |s: &ShinSections| s.ankle.centre.coords.dot(&up) - landmarks.ankle.s;
    let shin_ankle = shin.as_ref().filter(|s| {
        (rise(s) >= POINTED_ANKLE_RISE_M || landmarks.ankle.girth_m < MIN_STANDING_GIRTH_M)
            && rise(s) + landmarks.ankle.s - sole_s < ANKLE_SHARE * (landmarks.thigh_top.s - sole_s)
    });
    // A foot pointed nearly straight down hangs under an ankle the sections along up find
    // where it is: too high above the leg's lowest point for a standing ankle, and the foot too
    // nearly under it to reach out as one.
    let hanging = landmarks.foot.is_none() && landmarks.ankle.s - sole_s > HIGHEST_STANDING_ANKLE_M;
    // Refused only where the foot clearly points down: hanging, or the shin's ankle well above
    // the one sections along up found in the foot, where the leg read as posed would be dressed
    // to there. A thin ankle alone (a mannequin's ball joint) is read as posed where it cannot
    // be straightened, as any leg is.
    let foot_down = hanging || shin_ankle.is_some_and(|s| rise(s) >= POINTED_ANKLE_RISE_M);
    let why = match straighten(leg, side, &landmarks, shin_ankle, foot_down) {
        Ok(straight) => return Ok(straight),
        Err(why) => why,
    };
    let (Some(what_failed), true) = (why.refusal(), foot_down) else {
        return Ok(None);
    };
    let seen = match shin_ankle {
        Some(shin) => format!(
            "the leg's own sections put its ankle {:.3} m above its lowest point, {:.3} m \
             around, where sections along up found one {:.3} m around {:.3} m up, in the foot",
            shin.ankle.centre.coords.dot(&up) - sole_s,
            shin.ankle.girth_m,
            landmarks.ankle.girth_m,
            landmarks.ankle.s - sole_s,
        ),
        None => format!(
            "it hangs {:.3} m below its ankle, {:.3} m around",
            landmarks.ankle.s - sole_s,
            landmarks.ankle.girth_m,
        ),
    };
    Err(format!(
        "its foot points down ({seen}), and {what_failed}: fit the leg standing, export the \
         character with its rig, or give the part to dress with --axis"
    ))
}

/// Why a leg whose joints were read cannot be straightened.
enum Unread {
    /// No turn of its foot up to [`MAX_FOOT_TURN_DEG`] stands it on its heel and its ball.
    Unlevelled,
    /// Its joints do not straighten it into a leg read as standing, as long along its bones.
    Joints,
    /// Below the ankle its own sections found, it goes on along the line to its tip: no foot
    /// (a thin tube's ankle read high), so nothing to turn back.
    NoFoot,
}

impl Unread {
    /// What failed, for the refusal of a foot pointed down; `None` where there is no foot to
    /// refuse, and the leg is read as posed.
    fn refusal(&self) -> Option<&'static str> {
        match self {
            Unread::Unlevelled => {
                Some("it could not be turned back to stand on its heel and its ball")
            }
            Unread::Joints => Some(
                "straightened at the joints its own sections show, it does not read as a \
                 standing leg",
            ),
            Unread::NoFoot => None,
        }
    }
}

/// [`straightened`] once its ankle is known: the landmarks', or `shin_ankle`, the shin's own
/// sections', where those are used; `foot_down` where the foot points down (hanging, or the
/// shin's ankle well above the landmarks') and must be turned back. `Ok(None)` where the leg
/// stands straight enough; the error says why it cannot be read.
fn straighten(
    leg: &Leg,
    side: Side,
    landmarks: &Landmarks,
    shin_ankle: Option<&ShinSections>,
    foot_down: bool,
) -> Result<Option<(RestPose, Bend)>, Unread> {
    let up = leg.up;
    let mut bend = match shin_ankle {
        Some(shin) => bend_through(
            &shin.ankle.centre,
            &Point3::from(landmarks.thigh_top.centre),
            &shin.centres,
            &up,
        ),
        None => bend_of(landmarks, &up),
    }
    .ok_or(Unread::Joints)?;
    let (ankle, knee, top) = (
        Point3::from(bend.ankle),
        Point3::from(bend.knee),
        Point3::from(bend.thigh_top),
    );
    let (thigh, shin_up) = ((top - knee).normalize(), (knee - ankle).normalize());
    // Rest from pose: the thigh turned about its top to stand along up, then the shin about the
    // (turned) knee to continue it. A lone leg's up is found from its own shape, which a bend
    // tilts: its thigh is left as it is and only the knee straightened, and the straight leg's
    // up found again. A body's up is its whole figure's: the thigh is turned to it.
    let lone = landmarks.legs_found == 1 && leg.up_from == UpFrom::Anatomy;
    let thigh_to = if lone { thigh } else { up };
    let thigh_turn = about(&top, &least_turn(&thigh, &thigh_to));
    let knee_then = thigh_turn.transform_point(&knee);
    let shin_then = thigh_turn.transform_vector(&shin_up);
    let shin_turn = about(&knee_then, &least_turn(&shin_then, &thigh_to)) * thigh_turn;
    // The leg: below the top of the thigh along up (where the landmarks found the legs apart,
    // so a hip flexed or stretched does not reach the other leg through the crotch), its
    // pieces along the limb.
    let below_top: Vec<f64> = (leg.positions.iter()).map(|p| (top - p).dot(&up)).collect();
    let limb = [Point3::from(landmarks.sole), ankle, knee, top];
    let reach = landmarks.thigh_top.girth_m / std::f64::consts::TAU;
    let member = leg_vertices(leg, &limb, reach, |i| below_top[i] > 0.0).ok_or(Unread::Joints)?;
    // A foot pointed down is turned back about the ankle until it stands flat: one the shin's
    // own sections show pointed must be (unless it has no foot below); otherwise only where it
    // needs as much turning as a bend straightened.
    let ankle_girth = shin_ankle.map_or(landmarks.ankle.girth_m, |s| s.ankle.girth_m);
    let levelling = foot_turn(
        leg,
        &member,
        &ankle,
        ankle_girth,
        &shin_up,
        &shin_turn,
        &thigh_to,
    );
    let foot = match levelling {
        None if shin_ankle.is_some() || foot_down => return Err(Unread::Unlevelled),
        Some(Levelling::NoFoot) if foot_down => return Err(Unread::NoFoot),
        Some(Levelling::Turn(foot)) if foot_down => Some(foot),
        // A leg ending at its ankle (no foot found) has nothing below it to level.
        _ if landmarks.foot.is_none() => None,
        Some(Levelling::Turn(foot)) => Some(foot).filter(|f| f.degrees >= BENT_DEG),
        _ => None,
    };
    bend.foot_deg = foot.as_ref().map_or(0.0, |f| f.degrees);
    if leaves_mesh(leg, &bend.straight_axis()).is_none()
        && (bend.knee_deg.max(bend.thigh_deg)).max(bend.foot_deg) < BENT_DEG
    {
        return Ok(None);
    }
    let knee_radius = landmarks.knee.girth_m / std::f64::consts::TAU;
    let knee_band = JointBand {
        at: knee,
        // Square to the bisector of the thigh's and shin's lines: the plane between the bones.
        across: (-thigh - shin_up).try_normalize(1e-9).unwrap_or(-up),
        half: (KNEE_BAND * knee_radius).max(MIN_JOINT_BAND_M),
    };
    let rest_from_pose: Vec<Matrix4<f64>> = (leg.positions.iter().enumerate())
        .map(|(i, p)| {
            if !member[i] {
                return Matrix4::identity();
            }
            let on_leg = smoothstep(below_top[i] / HIP_BAND_M);
            let on_shin = knee_band.weight(p);
            let below_knee = match &foot {
                Some(f) => f.blended(&shin_turn, p),
                None => shin_turn,
            };
            let leg_matrix = thigh_turn * (1.0 - on_shin) + below_knee * on_shin;
            Matrix4::identity() * (1.0 - on_leg) + leg_matrix * on_leg
        })
        .collect();
    let world = linear_of(leg);
    let file = world.try_inverse().ok_or(Unread::Joints)?;
    let mut rest_leg = leg.clone();
    rest_leg.rig = None;
    rest_leg.rest = None;
    let mut pose_from_rest = Vec::with_capacity(leg.positions.len());
    let mut moved = 0.0f64;
    for (p, m) in rest_leg.positions.iter_mut().zip(&rest_from_pose) {
        let back = m.try_inverse().ok_or(Unread::Joints)?;
        let rest = m.transform_point(p);
        moved = moved.max((rest - *p).norm());
        *p = rest;
        pose_from_rest.push(file * back * world);
    }
    if lone {
        rest_leg.up = (anatomical_up(&rest_leg.positions, &rest_leg.triangles))
            .filter(BodyUp::clear)
            .map_or(up, |body| body.up);
    }
    let up = rest_leg.up;
    // Straightened, the leg must read as a standing one, around its straight axis; else the
    // fit reads it as posed, and says what it saw.
    let standing = find_landmarks(&rest_leg.positions, &rest_leg.triangles, up, side, None)
        .map_err(|_| Unread::Joints)?;
    let standing_bend = bend_of(&standing, &up).ok_or(Unread::Joints)?;
    let standing_axis = standing_bend.straight_axis();
    if leaves_mesh(&rest_leg, &standing_axis).is_some() {
        return Err(Unread::Joints);
    }
    // The same leg, as long straightened as it was along its bones: else the joints were not
    // the leg's (an ankle read in a pointed foot).
    let along_bones = (knee - ankle).norm() + (top - knee).norm();
    let standing_length = standing_axis.length();
    if (standing_length - along_bones).abs() > SAME_LENGTH * along_bones {
        return Err(Unread::Joints);
    }
    Ok(Some((
        RestPose {
            leg: rest_leg,
            pose_from_rest,
            skin_moved_m: moved,
        },
        bend,
    )))
}

/// The shin's ankle and the centres of the leg's own sections above it.
struct ShinSections {
    ankle: Station,
    /// Section centres from the top of the thigh down to the ankle.
    centres: Vec<Point3<f64>>,
}

/// The leg followed down from the top of its thigh by sections square to its own centreline
/// ([`super::centreline`]): they go round the shin down to the heel, where the foot's sections
/// along up do not; the ankle is the narrowest of them in the lower [`SHIN_ANKLE_SHARE`] of the
/// way, no thinner than a standing leg's. `None` where they stop within [`MIN_SHIN_TRACK_M`].
fn shin_sections(leg: &Leg, landmarks: &Landmarks) -> Option<ShinSections> {
    let top = Point3::from(landmarks.thigh_top.centre);
    let below =
        (landmarks.profile.iter().rev()).find(|r| landmarks.thigh_top.s - r.s >= START_DROP_M)?;
    let down = (Point3::from(below.centre) - top).try_normalize(1e-9)?;
    let skin = Skin::new(&leg.positions, &leg.triangles, &leg.up);
    let stations = skin.follow(&top, &down);
    // A leg's length followed, not a stub.
    let length: f64 = (stations.windows(2))
        .map(|w| (w[1].centre - w[0].centre).norm())
        .sum();
    if length < MIN_SHIN_TRACK_M {
        return None;
    }
    let lower = (stations.len() as f64 * (1.0 - SHIN_ANKLE_SHARE)) as usize;
    let (at, ankle) = (stations.iter().enumerate().skip(lower))
        .filter(|(_, s)| s.girth_m >= MIN_STANDING_GIRTH_M)
        .min_by(|a, b| a.1.girth_m.total_cmp(&b.1.girth_m))?;
    Some(ShinSections {
        ankle: *ankle,
        centres: stations[..=at].iter().map(|s| s.centre).collect(),
    })
}

/// What levelling a foot found.
enum Levelling {
    /// Its ball is not below its heel as posed: it stands.
    Stands,
    /// Nothing below the ankle reaches out of the line to its tip: no foot.
    NoFoot,
    /// The turn that stands it.
    Turn(FootTurn),
}

/// A pointed foot's turn back about the ankle, in the rest pose the shin's turn makes.
struct FootTurn {
    /// Rest from pose for the foot: the shin's turn, then the foot's about the ankle.
    turn: Matrix4<f64>,
    /// The foot's turn, degrees.
    degrees: f64,
    /// Where a vertex goes from the shin's turn to the foot's, in the rest pose.
    band: JointBand,
}

impl FootTurn {
    /// Rest from pose for vertex `p` (posed) below the knee: `shin_turn` and the foot's turn
    /// blended by the band's weight where the foot's turn takes `p`. Weighed at rest, as a rig's
    /// weights are painted: a pointed foot's heel, raised to the ankle's height as posed, is the
    /// foot's wholly.
    fn blended(&self, shin_turn: &Matrix4<f64>, p: &Point3<f64>) -> Matrix4<f64> {
        let w = self.band.weight(&self.turn.transform_point(p));
        shin_turn * (1.0 - w) + self.turn * w
    }
}

/// The band across a joint over which a vertex's weight goes from one bone to the next: the
/// plane through the joint square to `across` (the bisector of the two bones' lines), `half`
/// either side of it.
struct JointBand {
    at: Point3<f64>,
    across: Vector3<f64>,
    half: f64,
}

impl JointBand {
    /// How much of vertex `p` moves with the next bone: 0 to 1 across the band.
    fn weight(&self, p: &Point3<f64>) -> f64 {
        smoothstep(((p - self.at).dot(&self.across) + self.half) / (2.0 * self.half))
    }
}

/// The turn about the ankle that stands the foot flat again: after the shin's turn
/// (`shin_turn`, rest from pose) its heel and the ball of its foot (the lowest of its vertices
/// under [`HEEL_SHARE`] of the way along the foot's line to the toe tip, as posed, and of those
/// over [`BALL_SHARE`] of it) are level along `rest_up`. The foot turns up about the ankle's
/// hinge, square to the shin and to the plane of the ankle, the toe tip and the back of the
/// heel; the least turn that raises the ball, below the heel as posed, to its level is taken
/// ([`Levelling::Stands`] where the ball is not below the heel as posed, [`Levelling::NoFoot`]
/// where the heel lies under [`FOOT_DEPTH`] ankle radii off the line to the toe). `None` where
/// no turn up to [`MAX_FOOT_TURN_DEG`] levels them, or the foot has no toe or heel to level.
fn foot_turn(
    leg: &Leg,
    member: &[bool],
    ankle: &Point3<f64>,
    ankle_girth: f64,
    shin_up: &Vector3<f64>,
    shin_turn: &Matrix4<f64>,
    rest_up: &Vector3<f64>,
) -> Option<Levelling> {
    // The foot: the leg's vertices below the ankle, square to the shin; its tip the furthest.
    let foot: Vec<Point3<f64>> = (leg.positions.iter().zip(member))
        .filter(|&(p, &m)| m && (p - ankle).dot(shin_up) < 0.0)
        .map(|(p, _)| *p)
        .collect();
    let toe = foot
        .iter()
        .max_by(|a, b| (*a - ankle).norm().total_cmp(&(*b - ankle).norm()))?;
    let to_toe = (toe - ankle).try_normalize(1e-9)?;
    let reach = (toe - ankle).norm();
    let along = |p: &Point3<f64>| (p - ankle).dot(&to_toe);
    let half = (ankle_girth / std::f64::consts::TAU).max(MIN_JOINT_BAND_M);
    // The leg's vertices that may move with the foot: those under two of the ankle's radii
    // above it along the shin.
    let lower: Vec<&Point3<f64>> = (leg.positions.iter().zip(member))
        .filter(|&(p, &m)| m && (p - ankle).dot(shin_up) < 2.0 * half)
        .map(|(p, _)| p)
        .collect();
    // The ankle's hinge is square to the foot's own plane, through the ankle, the toe tip and
    // the back of the heel (the vertex near the ankle along the foot's line that lies furthest
    // from that line): turning about it keeps that plane, however far the foot points. (The
    // shin's line and the foot's are nearly one where it points straight down.)
    let off_line = |p: &Point3<f64>| ((p - ankle) - to_toe * along(p)).norm();
    let heel_back = (lower.iter())
        .filter(|p| along(p).abs() < HEEL_SHARE * reach)
        .max_by(|a, b| off_line(a).total_cmp(&off_line(b)))?;
    // A foot reaches out of the line to its toe: its heel lies well off it. A leg that goes on
    // below its ankle along that line (a tube, a stump) has no foot to turn.
    if off_line(heel_back) < FOOT_DEPTH * half {
        return Some(Levelling::NoFoot);
    }
    let hinge = (*heel_back - ankle).cross(&to_toe);
    // Square to the shin, as an ankle's hinge is.
    let hinge = hinge - shin_up * hinge.dot(shin_up);
    // Turned forwards about it, the toe rises towards the shin. Where the foot's line is far
    // enough from the shin's to say which way that is (a foot near standing, whose shin front
    // could lie further from the foot's line than a small heel), the hinge agrees with it.
    let lifts = to_toe.cross(shin_up);
    let hinge = if lifts.norm() > 0.5 && hinge.dot(&lifts) < 0.0 {
        -hinge
    } else {
        hinge
    };
    let ankle_then = shin_turn.transform_point(ankle);
    let hinge = Unit::try_new(shin_turn.transform_vector(&hinge), 1e-9)?;
    let turned = |degrees: f64| {
        let turn = about(
            &ankle_then,
            &Rotation3::from_axis_angle(&hinge, degrees.to_radians()),
        ) * shin_turn;
        // The band at rest: square to the bisector of the turned foot's line and down.
        let across = (turn.transform_vector(&to_toe) - rest_up).try_normalize(1e-9)?;
        Some(FootTurn {
            turn,
            degrees,
            band: JointBand {
                at: ankle_then,
                across,
                half,
            },
        })
    };
    // The heel and the ball, read along the foot's own line as posed so that turning it does
    // not change which vertices they are: the heel the vertices near the ankle along that line
    // (under it, and behind it), the ball those over [`BALL_SHARE`] of the way to the toe tip.
    let heel: Vec<&Point3<f64>> = (lower.iter().copied())
        .filter(|p| along(p) < HEEL_SHARE * reach)
        .collect();
    let ball: Vec<&Point3<f64>> = (lower.iter().copied())
        .filter(|p| along(p) > BALL_SHARE * reach)
        .collect();
    // The ball's height above the heel's, the foot turned `degrees`.
    let ball_over_heel = |degrees: f64| -> Option<f64> {
        let foot_turn = turned(degrees)?;
        let lowest = |part: &[&Point3<f64>]| {
            (part.iter())
                .map(|p| {
                    foot_turn
                        .blended(shin_turn, p)
                        .transform_point(p)
                        .coords
                        .dot(rest_up)
                })
                .min_by(f64::total_cmp)
        };
        Some(lowest(&ball)? - lowest(&heel)?).filter(|h| h.is_finite())
    };
    // Pointed, the ball lies below the heel as posed; the first turn tried that raises it to
    // the heel's level or over brackets the level one.
    let step = MAX_FOOT_TURN_DEG / FOOT_TURNS_TRIED as f64;
    let below = |k: usize| ball_over_heel(k as f64 * step).map(|h| h < 0.0);
    if below(0) != Some(true) {
        return Some(Levelling::Stands);
    }
    // The first turn tried not below level; one the foot cannot be read at ends the search.
    let level = (1..=FOOT_TURNS_TRIED)
        .find(|&k| below(k) != Some(true))
        .filter(|&k| below(k).is_some())?;
    let (mut lo, mut hi) = ((level - 1) as f64 * step, level as f64 * step);
    for _ in 0..30 {
        let mid = (lo + hi) / 2.0;
        match ball_over_heel(mid) {
            Some(h) if h < 0.0 => lo = mid,
            Some(_) => hi = mid,
            None => break,
        }
    }
    turned((lo + hi) / 2.0).map(Levelling::Turn)
}

/// The joints and bends of the leg as its landmarks' section centres trace it; `None` where
/// the profile is too short to have a knee between its ends.
fn bend_of(landmarks: &Landmarks, up: &Vector3<f64>) -> Option<Bend> {
    // An ankle thinner than any standing leg's is a section through the toes (a pointed foot):
    // not a joint to turn about.
    if landmarks.ankle.girth_m < MIN_STANDING_GIRTH_M {
        return None;
    }
    let centres: Vec<Point3<f64>> = (landmarks.profile.iter())
        .map(|r| Point3::from(r.centre))
        .collect();
    bend_through(
        &Point3::from(landmarks.ankle.centre),
        &Point3::from(landmarks.thigh_top.centre),
        &centres,
        up,
    )
}

/// The joints and bends of a leg from `ankle` to `top` whose sections' centres are `centres`;
/// `None` where none of them can be its knee.
fn bend_through(
    ankle: &Point3<f64>,
    top: &Point3<f64>,
    centres: &[Point3<f64>],
    up: &Vector3<f64>,
) -> Option<Bend> {
    let (ankle, top) = (*ankle, *top);
    // The knee: the section centre that best splits the centres into a shin's line and a
    // thigh's (least squares over both), among those where a knee can be.
    let shin_share = |knee: &Point3<f64>| {
        let (shin, thigh) = ((knee - ankle).norm(), (top - knee).norm());
        shin / (shin + thigh)
    };
    let misfit = |knee: &Point3<f64>| -> f64 {
        (centres.iter())
            .map(|c| distance_to_segment(c, &ankle, knee).min(distance_to_segment(c, knee, &top)))
            .map(|d| d * d)
            .sum()
    };
    let knee = (centres.iter())
        .filter(|k| KNEE_SHARE.contains(&shin_share(k)))
        .min_by(|a, b| misfit(a).total_cmp(&misfit(b)))
        .copied()?;
    let (thigh, shin) = (
        (top - knee).try_normalize(1e-9)?,
        (knee - ankle).try_normalize(1e-9)?,
    );
    Some(Bend {
        knee_deg: thigh.angle(&shin).to_degrees(),
        thigh_deg: thigh.angle(up).to_degrees(),
        foot_deg: 0.0,
        ankle: ankle.coords.into(),
        knee: knee.coords.into(),
        thigh_top: top.coords.into(),
    })
}

/// Distance from `p` to the segment from `a` to `b`.
fn distance_to_segment(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(&ab) / ab.norm_squared().max(1e-18)).clamp(0.0, 1.0);
    (p - (a + ab * t)).norm()
}

/// The least rotation taking the unit vector `from` to `to`; none where they are parallel to
/// rounding (`rotation_between` takes the arc cosine of a dot product a hair above 1 as NaN).
fn least_turn(from: &Vector3<f64>, to: &Vector3<f64>) -> Rotation3<f64> {
    if from.dot(to) >= 1.0 - 1e-12 {
        return Rotation3::identity();
    }
    Rotation3::rotation_between(from, to).unwrap_or_else(|| {
        // Opposite: half a turn about any axis square to them.
        let axis = from.cross(&Vector3::x()).try_normalize(1e-6);
        let axis = axis.unwrap_or_else(|| from.cross(&Vector3::y()).normalize());
        Rotation3::from_axis_angle(&Unit::new_normalize(axis), std::f64::consts::PI)
    })
}

/// The turn `r` about the point `pivot`, as a matrix.
fn about(pivot: &Point3<f64>, r: &Rotation3<f64>) -> Matrix4<f64> {
    Translation3::from(pivot.coords).to_homogeneous()
        * r.to_homogeneous()
        * Translation3::from(-pivot.coords).to_homogeneous()
}

/// `leg`'s map from file coordinates to world space (units and the quarter turns to Y up), as
/// a matrix.
fn linear_of(leg: &Leg) -> Matrix4<f64> {
    let mut m = Matrix4::identity();
    for k in 0..3 {
        let mut e = Point3::origin();
        e[k] = 1.0;
        m.fixed_view_mut::<3, 1>(0, k)
            .copy_from(&leg.world_from_file(&e).coords);
    }
    m
}

/// Per vertex, whether it is the leg's: on a triangle whose corners are all `inside` (below
/// the top of the thigh), in the piece nearest the ankle (`limb[1]`), or in a piece that touches
/// or passes into it, transitively, whose centre lies within `reach` of the `limb` (sole, ankle,
/// knee, thigh top): a mannequin's foot, shin, knee ball and thigh, not the other leg or a hand
/// that touches it. `None` where no triangle is inside.
fn leg_vertices(
    leg: &Leg,
    limb: &[Point3<f64>; 4],
    reach: f64,
    inside: impl Fn(usize) -> bool,
) -> Option<Vec<bool>> {
    let below: Vec<[u32; 3]> = (leg.triangles.iter())
        .filter(|t| t.iter().all(|&i| inside(i as usize)))
        .copied()
        .collect();
    let piece = triangle_pieces(&leg.positions, &below);
    let ankle = &limb[1];
    let start = (below.iter().zip(&piece))
        .min_by(|(a, _), (b, _)| {
            let near = |t: &[u32; 3]| {
                (t.iter())
                    .map(|&i| (leg.positions[i as usize] - ankle).norm())
                    .fold(f64::INFINITY, f64::min)
            };
            near(a).total_cmp(&near(b))
        })
        .map(|(_, &p)| p)?;
    let count = piece.iter().copied().max().map_or(0, |p| p as usize + 1);
    let mut centre = vec![(Vector3::zeros(), 0.0); count];
    for (t, &p) in below.iter().zip(&piece) {
        for &i in t {
            centre[p as usize].0 += leg.positions[i as usize].coords;
            centre[p as usize].1 += 1.0;
        }
    }
    let along_limb = |c: &Point3<f64>| {
        (limb.windows(2))
            .map(|w| distance_to_segment(c, &w[0], &w[1]))
            .fold(f64::INFINITY, f64::min)
    };
    let on_limb: Vec<bool> = (centre.iter().enumerate())
        .map(|(p, (sum, n))| p as u32 == start || along_limb(&Point3::from(sum / *n)) <= reach)
        .collect();
    // Pieces that touch, among those along the limb.
    let kept: Vec<[u32; 3]> = (below.iter().zip(&piece))
        .filter(|(_, &p)| on_limb[p as usize])
        .map(|(t, _)| *t)
        .collect();
    let kept_piece: Vec<u32> = (piece.iter())
        .filter(|&&p| on_limb[p as usize])
        .copied()
        .collect();
    let group = touching_groups(&leg.positions, &kept, &kept_piece);
    let start_group = group[start as usize];
    let mut member = vec![false; leg.positions.len()];
    for (t, &p) in kept.iter().zip(&kept_piece) {
        if group[p as usize] == start_group {
            for &i in t {
                member[i as usize] = true;
            }
        }
    }
    Some(member)
}

/// 0 below 0, 1 above 1, and the cubic smoothstep between.
fn smoothstep(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::leg::{load_leg, Units, UpChoice};

    /// The sample leg with its foot in a stride: its knee bent by `degrees` about the axis square
    /// to up and to its foot, blended over 4 cm as skinning blends it, and the whole leg turned
    /// back by half that about the top of its thigh (the hip flexed), so that its foot stands.
    fn bent_sample(degrees: f64) -> Leg {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/samples/makehuman_leg_foot.glb"
        );
        let mut leg = load_leg(std::path::Path::new(path), Units::Metres, UpChoice::Auto).unwrap();
        let standing =
            find_landmarks(&leg.positions, &leg.triangles, leg.up, Side::Left, None).unwrap();
        let knee = Point3::from(standing.knee.centre);
        let top = Point3::from(standing.thigh_top.centre);
        let foot = Vector3::from(standing.foot.unwrap().direction);
        let hinge = Unit::new_normalize(leg.up.cross(&foot));
        let bent = about(
            &knee,
            &Rotation3::from_axis_angle(&hinge, degrees.to_radians()),
        );
        let flexed = about(
            &top,
            &Rotation3::from_axis_angle(&hinge, -degrees.to_radians() / 2.0),
        );
        let up = leg.up;
        for p in &mut leg.positions {
            let below = smoothstep(((knee - *p).dot(&up) + 0.02) / 0.04);
            let at_knee = p.coords * (1.0 - below) + bent.transform_point(p).coords * below;
            *p = flexed.transform_point(&Point3::from(at_knee));
        }
        leg
    }

    #[test]
    fn a_bent_knee_is_found_from_the_sections_and_straightened_back_to_the_pose() {
        let leg = bent_sample(50.0);
        let (rest, bend) = straightened(&leg, Side::Left)
            .unwrap()
            .expect("a knee bent 50° is read");
        // Horizontal sections of leaning bones read the bend short (37.6° and 13.9° here); what
        // matters is that straightening it leaves a leg that stands.
        assert!((bend.knee_deg - 50.0).abs() < 15.0, "{bend:?}");
        assert!((bend.thigh_deg - 25.0).abs() < 12.0, "{bend:?}");
        // Its foot stands: not turned.
        assert_eq!(bend.foot_deg, 0.0, "{bend:?}");
        // The rest pose carried by its matrices is the file's pose, exactly.
        for ((r, m), p) in rest
            .leg
            .positions
            .iter()
            .zip(&rest.pose_from_rest)
            .zip(&leg.positions)
        {
            let back = leg.world_from_file(&m.transform_point(&rest.leg.file_from_world(r)));
            assert!((back - p).norm() < 1e-9, "{back} against {p}");
        }
        // Straightened, it stands: its knee bends less than the threshold.
        let standing = find_landmarks(
            &rest.leg.positions,
            &rest.leg.triangles,
            leg.up,
            Side::Left,
            None,
        )
        .unwrap();
        let again = bend_of(&standing, &rest.leg.up).unwrap();
        assert!(again.knee_deg < BENT_DEG, "{again:?}");
    }

    /// The sample leg with its foot pointed down by `degrees` about the axis square to up and
    /// to the foot, 2 cm under its ankle, blended over 4 cm as skinning blends it: a foot in a
    /// high heel, or a dancer's.
    fn pointed_sample(degrees: f64) -> (Leg, Landmarks) {
        let leg = bent_sample(0.0);
        let standing =
            find_landmarks(&leg.positions, &leg.triangles, leg.up, Side::Left, None).unwrap();
        let up = leg.up;
        let pivot = Point3::from(standing.ankle.centre) - up * 0.02;
        let foot = Vector3::from(standing.foot.unwrap().direction);
        let hinge = Unit::new_normalize(up.cross(&foot));
        let turn = about(
            &pivot,
            &Rotation3::from_axis_angle(&hinge, degrees.to_radians()),
        );
        let mut pointed = leg;
        for p in &mut pointed.positions {
            let below = smoothstep(((pivot - *p).dot(&up) + 0.02) / 0.04);
            *p = Point3::from(p.coords * (1.0 - below) + turn.transform_point(p).coords * below);
        }
        (pointed, standing)
    }

    #[test]
    fn a_pointed_foot_is_found_by_the_shins_own_sections_and_turned_back_to_stand() {
        // A high heel's, and a dancer's pointed nearly straight down (its heel, raised behind
        // the ankle, cut apart from it by sections along up).
        for degrees in [45.0, 75.0] {
            pointed_foot_stands(degrees);
        }
    }

    fn pointed_foot_stands(degrees: f64) {
        let (leg, standing) = pointed_sample(degrees);
        // Sections along up cut the pointed foot through its toes and put the ankle there.
        let posed = find_landmarks(&leg.positions, &leg.triangles, leg.up, Side::Left, None);
        let low_ankle = posed.map_or(true, |l| {
            (Vector3::from(standing.ankle.centre) - Vector3::from(l.ankle.centre)).dot(&leg.up)
                > POINTED_ANKLE_RISE_M
                || l.ankle.girth_m < MIN_STANDING_GIRTH_M
        });
        assert!(
            low_ankle,
            "the sections along up found the ankle where it is"
        );
        let (rest, bend) = (straightened(&leg, Side::Left).unwrap())
            .unwrap_or_else(|| panic!("a foot pointed {degrees}° is not read"));
        // Levelled on its heel and ball, which stand a few millimetres apart on the sample.
        assert!((bend.foot_deg - degrees).abs() < 5.0, "{bend:?}");
        // Its ankle is the leg's, within 3 cm of the standing leg's.
        let ankle_off = (Point3::from(bend.ankle) - Point3::from(standing.ankle.centre)).norm();
        assert!(ankle_off < 0.03, "ankle {ankle_off} m off");
        // Turned back, the foot stands: its toe tip found as far from its ankle as the standing
        // leg's, and its ankle as high above its sole, within 2 cm.
        let again = find_landmarks(
            &rest.leg.positions,
            &rest.leg.triangles,
            rest.leg.up,
            Side::Left,
            None,
        )
        .unwrap();
        let reach = |l: &Landmarks| {
            let toe = Point3::from(l.foot.expect("a foot").toe_tip);
            (toe - Point3::from(l.ankle.centre)).norm()
        };
        assert!((reach(&again) - reach(&standing)).abs() < 0.02, "{again:?}");
        let height = |l: &Landmarks| l.ankle.s - l.sole_s();
        assert!(
            (height(&again) - height(&standing)).abs() < 0.02,
            "{} against {}; reach {} against {}; {bend:?}",
            height(&again),
            height(&standing),
            reach(&again),
            reach(&standing)
        );
        // The rest pose carried by its matrices is the file's pose, exactly.
        for ((r, m), p) in (rest.leg.positions.iter())
            .zip(&rest.pose_from_rest)
            .zip(&leg.positions)
        {
            let back = leg.world_from_file(&m.transform_point(&rest.leg.file_from_world(r)));
            assert!((back - p).norm() < 1e-9, "{back} against {p}");
        }
    }

    #[test]
    fn a_foot_pointed_too_far_to_stand_is_refused_not_dressed_open() {
        // Past any dancer's: no turn the levelling tries stands it, and read as posed its
        // stocking would end in the foot.
        let (leg, _) = pointed_sample(MAX_FOOT_TURN_DEG + 15.0);
        let Err(refused) = straightened(&leg, Side::Left) else {
            panic!("a foot pointed past any dancer's is dressed");
        };
        assert!(refused.starts_with("its foot points down"), "{refused}");
        assert!(refused.contains("--axis"), "{refused}");
    }

    #[test]
    fn a_leg_in_pieces_moves_whole_and_the_other_leg_and_a_hand_touching_it_stay() {
        use crate::leg::test_meshes::add_box;
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        // A mannequin's leg along Y: foot, shin and thigh boxes passing into one another; the
        // other leg, apart; a hand touching the thigh from the side, off the limb.
        for (lo, hi) in [
            ([-0.05, 0.0, -0.05], [0.05, 0.1, 0.15]),
            ([-0.04, 0.08, -0.04], [0.04, 0.5, 0.04]),
            ([-0.06, 0.48, -0.06], [0.06, 0.9, 0.06]),
            ([0.2, 0.0, -0.05], [0.3, 0.9, 0.05]),
            ([0.06, 0.6, -0.02], [0.16, 0.7, 0.02]),
        ] {
            add_box(&mut positions, &mut triangles, lo, hi);
        }
        let mut leg = bent_sample(0.0);
        (leg.positions, leg.triangles) = (positions, triangles);
        let limb = [
            [0.0, 0.0, 0.0],
            [0.0, 0.1, 0.0],
            [0.0, 0.5, 0.0],
            [0.0, 0.9, 0.0],
        ]
        .map(Point3::from);
        let member = leg_vertices(&leg, &limb, 0.08, |_| true).unwrap();
        let pieces: Vec<bool> = member.chunks(8).map(|c| c.iter().all(|&m| m)).collect();
        assert_eq!(pieces, [true, true, true, false, false]);
        assert!(member.chunks(8).all(|c| c.iter().all(|&m| m == c[0])));
    }

    #[test]
    fn a_leg_standing_straight_is_left_as_it_is() {
        assert_eq!(
            straightened(&bent_sample(0.0), Side::Left).map(|s| s.is_none()),
            Ok(true)
        );
        assert_eq!(
            straightened(&bent_sample(10.0), Side::Left).map(|s| s.is_none()),
            Ok(true)
        );
    }
}
