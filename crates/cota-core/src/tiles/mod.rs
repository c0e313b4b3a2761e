//! Terrain tile pyramids cut from one global hierarchy: every tile of every
//! zoom is a subtree of the same bitree, so same-zoom neighbours share their
//! border vertices by construction and every tile meets its zoom's error
//! bound at every sample of the lattice it was cut from.
//!
//! Papers `000_ebf7e3a88dffd361.txt` (the bitree, its diamonds) and
//! `001_49f2c365e8c41172.txt` (one hierarchy over a mosaic of SRTM tiles);
//! the output format is Cesium's quantized-mesh-1.0 (CesiumGS/quantized-mesh)
//! on the geographic TMS of its specification, written by `cota-io`.
//!
//! 1. [`Lattice::resample`]: the source, bilinearly resampled once onto the
//!    tiling's lattice at the maximum zoom, over a window of whole tiles
//!    around its footprint, 0 m beyond ([`lattice`]);
//! 2. [`Prepared::new`]: one [`crate::Bitree`] over that window, whose squares
//!    are the tiles of every zoom from the window's alignment zoom on, and
//!    the coarse levels above it ([`cap`]); the error bound `e_z` per zoom
//!    ([`ErrorSchedule`]) and the threshold `e_z − margin_z` that leaves room
//!    for the format's quantization ([`plan`]);
//! 3. [`Prepared::cut`]: one tile, the subtree of its square, split where the
//!    global error exceeds the threshold ([`cut`]). The triangles larger than
//!    the tile are split by construction (the tile's two halves are its
//!    roots); a split point on a tile's border decides alike in both tiles
//!    that share it, and its ancestors in each tile split too (errors grow up
//!    the tree), so there is no T-junction across a border;
//! 4. the tile is encoded, decoded independently and checked with
//!    [`crate::check::check_placed_mesh`] at every lattice sample of its
//!    square (`cota-io`).

pub mod cap;
pub mod cut;
pub mod lattice;
pub mod plan;
pub mod scheme;

pub use cut::{Prepared, TileMesh, WaterMask};
pub use lattice::{resampling_deviation, Deviation, Lattice, LatticeOptions};
pub use plan::{TileRange, TilerOptions, ZoomPlan};
pub use scheme::{ErrorSchedule, GeographicScheme, TileId};

/// The largest `u`, `v` or height value of quantized-mesh-1.0.
pub const QUANTIZED_MAX: u32 = 32767;

/// Why a pyramid cannot be made.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum TilesError {
    /// The source is not in a geographic CRS.
    #[error("expected a source in a geographic CRS (longitude/latitude, e.g. EPSG:4326), found {crs}; reproject it first")]
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
    /// The source lies partly outside ±180° × ±90°.
    #[error("expected a source within longitudes -180..180 and latitudes -90..90, found {west}..{east}, {south}..{north}")]
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
    Mesh(#[from] crate::bitree::MeshError),
}
