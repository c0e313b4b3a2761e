//! Imagery over a DEM: paper `004_ab8d08b3e6a5a70a.txt`'s texture side.
//!
//! * [`image`]: [`RgbImage`], 8-bit RGB pixels (plain data; readers live in
//!   `cota-io`);
//! * [`drape`](mod@drape): where an image lies in the DEM's CRS ([`ImagePlacement`]),
//!   its resampling onto the *texture raster* that spans the DEM's samples
//!   (bilinear per channel, [`drape()`]) and the texture coordinates of a
//!   sample ([`uv`]);
//! * [`quadtree`]: the paper's unrestricted texture quadtree
//!   ([`TextureQuadtree`]): leaves of flat colour, the distortion `D(T)` and
//!   the byte count `C(T)`, exact.
//!
//! The pair of a mesh and a texture under a memory budget is chosen in
//! [`crate::pair`].

pub mod drape;
pub mod error;
pub mod image;
pub mod quadtree;

pub use drape::{drape, uv, DrapeOptions, ImagePlacement};
pub use error::TextureError;
pub use image::RgbImage;
pub use quadtree::{Leaf, TextureExtraction, TextureQuadtree};
