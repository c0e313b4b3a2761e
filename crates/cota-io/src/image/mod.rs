//! Reading imagery to drape on a DEM (paper `004_ab8d08b3e6a5a70a.txt`'s
//! satellite photograph): [`read_image`] and [`place_on`].
//!
//! * **Formats** (detected from content): GeoTIFF, any number of bands,
//!   read band by band with the DEM reader's GeoTIFF code (so every layout,
//!   compression and GeoKey it reads); PNG (`png`) and JPEG (`zune-jpeg`,
//!   pure Rust). Non-8-bit samples are stretched to 0–255 (`decode`).
//! * **Bands** ([`ImageOptions::bands`]): three 1-based bands taken as R, G,
//!   B (`[3, 2, 1]` is Landsat TM/ETM+ true colour), or one band as gray.
//!   Default: bands 1, 2, 3 of an image with three or more, band 1 as gray
//!   of a one- or two-band image.
//! * **Georeference**, in this order: the GeoTIFF's own (tags and GeoKeys);
//!   a world file beside the image (`world`: `.pgw`, `.jgw`, `.tfw`,
//!   `.wld`, …; no CRS); none, and the image is then stretched over the
//!   DEM's footprint ([`ImagePlacement::spanning`]).
//! * **CRS** ([`crs`]): the image must be in the DEM's CRS by the rule
//!   stated there (cota does not reproject); a mismatch is an error naming
//!   both.
//!
//! The resampling itself (bilinear per channel onto the texture raster
//! that spans the DEM's samples) is `cota_core::texture::drape`;
//! [`drape_file`] does the three steps in one call.

pub mod crs;
mod decode;
mod drape;
pub mod error;
mod world;

use std::path::{Path, PathBuf};

use cota_core::texture::{ImagePlacement, RgbImage};
use cota_core::{Crs, HeightGrid};

pub use self::decode::MAX_PIXELS;
pub use self::drape::{drape_file, DrapeFileOptions, Draped};
pub use self::error::{ImageError, ImageErrorKind};

/// Options of [`read_image`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub struct ImageOptions {
    /// The bands to read as R, G, B (1-based), or one band as gray. Default:
    /// `None` (see the module docs).
    pub bands: Option<Bands>,
}

impl ImageOptions {
    /// The defaults, as documented on each field.
    pub const DEFAULT: ImageOptions = ImageOptions { bands: None };

    /// Sets [`ImageOptions::bands`].
    pub const fn with_bands(mut self, bands: Option<Bands>) -> Self {
        self.bands = bands;
        self
    }
}

/// Which bands make the colours.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Bands {
    /// One band, as gray.
    Gray(u16),
    /// Three bands, as R, G, B.
    Rgb([u16; 3]),
}

impl Bands {
    /// Parses `3,2,1` or `4` (1-based band numbers).
    ///
    /// # Errors
    /// [`ImageErrorKind::BadBands`] for anything else.
    pub fn parse(text: &str) -> Result<Bands, ImageErrorKind> {
        let bad = || ImageErrorKind::BadBands(text.to_string());
        let v: Vec<u16> = text
            .split(',')
            .map(|s| s.trim().parse::<u16>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad())?;
        match *v.as_slice() {
            _ if v.contains(&0) => Err(bad()),
            [g] => Ok(Bands::Gray(g)),
            [r, g, b] => Ok(Bands::Rgb([r, g, b])),
            _ => Err(bad()),
        }
    }

    /// The bands as R, G, B (gray repeated).
    pub fn rgb(self) -> [u16; 3] {
        match self {
            Bands::Gray(g) => [g; 3],
            Bands::Rgb(b) => b,
        }
    }

    /// `3,2,1` or `4`.
    pub fn text(self) -> String {
        match self {
            Bands::Gray(g) => g.to_string(),
            Bands::Rgb([r, g, b]) => format!("{r},{g},{b}"),
        }
    }
}

/// An image as read.
#[derive(Debug, Clone)]
pub struct Image {
    /// The pixels.
    pub rgb: RgbImage,
    /// The file's format: `GeoTIFF`, `PNG` or `JPEG`.
    pub format: &'static str,
    /// Bands in the file.
    pub band_count: u16,
    /// The bands used.
    pub bands: Bands,
    /// `UInt8`, or how other samples were brought to 8 bits.
    pub data_type: &'static str,
    /// The CRS (`Unknown` without GeoKeys).
    pub crs: Crs,
    /// Where the image lies, when the file or a world file says.
    pub placement: Option<ImagePlacement>,
    /// Where the placement came from: "GeoTIFF tags", the world file's name,
    /// or "none".
    pub placement_source: String,
    /// The file read.
    pub path: PathBuf,
}

/// Reads an image (module docs).
///
/// # Errors
/// An [`ImageError`] naming `path`: unreadable, unknown or malformed
/// content, a band the image lacks ([`ImageErrorKind::MissingBand`]), an
/// unusable world file, an image beyond [`MAX_PIXELS`].
pub fn read_image(path: &Path, opts: &ImageOptions) -> Result<Image, ImageError> {
    read(path, opts).map_err(|k| ImageError::new(path, k))
}

/// Largest image file read: [`MAX_PIXELS`] pixels of four 16-bit bands
/// stored raw, plus 1 MiB of headers. Reading stops there, whatever the
/// file's size says (a device, a pipe, a growing file).
pub const MAX_IMAGE_FILE_BYTES: u64 = MAX_PIXELS * 8 + (1 << 20);

fn read(path: &Path, opts: &ImageOptions) -> Result<Image, ImageErrorKind> {
    let bytes = crate::limits::read_file_capped(path, MAX_IMAGE_FILE_BYTES)?;
    let (format, decoded, count, bands) = if bytes.starts_with(b"II") || bytes.starts_with(b"MM") {
        let count = decode::tiff_bands(&bytes)?;
        let bands = pick_bands(opts.bands, count)?;
        let mut wanted = bands.rgb().to_vec();
        wanted.dedup();
        (
            "GeoTIFF",
            decode::tiff(&bytes, path, count, &wanted)?,
            count,
            bands,
        )
    } else {
        let (format, d) = if bytes.starts_with(b"\x89PNG") {
            ("PNG", decode::png(&bytes)?)
        } else if bytes.starts_with(&[0xFF, 0xD8, 0xFF]) {
            ("JPEG", decode::jpeg(&bytes)?)
        } else {
            return Err(ImageErrorKind::UnknownFormat {
                found: crate::read::describe(&bytes),
            });
        };
        let count = d.bands.len() as u16;
        let bands = pick_bands(opts.bands, count)?;
        (format, d, count, bands)
    };
    let rgb = assemble(&decoded, bands)?;
    let (crs, placement, source) = match (&decoded.georef, world::find(path)) {
        (Some(g), _) => (
            g.crs.clone(),
            Some(ImagePlacement::from_georef(g)),
            "GeoTIFF tags".to_string(),
        ),
        (None, Some(w)) => (
            Crs::Unknown,
            Some(world::read(&w)?),
            w.display().to_string(),
        ),
        (None, None) => (Crs::Unknown, None, "none".to_string()),
    };
    Ok(Image {
        rgb,
        format,
        band_count: count,
        bands,
        data_type: decoded.data_type,
        crs,
        placement,
        placement_source: source,
        path: path.to_path_buf(),
    })
}

/// The bands to use: those asked for, checked against the image's count,
/// or the default (module docs). An alpha band is never chosen by default.
fn pick_bands(asked: Option<Bands>, count: u16) -> Result<Bands, ImageErrorKind> {
    let bands = asked.unwrap_or(if count >= 3 {
        Bands::Rgb([1, 2, 3])
    } else {
        Bands::Gray(1)
    });
    if bands.rgb().iter().any(|&b| b > count) {
        return Err(ImageErrorKind::MissingBand {
            asked: bands.text(),
            found: count,
        });
    }
    Ok(bands)
}

/// Interleaves the chosen bands into RGB pixels.
fn assemble(d: &decode::Decoded, bands: Bands) -> Result<RgbImage, ImageErrorKind> {
    let band = |b: u16| {
        d.bands
            .get(usize::from(b - 1))
            .and_then(|v| v.as_deref())
            .unwrap_or(&[])
    };
    let [r, g, b] = bands.rgb().map(band);
    let n = d.width * d.height;
    if [r, g, b].iter().any(|v| v.len() != n) {
        return Err(ImageErrorKind::Decode {
            format: "image",
            detail: format!("bands of another size than {}x{}", d.width, d.height),
        });
    }
    let px = (0..n).map(|i| [r[i], g[i], b[i]]).collect();
    Ok(RgbImage::new(d.width, d.height, px)?)
}

/// Where `image` lies on `grid`, and which CRS rule let it ([`crs`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Placed {
    /// The placement in the DEM's CRS.
    pub placement: ImagePlacement,
    /// The CRS rule that applied, or "stretched over the DEM's extent".
    pub rule: String,
}

/// Places `image` on `grid` (module docs). `assume_same_crs` overrides a
/// CRS the rule cannot match (`--assume-same-crs`).
///
/// # Errors
/// [`ImageErrorKind::CrsMismatch`] naming both CRSs.
pub fn place_on(
    image: &Image,
    grid: &HeightGrid,
    assume_same_crs: bool,
) -> Result<Placed, ImageError> {
    let Some(at) = image.placement else {
        return Ok(Placed {
            placement: ImagePlacement::spanning(grid, image.rgb.width(), image.rgb.height()),
            rule: "no georeference: stretched over the DEM's extent".to_string(),
        });
    };
    let g = grid.georef();
    // The image's pixel in metres, by the DEM's own metres per CRS unit.
    let pixel_m = at.pixel_x.abs() * grid.cell_size_m()[0] / g.pixel_x.abs();
    let dem = &g.crs;
    match crs::same_crs(dem, &image.crs, pixel_m, assume_same_crs) {
        Ok(rule) => Ok(Placed {
            placement: at,
            rule,
        }),
        Err(why) => Err(ImageError::new(
            &image.path,
            ImageErrorKind::CrsMismatch {
                dem: dem.to_string(),
                image: image.crs.to_string(),
                why,
            },
        )),
    }
}
