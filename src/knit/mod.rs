//! The knit: pattern (yarn kinds, point classes), the mass-spring model, and the shapes it is
//! built in (a flat patch now; the tube for fitting later).

pub mod model;
pub mod patch;
pub mod pattern;
pub mod tube;

pub use model::{Connection, Incident, Knit, Particles, PointId, Spring, Vec3};
pub use pattern::{Direction, Pattern, Tile, YarnKind};
