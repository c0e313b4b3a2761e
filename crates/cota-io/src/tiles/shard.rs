//! Sharded pyramids: each of `N` processes writes its part of the tiles
//! ([`cota_core::tiles::shard_plan`]) into one directory and records it in a
//! small file; the reduce checks the `N` records and writes `layer.json`.
//!
//! Every shard prepares the same global hierarchy from the whole input (the
//! tiles of a zoom depend on the errors of the whole lattice, and its plan
//! on the lattice's height range and steps), then cuts only its own tiles:
//! each tile is therefore byte for byte the tile a single process writes,
//! and the directory after the reduce is byte-identical to
//! [`super::write_pyramid`]'s. What the shards divide is the cutting,
//! encoding, checking and writing of the tiles, not the memory of the
//! hierarchy.
//!
//! * A shard is **idempotent**: it skips the tiles already there (written
//!   atomically, so complete), and its record is written atomically after
//!   its last tile, so a record proves the shard complete.
//! * The record `OUT/.cota-shard-I-of-N.json` holds the run manifest and the
//!   text of `layer.json`; the reduce refuses records that disagree or are
//!   missing (naming them), removes the temporary files a killed process
//!   left, writes `layer.json` and removes the records.

use std::path::{Path, PathBuf};
use std::time::Instant;

use cota_core::tiles::{Prepared, Shard};
use serde_json::{json, Value};

use super::layer::run_manifest;
use super::pyramid::{
    fold, layer_text, write_file_atomically, write_tiles, PyramidError, PyramidOptions,
    PyramidReport,
};

/// The record of shard `index` of `shards` under `out`.
pub fn shard_record_path(out: &Path, index: u32, shards: u32) -> PathBuf {
    out.join(format!(".cota-shard-{index}-of-{shards}.json"))
}

/// Writes the tiles of `shard` under `out` (skipping those already there
/// unless `force`), then its record; `progress(done)` after each tile.
///
/// # Errors
/// As [`super::write_pyramid`].
pub fn write_shard(
    prep: &Prepared<'_>,
    out: &Path,
    opts: &PyramidOptions,
    shard: &Shard,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<PyramidReport, PyramidError> {
    let t0 = Instant::now();
    let tiles: Vec<_> = shard.tiles().collect();
    let outcomes = write_tiles(prep, out, opts, &tiles, progress)?;
    let record = json!({
        "shard": shard.index,
        "shards": shard.shards,
        "tiles": shard.tile_count(),
        "run": run_manifest(prep, &opts.extensions, opts.gzip).to_string(),
        "layer": layer_text(prep, opts),
    });
    write_file_atomically(
        &shard_record_path(out, shard.index, shard.shards),
        format!("{record}\n").as_bytes(),
        opts.force,
    )?;
    Ok(PyramidReport {
        zooms: fold(prep, &outcomes),
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// Removes the temporary files (`.NAME.PID.tmp`) that a process killed
/// between writing a tile and renaming it left under `out`: the tiles
/// themselves are complete or absent, and every shard has recorded its end.
fn remove_temporaries(out: &Path) -> Result<(), PyramidError> {
    let mut stack = vec![out.to_path_buf()];
    while let Some(dir) = stack.pop() {
        let entries = std::fs::read_dir(&dir).map_err(|source| PyramidError::Io {
            path: dir.clone(),
            source,
        })?;
        for e in entries.flatten() {
            let p = e.path();
            let name = e.file_name().to_string_lossy().into_owned();
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                stack.push(p);
            } else if name.starts_with('.') && name.ends_with(".tmp") {
                std::fs::remove_file(&p).map_err(|source| PyramidError::Io { path: p, source })?;
            }
        }
    }
    Ok(())
}

/// What [`reduce_shards`] found.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct ReduceReport {
    /// Shards merged.
    pub shards: u32,
    /// Tiles they recorded.
    pub tiles: u64,
}

fn read_record(path: &Path) -> Result<Value, PyramidError> {
    let text = std::fs::read_to_string(path).map_err(|e| PyramidError::Shard {
        path: path.to_path_buf(),
        message: format!("expected a shard's record, could not read it: {e}"),
    })?;
    serde_json::from_str(&text).map_err(|e| PyramidError::Shard {
        path: path.to_path_buf(),
        message: format!("expected a shard's record (JSON), found invalid JSON: {e}"),
    })
}

/// The layer text and the tile count the records agree on, after checking
/// that each is of the run `run` (the text of `manifest`).
fn agreed(
    paths: &[PathBuf],
    records: &[Value],
    run: &str,
    manifest: &Path,
) -> Result<(String, u64), PyramidError> {
    let layer = records
        .first()
        .and_then(|r| r["layer"].as_str())
        .unwrap_or_default()
        .to_owned();
    let mut tiles = 0;
    for (p, r) in paths.iter().zip(records) {
        if r["run"].as_str() != Some(run)
            || r["layer"].as_str() != Some(layer.as_str())
            || layer.is_empty()
        {
            return Err(PyramidError::Shard {
                path: p.clone(),
                message: format!(
                    "expected a record of this run ({}), found one of another run or settings",
                    manifest.display()
                ),
            });
        }
        tiles += r["tiles"].as_u64().unwrap_or(0);
    }
    Ok((layer, tiles))
}

/// Reads the records of the `shards` shards under `out`, checks that all
/// are there and agree with each other and with `OUT/.cota-tiles.json`,
/// writes `layer.json` and removes the records. An existing read-only
/// `layer.json` is refused unless `replace_read_only` (the CLI's `--force`).
///
/// # Errors
/// [`PyramidError::Shard`] naming the missing or disagreeing records (the
/// directory is left as it was), [`PyramidError::Io`].
pub fn reduce_shards(
    out: &Path,
    shards: u32,
    replace_read_only: bool,
) -> Result<ReduceReport, PyramidError> {
    let paths: Vec<PathBuf> = (0..shards)
        .map(|i| shard_record_path(out, i, shards))
        .collect();
    let missing: Vec<String> = (0..shards)
        .filter(|&i| !paths[i as usize].is_file())
        .map(|i| i.to_string())
        .collect();
    if shards == 0 || !missing.is_empty() {
        return Err(PyramidError::Shard {
            path: out.to_path_buf(),
            message: format!(
                "expected the records of all {shards} shards, missing shard(s) {}; run them first",
                missing.join(", ")
            ),
        });
    }
    let manifest = out.join(".cota-tiles.json");
    let run = std::fs::read_to_string(&manifest).map_err(|source| PyramidError::Io {
        path: manifest.clone(),
        source,
    })?;
    let records = paths
        .iter()
        .map(|p| read_record(p))
        .collect::<Result<Vec<_>, _>>()?;
    let (layer, tiles) = agreed(&paths, &records, &run, &manifest)?;
    remove_temporaries(out)?;
    write_file_atomically(&out.join("layer.json"), layer.as_bytes(), replace_read_only)?;
    for p in &paths {
        std::fs::remove_file(p).map_err(|source| PyramidError::Io {
            path: p.clone(),
            source,
        })?;
    }
    Ok(ReduceReport { shards, tiles })
}
