//! The knit: pattern (yarn kinds, point classes), the mass-spring model, and the shapes it is
//! built in: the flat patch of the paper's experiment and the tube a fit starts from.

pub mod fabric;
pub mod model;
pub mod nylon;
pub mod patch;
pub mod path;
pub mod pattern;
pub mod settings;
pub mod tube;

pub use fabric::Fabric;
pub use model::{Connection, Face, Incident, Knit, Particles, PointId, ShortRows, Spring};
pub use pattern::{Pattern, Tile};
pub use settings::{
    KnitSettings, PatchSettings, Stretch, StretchAxis, TubeBottom, TubeHeel, TubeSettings, TubeTop,
    Yarn, Yarns, RELAXED_LENGTH_FRACTION,
};
