//! Pictures in two dimensions: the one raster-and-text layer every picture is drawn with, and
//! the pictures themselves (`density.png`, the patch picture, the colour bar, `bench.png`).

use image::{ImageEncoder, RgbImage};

use crate::error::{Error, Result};

pub mod bench_plot;
pub mod canvas;
pub mod colour_bar;
pub mod density_map;
pub mod patch_picture;

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
