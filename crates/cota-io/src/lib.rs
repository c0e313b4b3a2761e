//! # cota-io
//!
//! Everything in cota that touches a file:
//! * DEM readers ([`read_dem`]): SRTM `.hgt` and `.hgt.zip`, GeoTIFF (pure-Rust
//!   `tiff` crate), PNG terrain encodings (terrain-RGB, Terrarium, 16-bit gray),
//!   WebP terrain tiles, PMTiles v3 archives of such tiles, NumPy `.npy`/`.npz`,
//!   USGS ASCII DEMs and ESRI ASCII grids. The format is detected from the content, the file name
//!   only breaking ties.
//! * [`read_region`]: several files read in parallel, joined into one grid
//!   (`cota_core::grid::mosaic`) and their voids filled (`cota_core::grid::voids`).
//! * Imagery ([`image::read_image`]): GeoTIFF (band selection), PNG and JPEG
//!   with a world file or the DEM's extent, placed on a DEM in the same CRS.
//! * Mesh writers (OBJ, PLY, STL, GLB, and a textured GLB), each written
//!   atomically.
//! * `EXT_meshopt_compression` codecs ([`meshopt`]), for 3D Tiles terrain
//!   and glTF.
//!
//! The tile pyramids (quantized-mesh, 3D Tiles terrain, their archives and
//! the sharded tiling job) are the `cota-tiles` crate, built on this one.
//! * CRSs ([`crs`]): a grid's map to and from WGS 84 longitude/latitude
//!   (proj4rs), `--src-crs`, footprints.
//!
//! Every error names the file and says what was expected and what was found.
#![warn(missing_docs)]

pub mod crs;
pub mod dem;
pub mod error;
pub mod export;
pub mod image;
pub mod limits;
pub mod meshopt;
pub mod read;
pub mod relief;
pub mod stream_file;

pub use dem::{
    f32_storage_error_m, ArrayName, DataType, Dem, DemSummary, Format, PngEncoding, ReadOptions,
    TileRequest, DEFAULT_MAX_ABS_HEIGHT_M, MAX_ABS_HEIGHT_M,
};
pub use error::{ReadError, ReadErrorKind, RegionError};
pub use read::{
    read_dem, read_dem_bytes, read_dem_from, read_dems_counted, read_dems_with_progress,
    read_region, read_region_in_turn, read_region_with_progress, Region, RegionOptions,
};
