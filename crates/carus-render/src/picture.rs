//! RGBA8 pictures in memory (sRGB, straight alpha, rows top to bottom).

use crate::error::RenderError;

/// An RGBA8 picture: sRGB colour, straight alpha, row-major from the top-left.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    width: u32,
    height: u32,
    pixels: Vec<u8>,
}

impl Image {
    /// Wraps `width * height * 4` bytes.
    pub fn from_rgba(width: u32, height: u32, pixels: Vec<u8>) -> Result<Self, RenderError> {
        let expected = width as usize * height as usize * 4;
        if pixels.len() != expected {
            return Err(RenderError::PixelCount {
                width,
                height,
                expected,
                actual: pixels.len(),
            });
        }
        Ok(Self {
            width,
            height,
            pixels,
        })
    }

    /// A picture of one colour.
    pub fn filled(width: u32, height: u32, rgba: [u8; 4]) -> Self {
        Self {
            width,
            height,
            pixels: rgba.repeat(width as usize * height as usize),
        }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The RGBA bytes.
    pub fn pixels(&self) -> &[u8] {
        &self.pixels
    }

    /// Gives the RGBA bytes away.
    pub fn into_pixels(self) -> Vec<u8> {
        self.pixels
    }

    /// The pixel at column `x`, row `y` (from the top); `None` outside.
    pub fn pixel(&self, x: u32, y: u32) -> Option<[u8; 4]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = (y as usize * self.width as usize + x as usize) * 4;
        self.pixels[i..i + 4].try_into().ok()
    }

    /// Sets one pixel; outside the picture nothing happens.
    pub fn set_pixel(&mut self, x: u32, y: u32, rgba: [u8; 4]) {
        if x < self.width && y < self.height {
            let i = (y as usize * self.width as usize + x as usize) * 4;
            self.pixels[i..i + 4].copy_from_slice(&rgba);
        }
    }

    /// Copies `other` in with its top-left corner at (`x`, `y`), clipped to this picture.
    pub fn paste(&mut self, other: &Image, x: u32, y: u32) {
        let width = other.width.min(self.width.saturating_sub(x)) as usize;
        for row in 0..other.height.min(self.height.saturating_sub(y)) as usize {
            let from = row * other.width as usize * 4;
            let to = ((y as usize + row) * self.width as usize + x as usize) * 4;
            self.pixels[to..to + width * 4].copy_from_slice(&other.pixels[from..from + width * 4]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrong_byte_count_is_refused() {
        let err = Image::from_rgba(2, 2, vec![0; 15]).unwrap_err().to_string();
        assert!(err.contains("needs 16"), "{err}");
    }

    #[test]
    fn paste_clips_at_the_edges() {
        let mut big = Image::filled(4, 3, [0, 0, 0, 255]);
        big.paste(&Image::filled(3, 3, [9, 9, 9, 255]), 2, 1);
        assert_eq!(big.pixel(1, 1), Some([0, 0, 0, 255]));
        assert_eq!(big.pixel(2, 1), Some([9, 9, 9, 255]));
        assert_eq!(big.pixel(3, 2), Some([9, 9, 9, 255]));
        assert_eq!(big.pixel(3, 0), Some([0, 0, 0, 255]));
        assert_eq!(big.pixel(4, 0), None);
    }
}
