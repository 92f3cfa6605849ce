//! Pictures: the flat-patch drawing now; the yarn-level preview renderer later.

pub mod colormap;
pub mod patch_picture;
