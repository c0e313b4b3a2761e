//! What a DEM reader returns and is told: [`Dem`] (the grid and what the file
//! said about itself), [`Format`], [`DataType`], [`ReadOptions`] and
//! [`PngEncoding`]. Plain types: every reader in [`crate::read`] imports them,
//! and this module imports none of the readers.

use std::fmt;
use std::path::PathBuf;

use cota_core::{GeoRef, HeightGrid};

/// How to turn PNG pixels into heights.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PngEncoding {
    /// Mapbox terrain-RGB: h = -10000 + (R·65536 + G·256 + B)·0.1 m.
    TerrainRgb,
    /// Mapzen/AWS Terrarium: h = R·256 + G + B/256 − 32768 m.
    Terrarium,
    /// 16-bit (or 8-bit) grayscale: h = value · scale + offset (see [`ReadOptions`]).
    Gray16,
}

impl fmt::Display for PngEncoding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            PngEncoding::TerrainRgb => "terrain-rgb",
            PngEncoding::Terrarium => "terrarium",
            PngEncoding::Gray16 => "gray16",
        })
    }
}

/// Options for [`read_dem`](crate::read_dem).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct ReadOptions {
    /// PNG encoding. `None` picks by the image: RGB/RGBA images are read as
    /// terrain-RGB, grayscale images as gray16. Default: `None`. With any
    /// encoding, a pixel whose alpha (or `tRNS` transparency) is 0 is a void.
    pub png_encoding: Option<PngEncoding>,
    /// Metres per gray level for [`PngEncoding::Gray16`]. Default: 1.0.
    pub gray_scale_m: f64,
    /// Metres added after scaling for [`PngEncoding::Gray16`]. Default: 0.0.
    pub gray_offset_m: f64,
    /// Cell size in metres for formats that carry no georeference (PNG).
    /// Default: 1.0.
    pub cell_size_m: f64,
    /// 1-based band to read from a multi-band raster. `None` reads single-band
    /// files and refuses multi-band ones as ambiguous. Default: `None`.
    pub band: Option<u16>,
    /// The array to read from a NumPy `.npz` archive. `None` reads the only
    /// 2-D array, or the one named `elevation`, `dem`, `z`, `height` or
    /// `heights`, and refuses an archive where that is ambiguous (listing the
    /// names). Default: `None`.
    pub array: Option<ArrayName>,
    /// Which tiles to read from a tile archive (PMTiles): a zoom and a box.
    /// `None` refuses an archive (naming its zooms and bounds). Default: `None`.
    pub tiles: Option<TileRequest>,
    /// Largest grid, in samples, one file may declare; larger headers are
    /// refused before anything is allocated, and compressed inputs stop
    /// decompressing beyond it. `None`: the machine's default
    /// ([`crate::limits::default_max_samples`]; a gzipped `.hgt` then at most
    /// one 3601² tile). Never above [`cota_core::grid::MAX_SAMPLES`].
    /// Default: `None`.
    pub max_samples: Option<u64>,
    /// Largest height magnitude accepted, metres: a sample beyond ±this is
    /// refused, naming the file and the sample (a DEM in feet or
    /// centimetres, a wrong scale or an undeclared nodata is caught here
    /// rather than meshed). Heights are held as f32: within the default
    /// ±12,000 m (the deepest trench is −10,994 m, the highest summit
    /// 8,849 m) a height read from an f64 or text file is held to within
    /// 0.49 mm of the file's value (half a unit in the last place), exactly
    /// for integer files; beyond it that grows with the magnitude
    /// ([`f32_storage_error_m`]). At most [`MAX_ABS_HEIGHT_M`]. Default:
    /// [`DEFAULT_MAX_ABS_HEIGHT_M`].
    pub max_abs_height_m: f64,
}

/// The default [`ReadOptions::max_abs_height_m`]: 12,000 m.
pub const DEFAULT_MAX_ABS_HEIGHT_M: f64 = 12_000.0;

/// The largest [`ReadOptions::max_abs_height_m`] that may be asked: 10⁹ m.
/// Beyond it differences of f32 heights lose every metre, so such heights
/// are refused whatever the option.
pub const MAX_ABS_HEIGHT_M: f64 = 1e9;

/// The most an f32 height of magnitude up to `max_abs_m` may differ from
/// the value it was rounded from (half a unit in the last place of f32 at
/// that magnitude): 0.49 mm up to 16,384 m, 1 m at 2·10⁷ m. 0 for 0.
pub fn f32_storage_error_m(max_abs_m: f64) -> f64 {
    if !(max_abs_m.is_finite() && max_abs_m > 0.0) {
        return 0.0;
    }
    // ulp(x) = 2^(floor(log2 x) − 23) for a normal f32.
    let e = max_abs_m.log2().floor();
    0.5 * (e - 23.0).exp2()
}

/// The name of an array in a NumPy `.npz` archive (at most
/// [`ArrayName::MAX_LEN`] bytes; stored inline so that [`ReadOptions`] stays `Copy`).
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct ArrayName {
    bytes: [u8; ArrayName::MAX_LEN],
    len: u8,
}

impl ArrayName {
    /// The longest name accepted, in bytes.
    pub const MAX_LEN: usize = 64;

    /// The name, or `None` when it is empty or longer than [`ArrayName::MAX_LEN`] bytes.
    pub fn new(name: &str) -> Option<Self> {
        let src = name.as_bytes();
        if src.is_empty() || src.len() > Self::MAX_LEN {
            return None;
        }
        let mut bytes = [0u8; Self::MAX_LEN];
        bytes[..src.len()].copy_from_slice(src);
        Some(ArrayName {
            bytes,
            len: src.len() as u8,
        })
    }

    /// The name as given.
    pub fn as_str(&self) -> &str {
        std::str::from_utf8(&self.bytes[..usize::from(self.len)]).unwrap_or("")
    }
}

impl fmt::Debug for ArrayName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self.as_str(), f)
    }
}

impl fmt::Display for ArrayName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Tiles to read from a tile archive: a zoom level and a longitude/latitude
/// box (WGS 84 degrees); every tile of that zoom that touches the box is read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TileRequest {
    /// The zoom level.
    pub zoom: u8,
    /// West, south, east, north, in degrees.
    pub bbox_deg: [f64; 4],
}

impl ReadOptions {
    /// The defaults, as documented on each field.
    pub const DEFAULT: ReadOptions = ReadOptions {
        png_encoding: None,
        gray_scale_m: 1.0,
        gray_offset_m: 0.0,
        cell_size_m: 1.0,
        band: None,
        array: None,
        tiles: None,
        max_samples: None,
        max_abs_height_m: DEFAULT_MAX_ABS_HEIGHT_M,
    };

    /// Sets [`ReadOptions::png_encoding`].
    pub const fn with_png_encoding(mut self, e: Option<PngEncoding>) -> Self {
        self.png_encoding = e;
        self
    }

    /// Sets [`ReadOptions::gray_scale_m`] and [`ReadOptions::gray_offset_m`].
    pub const fn with_gray(mut self, scale_m: f64, offset_m: f64) -> Self {
        self.gray_scale_m = scale_m;
        self.gray_offset_m = offset_m;
        self
    }

    /// Sets [`ReadOptions::band`].
    pub const fn with_band(mut self, band: Option<u16>) -> Self {
        self.band = band;
        self
    }

    /// Sets [`ReadOptions::array`].
    pub const fn with_array(mut self, array: Option<ArrayName>) -> Self {
        self.array = array;
        self
    }

    /// Sets [`ReadOptions::tiles`].
    pub const fn with_tiles(mut self, tiles: Option<TileRequest>) -> Self {
        self.tiles = tiles;
        self
    }

    /// Sets [`ReadOptions::max_samples`].
    pub const fn with_max_samples(mut self, max_samples: Option<u64>) -> Self {
        self.max_samples = max_samples;
        self
    }

    /// Sets [`ReadOptions::max_abs_height_m`] (capped at [`MAX_ABS_HEIGHT_M`]).
    pub const fn with_max_abs_height_m(mut self, max_abs_height_m: f64) -> Self {
        self.max_abs_height_m = if max_abs_height_m < MAX_ABS_HEIGHT_M {
            max_abs_height_m
        } else {
            MAX_ABS_HEIGHT_M
        };
        self
    }

    /// Sets [`ReadOptions::cell_size_m`].
    pub const fn with_cell_size_m(mut self, cell_size_m: f64) -> Self {
        self.cell_size_m = cell_size_m;
        self
    }
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The file formats cota reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// SRTM `.hgt`: raw big-endian i16, n×n.
    SrtmHgt,
    /// SRTM `.hgt` inside a ZIP archive.
    SrtmHgtZip,
    /// GeoTIFF (or plain TIFF).
    GeoTiff,
    /// PNG with a height encoding.
    Png(PngEncoding),
    /// ESRI ASCII grid (`.asc`).
    EsriAscii,
    /// WebP with a height encoding (terrain-RGB or Terrarium).
    WebP(PngEncoding),
    /// Tiles of a PMTiles v3 archive (PNG or WebP, with this encoding).
    Pmtiles(PngEncoding),
    /// A NumPy `.npy` array.
    Npy,
    /// An array of a NumPy `.npz` archive.
    Npz,
    /// USGS ASCII DEM (`.dem`, type A header and B profiles).
    UsgsDem,
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Format::SrtmHgt => f.write_str("SRTM .hgt"),
            Format::SrtmHgtZip => f.write_str("SRTM .hgt.zip"),
            Format::GeoTiff => f.write_str("GeoTIFF"),
            Format::Png(e) => write!(f, "PNG ({e})"),
            Format::EsriAscii => f.write_str("ESRI ASCII grid"),
            Format::WebP(e) => write!(f, "WebP ({e})"),
            Format::Pmtiles(e) => write!(f, "PMTiles ({e} tiles)"),
            Format::Npy => f.write_str("NumPy .npy"),
            Format::Npz => f.write_str("NumPy .npz"),
            Format::UsgsDem => f.write_str("USGS ASCII DEM"),
        }
    }
}

/// The sample type stored in the file, before conversion to f32 metres.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DataType {
    /// 8-bit signed.
    I8,
    /// 8-bit unsigned.
    U8,
    /// 16-bit signed.
    I16,
    /// 16-bit unsigned.
    U16,
    /// 32-bit signed.
    I32,
    /// 32-bit unsigned.
    U32,
    /// 32-bit float.
    F32,
    /// 64-bit float.
    F64,
    /// 64-bit signed.
    I64,
    /// 8-bit RGB(A) pixels decoded by a PNG encoding.
    Rgb8,
    /// Decimal text of unknown type. The ESRI ASCII reader reports
    /// [`DataType::I32`] when every value is an integer, else [`DataType::F32`].
    Text,
}

impl fmt::Display for DataType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DataType::I8 => "Int8",
            DataType::U8 => "UInt8",
            DataType::I16 => "Int16",
            DataType::U16 => "UInt16",
            DataType::I32 => "Int32",
            DataType::U32 => "UInt32",
            DataType::F32 => "Float32",
            DataType::F64 => "Float64",
            DataType::I64 => "Int64",
            DataType::Rgb8 => "RGB8",
            DataType::Text => "text",
        })
    }
}

/// A DEM as read from one file: the grid (voids as NaN, not yet filled) and
/// what the file said about itself.
#[derive(Debug, Clone)]
pub struct Dem {
    /// The heights and georeference. Voids are NaN.
    pub grid: HeightGrid,
    /// The detected format.
    pub format: Format,
    /// The sample type in the file.
    pub data_type: DataType,
    /// The nodata value the file declared, if any.
    pub nodata: Option<f64>,
    /// The file read.
    pub path: PathBuf,
}

impl Dem {
    /// What the file held, as read: everything but the heights.
    pub fn summary(&self) -> DemSummary {
        let g = &self.grid;
        DemSummary {
            path: self.path.clone(),
            format: self.format,
            data_type: self.data_type,
            nodata: self.nodata,
            width: g.width(),
            height: g.height(),
            nodata_count: g.void_count(),
            range: g.valid_range(),
            georef: g.georef().clone(),
            cell_size_m: g.cell_size_m(),
        }
    }
}

/// One file as read, without its heights ([`Dem::summary`]): what
/// [`read_region`](crate::read_region) reports of each file it joined.
#[derive(Debug, Clone)]
pub struct DemSummary {
    /// The file read.
    pub path: PathBuf,
    /// The detected format.
    pub format: Format,
    /// The sample type in the file.
    pub data_type: DataType,
    /// The nodata value the file declared, if any.
    pub nodata: Option<f64>,
    /// Width in samples.
    pub width: usize,
    /// Height in samples.
    pub height: usize,
    /// Void samples (nodata or NaN) in the file.
    pub nodata_count: usize,
    /// Lowest and highest valid heights, metres; `None` when every sample is a void.
    pub range: Option<(f32, f32)>,
    /// The file's georeference.
    pub georef: GeoRef,
    /// Cell size in metres `[dx, dy]` ([`HeightGrid::cell_size_m`]).
    pub cell_size_m: [f64; 2],
}
