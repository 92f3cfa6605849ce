//! The yarn-level preview (`preview.png`, `knitfit render`): a ray-traced still of the fitted
//! stocking on the leg (Sakaguchi & Miyata §7–8), from the leg surface and the yarn polylines
//! alone. The camera, the yarn lookup along a ray, the shading and the sampling each have a
//! file; `render` puts them together per pixel.

pub mod camera;
pub mod render;
pub mod sampling;
pub mod settings;
pub mod shading;
pub mod yarn_lookup;

pub use render::{
    encode_preview, render_prepared, render_preview, PreparedScene, Preview, PreviewBuffers,
    PreviewInput, PreviewStats,
};
pub use settings::{CameraSettings, RenderMode, RenderSettings, View};
