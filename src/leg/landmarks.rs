//! The leg's landmarks, read from girth profiles along the body: which way is up, which leg to
//! dress, the sole and toe, the foot's direction, the ankle, the knee and the top of the thigh.
//!
//! Method: horizontal slicing with loop tracking, as body-scanner software finds landmarks
//! (Leong, Fang & Tsai 2007, "Automatic body feature extraction from a marker-less scanned human
//! body", Computer-Aided Design 39(7); Wang 2005, "Parameterization and parametric design of
//! mannequins", CAD 37(1)); the anthropometric definitions follow ISO 8559-1 (ankle girth: the
//! smallest above the malleoli; crotch: where the legs join).
//!
//! - **Up** ([`anatomical_up`]): of the principal axes nearly as long as the longest (a T-pose's
//!   span matches its height), the one whose ends differ most in girth, pointed away from the
//!   slimmer end (feet and calves are slimmer than thighs, hips, or a head and shoulders).
//!   Only where the ends differ by [`CLEAR_ENDS_RATIO`] or more (a limb's, 1.4 to 3.3) does the
//!   shape overrule glTF's +Y ([`BodyUp::clear`]). Raised arms make the hands the slimmer end:
//!   where only read the other way up does a leg stand on a foot
//!   ([`Landmarks::stands_on_a_foot`]), up is that way ([`BodyUp::on_its_feet`]); a "leg"
//!   shorter than [`MIN_LEG_LENGTH_PER_GIRTH`] of its top's girth is an arm, not a leg.
//! - **The legs**: the closed loops [`SEED_HEIGHT_M`] above the lowest point (a foot cut there at
//!   its sole is read from higher up), followed up and down: the loop enclosing the last centre, or
//!   else the nearest within [`MAX_STEP_M`]. Following stops where the mesh is cut, or where two legs'
//!   loops become one (the crotch), or a leg's girth jumps there once it has risen a shin's
//!   length. Loops thinner than an ankle that meet within [`TOES_JOIN_M`] are the toes of one
//!   foot standing on them (a stride's back foot); two that overlap as circles of their girths
//!   and meet within it both above and below are one limb cut apart by a fold (a steeply
//!   pointed foot's heel beside its ankle).
//! - **Facing and side**: the character faces where its standing feet point, on average, where
//!   they agree within [`FEET_AGREE_DEG`]; its left is `up × facing`. Where they disagree, left
//!   is taken from the lowest foot alone; with no foot the character faces +Z, as glTF
//!   characters do. The pictures' views are taken from it ([`Landmarks::stance`]). A kneeling
//!   figure, its toes pointing back, is taken to face backwards.
//!   Where the file's rig names the legs ([`super::rig`]), its leg on the side asked for is the
//!   one whose section stands under its ankle joint. A lone standing leg with a section over
//!   [`LIFTED_LEG_OFF_CENTRE_M`] to the other side of the body's centre is that side's: the leg
//!   asked for is lifted, and refused as such rather than the other dressed.
//! - **Ankle**: the smallest girth between the foot and a third of the way up; **knee**: the
//!   smallest between 35 % and 70 % of the way from ankle to thigh top; either, within
//!   [`SEAM_NEAR_M`] of sections through two pieces (a mannequin's joint), is their middle;
//!   **toe**: the foot's vertex furthest from the ankle's centre line; a foot is there when that
//!   reaches more than [`FOOT_REACH`] ankle radii; **sole**: the lowest vertex within the foot's
//!   reach (or under the leg's lowest section). Toe and sole are taken only from vertices nearer
//!   the leg's own centre line than another leg's: the other foot is within reach, and may be
//!   lower.
//!
//! Sections skip a flat cap over the cut ([`super::caps`]): a leg closed there reads as open.
//!
//! Why this holds on character exports: girths are convex-hull perimeters of loops, so folds,
//! dents and small self-intersections do not move them; loops are walked on the cleaned mesh
//! ([`super::clean`]), without repeated faces and debris; following a loop by enclosure keeps
//! to one limb when a hand, the other leg or an eye is in the same plane; and the orientation
//! comes from the shape, not the file's axes, so a Z-up, lying or moved character reads alike.

use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use serde::{Deserialize, Serialize};

use super::caps::open_cut_caps;
use super::rig::{Rig, RigLeg};
use super::slice::{piece_bit, Loop, Slicer};
use super::Side;
use crate::base::Stance;

/// The file holds more than the leg standing alone (a body, a lifted leg) where it rises this
/// far above that leg's top, metres: more than a thigh's cut slanted 40°, less than a torso.
pub const BODY_ABOVE_M: f64 = 0.15;
/// A lone standing leg whose section furthest from the body's centre is this far to one side
/// is that side's leg, metres: a leg alone is centred on itself, a body's thigh is about a hip's
/// half-width off (0.11 m on MHR's body standing on one leg, whose foot is 7 mm off).
pub const LIFTED_LEG_OFF_CENTRE_M: f64 = 0.05;
/// Narrowest and widest a standing leg's section just above its sole can be, metres: a child's
/// ankle is about 0.14 m around, an adult's foot under 0.35 m there; an ear is 0.09 m, a head 8
/// cm below its crown 0.45 m or more.
pub const MIN_STANDING_GIRTH_M: f64 = 0.12;
const MAX_STANDING_GIRTH_M: f64 = 0.4;
/// Furthest a rig's ankle joint may be from a leg's seed section, across up, for the rig to say
/// which leg that is, metres.
const RIG_ANKLE_OVER_SEED_M: f64 = 0.15;
/// Height above the lowest point where the legs are first looked for, metres (above a foot's
/// toes, at or below the ankle).
pub const SEED_HEIGHT_M: f64 = 0.08;
/// Longest span along up that can be a body, metres (the tallest leg file accepted is 3 m tall
/// along its file axis; a turned one may span a little more).
pub const MAX_SPAN_M: f64 = 4.5;
/// How far a leg's loop goes on up from its seed, at the least, metres: a shin above an ankle
/// does for ten centimetres or more, a box beside the leg does not.
const MIN_LIMB_RISE_M: f64 = 0.10;
/// How far a followed limb rises from its seed before a jump in its girth can be the crotch,
/// metres: a shin's length (a crotch stands 0.45 m or more above the sole).
const JUMP_MIN_RISE_M: f64 = 0.3;
/// Loops of toes join within this rise, metres: a foot's toes meet at their ball.
pub const TOES_JOIN_M: f64 = 0.1;
/// Two loops of one section whose centres are closer than this share of the sum of their
/// radii (each a circle's of its girth) overlap as circles: one limb cut apart by a fold, not
/// two limbs side by side (a pointed foot's heel lobe lies at 0.86–0.89).
const LOBE_OVERLAP: f64 = 0.95;
/// Spacing of the sections, metres.
pub const SLICE_STEP_M: f64 = 0.0025;
/// Furthest a limb's centre may move between two sections, metres.
pub const MAX_STEP_M: f64 = 0.03;
/// A principal axis at least this fraction of the longest one's extent is a candidate for up.
pub const CANDIDATE_EXTENT: f64 = 0.6;
/// The least ratio of the mean girths of a body's two ends (the thicker over the slimmer) for
/// its shape to say which way is up: the legs and bodies of the samples and the zoo have 1.36
/// or more (a leg with its foot: ankle against thigh; a body: feet against hips and chest).
pub const CLEAR_ENDS_RATIO: f64 = 1.2;
/// A followed leg whose girth grows by this factor within [`JUMP_SPAN_M`] has reached the
/// crotch (a thigh grows far slower).
pub const GIRTH_JUMP: f64 = 1.5;
/// See [`GIRTH_JUMP`], metres.
pub const JUMP_SPAN_M: f64 = 0.02;
/// A leg whose seed lies less than this above its lowest section, metres, was cut near its
/// sole (a flat foot beside one on its toes, lower; a standing one's seed is [`SEED_HEIGHT_M`]
/// up): its foot is read from a seed's height higher.
const FLAT_FOOT_BELOW_SEED_M: f64 = 0.04;
/// Smallest girth of a loop that can be a leg, metres.
pub const MIN_LEG_GIRTH_M: f64 = 0.08;
/// A leg on its foot reaches from its sole to the top of its thigh at least this share of the
/// girth there: the samples' and the zoo's adults 1.2–1.5, a heavy thigh's (0.8 m around on a
/// 0.75 m leg) 0.9. An arm read upside down, its hand taken for a foot and its shoulders with
/// the head for a crotch, reaches half of it.
pub const MIN_LEG_LENGTH_PER_GIRTH: f64 = 0.7;
/// A foot reaches this many ankle radii from the ankle's centre line.
pub const FOOT_REACH: f64 = 2.0;
/// A standing foot's toe tip lies no higher above the sole than this share of its reach forward
/// of the ankle (an adult's, 2 cm over 15–20).
pub const TOE_LOW_SHARE: f64 = 1.0 / 3.0;
/// How far from a run of sections through two pieces or more the narrowest section may lie and
/// still be that seam's joint, metres.
pub const SEAM_NEAR_M: f64 = 0.02;
/// How far above a leg's open end its skin is looked for again, metres: skin that goes on
/// around the same centre within this was a hole, not a cut.
pub const HOLE_PROBE_M: f64 = 0.15;
/// Furthest a vertex of the foot may be from the ankle's centre line, metres.
pub const FOOT_MAX_M: f64 = 0.4;
/// Feet whose lowest section lies within this of the lowest one's stand, metres: their mean
/// direction is where the character faces (a foot lifted higher may point anywhere).
pub const STANDING_M: f64 = 0.03;
/// Standing feet further apart in direction than this, degrees, do not say where the character
/// faces: each foot's toe-out is 5–15°; a foot turned out further is a pose.
pub const FEET_AGREE_DEG: f64 = 45.0;

/// One section of a followed leg.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Ring {
    /// Height along up, metres (absolute: the dot product with up).
    #[serde(skip)]
    pub s: f64,
    /// Centre of the loop, world space.
    pub centre: [f64; 3],
    /// Girth (convex perimeter), metres.
    pub girth_m: f64,
    /// Distance to the other leg's section at this height, metres (infinite where there is
    /// none).
    #[serde(skip)]
    pub gap_m: f64,
    /// The mesh's connected pieces the section runs through ([`Slicer::pieces_of`]): one for a
    /// limb modelled whole, several where it is modelled in pieces.
    #[serde(skip)]
    pub pieces: u64,
}

/// How the top of the thigh was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ThighTopKind {
    /// Where the two legs' sections join.
    Crotch,
    /// Where the mesh is cut.
    Cut,
}

/// The foot, where the leg has one.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Foot {
    /// The vertex furthest forward, world space.
    pub toe_tip: [f64; 3],
    /// Unit vector from the ankle to the toe, square to up.
    pub direction: [f64; 3],
}

/// The landmarks of the leg to dress (see module docs), world space, metres.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Landmarks {
    /// Unit vector pointing up the body.
    pub up: [f64; 3],
    /// Unit vector where the character faces, square to up (module docs): what its left and
    /// right, and the pictures' front and side, are taken from; `None` where no foot stands, or
    /// the standing feet disagree.
    pub facing: Option<[f64; 3]>,
    /// Legs found at the bottom of the mesh.
    pub legs_found: usize,
    /// The dressed leg's side, where the file holds both.
    pub side: Option<Side>,
    /// The leg's lowest vertex.
    pub sole: [f64; 3],
    /// The foot, if the leg has one.
    pub foot: Option<Foot>,
    /// The narrowest section above the foot.
    pub ankle: Ring,
    /// The narrowest section between calf and thigh.
    pub knee: Ring,
    /// The highest section of the leg alone.
    pub thigh_top: Ring,
    /// Whether `thigh_top` is the crotch or a cut.
    pub thigh_top_kind: ThighTopKind,
    /// Every section of the leg, from the ankle to the thigh top, one per [`SLICE_STEP_M`].
    #[serde(skip)]
    pub profile: Vec<Ring>,
    /// The rig's joints of this leg, where the file's skin names them and they lie in it.
    pub rig: Option<RigAgreement>,
}

/// The rig's leg that the dressed leg's sections go around, and how far its joints are from
/// the sections found.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RigAgreement {
    /// The naming scheme of the rig ([`Rig::naming`]).
    pub naming: &'static str,
    /// The rig's side of this leg.
    pub side: Side,
    /// Its joints, world space.
    pub joints: RigLeg,
    /// Distance from the ankle section's centre to the ankle joint, metres.
    pub ankle_m: f64,
    /// Distance from the knee section's centre to the knee joint, metres.
    pub knee_m: f64,
}

impl RigAgreement {
    /// The rig's leg whose ankle and knee joints lie within the dressed leg's ankle and knee
    /// sections (within their girth's radius of the centre, across up), nearest first; `None`
    /// where neither of its legs does (a rig for another mesh, or in other units).
    fn of(rig: &Rig, ankle: &Ring, knee: &Ring, up: &Vector3<f64>) -> Option<RigAgreement> {
        let across = |r: &Ring, p: [f64; 3]| {
            let d = Vector3::from(p) - Vector3::from(r.centre);
            (d - up * d.dot(up)).norm()
        };
        let within = |r: &Ring, p: [f64; 3]| across(r, p) <= r.girth_m / std::f64::consts::TAU;
        [Side::Left, Side::Right]
            .into_iter()
            .filter_map(|side| Some((side, *rig.leg(side)?)))
            .filter(|(_, j)| within(ankle, j.ankle) && within(knee, j.knee))
            .map(|(side, joints)| RigAgreement {
                naming: rig.naming,
                side,
                joints,
                ankle_m: (Point3::from(joints.ankle) - Point3::from(ankle.centre)).norm(),
                knee_m: (Point3::from(joints.knee) - Point3::from(knee.centre)).norm(),
            })
            .min_by(|a, b| (a.ankle_m + a.knee_m).total_cmp(&(b.ankle_m + b.knee_m)))
    }
}

impl Landmarks {
    /// Whether the leg stands on a foot: an ankle no thinner than a standing leg's
    /// ([`MIN_STANDING_GIRTH_M`]) above a foot whose toe tip lies low and forward, no higher
    /// above the sole than [`TOE_LOW_SHARE`] of its reach across up from the ankle. A hand or a
    /// head read as a leg's end does not: its "ankle" is a finger or a neck, and its furthest
    /// point from it is as high as it is far.
    pub fn stands_on_a_foot(&self) -> bool {
        let up = Vector3::from(self.up);
        self.ankle.girth_m >= MIN_STANDING_GIRTH_M
            && self.foot.is_some_and(|foot| {
                let toe = Vector3::from(foot.toe_tip);
                let rise = toe.dot(&up) - self.sole_s();
                let from_ankle = toe - Vector3::from(self.ankle.centre);
                let reach = (from_ankle - up * from_ankle.dot(&up)).norm();
                rise <= TOE_LOW_SHARE * reach
            })
    }

    /// The stance the character is pictured in ([`Stance::pictured`]): glTF's facing, +Z, where
    /// its feet do not say.
    pub fn stance(&self) -> Stance {
        let up = Vector3::from(self.up);
        let facing = self
            .facing
            .map_or_else(|| Stance::upright(up).facing, Vector3::from);
        Stance::pictured(up, facing)
    }

    /// The section of the profile nearest height `s`.
    pub fn ring_at(&self, s: f64) -> Ring {
        let k = self.profile.partition_point(|r| r.s < s);
        let below = k.saturating_sub(1);
        let above = k.min(self.profile.len() - 1);
        if (self.profile[above].s - s).abs() < (s - self.profile[below].s).abs() {
            self.profile[above]
        } else {
            self.profile[below]
        }
    }

    /// The highest height up to which the thigh's sections, from the knee up, keep `clearance`
    /// from the other leg's (the thigh top where the file holds one leg). Knees or ankles that
    /// touch do not end a stocking: only the thighs near the crotch do.
    pub fn clear_of_other_leg(&self, clearance: f64) -> f64 {
        self.profile
            .iter()
            .filter(|r| r.s >= self.knee.s)
            .take_while(|r| r.gap_m >= clearance)
            .last()
            .map_or(self.knee.s, |r| r.s)
    }

    /// Height of the sole along up.
    pub fn sole_s(&self) -> f64 {
        Vector3::from(self.sole).dot(&Vector3::from(self.up))
    }
}

/// Up a body as its shape shows it ([`anatomical_up`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyUp {
    /// Unit vector up the body.
    pub up: Vector3<f64>,
    /// The mean girth of its thicker end over its slimmer one's; infinite where only one end
    /// has a closed section (the other is an open cut, the top).
    pub ends_ratio: f64,
    /// True where up was taken the other way from the slimmer end, because only read this way
    /// up do the legs found stand on a foot (arms raised over the head: hands and forearms
    /// slimmer than the shins).
    pub on_its_feet: bool,
}

impl BodyUp {
    /// True when the shape says which way is up clearly enough to overrule glTF's +Y: its ends
    /// differ by [`CLEAR_ENDS_RATIO`] or more, or it stands on its feet only one way up.
    pub fn clear(&self) -> bool {
        self.on_its_feet || self.ends_ratio >= CLEAR_ENDS_RATIO
    }
}

/// Up the body (see module docs): of the principal axes nearly as long as the longest, the one
/// whose ends differ most in girth, pointed away from the slimmer end; `None` for a mesh with
/// no area or no closed section.
pub fn anatomical_up(positions: &[Point3<f64>], triangles: &[[u32; 3]]) -> Option<BodyUp> {
    let mut area_sum = 0.0;
    let mut centroid = Vector3::zeros();
    let mut second = Matrix3::zeros();
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize].coords);
        let area = (b - a).cross(&(c - a)).norm() / 2.0;
        let m = (a + b + c) / 3.0;
        area_sum += area;
        centroid += m * area;
        second += m * m.transpose() * area;
    }
    if !(area_sum > 0.0 && area_sum.is_finite()) {
        return None;
    }
    centroid /= area_sum;
    let eigen = SymmetricEigen::new(second / area_sum - centroid * centroid.transpose());
    // Every principal axis nearly as long as the longest is a candidate: a T-posed character's
    // arm span can match its height.
    let axes: Vec<Vector3<f64>> = (0..3)
        .map(|k| eigen.eigenvectors.column(k).into_owned())
        .collect();
    let extent = |axis: &Vector3<f64>| {
        let (lo, hi) = positions
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                let s = p.coords.dot(axis);
                (lo.min(s), hi.max(s))
            });
        hi - lo
    };
    let extents: Vec<f64> = axes.iter().map(extent).collect();
    let longest = extents.iter().copied().fold(0.0, f64::max);
    let mut order: Vec<usize> = (0..3).collect();
    order.sort_by(|&a, &b| extents[b].total_cmp(&extents[a]));
    // Ranked by the ratio of their ends' girths; an axis with an open end ranks as an even one
    // (1) but is clear: its open end is the top.
    let mut best: Option<(f64, BodyUp)> = None;
    for k in order {
        if extents[k] < CANDIDATE_EXTENT * longest {
            continue;
        }
        let Some((ratio, up)) = signed_by_slimmer_end(positions, triangles, axes[k]) else {
            continue;
        };
        let rank = if ratio.is_finite() { ratio } else { 1.0 };
        if best.is_none_or(|(b, _)| rank > b) {
            best = Some((
                rank,
                BodyUp {
                    up,
                    ends_ratio: ratio,
                    on_its_feet: false,
                },
            ));
        }
    }
    let body = best.map(|(_, body)| body)?;
    // The slimmer end is the feet's, unless the arms are raised over the head: then hands and
    // forearms end the body slimmer than its shins. The landmarks tell them apart, as a foot
    // reaches forward from its ankle and a hand does not: where only the other way up has a
    // leg standing on a foot, the body stands that way.
    if !on_a_foot(positions, triangles, &body.up) && on_a_foot(positions, triangles, &-body.up) {
        return Some(BodyUp {
            up: -body.up,
            on_its_feet: true,
            ..body
        });
    }
    Some(body)
}

/// Whether read with `up` the mesh has a leg, either side, whose landmarks find a foot.
fn on_a_foot(positions: &[Point3<f64>], triangles: &[[u32; 3]], up: &Vector3<f64>) -> bool {
    [Side::Left, Side::Right].into_iter().any(|side| {
        find_landmarks(positions, triangles, *up, side, None).is_ok_and(|l| l.stands_on_a_foot())
    })
}

/// `axis` pointed away from its slimmer end (the mean girth of the closed sections in each end
/// quarter), with how much slimmer it is (a ratio of at least 1); `None` without any closed
/// section. An end with none counts as the top (an open cut), the ratio infinite.
fn signed_by_slimmer_end(
    positions: &[Point3<f64>],
    triangles: &[[u32; 3]],
    axis: Vector3<f64>,
) -> Option<(f64, Vector3<f64>)> {
    let slicer = Slicer::new(positions, triangles, axis);
    let (lo, hi) = slicer.range();
    let end_girth = |from: f64, to: f64| {
        let (mut sum, mut count) = (0.0, 0usize);
        for k in 0..40 {
            let s = from + (to - from) * (k as f64 + 0.5) / 40.0;
            for l in slicer.loops_at(s).iter().filter(|l| l.closed) {
                sum += slicer.girth(l);
                count += 1;
            }
        }
        (count > 0).then(|| sum / count as f64)
    };
    let quarter = (hi - lo) / 4.0;
    match (end_girth(lo, lo + quarter), end_girth(hi - quarter, hi)) {
        (Some(bottom), Some(top)) if top < bottom => Some((bottom / top, -axis)),
        (Some(bottom), Some(top)) => Some((top / bottom.max(f64::MIN_POSITIVE), axis)),
        (None, Some(_)) => Some((f64::INFINITY, -axis)),
        (Some(_), None) => Some((f64::INFINITY, axis)),
        (None, None) => None,
    }
}

/// How the character in a world-space mesh stands (up from [`anatomical_up`], facing from
/// its landmarks): what a picture of a finished fit is seen from, where only the leg mesh is
/// at hand. glTF's stance where neither is found.
pub fn stance_of(positions: &[Point3<f64>], triangles: &[[u32; 3]]) -> Stance {
    let Some(BodyUp { up, .. }) = anatomical_up(positions, triangles).filter(BodyUp::clear) else {
        return Stance::default();
    };
    find_landmarks(positions, triangles, up, Side::Left, None)
        .map_or_else(|_| Stance::pictured(up, Vector3::z()), |l| l.stance())
}

/// Why no leg's landmarks were found: what was seen, in a sentence, and whether it suggests the
/// mesh was read the wrong way up. The caller knows whether up was given or found from the
/// anatomy, and so what to advise.
#[derive(Clone, Debug, PartialEq)]
pub struct NoLandmarks {
    /// What was seen, where and how big.
    pub seen: String,
    /// True when a leg read the other way up would make sense of what was seen.
    pub up_in_doubt: bool,
}

impl From<String> for NoLandmarks {
    fn from(seen: String) -> Self {
        NoLandmarks {
            seen,
            up_in_doubt: false,
        }
    }
}

impl From<&str> for NoLandmarks {
    fn from(seen: &str) -> Self {
        seen.to_string().into()
    }
}

impl std::fmt::Display for NoLandmarks {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.seen)
    }
}

/// Finds the landmarks of the leg on `side` (see module docs) of the cleaned mesh, with `up`
/// the unit vector up the body. The error says what was seen instead.
pub fn find_landmarks(
    positions: &[Point3<f64>],
    triangles: &[[u32; 3]],
    up: Vector3<f64>,
    side: Side,
    rig: Option<&Rig>,
) -> Result<Landmarks, NoLandmarks> {
    // The sections follow the skin: a cap over the cut would make the leg seem to narrow to a
    // point at its top.
    let (skin, _) = open_cut_caps(positions, triangles, &up);
    let slicer = Slicer::new(positions, &skin, up);
    let (lo, hi) = slicer.range();
    // Sections every few millimetres over a span no body has would take minutes, for nothing.
    if hi - lo > MAX_SPAN_M {
        return Err(format!(
            "the mesh spans {:.1} m along its up direction, more than a body's {MAX_SPAN_M} m: \
             check leg.units (--units), or remove the other geometry from the file",
            hi - lo
        )
        .into());
    }
    let heights = |from: f64, to: f64, step: f64| {
        let n = ((to - from) / step).floor().max(0.0) as usize;
        (0..=n).map(move |k| from + step * k as f64)
    };
    // The legs: closed loops just above the lowest point.
    // The height in the band with the most legs, the lowest of those: a foot lifted off the
    // ground (a walking pose) is found a little higher.
    let seeds: Vec<Ring> = heights(lo + SEED_HEIGHT_M, (lo + 3.0 * SEED_HEIGHT_M).min(hi), 0.01)
        .map(|s| legs_at(&slicer, s))
        .fold(Vec::new(), |best, rings| {
            if rings.len() > best.len() {
                rings
            } else {
                best
            }
        });
    // A seed is a limb only where its loop goes on up for a limb's length: a box or a prop
    // standing in the seeds' band ends within centimetres, and would be dressed as the leftmost
    // leg.
    let rises = |seed: &Ring| {
        let top = seed.s + MIN_LIMB_RISE_M;
        let followed = follow(
            &slicer,
            &[*seed],
            heights(seed.s, top, SLICE_STEP_M).skip(1),
            false,
        );
        followed.rings[0]
            .last()
            .is_some_and(|r| r.s >= top - SLICE_STEP_M)
    };
    let seeds: Vec<Ring> = seeds.into_iter().filter(rises).collect();
    // A foot standing on its toes (a stride's back foot, a pointed foot) is cut through its
    // toes: loops thinner than any ankle that become one a few centimetres up are one limb,
    // seeded at the widest of them. A foot pointed steeply is cut through its ankle and, apart,
    // its heel raised behind it: two loops, neither as thin as a toe, closer than their radii
    // add up to (as circles of their girths they overlap) that become one a few centimetres
    // both up and down are one limb, seeded at the one over its lowest end (the ankle over the
    // toes, not the heel behind it). Two legs with their ankles side by side may be as close
    // (an ankle is wider than its girth's circle), but do not become one both above and below.
    let joins_soon = |a: &Ring, b: &Ring| {
        let up = heights(a.s, a.s + TOES_JOIN_M, SLICE_STEP_M).skip(1);
        follow(&slicer, &[*a, *b], up, false).joined
    };
    let joins_below = |a: &Ring, b: &Ring| {
        let down = heights((a.s - TOES_JOIN_M).max(lo), a.s, SLICE_STEP_M)
            .rev()
            .skip(1);
        follow(&slicer, &[*a, *b], down, false).joined
    };
    let overlap = |a: &Ring, b: &Ring| {
        let apart = (Vector3::from(a.centre) - Vector3::from(b.centre)).norm();
        apart < LOBE_OVERLAP * (a.girth_m + b.girth_m) / std::f64::consts::TAU
    };
    // How far a loop's centre lies, across up, from the centre of the last section below it.
    let off_its_end = |r: &Ring| {
        let down = heights(lo, r.s, SLICE_STEP_M).rev().skip(1);
        let end = follow(&slicer, &[*r], down, false).rings[0].last().copied();
        let d = Vector3::from(end.unwrap_or(*r).centre) - Vector3::from(r.centre);
        (d - up * d.dot(&up)).norm()
    };
    let seeds: Vec<Ring> = (seeds.iter().enumerate())
        .filter(|&(k, r)| {
            !(seeds.iter().enumerate()).any(|(j, o)| {
                let toes = || {
                    r.girth_m < MIN_STANDING_GIRTH_M
                        && (o.girth_m, k) > (r.girth_m, j)
                        && joins_soon(r, o)
                };
                let lobe = || {
                    r.girth_m.min(o.girth_m) >= MIN_STANDING_GIRTH_M
                        && overlap(r, o)
                        && (off_its_end(o), j) < (off_its_end(r), k)
                        && joins_soon(r, o)
                        && joins_below(r, o)
                };
                j != k && (toes() || lobe())
            })
        })
        .map(|(_, r)| *r)
        .collect();
    let seeds = Some(seeds).filter(|rings| !rings.is_empty()).ok_or(
        "no closed cross-section near its lowest point looks like a leg (the mesh is open \
                all around there, or has holes)",
    )?;
    let seed_s = seeds[0].s;
    let mut down = follow(
        &slicer,
        &seeds,
        heights(lo, seed_s, SLICE_STEP_M).rev().skip(1),
        false,
    );
    let feet: Vec<Option<Foot>> = (0..seeds.len())
        .map(|i| {
            let mut low = down.rings[i].clone();
            low.reverse();
            low.push(seeds[i]);
            let on_limb = on_pieces(&slicer, &low);
            let near_its_sole = seeds[i].s - low[0].s < FLAT_FOOT_BELOW_SEED_M;
            let along_a_foot = seeds[i].girth_m > MAX_STANDING_GIRTH_M;
            foot(positions, &up, &low, &seeds, i, on_limb).or_else(|| {
                // A flat foot beside one on its toes, a few centimetres lower, is first cut near
                // its sole or along its length, with no foot below the section: it is read from
                // its section a seed's height higher, as a standing pair's is.
                (near_its_sole || along_a_foot).then_some(())?;
                let top = seeds[i].s + SEED_HEIGHT_M;
                let higher = heights(seeds[i].s, top, SLICE_STEP_M).skip(1);
                let above = follow(&slicer, &[seeds[i]], higher, false).rings[0].clone();
                let ankle = *above.last().filter(|r| r.s >= top - SLICE_STEP_M)?;
                (ankle.girth_m <= MAX_STANDING_GIRTH_M).then_some(())?;
                low.extend(above);
                foot(positions, &up, &low, &seeds, i, on_pieces(&slicer, &low))
            })
        })
        .collect();
    let soles: Vec<Option<f64>> = down.rings.iter().map(|r| Some(r.last()?.s)).collect();
    let facing = facing(&feet, &soles, &up);
    // Left and right: from the facing, or where the feet disagree, the lowest foot's direction.
    let forward = facing
        .or_else(|| lowest_foot(&feet, &soles))
        .unwrap_or_else(|| Stance::upright(up).facing);
    let left = up.cross(&forward);

    let leftness = |r: &Ring| Vector3::from(r.centre).dot(&left);
    let across = |r: &Ring, p: [f64; 3]| {
        let d = Vector3::from(r.centre) - Vector3::from(p);
        (d - up * d.dot(&up)).norm()
    };
    // The rig's leg on `side`, where its ankle stands over a seed: its names say which leg is
    // the left, whatever way the feet point.
    let by_rig = rig.and_then(|r| r.leg(side)).and_then(|leg| {
        (0..seeds.len())
            .map(|i| (i, across(&seeds[i], leg.ankle)))
            .filter(|&(_, d)| d <= RIG_ANKLE_OVER_SEED_M)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    });
    let chosen = by_rig
        .or_else(|| match side {
            Side::Left => (0..seeds.len())
                .max_by(|&a, &b| leftness(&seeds[a]).total_cmp(&leftness(&seeds[b]))),
            Side::Right => (0..seeds.len())
                .min_by(|&a, &b| leftness(&seeds[a]).total_cmp(&leftness(&seeds[b]))),
        })
        .unwrap_or(0);
    // Up from the seeds: the chosen leg and its nearest neighbour, until they join or end.
    let other = (0..seeds.len()).filter(|&i| i != chosen).min_by(|&a, &b| {
        let d = |i: usize| {
            (Vector3::from(seeds[i].centre) - Vector3::from(seeds[chosen].centre)).norm()
        };
        d(a).total_cmp(&d(b))
    });
    let pair: Vec<Ring> = std::iter::once(seeds[chosen])
        .chain(other.map(|o| seeds[o]))
        .collect();
    let upward = follow(
        &slicer,
        &pair,
        heights(seed_s, hi, SLICE_STEP_M).skip(1),
        true,
    );
    let mut profile = std::mem::take(&mut down.rings[chosen]);
    profile.reverse();
    profile.push(seeds[chosen]);
    profile.extend(upward.rings[0].iter().copied());
    let thigh_top_kind = if upward.joined {
        ThighTopKind::Crotch
    } else {
        ThighTopKind::Cut
    };
    if !upward.joined {
        hole_above(
            &slicer,
            profile.last().copied().unwrap_or(seeds[chosen]),
            hi,
        )?;
    }
    let foot = feet[chosen];
    let on_limb = on_pieces(&slicer, &profile);
    let sole = sole(
        positions,
        &up,
        &profile,
        foot.is_some(),
        &seeds,
        chosen,
        on_limb,
    );
    let sole_s = sole.coords.dot(&up);
    let top = *profile
        .last()
        .ok_or("the leg has no closed cross-section")?;
    // One leg standing where a body has two: the other is lifted (a stride, a sit, a kneel).
    // Its side is told by its section furthest from the body's centre: a foot stood on alone is
    // under the centre, and its thigh is off to its side; a thigh followed up to where a lifted
    // one joins it, level with the hip, ends in the pelvis, and its foot is off to its side.
    // Dressing it for the other side would be a stocking on the wrong leg. A leg alone, with
    // nothing of the file higher than its top but the slant of its cut, has no body's centre to
    // be off (its own lean can be).
    if seeds.len() == 1 && by_rig.is_none() && hi - top.s > BODY_ABOVE_M {
        let centre = area_centroid(positions, triangles).dot(&left);
        let off_centre = (profile.iter())
            .map(|r| leftness(r) - centre)
            .max_by(|a, b| a.abs().total_cmp(&b.abs()))
            .unwrap_or(0.0);
        let standing = if off_centre > 0.0 {
            Side::Left
        } else {
            Side::Right
        };
        if standing != side && off_centre.abs() > LIFTED_LEG_OFF_CENTRE_M {
            return Err(format!(
                "the only leg standing at the lowest point is the character's {} ({:.2} m from \
                 the body's centre): its {} leg does not reach down (lifted in a stride, a sit \
                 or a kneel), and a leg whose foot does not stand is read only with its rig: \
                 export the character with its skin, fit it standing, dress the {} leg \
                 (--side {}), or give the part to dress with --axis",
                standing.name(),
                off_centre.abs(),
                side.name(),
                standing.name(),
                standing.name()
            )
            .into());
        }
    }
    let leg_height = top.s - sole_s;
    if leg_height < 0.15 {
        // Beside a leg on its foot that rises a leg's length, a short one is lifted or bent out
        // of the sections' plane, not upside down.
        let rise = |i: usize| {
            let up = follow(
                &slicer,
                &[seeds[i]],
                heights(seed_s, hi, SLICE_STEP_M).skip(1),
                false,
            );
            up.rings[0].last().map_or(0.0, |r| r.s - seed_s)
        };
        // Only a leg standing on a foot counts, its lowest section an ankle's or a foot's: read
        // upside down, a head rises as far into the torso, and so does an ear beside it.
        let other_rise = (0..seeds.len())
            .filter(|&i| {
                i != chosen
                    && feet[i].is_some()
                    && (MIN_STANDING_GIRTH_M..=MAX_STANDING_GIRTH_M).contains(&seeds[i].girth_m)
            })
            .map(rise)
            .fold(0.0, f64::max);
        if other_rise > 0.3 {
            return Err(format!(
                "the {} leg's sections stop {leg_height:.3} m above its lowest point, while the \
                 other leg's rise {other_rise:.2} m: it is lifted or bent out of standing (a \
                 stride, a sit), and a leg whose sections do not rise from its foot is read \
                 only with its rig: export the character with its skin, fit it standing, or give \
                 the part to dress with --axis",
                side.name()
            )
            .into());
        }
        return Err(NoLandmarks {
            seen: format!(
                "the leg found is only {leg_height:.3} m from its lowest point to the top of its \
                 thigh"
            ),
            up_in_doubt: true,
        });
    }
    // A leg is longer than its thigh is around; an arm over a head read upside down is not.
    if foot.is_some() && leg_height < MIN_LEG_LENGTH_PER_GIRTH * top.girth_m {
        return Err(NoLandmarks {
            seen: format!(
                "the leg found is {leg_height:.3} m from its sole to the top of its thigh, \
                 which is {:.3} m around: too short for a leg on its foot (an arm with its hand \
                 read as a foot?)",
                top.girth_m
            ),
            up_in_doubt: true,
        });
    }
    let narrowest = |from: f64, to: f64| {
        profile
            .iter()
            .filter(|r| r.s >= from && r.s <= to)
            .min_by(|a, b| a.girth_m.total_cmp(&b.girth_m))
            .copied()
    };
    let lowest = profile[0].s;
    let ankle =
        narrowest((sole_s + 0.03).max(lowest), sole_s + leg_height / 3.0).unwrap_or(profile[0]);
    // A thigh is wider than an ankle; one clearly narrower means the body is upside down.
    if top.girth_m < 0.9 * ankle.girth_m {
        return Err(NoLandmarks {
            seen: format!(
                "the leg found narrows upwards (ankle {:.3} m around, top of the thigh {:.3} m)",
                ankle.girth_m, top.girth_m
            ),
            up_in_doubt: true,
        });
    }
    let span = top.s - ankle.s;
    let knee = narrowest(ankle.s + 0.35 * span, ankle.s + 0.7 * span)
        .unwrap_or(profile[profile.len() / 2]);
    let (ankle, knee) = (at_the_seam(&profile, ankle), at_the_seam(&profile, knee));
    profile.retain(|r| r.s >= ankle.s);
    let rig = rig.and_then(|r| RigAgreement::of(r, &ankle, &knee, &up));
    Ok(Landmarks {
        up: up.into(),
        facing: facing.map(Into::into),
        legs_found: seeds.len(),
        side: (seeds.len() > 1).then_some(side),
        sole: sole.coords.into(),
        foot,
        ankle,
        knee,
        thigh_top: top,
        thigh_top_kind,
        profile,
        rig,
    })
}

/// A limb in pieces bends where its pieces meet: a mannequin's joint is the run of sections
/// through two pieces or more (where one passes into the next, with the ball inside), and the
/// narrowest section near it is set by how much wider one piece was made than the other, not
/// by the joint. Where `found` lies in such a run of `profile`, or within [`SEAM_NEAR_M`] of
/// it, the joint is the run's middle section; elsewhere (a limb modelled whole), `found`.
fn at_the_seam(profile: &[Ring], found: Ring) -> Ring {
    let seamed = |r: &Ring| r.pieces.count_ones() >= 2;
    (profile.chunk_by(|a, b| seamed(a) == seamed(b)))
        .filter(|run| seamed(&run[0]))
        .find(|run| {
            (run[0].s - SEAM_NEAR_M..=run[run.len() - 1].s + SEAM_NEAR_M).contains(&found.s)
        })
        .map_or(found, |run| run[run.len() / 2])
}

/// The centre of the surface `triangles`, each weighed by its area.
fn area_centroid(positions: &[Point3<f64>], triangles: &[[u32; 3]]) -> Vector3<f64> {
    let (mut sum, mut area) = (Vector3::zeros(), 0.0);
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let w = (b - a).cross(&(c - a)).norm();
        sum += (a.coords + b.coords + c.coords) * (w / 3.0);
        area += w;
    }
    if area > 0.0 {
        sum / area
    } else {
        Vector3::zeros()
    }
}

/// The feet with a direction, each with the height of its leg's lowest section (`soles[i]`).
fn feet_with_soles(feet: &[Option<Foot>], soles: &[Option<f64>]) -> Vec<(Vector3<f64>, f64)> {
    feet.iter()
        .zip(soles)
        .filter_map(|(f, s)| Some((Vector3::from(f.as_ref()?.direction), (*s)?)))
        .collect()
}

/// Where the character faces, square to `up` (module docs): the mean direction of the feet
/// standing within [`STANDING_M`] of the lowest; `None` where no foot stands, or two standing
/// feet point more than [`FEET_AGREE_DEG`] apart (a foot turned out, a dancer's position: their
/// mean would turn the character).
fn facing(feet: &[Option<Foot>], soles: &[Option<f64>], up: &Vector3<f64>) -> Option<Vector3<f64>> {
    let feet = feet_with_soles(feet, soles);
    let lowest = feet.iter().map(|f| f.1).fold(f64::INFINITY, f64::min);
    let standing: Vec<Vector3<f64>> = feet
        .iter()
        .filter(|f| f.1 <= lowest + STANDING_M)
        .map(|f| f.0)
        .collect();
    let agree = FEET_AGREE_DEG.to_radians().cos();
    let disagree = standing
        .iter()
        .enumerate()
        .any(|(i, a)| standing[i + 1..].iter().any(|b| a.dot(b) < agree));
    let sum: Vector3<f64> = standing.iter().sum();
    (!disagree)
        .then(|| (sum - up * up.dot(&sum)).try_normalize(1e-9))
        .flatten()
}

/// The direction of the foot standing lowest (a lifted foot may point anywhere), if any.
fn lowest_foot(feet: &[Option<Foot>], soles: &[Option<f64>]) -> Option<Vector3<f64>> {
    feet_with_soles(feet, soles)
        .into_iter()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|f| f.0)
}

/// Where a followed leg ends without joining another at `last`: a cut, unless its skin goes on
/// around the same place within [`HOLE_PROBE_M`] above. Then the end was a hole too big to
/// count as closed, and no stocking can be fitted over it: the error says where.
fn hole_above(slicer: &Slicer, last: Ring, hi: f64) -> Result<(), String> {
    let centre = Point3::from(last.centre);
    let mut s = last.s + SLICE_STEP_M;
    while s <= (last.s + HOLE_PROBE_M).min(hi) {
        let resumes = slicer
            .loops_at(s)
            .iter()
            .any(|l| l.closed && slicer.encloses(l, &centre));
        if resumes {
            return Err(format!(
                "its skin has a hole: the leg's sections are open for {:.0} mm above the point \
                 ({:.3}, {:.3}, {:.3}) m and whole again above it; fill the hole in a modelling \
                 tool (or give leg.axis below it)",
                1000.0 * (s - last.s),
                last.centre[0],
                last.centre[1],
                last.centre[2]
            ));
        }
        s += SLICE_STEP_M;
    }
    Ok(())
}

/// The closed loops at height `s` big enough to be legs, as rings.
fn legs_at(slicer: &Slicer, s: f64) -> Vec<Ring> {
    slicer
        .loops_at(s)
        .iter()
        .filter(|l| l.closed)
        .map(|l| ring(slicer, l, s))
        .filter(|r| r.girth_m >= MIN_LEG_GIRTH_M)
        .collect()
}

fn ring(slicer: &Slicer, l: &Loop, s: f64) -> Ring {
    Ring {
        s,
        centre: l.centre().coords.into(),
        girth_m: slicer.girth(l),
        gap_m: f64::INFINITY,
        pieces: slicer.pieces_of(l),
    }
}

/// The shortest distance between the points of two loops, metres.
fn gap(a: &Loop, b: &Loop) -> f64 {
    a.points
        .iter()
        .flat_map(|p| b.points.iter().map(move |q| (p - q).norm()))
        .fold(f64::INFINITY, f64::min)
}

/// Limbs followed through a run of sections.
struct Followed {
    /// Per limb, its rings in the order of the heights.
    rings: Vec<Vec<Ring>>,
    /// True when the first two limbs' loops became one.
    joined: bool,
}

/// Follows each of `start` through the sections at `heights` (see module docs) until it ends;
/// stops all at once when the first two join. Going `upward`, the first limb's girth growing by
/// half within [`JUMP_SPAN_M`], once it is half again as wide as where it started, counts as
/// joining too: its loop took in the other leg at the crotch, where the other leg was not
/// followed (its foot lifted out of the seeds' band, or cut off).
fn follow(
    slicer: &Slicer,
    start: &[Ring],
    heights: impl Iterator<Item = f64>,
    upward: bool,
) -> Followed {
    let mut rings: Vec<Vec<Ring>> = vec![Vec::new(); start.len()];
    let mut last: Vec<Option<Ring>> = start.iter().copied().map(Some).collect();
    for s in heights {
        if last.iter().all(Option::is_none) {
            break;
        }
        let loops: Vec<Loop> = slicer
            .loops_at(s)
            .into_iter()
            .filter(|l| l.closed)
            .collect();
        let mut taken: Vec<Option<usize>> = vec![None; start.len()];
        for (i, prev) in last.iter().enumerate() {
            let Some(prev) = prev else { continue };
            let at = Point3::from(prev.centre);
            // Only a loop of the pieces the limb runs through: a box standing beside the leg
            // where its section ends is not where the leg goes on.
            let on_limb = |l: &Loop| slicer.pieces_of(l) & prev.pieces != 0;
            taken[i] = loops
                .iter()
                .position(|l| on_limb(l) && slicer.encloses(l, &at))
                .or_else(|| {
                    loops
                        .iter()
                        .enumerate()
                        .filter(|(_, l)| on_limb(l))
                        .map(|(k, l)| (k, (l.centre() - at - slicer.up() * (s - prev.s)).norm()))
                        .filter(|&(_, d)| d <= MAX_STEP_M)
                        .min_by(|a, b| a.1.total_cmp(&b.1))
                        .map(|(k, _)| k)
                });
        }
        // Only once the limb has grown well past where it started, and risen a shin's length:
        // a seed in a lifted foot grows as fast into its heel, one in a toe into its foot.
        let jumped = upward
            && s - start[0].s >= JUMP_MIN_RISE_M
            && taken[0].is_some_and(|k| {
                let below = rings[0].iter().rev().find(|r| r.s <= s - JUMP_SPAN_M);
                below.is_some_and(|r| {
                    r.girth_m >= GIRTH_JUMP * start[0].girth_m
                        && slicer.girth(&loops[k]) > GIRTH_JUMP * r.girth_m
                })
            });
        if jumped || (start.len() > 1 && taken[0].is_some() && taken[0] == taken[1]) {
            return Followed {
                rings,
                joined: true,
            };
        }
        let between = match (taken.first(), taken.get(1)) {
            (Some(&Some(a)), Some(&Some(b))) => gap(&loops[a], &loops[b]),
            _ => f64::INFINITY,
        };
        for i in 0..start.len() {
            match taken[i] {
                Some(k) if last[i].is_some() => {
                    let r = Ring {
                        gap_m: between,
                        ..ring(slicer, &loops[k], s)
                    };
                    rings[i].push(r);
                    last[i] = Some(r);
                }
                _ => last[i] = None,
            }
        }
    }
    Followed {
        rings,
        joined: false,
    }
}

/// Whether a vertex is on the pieces the sections `rings` of a limb run through: its foot and
/// sole are looked for there, not on a box standing beside it.
fn on_pieces<'a>(slicer: &'a Slicer, rings: &[Ring]) -> impl Fn(usize) -> bool + 'a {
    let pieces = rings.iter().fold(0, |bits, r| bits | r.pieces);
    move |k| {
        slicer
            .piece_of_vertex(k)
            .is_some_and(|p| pieces & piece_bit(p) != 0)
    }
}

/// The foot of limb `i`, from its rings ascending from the bottom to its seed (`low`): the
/// vertices below the seed's section, nearer its centre line than any other limb's.
fn foot(
    positions: &[Point3<f64>],
    up: &Vector3<f64>,
    low: &[Ring],
    seeds: &[Ring],
    i: usize,
    on_limb: impl Fn(usize) -> bool,
) -> Option<Foot> {
    // The seed's section, at the ankle or above it: a narrower one lower down can be a patch of
    // sole, off to one side of the foot.
    let ankle = low.last()?;
    let centre = Vector3::from(ankle.centre);
    let across = |p: &Vector3<f64>, c: &Vector3<f64>| {
        let d = p - c;
        d - up * d.dot(up)
    };
    let (mut toe, mut reach) = (None, 0.0);
    for (k, p) in positions.iter().enumerate() {
        let p = p.coords;
        if p.dot(up) >= ankle.s || !on_limb(k) {
            continue;
        }
        let d = across(&p, &centre).norm();
        if d > reach && d <= FOOT_MAX_M && !nearer_other_limb(&p, up, d, seeds, i) {
            (toe, reach) = (Some(p), d);
        }
    }
    let radius = ankle.girth_m / std::f64::consts::TAU;
    let toe = toe.filter(|_| reach > FOOT_REACH * radius)?;
    Some(Foot {
        toe_tip: toe.into(),
        direction: across(&toe, &centre).normalize().into(),
    })
}

/// True when `p`, `d` across from limb `i`'s centre line, is nearer another limb's (the lines
/// through `seeds`' centres along `up`): it belongs to that limb's foot, not limb `i`'s.
fn nearer_other_limb(
    p: &Vector3<f64>,
    up: &Vector3<f64>,
    d: f64,
    seeds: &[Ring],
    i: usize,
) -> bool {
    seeds.iter().enumerate().any(|(k, r)| {
        let q = p - Vector3::from(r.centre);
        k != i && (q - up * q.dot(up)).norm() < d
    })
}

/// The lowest point of limb `chosen` (of `seeds`): the lowest vertex under its rings (its
/// foot's reach when it has one) that is not nearer another limb. The other foot of a body is
/// well within a foot's reach, and is the lowest point where the body stands on it or leans
/// that way, so without the second rule the sole, and the ankle found above it, would be read
/// off the wrong foot.
fn sole(
    positions: &[Point3<f64>],
    up: &Vector3<f64>,
    profile: &[Ring],
    has_foot: bool,
    seeds: &[Ring],
    chosen: usize,
    on_limb: impl Fn(usize) -> bool,
) -> Point3<f64> {
    let bottom = profile[0];
    let centre = Vector3::from(bottom.centre);
    let seed = Vector3::from(seeds[chosen].centre);
    let reach = if has_foot {
        FOOT_MAX_M
    } else {
        bottom.girth_m / std::f64::consts::PI
    };
    let across = |p: &Vector3<f64>, c: &Vector3<f64>| {
        let d = p - c;
        (d - up * d.dot(up)).norm()
    };
    (positions.iter().enumerate())
        .filter(|&(k, p)| {
            on_limb(k)
                && across(&p.coords, &centre) <= reach
                && !nearer_other_limb(&p.coords, up, across(&p.coords, &seed), seeds, chosen)
        })
        .map(|(_, p)| p)
        .min_by(|a, b| a.coords.dot(up).total_cmp(&b.coords.dot(up)))
        .copied()
        .unwrap_or(Point3::from(bottom.centre))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::leg::test_meshes::add_box;

    #[test]
    fn a_mesh_longer_than_any_body_is_refused_before_slicing() {
        let positions = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(0.1, 0.0, 0.0),
            Point3::new(0.0, 50.0, 0.1),
        ];
        let err =
            find_landmarks(&positions, &[[0, 1, 2]], Vector3::y(), Side::Left, None).unwrap_err();
        assert!(err.seen.contains("spans 50.0 m"), "{err}");
    }

    #[test]
    fn the_sole_of_the_leg_dressed_is_on_its_own_foot_when_the_other_foot_is_lower() {
        // Two legs 0.8 m tall, 0.3 m apart, each with a foot forward (+Z); the right one (−X,
        // since the body faces +Z) stands 3 cm lower. Its foot is within a foot's reach of the
        // left leg, and lower.
        let (positions, triangles) = legs_with_feet(0.0, -0.03);
        for (side, x, y) in [(Side::Left, 0.15, 0.0), (Side::Right, -0.15, -0.03)] {
            let l = find_landmarks(&positions, &triangles, Vector3::y(), side, None).unwrap();
            assert_eq!(l.legs_found, 2);
            assert!(l.foot.is_some(), "{side:?}");
            assert!((l.ankle.centre[0] - x).abs() < 1e-9, "{side:?}: {l:?}");
            assert_eq!(l.sole[1], y, "{side:?}: sole {:?}", l.sole);
            assert!(l.sole[0] * x > 0.0, "{side:?}: sole {:?}", l.sole);
        }
    }

    #[test]
    fn a_body_turned_about_its_up_faces_where_its_feet_point_and_keeps_its_left() {
        // Two legs with feet forward (+Z), standing level, the left one at +X; then the same
        // turned 40° about up.
        let (positions, triangles) = legs_with_feet(0.0, 0.0);
        for degrees in [0.0, 40.0] {
            let turn =
                nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), f64::to_radians(degrees));
            let turned: Vec<Point3<f64>> = positions.iter().map(|p| turn * p).collect();
            let l = find_landmarks(&turned, &triangles, Vector3::y(), Side::Left, None).unwrap();
            let forward = turn * Vector3::z();
            let facing = Vector3::from(l.facing.expect("both feet point forward"));
            // Within the boxes' toe tips' 11° (a corner of each box is its tip).
            assert!(facing.dot(&forward) > 0.97, "{degrees}°: facing {facing}");
            assert!(facing.dot(&Vector3::y()).abs() < 1e-9);
            let left_leg = turn * Vector3::new(0.15, 0.0, 0.0);
            assert!(
                Vector3::from(l.ankle.centre).dot(&left_leg) > 0.0,
                "{degrees}°"
            );
            let stance = l.stance();
            if degrees == 0.0 {
                assert_eq!(stance, Stance::default());
            } else {
                assert!(stance.facing.dot(&forward) > 0.97, "{stance:?}");
            }
        }
    }

    #[test]
    fn a_body_with_its_arms_raised_stands_on_its_feet_not_its_hands() {
        // Box legs with feet (0.4 m around), a trunk and head, and arms 0.2 m around raised
        // 0.7 m over the shoulders: the end with the hands is the slimmer one, and only read
        // with +Y up does a leg stand on a foot.
        let (positions, triangles) = box_body(true);
        let body = anatomical_up(&positions, &triangles).unwrap();
        assert!(body.up.dot(&Vector3::y()) > 0.99, "{body:?}");
        assert!(body.on_its_feet && body.clear(), "{body:?}");
        // Upside down, the same body is read the same way up.
        let flipped: Vec<Point3<f64>> = (positions.iter())
            .map(|p| Point3::new(p.x, -p.y, -p.z))
            .collect();
        let body = anatomical_up(&flipped, &triangles).unwrap();
        assert!(body.up.dot(&-Vector3::y()) > 0.99, "{body:?}");
        // Its arms down, the slimmer end is the feet's, as it always was.
        let (positions, triangles) = box_body(false);
        let body = anatomical_up(&positions, &triangles).unwrap();
        assert!(body.up.dot(&Vector3::y()) > 0.99, "{body:?}");
        assert!(!body.on_its_feet && body.clear(), "{body:?}");
    }

    #[test]
    fn a_joint_found_near_where_two_pieces_overlap_is_their_middle() {
        // Sections every 2.5 mm up a limb, through two pieces between 0.48 and 0.52 m.
        let profile: Vec<Ring> = (0..=400)
            .map(|k| {
                let s = k as f64 * 0.0025;
                Ring {
                    s,
                    centre: [0.0, s, 0.0],
                    girth_m: 0.3,
                    gap_m: f64::INFINITY,
                    pieces: if (0.48..=0.52).contains(&s) {
                        0b11
                    } else {
                        0b01
                    },
                }
            })
            .collect();
        let at = |s: f64| profile[(s / 0.0025).round() as usize];
        // Found 1.5 cm below the seam (the narrower piece's section below the wider one): the
        // seam's middle. Found 5 cm away: where it was found.
        assert!((at_the_seam(&profile, at(0.465)).s - 0.5).abs() < 0.003);
        assert!((at_the_seam(&profile, at(0.5)).s - 0.5).abs() < 0.003);
        assert_eq!(at_the_seam(&profile, at(0.43)).s, at(0.43).s);
        // A limb in one piece keeps what was found.
        let whole: Vec<Ring> = (profile.iter())
            .map(|r| Ring { pieces: 0b01, ..*r })
            .collect();
        assert_eq!(at_the_seam(&whole, at(0.465)).s, at(0.465).s);
    }

    /// [`legs_with_feet`] under a trunk and a head, with arms 0.2 m around hanging at its sides
    /// or `raised` 0.7 m over its shoulders.
    fn box_body(raised: bool) -> (Vec<Point3<f64>>, Vec<[u32; 3]>) {
        let (mut positions, mut triangles) = legs_with_feet(0.0, 0.0);
        let mut add = |lo, hi| add_box(&mut positions, &mut triangles, lo, hi);
        add([-0.22, 0.78, -0.1], [0.22, 1.4, 0.1]);
        add([-0.1, 1.38, -0.1], [0.1, 1.65, 0.1]);
        let (low, high) = if raised { (1.25, 2.1) } else { (0.7, 1.4) };
        for x in [-0.27, 0.27] {
            add([x - 0.025, low, -0.025], [x + 0.025, high, 0.025]);
        }
        (positions, triangles)
    }

    /// Two legs 0.8 m tall, 0.3 m apart, the left one (+X) standing at y = 0 and the right one
    /// `right_lift` metres higher, each with a box foot forward (+Z), a piece of its own pushed
    /// 1 cm into the leg; the right foot turned out `right_turn_deg` about its leg's axis,
    /// towards −X.
    fn legs_with_feet(right_turn_deg: f64, right_lift: f64) -> (Vec<Point3<f64>>, Vec<[u32; 3]>) {
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        for (x, y) in [(0.15, 0.0), (-0.15, right_lift)] {
            let leg = ([x - 0.05, y, -0.05], [x + 0.05, y + 0.8, 0.05]);
            let foot = ([x - 0.05, y, 0.04], [x + 0.05, y + 0.04, 0.25]);
            add_box(&mut positions, &mut triangles, leg.0, leg.1);
            add_box(&mut positions, &mut triangles, foot.0, foot.1);
        }
        let turn =
            nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), -right_turn_deg.to_radians());
        let n = positions.len();
        for p in &mut positions[n - 8..] {
            let axis = Point3::new(-0.15, p.y, 0.0);
            *p = axis + turn * (*p - axis);
        }
        (positions, triangles)
    }

    #[test]
    fn the_rig_says_which_leg_is_the_left_over_where_the_feet_point() {
        // The feet point +Z, so the geometry takes +X for the left; a rig whose left leg
        // stands at −X (a character exported facing −Z with its feet turned back, a mirrored
        // export) is the word on it.
        let (positions, triangles) = legs_with_feet(0.0, 0.0);
        let leg = |x: f64| RigLeg {
            hip: [x, 0.8, 0.0],
            knee: [x, 0.45, 0.0],
            ankle: [x, 0.08, 0.0],
            toe: None,
        };
        let rig = Rig {
            naming: "named",
            left: Some(leg(-0.15)),
            right: Some(leg(0.15)),
        };
        for (side, x) in [(Side::Left, -0.15), (Side::Right, 0.15)] {
            let l = find_landmarks(&positions, &triangles, Vector3::y(), side, Some(&rig)).unwrap();
            assert!((l.ankle.centre[0] - x).abs() < 1e-9, "{side:?}: {l:?}");
            let agreement = l.rig.expect("the rig's ankle and knee lie in this leg");
            assert_eq!(agreement.side, side);
        }
        let l = find_landmarks(&positions, &triangles, Vector3::y(), Side::Left, None).unwrap();
        assert!(
            l.ankle.centre[0] > 0.0,
            "without the rig, the feet say: {l:?}"
        );
    }

    #[test]
    fn a_lone_standing_leg_is_not_dressed_for_the_side_that_is_lifted() {
        // The right leg (−X) lifted 30 cm, above where legs are looked for: only the left
        // stands, 0.15 m to the left of the body's centre.
        let (positions, triangles) = legs_with_feet(0.0, 0.3);
        let l = find_landmarks(&positions, &triangles, Vector3::y(), Side::Left, None).unwrap();
        assert!(l.ankle.centre[0] > 0.0, "{l:?}");
        let err =
            find_landmarks(&positions, &triangles, Vector3::y(), Side::Right, None).unwrap_err();
        assert!(
            err.seen.contains("the only leg standing") && err.seen.contains("--side left"),
            "{err}"
        );
        assert!(!err.up_in_doubt);
    }

    #[test]
    fn feet_that_disagree_do_not_turn_the_character_and_a_lifted_one_is_not_asked() {
        // Both standing: they disagree by 60°, so the feet do not say where it faces, and it
        // is pictured along the file's axes.
        let (positions, triangles) = legs_with_feet(60.0, 0.0);
        let l = find_landmarks(&positions, &triangles, Vector3::y(), Side::Left, None).unwrap();
        assert_eq!(l.facing, None, "{l:?}");
        assert_eq!(l.stance(), Stance::default());
        // The turned foot lifted 5 cm: the standing one says where the character faces.
        let (positions, triangles) = legs_with_feet(60.0, 0.05);
        let l = find_landmarks(&positions, &triangles, Vector3::y(), Side::Left, None).unwrap();
        let facing = Vector3::from(l.facing.expect("one foot stands"));
        assert!(facing.dot(&Vector3::z()) > 0.97, "{facing}");
        assert!(
            l.ankle.centre[0] > 0.0,
            "the left leg: {:?}",
            l.ankle.centre
        );
    }
}
