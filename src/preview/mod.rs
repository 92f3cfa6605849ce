//! The yarn-level preview (`preview.png`, `knitfit render`; the scene's `render` settings): a
//! ray-traced still of the fitted stocking on the leg (Sakaguchi & Miyata §7–8), from the leg
//! surface and the yarn polylines alone. The camera, the yarn lookup along a ray, the shading
//! and the sampling each have a file; `trace` puts them together per pixel.

pub mod camera;
pub mod sampling;
pub mod screen_bins;
pub mod settings;
pub mod shading;
pub mod trace;
pub mod yarn_lookup;

pub use settings::{CameraSettings, PreviewSettings, RenderMode, View};
pub use trace::{
    encode_preview, render_prepared, render_preview, PreparedScene, Preview, PreviewBuffers,
    PreviewInput, PreviewStats,
};
