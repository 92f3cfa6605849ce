//! Writers for the files a run produces. One [`YarnGeometry`](crate::base::YarnGeometry) feeds every format, so PLY and glTF
//! carry the same points, segments and attributes.
//!
//! Every writer returns bytes; [`atomic::write_all`] puts them on disk (temporary name, then
//! rename), so a failed run leaves nothing half-written.

pub mod atomic;
pub mod gltf;
pub mod ply;
