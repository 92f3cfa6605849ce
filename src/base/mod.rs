//! The shared vocabulary at the bottom of the layers: vectors and frames, grid sizes, yarn kinds
//! and yarn geometry, triangle surfaces, colours. Every stage may use it; it uses no stage.

pub mod colour;
pub mod frame;
pub mod grid;
pub mod mesh;
pub mod near;
pub mod settings;
pub mod yarn;

pub use frame::{perpendicular_frame, Stance, Vec3};
pub use grid::GridSize;
pub use mesh::{area_weighted_normals, vertex_normals, Material, SurfaceMesh};
pub use near::PointGrid;
pub use yarn::{Direction, PerDirection, PerYarn, Segment, YarnGeometry, YarnKind};
