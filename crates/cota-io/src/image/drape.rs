//! [`drape_file`]: an image file read, placed on a DEM and resampled onto
//! the texture raster that spans the DEM's samples, in one call: what
//! `cota mesh --texture`, `cota pair` and `cota serve --texture` drape.

use std::path::Path;

use cota_core::texture::{drape, DrapeOptions, RgbImage};
use cota_core::{Crs, HeightGrid};

use super::{place_on, read_image, Bands, ImageError, ImageErrorKind, ImageOptions};

/// Options of [`drape_file`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub struct DrapeFileOptions {
    /// How the image is read (its bands). Default: [`ImageOptions::DEFAULT`].
    pub image: ImageOptions,
    /// Drape even when the CRS rule cannot tell that the image's CRS is the
    /// DEM's (`--assume-same-crs`). Default: false.
    pub assume_same_crs: bool,
    /// The texture raster's bounds (its largest side, texels). Default:
    /// [`DrapeOptions::DEFAULT`] (8192 texels).
    pub drape: DrapeOptions,
}

impl DrapeFileOptions {
    /// The defaults, as documented on each field.
    pub const DEFAULT: DrapeFileOptions = DrapeFileOptions {
        image: ImageOptions::DEFAULT,
        assume_same_crs: false,
        drape: DrapeOptions::DEFAULT,
    };

    /// Sets [`DrapeFileOptions::image`].
    pub const fn with_image(mut self, image: ImageOptions) -> Self {
        self.image = image;
        self
    }

    /// Sets [`DrapeFileOptions::assume_same_crs`].
    pub const fn with_assume_same_crs(mut self, yes: bool) -> Self {
        self.assume_same_crs = yes;
        self
    }

    /// Sets [`DrapeFileOptions::drape`].
    pub const fn with_drape(mut self, drape: DrapeOptions) -> Self {
        self.drape = drape;
        self
    }
}

/// An image draped on a DEM: the texture raster and where it came from
/// (the image's own pixels are not kept).
#[derive(Debug, Clone)]
pub struct Draped {
    /// The texture raster spanning the DEM's samples
    /// (`cota_core::texture::drape`): texel `(0, 0)` at the north-west sample.
    pub texture: RgbImage,
    /// The file's format: `GeoTIFF`, `PNG` or `JPEG`.
    pub format: &'static str,
    /// The image's size as read, pixels (width, height).
    pub image_size: [usize; 2],
    /// Bands in the file.
    pub band_count: u16,
    /// The bands used.
    pub bands: Bands,
    /// The image's CRS (`Unknown` without GeoKeys).
    pub image_crs: Crs,
    /// Where the image's placement came from: "GeoTIFF tags", a world
    /// file's name, or "none".
    pub placement_source: String,
    /// The CRS rule that let the image be placed, or that it was stretched
    /// over the DEM's extent.
    pub rule: String,
}

/// Reads `path` ([`read_image`]), places it on `grid` ([`place_on`]) and
/// resamples it bilinearly onto the texture raster spanning `grid`'s
/// samples, at most [`DrapeOptions::max_side_texels`] a side.
///
/// # Errors
/// An [`ImageError`] naming `path`: unreadable or unknown content, bands
/// the image lacks, a CRS other than the DEM's, an image that does not
/// cover the DEM ([`ImageErrorKind::Placement`]).
pub fn drape_file(
    path: &Path,
    grid: &HeightGrid,
    opts: &DrapeFileOptions,
) -> Result<Draped, ImageError> {
    let img = read_image(path, &opts.image)?;
    let placed = place_on(&img, grid, opts.assume_same_crs)?;
    let texture = drape(&img.rgb, &placed.placement, grid, &opts.drape)
        .map_err(|e| ImageError::new(path, ImageErrorKind::Placement(e)))?;
    Ok(Draped {
        texture,
        format: img.format,
        image_size: [img.rgb.width(), img.rgb.height()],
        band_count: img.band_count,
        bands: img.bands,
        image_crs: img.crs,
        placement_source: img.placement_source,
        rule: placed.rule,
    })
}
