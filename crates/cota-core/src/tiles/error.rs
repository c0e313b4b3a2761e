//! Why a pyramid cannot be made: the one error type of the tiles family
//! (format limits from the quantized-mesh-1.0 specification,
//! CesiumGS/quantized-mesh).

use super::scheme::TileId;

/// Why a pyramid cannot be made.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum TilesError {
    /// The source is not in longitude/latitude (a projected source goes
    /// through [`super::Lattice::resample_sources`] with its projection), or
    /// its CRS cannot be placed on the Earth.
    #[error("expected a source in longitude/latitude (EPSG:4326) or a CRS that can be placed on the Earth, found {crs}")]
    NotGeographic {
        /// The CRS found.
        crs: String,
    },
    /// The source has voids.
    #[error(
        "expected a source without voids, found one at column {col}, row {row}; fill them first"
    )]
    Voids {
        /// Column of the first void.
        col: usize,
        /// Row of the first void.
        row: usize,
    },
    /// The data cross both the antimeridian and the prime meridian (wider
    /// than half the world): the lattice has an edge at one of them
    /// ([`super::scheme`]'s module docs).
    #[error("expected data that cross at most one of the antimeridian and the prime meridian, found data across both (longitudes {west:.4}..{east:.4}); tile the eastern and western parts apart")]
    AcrossAntimeridian {
        /// Western edge, degrees (beyond 180° when given so).
        west: f64,
        /// Eastern edge, degrees.
        east: f64,
    },
    /// The source's footprint encloses a pole, which the geographic tiling
    /// cannot hold (its top and bottom rows are the poles themselves).
    #[error("expected a source that does not enclose a pole, found one whose footprint goes round the {pole} pole; crop the input to keep the pole outside it")]
    AroundPole {
        /// "north" or "south".
        pole: &'static str,
    },
    /// The source lies partly outside ±180° × ±90°.
    #[error("expected a source within longitudes -180..180 and latitudes -90..90, found {west:.4}..{east:.4}, {south:.4}..{north:.4}")]
    OutsideWorld {
        /// Western edge, degrees.
        west: f64,
        /// Southern edge, degrees.
        south: f64,
        /// Eastern edge, degrees.
        east: f64,
        /// Northern edge, degrees.
        north: f64,
    },
    /// The lattice window would be too large.
    #[error("the lattice window of {width}x{height} samples exceeds the limit of 2^31 samples; choose a lower --max-zoom")]
    TooLarge {
        /// Window width in samples.
        width: u64,
        /// Window height in samples.
        height: u64,
    },
    /// Inconsistent options.
    #[error("{0}")]
    BadOptions(String),
    /// The bound at a zoom leaves no room for the format's quantization.
    #[error("the error bound {max_error_m} m at zoom {zoom} is below what quantization alone can cost there ({margin_m} m); choose a larger bound or a lower --max-zoom")]
    BelowQuantization {
        /// The zoom.
        zoom: u8,
        /// Its bound, metres.
        max_error_m: f64,
        /// The quantization margin, metres.
        margin_m: f64,
    },
    /// A tile outside the pyramid.
    #[error("tile {tile} is not in the pyramid (zooms {min_zoom}..={max_zoom} over the source)")]
    NoSuchTile {
        /// The tile asked for.
        tile: TileId,
        /// The pyramid's first zoom.
        min_zoom: u8,
        /// The pyramid's last zoom.
        max_zoom: u8,
    },
    /// The window's bitree could not be built.
    #[error(transparent)]
    Mesh(#[from] crate::error::MeshError),
}
