//! PNG encoding, decoding and writing: the crate's only file-system access.

use std::path::Path;

use image::ImageEncoder;

use crate::error::RenderError;
use crate::picture::Image;

impl Image {
    /// PNG bytes of the picture (for example to embed as base64 in a
    /// self-contained HTML report).
    pub fn encode_png(&self) -> Result<Vec<u8>, RenderError> {
        let mut bytes = Vec::new();
        image::codecs::png::PngEncoder::new(&mut bytes)
            .write_image(
                self.pixels(),
                self.width(),
                self.height(),
                image::ExtendedColorType::Rgba8,
            )
            .map_err(|source| RenderError::Png {
                during: "encoding",
                source,
            })?;
        Ok(bytes)
    }

    /// Reads PNG bytes of any colour type into RGBA8.
    pub fn decode_png(bytes: &[u8]) -> Result<Self, RenderError> {
        let decoded = image::load_from_memory_with_format(bytes, image::ImageFormat::Png)
            .map_err(|source| RenderError::Png {
                during: "decoding",
                source,
            })?
            .into_rgba8();
        let (width, height) = decoded.dimensions();
        Image::from_rgba(width, height, decoded.into_raw())
    }

    /// Writes the picture as a PNG file.
    pub fn save_png(&self, path: impl AsRef<Path>) -> Result<(), RenderError> {
        let path = path.as_ref();
        std::fs::write(path, self.encode_png()?).map_err(|source| RenderError::Write {
            path: path.to_path_buf(),
            source,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trip_keeps_every_byte() {
        let mut picture = Image::filled(5, 3, [10, 20, 30, 255]);
        picture.set_pixel(4, 2, [250, 0, 128, 77]);
        let back = Image::decode_png(&picture.encode_png().unwrap()).unwrap();
        assert_eq!(back, picture);
    }

    #[test]
    fn garbage_is_a_decoding_error() {
        let err = Image::decode_png(b"not a png").unwrap_err().to_string();
        assert!(err.contains("decoding"), "{err}");
    }

    #[test]
    fn unwritable_path_is_named() {
        let picture = Image::filled(1, 1, [0; 4]);
        let err = picture
            .save_png("/nonexistent-carus-dir/x.png")
            .unwrap_err()
            .to_string();
        assert!(err.contains("/nonexistent-carus-dir/x.png"), "{err}");
    }
}
