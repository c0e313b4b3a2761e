//! The plan step's frame of a sharded pyramid over parts,
//! `OUT/.cota-shards-N.json`: what every shard needs of the whole lattice
//! (its frame, statistics and where each input file lies), written once by
//! the plan step ([`super::shard::write_plan`]) and read by every shard and
//! the reduce. JSON, with every `f64` as the hexadecimal of its bits.
//!
//! `from_greenwich` records a lattice counted from 0° (a footprint across
//! the antimeridian, [`GeographicScheme::from_greenwich`]); a frame without
//! it (written before it was recorded) counts from 180° W.

use std::path::{Path, PathBuf};

use cota_core::tiles::{GeographicScheme, LatticeFrame, LatticeStats, LevelStats};
use cota_core::{Crs, GeoRef, PixelIs};
use serde_json::{json, Value};

use super::pyramid::{write_file_atomically, PyramidError};

/// What the plan step records for shards that hold only their part of the
/// lattice: `OUT/.cota-shards-N.json`.
#[derive(Debug, Clone, PartialEq)]
pub struct ShardFrame {
    /// The settings it was made with (a shard with other settings refuses it).
    pub key: String,
    /// The number of shards.
    pub shards: u32,
    /// The band zoom: the tiles coarser than it are cut by the reduce.
    pub band_zoom: u8,
    /// How many tiles are coarser than the band zoom.
    pub coarse_tiles: u64,
    /// The whole lattice's frame.
    pub frame: LatticeFrame,
    /// The whole lattice's statistics.
    pub stats: LatticeStats,
    /// Each input file and its samples in the whole source, `[c0, r0, c1,
    /// r1]` inclusive; empty when a shard must read every file (voids to
    /// fill, a `--bbox`, a single file).
    pub files: Vec<(String, [usize; 4])>,
}

/// The path of the frame of `shards` shards under `out`.
pub fn shard_frame_path(out: &Path, shards: u32) -> PathBuf {
    out.join(format!(".cota-shards-{shards}.json"))
}

/// An `f64` as the hexadecimal of its bits: JSON numbers do not round-trip
/// every `f64` exactly through serde_json's parser.
fn bits(v: f64) -> String {
    format!("{:016x}", v.to_bits())
}

fn unbits(v: &Value) -> Option<f64> {
    u64::from_str_radix(v.as_str()?, 16)
        .ok()
        .map(f64::from_bits)
}

impl ShardFrame {
    fn to_json(&self) -> Value {
        let (f, g) = (&self.frame, &self.frame.source_georef);
        json!({
            "key": self.key,
            "shards": self.shards,
            "band_zoom": self.band_zoom,
            "coarse_tiles": self.coarse_tiles,
            "max_zoom": f.scheme.max_zoom,
            "tile_cells": f.scheme.tile_cells,
            "from_greenwich": f.scheme.from_greenwich,
            "footprint": f.footprint.map(bits),
            "window": f.window,
            "align_zoom": f.align_zoom,
            "source": [bits(g.origin_x), bits(g.origin_y), bits(g.pixel_x), bits(g.pixel_y)],
            "source_area": matches!(g.pixel_is, PixelIs::Area),
            "source_size": f.source_size,
            "fit_m": bits(f.fit_m),
            "stats": [bits(f64::from(self.stats.lo_m)), bits(f64::from(self.stats.hi_m)), bits(self.stats.max_step_m), bits(self.stats.residual_m)],
            "level_slopes": self.stats.levels.slope.iter().map(|v| bits(*v)).collect::<Vec<_>>(),
            "level_spans": self.stats.levels.span_m.iter().map(|v| bits(*v)).collect::<Vec<_>>(),
            "files": self.files.iter().map(|(p, e)| json!([p, e])).collect::<Vec<_>>(),
        })
    }

    fn from_json(v: &Value) -> Option<ShardFrame> {
        let f64s = |k: &str, n: usize| -> Option<Vec<f64>> {
            let a = v[k].as_array()?;
            (a.len() == n).then_some(())?;
            a.iter().map(unbits).collect()
        };
        let u64s =
            |v: &Value| -> Option<Vec<u64>> { v.as_array()?.iter().map(Value::as_u64).collect() };
        let small = |k: &str| v[k].as_u64().and_then(|n| u8::try_from(n).ok());
        let fp = f64s("footprint", 4)?;
        let src = f64s("source", 4)?;
        let st = f64s("stats", 4)?;
        let list = |k: &str| -> Option<Vec<f64>> { v[k].as_array()?.iter().map(unbits).collect() };
        let levels = LevelStats {
            slope: list("level_slopes")?,
            span_m: list("level_spans")?,
        };
        (levels.slope.len() == levels.span_m.len()).then_some(())?;
        let win = u64s(&v["window"])?;
        let size = u64s(&v["source_size"])?;
        let files = v["files"]
            .as_array()?
            .iter()
            .map(|f| {
                let e = u64s(&f[1])?;
                let e: Vec<usize> = e
                    .iter()
                    .map(|&n| usize::try_from(n).ok())
                    .collect::<Option<_>>()?;
                Some((f[0].as_str()?.to_owned(), <[usize; 4]>::try_from(e).ok()?))
            })
            .collect::<Option<Vec<_>>>()?;
        Some(ShardFrame {
            key: v["key"].as_str()?.to_owned(),
            shards: u32::try_from(v["shards"].as_u64()?).ok()?,
            band_zoom: small("band_zoom")?,
            coarse_tiles: v["coarse_tiles"].as_u64()?,
            frame: LatticeFrame {
                scheme: GeographicScheme {
                    max_zoom: small("max_zoom")?,
                    tile_cells: u32::try_from(v["tile_cells"].as_u64()?).ok()?,
                    // Absent from frames written before the antimeridian
                    // was sharded: their lattices count from 180° W.
                    from_greenwich: match v.get("from_greenwich") {
                        None => false,
                        Some(b) => b.as_bool()?,
                    },
                },
                footprint: [fp[0], fp[1], fp[2], fp[3]],
                window: <[u64; 4]>::try_from(win).ok()?,
                align_zoom: small("align_zoom")?,
                source_georef: GeoRef {
                    crs: Crs::Epsg(4326),
                    origin_x: src[0],
                    origin_y: src[1],
                    pixel_x: src[2],
                    pixel_y: src[3],
                    pixel_is: if v["source_area"].as_bool()? {
                        PixelIs::Area
                    } else {
                        PixelIs::Point
                    },
                    known: true,
                },
                source_size: [
                    usize::try_from(size.first().copied()?).ok()?,
                    usize::try_from(size.get(1).copied()?).ok()?,
                ],
                fit_m: unbits(&v["fit_m"])?,
            },
            stats: LatticeStats {
                lo_m: st[0] as f32,
                hi_m: st[1] as f32,
                max_step_m: st[2],
                levels,
                residual_m: st[3],
            },
            files,
        })
    }
}

/// A window inside the world, at least a cell wide and high.
fn sane_window(w: [u64; 4], s: &GeographicScheme) -> bool {
    w[0] < w[2] && w[1] < w[3] && w[2] <= 2 * s.root_cells() && w[3] <= s.root_cells()
}

/// The path of the plan step's layout of `shards` shards under `out`: the
/// frame before the statistics, written first by a plan step run in parts
/// ([`super::plan_parts`]) and removed once the frame is written.
pub fn plan_layout_path(out: &Path, shards: u32) -> PathBuf {
    out.join(format!(".cota-layout-{shards}.json"))
}

/// Writes `frame` to [`shard_frame_path`] atomically.
///
/// # Errors
/// [`PyramidError::Io`].
pub fn write_shard_frame(out: &Path, frame: &ShardFrame) -> Result<(), PyramidError> {
    write_frame_to(&shard_frame_path(out, frame.shards), frame)
}

/// Writes the layout `frame` (statistics not yet known) to
/// [`plan_layout_path`] atomically.
///
/// # Errors
/// As [`write_shard_frame`].
pub fn write_plan_layout(out: &Path, frame: &ShardFrame) -> Result<(), PyramidError> {
    write_frame_to(&plan_layout_path(out, frame.shards), frame)
}

fn write_frame_to(path: &Path, frame: &ShardFrame) -> Result<(), PyramidError> {
    let text = format!("{}\n", frame.to_json());
    write_file_atomically(path, text.as_bytes(), false)
}

/// The frame of `shards` shards under `out`, `None` when there is none.
///
/// # Errors
/// [`PyramidError::Shard`] for a file that is not a frame.
pub fn read_shard_frame(out: &Path, shards: u32) -> Result<Option<ShardFrame>, PyramidError> {
    read_frame_at(shard_frame_path(out, shards))
}

/// The layout of `shards` shards under `out` ([`plan_layout_path`]),
/// `None` when there is none.
///
/// # Errors
/// [`PyramidError::Shard`] for a file that is not a frame.
pub fn read_plan_layout(out: &Path, shards: u32) -> Result<Option<ShardFrame>, PyramidError> {
    read_frame_at(plan_layout_path(out, shards))
}

fn read_frame_at(path: PathBuf) -> Result<Option<ShardFrame>, PyramidError> {
    if !path.is_file() {
        return Ok(None);
    }
    let v = read_record(&path)?;
    ShardFrame::from_json(&v)
        .filter(|f| {
            let s = &f.frame.scheme;
            f.band_zoom <= s.max_zoom
                && f.frame.align_zoom <= f.band_zoom
                && s.tile_cells.is_power_of_two()
                && (2..=4096).contains(&s.tile_cells)
                && s.max_zoom <= 30 - s.tile_cells.trailing_zeros() as u8
                && f.shards > 0
                && sane_window(f.frame.window, s)
                && f.frame.source_size.iter().all(|&n| n >= 2)
                && f.stats.lo_m.is_finite()
                && f.stats.hi_m.is_finite()
                && f.stats.max_step_m.is_finite()
        })
        .map(Some)
        .ok_or_else(|| PyramidError::Shard {
            path,
            message: "expected the plan step's frame (key, shards, band_zoom, window, source, stats, files, a valid scheme), found another JSON object".into(),
        })
}

/// A shard's record or the frame as JSON, naming the file when it is not.
pub(super) fn read_record(path: &Path) -> Result<Value, PyramidError> {
    let text = std::fs::read_to_string(path).map_err(|e| PyramidError::Shard {
        path: path.to_path_buf(),
        message: format!("expected a shard's record, could not read it: {e}"),
    })?;
    serde_json::from_str(&text).map_err(|e| PyramidError::Shard {
        path: path.to_path_buf(),
        message: format!("expected a shard's record (JSON), found invalid JSON: {e}"),
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn frame(from_greenwich: bool) -> ShardFrame {
        let scheme = GeographicScheme {
            max_zoom: 9,
            tile_cells: 64,
            from_greenwich,
        };
        ShardFrame {
            key: "k".into(),
            shards: 2,
            band_zoom: 7,
            coarse_tiles: 12,
            frame: LatticeFrame {
                scheme,
                footprint: [10.5, 20.25, 30.0, 40.0],
                window: [0, 0, 128, 64],
                align_zoom: 5,
                source_georef: GeoRef {
                    crs: Crs::Epsg(4326),
                    origin_x: 179.0,
                    origin_y: 1.0,
                    pixel_x: 1.0 / 1200.0,
                    pixel_y: -1.0 / 1200.0,
                    pixel_is: PixelIs::Point,
                    known: true,
                },
                source_size: [2401, 1201],
                fit_m: 0.5,
            },
            stats: LatticeStats {
                lo_m: -3.0,
                hi_m: 900.0,
                max_step_m: 12.5,
                levels: LevelStats {
                    slope: vec![0.25],
                    span_m: vec![3.0],
                },
                residual_m: 0.125,
            },
            files: vec![("a.hgt".into(), [0, 0, 1200, 1200])],
        }
    }

    /// A lattice counted from 0° round-trips; a frame written before the
    /// field was recorded (without it) reads as counted from 180° W.
    #[test]
    fn the_origin_of_the_columns_round_trips_and_old_frames_still_read() {
        let dir = tempfile::tempdir().unwrap();
        for g in [false, true] {
            write_shard_frame(dir.path(), &frame(g)).unwrap();
            let back = read_shard_frame(dir.path(), 2).unwrap().unwrap();
            assert_eq!(back, frame(g));
        }
        let path = shard_frame_path(dir.path(), 2);
        let mut v = read_record(&path).unwrap();
        v.as_object_mut().unwrap().remove("from_greenwich");
        std::fs::write(&path, v.to_string()).unwrap();
        let old = read_shard_frame(dir.path(), 2).unwrap().unwrap();
        assert_eq!(old, frame(false));
        v["from_greenwich"] = json!("yes");
        std::fs::write(&path, v.to_string()).unwrap();
        assert!(read_shard_frame(dir.path(), 2).is_err());
    }
}
