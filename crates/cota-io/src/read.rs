//! Reading a DEM file into a [`HeightGrid`]: format detection and dispatch.
//!
//! Detection looks at the content first (magic bytes of ZIP, TIFF, PNG; the
//! keywords of an ESRI ASCII header; the exact byte size of an SRTM tile) and
//! uses the file name only where content cannot decide (a raw `.hgt` has no
//! header, so its size and name are all there is).

use std::fmt;
use std::path::{Path, PathBuf};

use cota_core::HeightGrid;

use crate::error::{ReadError, ReadErrorKind};

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

/// Options for [`read_dem`].
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
}

impl ReadOptions {
    /// The defaults, as documented on each field.
    pub const DEFAULT: ReadOptions = ReadOptions {
        png_encoding: None,
        gray_scale_m: 1.0,
        gray_offset_m: 0.0,
        cell_size_m: 1.0,
        band: None,
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
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Format::SrtmHgt => f.write_str("SRTM .hgt"),
            Format::SrtmHgtZip => f.write_str("SRTM .hgt.zip"),
            Format::GeoTiff => f.write_str("GeoTIFF"),
            Format::Png(e) => write!(f, "PNG ({e})"),
            Format::EsriAscii => f.write_str("ESRI ASCII grid"),
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

/// What the first bytes of a file look like.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Sniffed {
    Gzip,
    Zip,
    Tiff,
    Png,
    Ascii,
    Unknown,
}

/// Keys that may open an ESRI ASCII grid header (lower case).
const ASCII_HEADER_KEYS: [&str; 6] = [
    "ncols",
    "nrows",
    "xllcorner",
    "xllcenter",
    "yllcorner",
    "yllcenter",
];

/// Classifies content by its magic bytes and, for text, its first keyword.
pub(crate) fn sniff(bytes: &[u8]) -> Sniffed {
    if bytes.starts_with(b"\x1f\x8b") {
        Sniffed::Gzip
    } else if bytes.starts_with(b"PK\x03\x04") || bytes.starts_with(b"PK\x05\x06") {
        Sniffed::Zip
    } else if bytes.starts_with(b"II*\0")
        || bytes.starts_with(b"MM\0*")
        || bytes.starts_with(b"II+\0")
        || bytes.starts_with(b"MM\0+")
    {
        Sniffed::Tiff
    } else if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        Sniffed::Png
    } else {
        let head = &bytes[..bytes.len().min(64)];
        let head = head.strip_prefix(b"\xef\xbb\xbf").unwrap_or(head); // UTF-8 BOM
        let text = String::from_utf8_lossy(head).to_ascii_lowercase();
        let t = text.trim_start();
        if ASCII_HEADER_KEYS.iter().any(|k| t.starts_with(k)) {
            Sniffed::Ascii
        } else {
            Sniffed::Unknown
        }
    }
}

/// Describes unrecognised content for an error message.
pub(crate) fn describe_bytes(bytes: &[u8]) -> String {
    let n = bytes.len().min(8);
    let printable = bytes[..n]
        .iter()
        .all(|b| b.is_ascii_graphic() || *b == b' ' || *b == b'\n' || *b == b'\r' || *b == b'\t');
    if printable {
        let s = String::from_utf8_lossy(&bytes[..bytes.len().min(24)]);
        format!(
            "text starting {:?} ({} bytes)",
            s.lines().next().unwrap_or(""),
            bytes.len()
        )
    } else {
        let hex: Vec<String> = bytes[..n].iter().map(|b| format!("{b:02x}")).collect();
        format!("bytes {} ({} bytes)", hex.join(" "), bytes.len())
    }
}

/// Reads one DEM file.
///
/// # Errors
/// A [`ReadError`] naming `path` and saying what was expected and found.
pub fn read_dem(path: &Path, opts: &ReadOptions) -> Result<Dem, ReadError> {
    let wrap = |kind| ReadError::new(path, kind);
    let bytes = std::fs::read(path).map_err(|e| wrap(ReadErrorKind::Io(e)))?;
    if bytes.is_empty() {
        return Err(wrap(ReadErrorKind::Empty));
    }
    decode_bytes(&bytes, path, opts).map_err(wrap)
}

/// Applies [`cota_core::GeoRef::guess_geographic`] to a freshly read DEM.
fn with_guessed_crs(mut dem: Dem) -> Dem {
    let g = &dem.grid;
    if let Some(crs) = g.georef().guess_geographic(g.width(), g.height()) {
        let mut georef = g.georef().clone();
        georef.crs = crs;
        dem.grid.set_georef(georef);
    }
    dem
}

/// Decodes DEM content already in memory; `path` supplies the name (SRTM
/// position, extension) and is used in no other way. This is what the fuzzers call.
///
/// # Errors
/// A [`ReadError`] naming `path`.
pub fn read_dem_bytes(bytes: &[u8], path: &Path, opts: &ReadOptions) -> Result<Dem, ReadError> {
    if bytes.is_empty() {
        return Err(ReadError::new(path, ReadErrorKind::Empty));
    }
    decode_bytes(bytes, path, opts).map_err(|k| ReadError::new(path, k))
}

/// Decodes DEM content; `path` supplies the name (SRTM position, extension).
pub(crate) fn decode_bytes(
    bytes: &[u8],
    path: &Path,
    opts: &ReadOptions,
) -> Result<Dem, ReadErrorKind> {
    let dem = match sniff(bytes) {
        // gzip (`N00E010.hgt.gz` as served by the AWS/Mapzen "skadi" tiles, or
        // any other gzipped DEM): decompress and read what is inside.
        Sniffed::Gzip => gunzip_and_decode(bytes, path, opts),
        // A ZIP is read as a zipped SRTM tile (the only zipped format cota knows).
        Sniffed::Zip => crate::srtm::decode(bytes, path, opts),
        Sniffed::Tiff => crate::geotiff::decode(bytes, path, opts),
        Sniffed::Png => crate::png::decode(bytes, path, opts),
        Sniffed::Ascii => crate::asc::decode(bytes, path, opts),
        // A raw .hgt has no magic: the SRTM reader decides by size and name.
        Sniffed::Unknown if crate::srtm::looks_like_hgt(bytes, path) => {
            crate::srtm::decode(bytes, path, opts)
        }
        Sniffed::Unknown => Err(ReadErrorKind::UnknownFormat {
            found: format!("{}{}", describe_bytes(bytes), name_hint(path)),
        }),
    }?;
    Ok(with_guessed_crs(dem))
}

/// Largest expansion of DEFLATE, used to refuse gzip bombs early.
const MAX_GZIP_RATIO: u64 = 1032;

/// Decompresses a gzip file (one level) and decodes its content under the
/// name without `.gz`. The output is capped at what the sample limit allows
/// (8 bytes per sample at most) and at DEFLATE's largest ratio.
fn gunzip_and_decode(bytes: &[u8], path: &Path, opts: &ReadOptions) -> Result<Dem, ReadErrorKind> {
    use std::io::Read;
    let cap = (cota_core::grid::MAX_SAMPLES * 8).min(bytes.len() as u64 * MAX_GZIP_RATIO);
    let mut inner = Vec::new();
    flate2::read::GzDecoder::new(bytes)
        .take(cap + 1)
        .read_to_end(&mut inner)
        .map_err(|e| {
            crate::error::malformed("a complete gzip stream", format!("a broken one ({e})"))
        })?;
    if inner.len() as u64 > cap {
        return Err(crate::error::malformed(
            format!("a gzip stream of at most {cap} bytes once decompressed"),
            "more (a gzip bomb or a grid beyond the sample limit)",
        ));
    }
    if inner.is_empty() {
        return Err(crate::error::malformed(
            "a DEM inside the gzip stream",
            "nothing",
        ));
    }
    if sniff(&inner) == Sniffed::Gzip {
        return Err(ReadErrorKind::Unsupported {
            what: "gzip nesting".into(),
            detail: "a gzip stream inside a gzip stream; decompress the outer one first".into(),
        });
    }
    let name = match path.extension() {
        Some(e) if e.eq_ignore_ascii_case("gz") => path.with_extension(""),
        _ => path.to_path_buf(),
    };
    let mut dem = decode_bytes(&inner, &name, opts)?;
    dem.path = path.to_path_buf();
    Ok(dem)
}

/// For unrecognised content, what the file's extension promised and lacks
/// (e.g. ", not a PNG despite the .png name: no PNG signature 89 50 4e 47");
/// empty when the extension says nothing.
fn name_hint(path: &Path) -> String {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let lacks = match ext.as_str() {
        "png" => "a PNG: no PNG signature 89 50 4e 47 0d 0a 1a 0a",
        "tif" | "tiff" => "a TIFF: no TIFF header II*\\0 or MM\\0*",
        "asc" => "an ESRI ASCII grid: no header key such as ncols",
        "zip" => "a ZIP archive: no PK\\x03\\x04 signature",
        _ => return String::new(),
    };
    format!(", not {lacks} despite the .{ext} name")
}
