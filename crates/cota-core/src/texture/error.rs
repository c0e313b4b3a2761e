//! The errors of the texture family ([`super`]): bad images, images that do
//! not cover the DEM.

/// What went wrong with an image or its placement over a DEM.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TextureError {
    /// The pixel count does not match the dimensions, or a side is 0.
    #[error(
        "expected {width}x{height} = {expected} RGB pixels (each side at least 1), found {found}"
    )]
    BadSize {
        /// Width asked for.
        width: usize,
        /// Height asked for.
        height: usize,
        /// `width × height`.
        expected: usize,
        /// Pixels given.
        found: usize,
    },
    /// A placement with a zero, NaN or infinite pixel size or origin.
    #[error("expected a finite image placement with non-zero pixel sizes, found origin ({origin_x}, {origin_y}), pixel ({pixel_x}, {pixel_y})")]
    BadPlacement {
        /// Origin x.
        origin_x: f64,
        /// Origin y.
        origin_y: f64,
        /// Pixel width.
        pixel_x: f64,
        /// Pixel height.
        pixel_y: f64,
    },
    /// Some of the DEM's extent lies outside the image.
    #[error("expected an image covering the DEM's samples {dem}, found an image over {image}: {uncovered} of {texels} texel centres lie outside it")]
    NotCovered {
        /// The DEM's sample extent, as text (`x0..x1 × y0..y1` in CRS units).
        dem: String,
        /// The image's extent, as text.
        image: String,
        /// Texels of the texture raster whose centre the image misses.
        uncovered: usize,
        /// Texels of the texture raster.
        texels: usize,
    },
}
