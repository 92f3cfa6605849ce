//! The leg: loading from glTF or PLY into world space (metres, Y up), the long axis, and the
//! collider the yarn slides on.

pub mod axis;
pub mod collider;
pub mod load;
pub mod orient;
pub mod ply;
pub mod section;
pub mod settings;
pub mod weld;

pub use axis::{detect_axis, leaves_mesh, Axis, AxisSource};
pub use collider::{Closest, Collider};
pub use load::{decode_leg, load_leg, read_leg_file, Leg, LegFile};
pub use settings::{ContactMethod, LegAxis, LegSettings, Units, UpAxis};
