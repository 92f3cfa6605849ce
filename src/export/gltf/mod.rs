//! Binary glTF: the writer of every `.glb` knitfit makes, and the reader of its own
//! `stocking.glb` (what `knitfit render` draws from).

pub mod read;
pub mod write;

pub use read::{read_stocking_glb, StockingGlb};
pub use write::{write_glb, write_nodes_glb, write_scenes_glb, GlbBuilder, GlbNode};
