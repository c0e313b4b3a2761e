//! Terrain tile pyramids cut from one global hierarchy: every tile of every
//! zoom is a subtree of the same bitree, so same-zoom neighbours share their
//! border vertices by construction, and every tile is within its zoom's
//! bound `e_z` **as the client draws it** (flat triangles between the
//! vertices' ECEF positions on WGS 84) of the **source's own samples**.
//!
//! Papers `000_ebf7e3a88dffd361.txt` (the bitree, its diamonds) and
//! `001_49f2c365e8c41172.txt` (one hierarchy over a mosaic of DEMs of
//! different sizes and resolutions); the output format is Cesium's
//! quantized-mesh-1.0 (CesiumGS/quantized-mesh) on the geographic TMS of its
//! specification, written by `cota-io`.
//!
//! 1. [`Lattice::resample`] (one geographic source) or
//!    [`Lattice::resample_sources`] (several, any CRS through a
//!    [`crate::grid::GeoTransform`], any resolution: [`sources`]): the data
//!    resampled once onto the tiling's lattice at the maximum zoom, over a
//!    window of whole tiles around its footprint, the ellipsoid (0 m) beyond
//!    it within one finest tile, along a level-ended ramp ([`lattice`]);
//!    where the lattice is at least as fine as the source, its points are
//!    then fitted to the source's samples ([`fit`]) so that the lattice's
//!    unit triangles pass within `e_Z/2` of them;
//! 2. [`Prepared::new`] / [`Prepared::new_sampled`]: one [`crate::Bitree`]
//!    over that window, whose squares are the tiles of every zoom from the
//!    window's alignment zoom on, and the coarse levels above it ([`cap`]);
//!    per zoom the bound `e_z` ([`ErrorSchedule`]), the format's
//!    quantization margin ([`plan`]) and the as-drawn curvature term per
//!    level ([`drawn`]); per split point its error against the source's
//!    samples in its triangles ([`source_error`], [`samples`]), carried up
//!    the hierarchy by the closure of `crate::bitree::closure`;
//! 3. [`Prepared::cut`]: one tile, the subtree of its square, split where
//!    the lattice error plus the curvature term, or the source error,
//!    exceeds the zoom's threshold ([`cut`]). The triangles larger than the
//!    tile are split by construction (the tile's two halves are its roots);
//!    a split point on a tile's border decides alike in both tiles that
//!    share it, and its ancestors in each tile split too (errors grow up the
//!    tree), so there is no T-junction across a border. Tiles are made only
//!    where their square meets the data's footprint ([`coverage`]);
//! 4. sharded: the tiles coarser than the band zoom from the shards' partial
//!    maxima ([`partial`]), merged by a reducer ([`merge`]) exactly;
//! 5. across the antimeridian, the lattice counts its columns from 0°
//!    instead of 180° W, so the footprint is contiguous on it and steps 1
//!    to 4 are unchanged; tiles are addressed modulo the world's columns
//!    ([`scheme`]'s module docs, [`GeographicScheme::address`]);
//! 6. the tile is encoded, decoded independently and checked with
//!    [`crate::mesh::check::check_placed_mesh`] at every lattice sample of its
//!    square, and as drawn in ECEF at every source sample and at random
//!    points (`cota-io`'s `tiles::drawn`).

pub mod cap;
pub mod coverage;
pub mod cut;
pub mod drawn;
mod error;
pub mod estimate;
pub mod fit;
pub mod lattice;
pub mod merge;
pub mod partial;
pub mod plan;
pub mod relevant;
mod row_blocks;
pub mod samples;
pub mod scheme;
pub mod shard;
pub mod source_error;
pub mod sources;

pub use coverage::Coverage;
pub use cut::{addressed, Prepared, TileMesh, WaterMask, NORMAL_REACH_CELLS};
pub use drawn::{DrawnBound, LevelStats};
pub use error::TilesError;
pub use estimate::{estimate, Estimate};
pub use lattice::{
    resampling_deviation, resampling_deviation_with_progress, Deviation, Lattice, LatticeFrame,
    LatticeOptions, SourcePart,
};
pub use merge::CoarseHierarchy;
pub use partial::{BandCorners, CoarsePartial, FinePoint, WATER_UNKNOWN};
pub use plan::{coarse_level_stats_in, LatticeStats, PartStats, TileRange, TilerOptions, ZoomPlan};
pub use scheme::{ErrorSchedule, GeographicScheme, TileId};
pub use shard::{band_zoom, owned_region, part_region, shard_plan, Shard};
pub use sources::{Resampled, Source};

/// The largest `u`, `v` or height value of quantized-mesh-1.0.
pub const QUANTIZED_MAX: u32 = 32767;
