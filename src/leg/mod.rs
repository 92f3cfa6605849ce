//! The leg: loading (glTF or PLY) into world space (metres, Y up), cleaning, the landmarks that say
//! where the stocking goes, the axis it is stretched along, and the collider the yarn slides on.

pub mod axis;
pub mod caps;
pub mod centreline;
pub mod clean;
pub mod collider;
pub mod curvature;
pub mod landmarks;
pub mod load;
pub mod orient;
pub mod ply;
pub mod rig;
pub mod settings;
pub mod slice;
pub mod solid;
#[cfg(test)]
pub(crate) mod test_meshes;
pub mod unbend;
pub mod weld;

pub use axis::{leaves_mesh, Axis, AxisSource};
pub use clean::Cleaned;
pub use collider::{Closest, Collider};
pub use curvature::SkinCurvature;
pub use landmarks::{find_landmarks, Landmarks, NoLandmarks, ThighTopKind};
pub use load::{decode_leg, load_leg, read_leg_file, Leg, LegFile, RestPose};
pub use rig::{Rig, RigLeg};
pub use settings::{ContactMethod, LegAxis, LegSettings, Side, Units, UpAxis, UpChoice, UpFrom};
