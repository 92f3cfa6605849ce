//! Pictures: the flat-patch drawing, the leg's density picture, and the yarn-level preview
//! renderer (`preview`: camera, yarn lookup, shading).

use image::{ImageEncoder, RgbImage};

use crate::error::{Error, Result};

pub use settings::{CameraSettings, RenderMode, RenderSettings, View};

pub mod bench_plot;
pub mod camera;
pub mod density_bar;
pub mod density_picture;
pub mod patch_picture;
pub mod preview;
pub mod settings;
pub mod shading;
pub mod stocking_glb;
pub mod yarn_lookup;

/// Encodes an image as PNG bytes for the file `file_name`.
///
/// Errors: [`Error::Encode`] naming `file_name` if the encoder fails.
pub fn encode_png(image: &RgbImage, file_name: &str) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(
            image.as_raw(),
            image.width(),
            image.height(),
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| Error::Encode {
            what: file_name.into(),
            message: e.to_string(),
        })?;
    Ok(bytes)
}
