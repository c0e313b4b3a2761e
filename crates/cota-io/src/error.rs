//! Errors of the readers and writers. Every message names the file.

use std::fmt;
use std::path::{Path, PathBuf};

/// A failure to read a DEM: the file and what went wrong.
///
/// Displays on one line as `FILE: what was expected, what was found`.
#[derive(Debug, thiserror::Error)]
#[error("{}: {kind}", path.display())]
pub struct ReadError {
    /// The file being read.
    pub path: PathBuf,
    /// What went wrong.
    pub kind: ReadErrorKind,
}

impl ReadError {
    /// Wraps `kind` with the file's path.
    pub fn new(path: &Path, kind: ReadErrorKind) -> Self {
        ReadError {
            path: path.to_path_buf(),
            kind,
        }
    }
}

/// What went wrong while reading a DEM.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReadErrorKind {
    /// The OS refused (missing file, permission, ...).
    #[error("cannot read the file: {0}")]
    Io(#[from] std::io::Error),
    /// The file has no bytes.
    #[error("expected a DEM, found an empty file (0 bytes)")]
    Empty,
    /// The content matches no supported format.
    #[error("expected an SRTM .hgt, .hgt.zip, GeoTIFF, PNG, WebP, PMTiles, NumPy .npy/.npz, USGS .dem or ESRI ASCII grid, found {found}")]
    UnknownFormat {
        /// A description of what the first bytes look like.
        found: String,
    },
    /// The content is not what its format requires.
    #[error("expected {expected}, found {found}")]
    Malformed {
        /// What the format requires.
        expected: String,
        /// What the file holds.
        found: String,
    },
    /// A valid file using a feature cota does not read.
    #[error("unsupported {what}: {detail}")]
    Unsupported {
        /// The feature (e.g. "GeoTIFF compression").
        what: String,
        /// Which value and what is supported instead.
        detail: String,
    },
    /// The header promises a grid over the sample limit
    /// ([`ReadOptions::max_samples`](crate::ReadOptions::max_samples)).
    #[error(
        "too large: a header of {width}x{height} ({} samples), over the limit of {max} samples \
         (raise it with --max-samples)",
        u128::from(*width) * u128::from(*height)
    )]
    TooLarge {
        /// Width from the header.
        width: u64,
        /// Height from the header.
        height: u64,
        /// The limit.
        max: u64,
    },
    /// Memory for the grid could not be allocated.
    #[error("too large: cannot allocate {bytes} bytes for {what}")]
    OutOfMemory {
        /// What was being allocated.
        what: String,
        /// The bytes asked for.
        bytes: u64,
    },
    /// A compressed input expands beyond what its content may be.
    #[error(
        "too large: {what} expands past {limit} bytes (the most its content may be within \
         the sample limit; a decompression bomb, or raise the limit with --max-samples)"
    )]
    Expands {
        /// The compressed input (e.g. "the gzip stream").
        what: String,
        /// The byte limit.
        limit: u64,
    },
    /// The file (or standard input) holds more bytes than any DEM within the
    /// sample limit may take ([`crate::limits::max_file_bytes`]); refused
    /// before it is read.
    #[error(
        "too large: {bytes} bytes, over the {limit} bytes a DEM of at most {max_samples} samples \
         may take ({per_sample} bytes per sample; raise the limit with --max-samples)"
    )]
    FileTooLarge {
        /// The file's size in bytes (for a stream: the bytes read before it stopped).
        bytes: u64,
        /// The byte limit.
        limit: u64,
        /// The sample limit it comes from.
        max_samples: u64,
        /// The bytes allowed per sample.
        per_sample: u64,
    },
    /// A height beyond [`crate::ReadOptions::max_abs_height_m`].
    #[error(
        "expected heights within ±{limit_m} m (metres above sea level), found {} m at column \
         {col}, row {row}: heights in feet or centimetres, a scale, or an undeclared nodata? \
         {hint}{}",
        cota_core::criteria::plain(*found_m),
        if *limit_m < crate::dem::MAX_ABS_HEIGHT_M { ", or pass --any-height to accept such heights" } else { "" }
    )]
    AbsurdHeight {
        /// The height found, metres.
        found_m: f64,
        /// Its column (0 west).
        col: usize,
        /// Its row (0 north).
        row: usize,
        /// The limit, metres.
        limit_m: f64,
        /// What to do, for this format.
        hint: &'static str,
    },
    /// The grid could not be built from what was read.
    #[error(transparent)]
    Grid(#[from] cota_core::GridError),
}

/// Shorthand for [`ReadErrorKind::Malformed`].
pub(crate) fn malformed(expected: impl fmt::Display, found: impl fmt::Display) -> ReadErrorKind {
    ReadErrorKind::Malformed {
        expected: expected.to_string(),
        found: found.to_string(),
    }
}

/// Maps a dimension check failure to the reader's error.
pub(crate) fn too_large(e: cota_core::GridError) -> ReadErrorKind {
    match e {
        cota_core::GridError::TooLarge { width, height, max } => {
            ReadErrorKind::TooLarge { width, height, max }
        }
        other => ReadErrorKind::Grid(other),
    }
}

/// A failure of [`read_region`](crate::read_region): one file, the join, or
/// the void fill.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RegionError {
    /// No file was given.
    #[error("expected at least one DEM file, found none")]
    NoFiles,
    /// A file could not be read (the first failing one, in input order).
    #[error(transparent)]
    Read(#[from] ReadError),
    /// The files could not be joined into one grid. (The message names the
    /// files; the mosaic's own error is the [`source`](std::error::Error::source).)
    #[error("mosaicking {files}")]
    Mosaic {
        /// The files, joined with ", ".
        files: String,
        /// Why.
        source: cota_core::grid::mosaic::MosaicError,
    },
    /// The voids could not be filled (or the policy refuses them); the fill's
    /// own error is the [`source`](std::error::Error::source).
    #[error("void policy")]
    Fill(#[source] cota_core::grid::voids::VoidError),
    /// Inputs in different CRSs cannot share one grid.
    #[error("expected inputs in one CRS to join into one grid, found {first} ({first_crs}) and {other} ({other_crs}); cota tiles and cota serve's tiles take them (each resampled onto the tiling's lattice)")]
    Crs {
        /// A file of the first CRS.
        first: String,
        /// Its CRS.
        first_crs: String,
        /// A file of another.
        other: String,
        /// Its CRS.
        other_crs: String,
    },
}
