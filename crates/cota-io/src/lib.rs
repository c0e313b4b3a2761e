//! # cota-io
//!
//! Everything in cota that touches a file:
//! * DEM readers ([`read_dem`]): SRTM `.hgt` and `.hgt.zip`, GeoTIFF (pure-Rust
//!   `tiff` crate), PNG terrain encodings (terrain-RGB, Terrarium, 16-bit gray)
//!   and ESRI ASCII grids. The format is detected from the content, the file name
//!   only breaking ties.
//! * Mesh writers (OBJ, PLY, STL, GLB), each written atomically.
//! * Cesium quantized-mesh-1.0 terrain pyramids ([`tiles`]).
//!
//! Every error names the file and says what was expected and what was found.
#![warn(missing_docs)]

pub mod error;
pub mod read;

mod asc;
mod geotiff;
mod png;
mod srtm;

pub mod export;
pub mod stream_file;
pub mod tiles;

pub use error::{ReadError, ReadErrorKind};
pub use read::{read_dem, read_dem_bytes, DataType, Dem, Format, PngEncoding, ReadOptions};
