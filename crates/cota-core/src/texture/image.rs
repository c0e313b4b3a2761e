//! [`RgbImage`]: 8-bit RGB pixels, row 0 north (top), the one image type of
//! the texture family. Plain data: `cota-io` decodes files into it and
//! encodes it as PNG.

use super::error::TextureError;

/// An 8-bit RGB image, row-major from the top-left pixel.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RgbImage {
    width: usize,
    height: usize,
    pixels: Vec<[u8; 3]>,
}

impl RgbImage {
    /// An image of `width × height` pixels, row-major from the top-left one.
    ///
    /// # Errors
    /// [`TextureError::BadSize`] when a side is 0 or `pixels` has another length.
    pub fn new(width: usize, height: usize, pixels: Vec<[u8; 3]>) -> Result<Self, TextureError> {
        let expected = width.saturating_mul(height);
        if width == 0 || height == 0 || pixels.len() != expected {
            return Err(TextureError::BadSize {
                width,
                height,
                expected,
                found: pixels.len(),
            });
        }
        Ok(RgbImage {
            width,
            height,
            pixels,
        })
    }

    /// An image whose size the caller has already checked (`w, h ≥ 1`,
    /// `pixels.len() == w·h`).
    pub(crate) fn from_valid(width: usize, height: usize, pixels: Vec<[u8; 3]>) -> Self {
        debug_assert!(width >= 1 && height >= 1 && pixels.len() == width * height);
        RgbImage {
            width,
            height,
            pixels,
        }
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The pixels, row-major from the top-left one.
    pub fn pixels(&self) -> &[[u8; 3]] {
        &self.pixels
    }

    /// The pixel at column `x`, row `y` (both in range).
    #[inline]
    pub fn get(&self, x: usize, y: usize) -> [u8; 3] {
        self.pixels[y * self.width + x]
    }

    /// The pixels as bytes, `R, G, B` per pixel.
    pub fn as_bytes(&self) -> &[u8] {
        self.pixels.as_flattened()
    }
}
