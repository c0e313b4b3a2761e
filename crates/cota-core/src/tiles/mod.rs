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
//! 4. sharded: the tiles coarser than the band zoom from the shards' partial
//!    maxima ([`partial`]), merged by a reducer ([`merge`]) exactly;
//! 5. the tile is encoded, decoded independently and checked with
//!    [`crate::mesh::check::check_placed_mesh`] at every lattice sample of its
//!    square (`cota-io`).

pub mod cap;
pub mod coverage;
pub mod cut;
pub mod drawn;
mod error;
pub mod fit;
pub mod lattice;
pub mod merge;
pub mod partial;
pub mod plan;
pub mod samples;
pub mod scheme;
pub mod shard;
pub mod source_error;
pub mod sources;

pub use coverage::Coverage;
pub use cut::{Prepared, TileMesh, WaterMask, NORMAL_REACH_CELLS};
pub use drawn::{DrawnBound, LevelStats};
pub use error::TilesError;
pub use lattice::{
    resampling_deviation, Deviation, Lattice, LatticeFrame, LatticeOptions, SourcePart,
};
pub use merge::CoarseHierarchy;
pub use partial::{BandCorners, CoarsePartial, FinePoint, WATER_UNKNOWN};
pub use plan::{coarse_level_stats_in, LatticeStats, PartStats, TileRange, TilerOptions, ZoomPlan};
pub use scheme::{ErrorSchedule, GeographicScheme, TileId};
pub use shard::{band_zoom, owned_region, part_region, shard_plan, Shard};
pub use sources::{Resampled, Source};

/// The largest `u`, `v` or height value of quantized-mesh-1.0.
pub const QUANTIZED_MAX: u32 = 32767;
