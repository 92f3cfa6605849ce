//! The leg's joints as a character's rig names them: hip, knee, ankle and toe of each side, read
//! from the joints of the file's glTF skins ([`super::load`] poses the mesh by them, and keeps
//! their places).
//!
//! Method: each joint's name is matched against the leg bones of the naming schemes character
//! tools export (Mixamo `mixamorig:LeftUpLeg`, MakeHuman/MPFB `upperleg01.L`, Rigify
//! `DEF-thigh.L`, Unreal `thigh_l`, VRM/VRoid `J_Bip_L_UpperLeg`, SMPL-X `left_hip`, CMU and
//! Blender's `LeftUpLeg`, `Thigh.L`): the name is split into words, a side word (`left`, `l`)
//! is taken out and the rest compared with each joint's known bone names. A glTF joint is its
//! bone's head, so the upper leg's joint is the hip, the lower leg's the knee, the foot's the
//! ankle, and the toes' the ball of the foot. Twist, roll and helper bones (`.001`, `twist`,
//! `ORG-`, `MCH-`) are not joints of the leg.
//!
//! Contract: a side's joints are kept only when its hip, knee and ankle are all named and hip to
//! knee and knee to ankle are each at least [`MIN_BONE_M`]; a file with no such side has no
//! rig. The geometry checks them and is the fallback
//! ([`super::landmarks`]): a rig only says which leg is which and where its joints are.

use nalgebra::Point3;
use serde::Serialize;

use super::Side;

/// Shortest thigh or shin a rig's leg may have, metres: joints closer than this are not a
/// leg's (a rig scaled to centimetres read in metres, or a helper chain).
pub const MIN_BONE_M: f64 = 0.15;

/// The joints of one leg, world space (metres, Y up).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RigLeg {
    /// The hip joint (the upper leg bone's head).
    pub hip: [f64; 3],
    /// The knee joint.
    pub knee: [f64; 3],
    /// The ankle joint.
    pub ankle: [f64; 3],
    /// The ball of the foot (the toe bone's head), where the rig has one.
    pub toe: Option<[f64; 3]>,
}

/// The leg joints a file's skins name, world space.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Rig {
    /// The naming scheme recognised (`mixamo`, `makehuman`, `rigify`, `unreal`, `vrm`, `smpl`,
    /// or `named` for a plain `LeftUpLeg`/`thigh.L` naming).
    pub naming: &'static str,
    /// The character's left leg.
    pub left: Option<RigLeg>,
    /// The character's right leg.
    pub right: Option<RigLeg>,
}

/// A leg joint, as a bone name says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Joint {
    Hip,
    Knee,
    Ankle,
    /// SMPL's `foot` (its ankle is `ankle`) and every scheme's toe bone.
    Toe,
    /// A bone named `foot`: the ankle, unless the side also names an `ankle` (then it is SMPL's
    /// ball of the foot).
    Foot,
}

/// Bone names (words run together, side taken out) of each leg joint.
const BONE_NAMES: [(Joint, &[&str]); 5] = [
    (
        Joint::Hip,
        &["upleg", "upperleg", "upperleg01", "thigh", "hip", "femur"],
    ),
    (
        Joint::Knee,
        &[
            "leg",
            "lowerleg",
            "lowerleg01",
            "shin",
            "calf",
            "knee",
            "tibia",
            "shank",
        ],
    ),
    (Joint::Ankle, &["ankle"]),
    (Joint::Foot, &["foot"]),
    (
        Joint::Toe,
        &["toebase", "toe", "toes", "ball", "toe11", "toe1"],
    ),
];

impl Rig {
    /// The rig named by `joints` (name, place in world space), if a side's hip, knee and ankle
    /// are all there (module docs).
    pub fn from_joints(joints: &[(String, Point3<f64>)]) -> Option<Rig> {
        let mut found: [[Option<Point3<f64>>; 5]; 2] = [[None; 5]; 2];
        for (name, place) in joints {
            let Some((side, joint)) = leg_joint(name) else {
                continue;
            };
            let slot = &mut found[side as usize][joint as usize];
            // The first named wins: a chain's head comes before its copies in every exporter.
            slot.get_or_insert(*place);
        }
        let leg = |slots: &[Option<Point3<f64>>; 5]| -> Option<RigLeg> {
            let hip = slots[Joint::Hip as usize]?;
            let knee = slots[Joint::Knee as usize]?;
            let foot = slots[Joint::Foot as usize];
            let (ankle, toe) = match slots[Joint::Ankle as usize] {
                Some(ankle) => (ankle, slots[Joint::Toe as usize].or(foot)),
                None => (foot?, slots[Joint::Toe as usize]),
            };
            let long_enough =
                (hip - knee).norm() >= MIN_BONE_M && (knee - ankle).norm() >= MIN_BONE_M;
            long_enough.then_some(RigLeg {
                hip: hip.into(),
                knee: knee.into(),
                ankle: ankle.into(),
                toe: toe.map(Into::into),
            })
        };
        let left = leg(&found[Side::Left as usize]);
        let right = leg(&found[Side::Right as usize]);
        if left.is_none() && right.is_none() {
            return None;
        }
        Some(Rig {
            naming: naming(joints.iter().map(|(n, _)| n.as_str())),
            left,
            right,
        })
    }

    /// The joints of the leg on `side`.
    pub fn leg(&self, side: Side) -> Option<&RigLeg> {
        match side {
            Side::Left => self.left.as_ref(),
            Side::Right => self.right.as_ref(),
        }
    }
}

/// The side and joint a bone's name says, if it names a leg joint (module docs).
fn leg_joint(name: &str) -> Option<(Side, Joint)> {
    let lower = name.to_ascii_lowercase();
    // Mixamo's and other namespaces: `mixamorig:LeftUpLeg`, `Armature|thigh.L`.
    let bare = lower.rsplit([':', '|']).next().unwrap_or(&lower);
    // Rigify's control and mechanism bones are not the deforming leg.
    if ["org-", "mch-", "tweak", "ik", "pole", "target"]
        .iter()
        .any(|p| bare.starts_with(p))
    {
        return None;
    }
    let bare = bare
        .strip_prefix("def-")
        .or_else(|| bare.strip_prefix("j_bip_"))
        .unwrap_or(bare);
    if bare.contains("twist") || bare.contains("roll") || bare.contains("helper") {
        return None;
    }
    let words = split_words(bare);
    let (side, rest) = take_side(&words)?;
    // A copy in a chain (`thigh.L.001`) is a twist or a segment, not the joint.
    if rest
        .iter()
        .any(|w| w.chars().all(|c| c.is_ascii_digit()) && w.len() >= 3)
    {
        return None;
    }
    let joined: String = rest.concat();
    BONE_NAMES
        .iter()
        .find(|(_, names)| names.contains(&joined.as_str()))
        .map(|&(joint, _)| (side, joint))
}

/// `name` split at `_`, `.`, `-`, spaces and lower-to-upper case changes (already lowercased, so
/// `LeftUpLeg` has become one word: its side is a prefix, see [`take_side`]).
fn split_words(name: &str) -> Vec<&str> {
    name.split(['_', '.', '-', ' '])
        .filter(|w| !w.is_empty())
        .collect()
}

/// The side a bone's words name, and the words without it: a word `left`/`l`/`right`/`r`, or
/// a first word starting with `left`/`right` (`leftupleg`).
fn take_side<'a>(words: &[&'a str]) -> Option<(Side, Vec<&'a str>)> {
    for (k, w) in words.iter().enumerate() {
        let side = match *w {
            "left" | "l" => Some(Side::Left),
            "right" | "r" => Some(Side::Right),
            _ => None,
        };
        if let Some(side) = side {
            let rest = words
                .iter()
                .enumerate()
                .filter(|&(i, _)| i != k)
                .map(|(_, w)| *w)
                .collect();
            return Some((side, rest));
        }
    }
    let first = words.first()?;
    for (prefix, side) in [("left", Side::Left), ("right", Side::Right)] {
        if let Some(rest) = first.strip_prefix(prefix) {
            let mut words: Vec<&str> = words[1..].to_vec();
            words.insert(0, rest);
            return Some((side, words.into_iter().filter(|w| !w.is_empty()).collect()));
        }
    }
    None
}

/// The naming scheme `names` follow, for the report.
fn naming<'a>(names: impl Iterator<Item = &'a str>) -> &'static str {
    let names: Vec<String> = names.map(str::to_ascii_lowercase).collect();
    let any = |f: &dyn Fn(&str) -> bool| names.iter().any(|n| f(n));
    if any(&|n| n.starts_with("mixamorig")) {
        "mixamo"
    } else if any(&|n| n.starts_with("def-")) {
        "rigify"
    } else if any(&|n| n.starts_with("j_bip_")) {
        "vrm"
    } else if any(&|n| n.contains("upperleg01")) {
        "makehuman"
    } else if any(&|n| n == "left_knee") {
        "smpl"
    } else if any(&|n| n == "calf_l") {
        "unreal"
    } else {
        "named"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_leg_joints_of_every_naming_scheme_are_read() {
        let cases = [
            ("mixamorig:LeftUpLeg", Some((Side::Left, Joint::Hip))),
            ("mixamorig:RightLeg", Some((Side::Right, Joint::Knee))),
            ("mixamorig:LeftFoot", Some((Side::Left, Joint::Foot))),
            ("mixamorig:LeftToeBase", Some((Side::Left, Joint::Toe))),
            ("upperleg01.L", Some((Side::Left, Joint::Hip))),
            ("lowerleg01.R", Some((Side::Right, Joint::Knee))),
            ("DEF-thigh.L", Some((Side::Left, Joint::Hip))),
            ("DEF-thigh.L.001", None),
            ("ORG-thigh.L", None),
            ("DEF-shin.R", Some((Side::Right, Joint::Knee))),
            ("thigh_l", Some((Side::Left, Joint::Hip))),
            ("calf_r", Some((Side::Right, Joint::Knee))),
            ("calf_twist_01_l", None),
            ("ball_l", Some((Side::Left, Joint::Toe))),
            ("J_Bip_L_UpperLeg", Some((Side::Left, Joint::Hip))),
            ("J_Bip_R_LowerLeg", Some((Side::Right, Joint::Knee))),
            ("left_hip", Some((Side::Left, Joint::Hip))),
            ("left_ankle", Some((Side::Left, Joint::Ankle))),
            ("right_foot", Some((Side::Right, Joint::Foot))),
            ("Thigh.L", Some((Side::Left, Joint::Hip))),
            ("LeftHand", None),
            ("Hips", None),
            ("spine", None),
        ];
        for (name, want) in cases {
            assert_eq!(leg_joint(name), want, "{name}");
        }
    }

    fn joints(names: &[&str], places: &[[f64; 3]]) -> Vec<(String, Point3<f64>)> {
        names
            .iter()
            .zip(places)
            .map(|(n, p)| (n.to_string(), Point3::from(*p)))
            .collect()
    }

    #[test]
    fn smpl_s_foot_is_the_ball_and_mixamo_s_the_ankle() {
        let places = [
            [0.1, 0.9, 0.0],
            [0.1, 0.5, 0.0],
            [0.1, 0.1, 0.0],
            [0.1, 0.02, 0.12],
        ];
        let smpl = Rig::from_joints(&joints(
            &["left_hip", "left_knee", "left_ankle", "left_foot"],
            &places,
        ))
        .unwrap();
        assert_eq!(smpl.naming, "smpl");
        let left = smpl.left.unwrap();
        assert_eq!((left.ankle, left.toe), (places[2], Some(places[3])));
        let mixamo = Rig::from_joints(&joints(
            &[
                "mixamorig:LeftUpLeg",
                "mixamorig:LeftLeg",
                "mixamorig:LeftFoot",
                "mixamorig:LeftToeBase",
            ],
            &places,
        ))
        .unwrap();
        assert_eq!(mixamo.naming, "mixamo");
        assert_eq!(mixamo.left.unwrap(), left);
        assert!(mixamo.right.is_none());
    }

    #[test]
    fn a_leg_too_short_or_missing_its_knee_is_no_rig() {
        let short = [[0.1, 0.09, 0.0], [0.1, 0.05, 0.0], [0.1, 0.01, 0.0]];
        assert!(Rig::from_joints(&joints(&["thigh.L", "shin.L", "foot.L"], &short)).is_none());
        let places = [[0.1, 0.9, 0.0], [0.1, 0.1, 0.0]];
        assert!(Rig::from_joints(&joints(&["thigh.L", "foot.L"], &places)).is_none());
    }
}
