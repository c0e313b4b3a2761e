//! # cota-tiles
//!
//! Terrain tile pyramids, between `cota-io` (the readers) and the front ends
//! (`cota tiles`, `cota serve`, `cota.tiles`): Cesium quantized-mesh-1.0 (the
//! encoder, an independent decoder, `layer.json`) and 3D Tiles terrain
//! ([`glb_tile`], [`tileset3d`], [`pyramid3d`]), written as a directory tree,
//! one MBTiles archive ([`mbtiles`]) or one 3D Tiles Archive ([`archive3tz`]);
//! the as-drawn checker ([`drawn`]); and the sharded tiling job ([`job`]).
//!
//! The tiles themselves are cut by [`cota_core::tiles`]; this crate turns
//! them into bytes, decodes the bytes back, checks the decoded tile against
//! its error bound as the client draws it, and writes it atomically.
//!
//! ```
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use cota_core::tiles::{Lattice, LatticeOptions, Prepared, TilerOptions};
//! use cota_core::{Crs, GeoRef, HeightGrid, LonLat, PixelIs};
//! use cota_tiles::drawn::{Against, SourceGrid};
//! use cota_tiles::{write_pyramid, PyramidOptions};
//! let n = 61;
//! let heights = (0..n * n).map(|i| 300.0 + ((i % n) as f32 * 0.2).sin() * 40.0).collect();
//! let georef = GeoRef { crs: Crs::WGS84, origin_x: 10.0, origin_y: 1.0, pixel_x: 0.01,
//!     pixel_y: -0.01, pixel_is: PixelIs::Point, known: true };
//! let source = HeightGrid::new(n, n, heights, georef)?;
//! let lattice = Lattice::resample(&source, &LatticeOptions::DEFAULT)?;
//! let prepared = Prepared::new(&lattice, &source, &TilerOptions::DEFAULT)?;
//! // Every tile checked as drawn (flat ECEF triangles) against the source's
//! // samples, and against the ellipsoid farther than 0.5° from its footprint.
//! let grid = SourceGrid { grid: &source, transform: &LonLat };
//! let against = Against::new(vec![grid], vec![[10.0, 0.4, 10.6, 1.0]], 0.5);
//! let out = tempfile::tempdir()?;
//! let opts = PyramidOptions::DEFAULT;
//! let report = write_pyramid(&prepared, out.path(), &opts, Some(&against), &|_| {})?;
//! assert_eq!(report.written(), prepared.tile_count());
//! assert!(out.path().join("layer.json").is_file());
//! # Ok(())
//! # }
//! ```

#![warn(missing_docs)]

pub mod archive3tz;
pub mod coarse;
pub mod decode;
pub mod drawn;
pub mod ellipsoid;
pub mod frame;
pub mod glb_decode;
pub mod glb_tile;
pub mod job;
pub mod journal;
pub mod layer;
pub mod mbtiles;
pub mod output;
pub mod part;
pub mod plan_frame;
pub mod plan_parts;
pub mod pyramid;
pub mod pyramid3d;
pub mod quantized_mesh;
pub mod seams;
pub mod shard;
pub mod tileset3d;

pub use archive3tz::{is_3tz, pack_3tz, staging_path, write_3tz, Tz3Reader};
pub use coarse::{
    corners_path, partial_path, read_band_corners, read_partial, write_band_corners, write_partial,
    write_reduced_coarse, write_shard_partial, PartialHeader,
};
pub use decode::{decode, DecodeError, DecodedTile, Header};
pub use frame::{
    plan_layout_path, read_plan_layout, read_shard_frame, shard_frame_path, write_plan_layout,
    write_shard_frame, ShardFrame,
};
pub use job::{input_key, JobInput, PathsInput, ReadPart, TileJob, TileSettings};
pub use journal::JOURNAL_DIR;
pub use layer::layer_json;
pub use mbtiles::{is_mbtiles, write_mbtiles, MbtilesReader};
pub use output::{check_output, write_output};
pub use part::{
    file_extents, frame_of, load_part, read_part_files, read_part_files_in_turn, Part, PartError,
};
pub use plan_frame::{
    merge_plan, mosaic_frame, plan_layout, plan_part, stream_frame, summarize_files, MosaicFrame,
    PlanPart,
};
pub use plan_parts::{finish_plan, plan_layout_or, plan_part_path, run_plan_part, PlanPartReport};
pub use pyramid::{
    finish_tile, make_tile, tile_path, write_file_atomically, write_pyramid, MadeTile,
    PyramidError, PyramidOptions, PyramidReport, TileFormat, ZoomReport,
};
pub use pyramid3d::{make_glb_tile, make_tiles3d, tiles3d, write_tiles3d};
pub use quantized_mesh::{encode, encode_tile, EncodeError, Extensions, TileExtensions, TileFrame};
pub use seams::{compare_border, edge_lists_match, BorderCheck, Neighbour};
pub use shard::{reduce_shards, shard_record_path, write_plan, write_shard, ReduceReport};
