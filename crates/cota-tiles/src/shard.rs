//! Sharded pyramids: each of `N` processes writes its part of the tiles
//! ([`cota_core::tiles::shard_plan`]) into one directory and records it in a
//! small file; the reduce checks the `N` records and writes `layer.json`.
//!
//! Two ways to run a shard, both byte for byte the tiles a single process
//! writes, so the directory after the reduce is byte-identical to
//! [`super::write_pyramid`]'s:
//!
//! * **Parts** (after the plan step): the plan step records in
//!   `OUT/.cota-shards-N.json` ([`ShardFrame`]) what every shard needs of the
//!   whole: the lattice's frame, its statistics (height range, largest
//!   step: they set every zoom's threshold) and where each input file lies,
//!   and beside it the heights at the band zoom's tile corners. A shard then
//!   reads only the files its part of the lattice reads
//!   ([`cota_core::tiles::part_region`]), resamples and builds the bitree of
//!   that part only, cuts its tiles of the band zoom
//!   ([`cota_core::tiles::band_zoom`]) and finer, and writes its partial
//!   maxima of the coarser tiles ([`super::coarse`]); the reduce merges them
//!   and cuts those tiles, exactly the whole hierarchy's.
//! * **Whole** (no plan step): every shard prepares the whole hierarchy from
//!   the whole input and cuts only its own tiles (all zooms).
//!
//! * A shard is **idempotent**: it skips the tiles already there (written
//!   atomically, so complete), and its record is written atomically after
//!   its last tile, so a record proves the shard complete.
//! * The record `OUT/.cota-shard-I-of-N.json` holds the run manifest and the
//!   text of `layer.json`; the reduce refuses records that disagree or are
//!   missing (naming them), removes the temporary files a killed process
//!   left and the journals of killed runs that left no tile unfinished
//!   ([`super::journal`]; one that did is refused), writes `layer.json` and removes the records and the frame.

use std::path::{Path, PathBuf};
use std::time::Instant;

use cota_core::tiles::{BandCorners, Prepared, Shard, SourcePart, TileId};
use serde_json::{json, Value};

use super::coarse::{
    remove_coarse_files, write_band_corners, write_reduced_coarse, write_shard_partial,
};
use super::frame::{
    read_record, read_shard_frame, shard_frame_path, write_shard_frame, ShardFrame,
};
use super::journal::clear_gone_journals;
use super::layer::run_manifest;
use super::pyramid::{
    fold, layer_text, write_file_atomically, write_tiles, PyramidError, PyramidOptions,
    PyramidReport,
};

/// The record of shard `index` of `shards` under `out`.
pub fn shard_record_path(out: &Path, index: u32, shards: u32) -> PathBuf {
    out.join(format!(".cota-shard-{index}-of-{shards}.json"))
}

/// The plan step's output for shards over parts: the band corners (every
/// one known, [`super::coarse`]), then the frame, whose presence tells the
/// shards that the plan step is done.
///
/// # Errors
/// [`PyramidError::Shard`] for a corner not known, [`PyramidError::Io`].
pub fn write_plan(
    out: &Path,
    frame: &ShardFrame,
    corners: &BandCorners,
) -> Result<(), PyramidError> {
    write_band_corners(out, frame.shards, corners)?;
    write_shard_frame(out, frame)
}

/// Writes the tiles of `shard` under `out` (skipping those already there
/// unless `force`), then, for a shard over a part (`frame`: the plan step's),
/// its partial maxima of the coarser tiles ([`super::coarse`]), then its
/// record; `progress(done)` after each tile.
///
/// # Errors
/// As [`super::write_pyramid`].
pub fn write_shard(
    prep: &Prepared<'_>,
    out: &Path,
    opts: &PyramidOptions,
    shard: &Shard,
    frame: Option<(&ShardFrame, SourcePart<'_>)>,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<PyramidReport, PyramidError> {
    let t0 = Instant::now();
    // The plan's tiles are the lattice's; written at their addresses.
    let s = *prep.lattice().scheme();
    let tiles: Vec<_> = shard.tiles().map(|t| s.address(t)).collect();
    let outcomes = write_tiles(prep, out, opts, None, &tiles, progress)?;
    if let Some((f, source)) = frame {
        write_shard_partial(prep, source, out, f, shard.index, opts)?;
    }
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

/// Refuses the reduce while a gone run's journal names tiles it began and
/// did not end: no shard made them again since, so they may be partial.
fn refuse_unfinished(left: Vec<(PathBuf, Vec<TileId>)>) -> Result<(), PyramidError> {
    let Some((path, tiles)) = left.into_iter().next() else {
        return Ok(());
    };
    let named: Vec<String> = tiles
        .iter()
        .take(4)
        .map(|t| format!("{}/{}/{}", t.z, t.x, t.y))
        .collect();
    Err(PyramidError::Shard {
        path,
        message: format!(
            "expected every tile ended, found {} begun by a killed run and not made again ({}); \
             run the shard holding them again",
            tiles.len(),
            named.join(", ")
        ),
    })
}

/// What [`reduce_shards`] found.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct ReduceReport {
    /// Shards merged.
    pub shards: u32,
    /// Tiles in the pyramid: those the shards recorded, plus the tiles
    /// coarser than the band zoom when shards ran over parts.
    pub tiles: u64,
    /// Of those coarser tiles, how many this reduce wrote (the others were
    /// there from an interrupted reduce).
    pub coarse_written: u64,
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
    progress: &(dyn Fn(u64) + Sync),
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
    refuse_unfinished(clear_gone_journals(out)?)?;
    // After a plan step the shards hold only the band zoom and finer: the
    // coarser tiles are cut here from their partial maxima, and count too.
    let frame = read_shard_frame(out, shards)?;
    let [written, kept] = match &frame {
        Some(f) => write_reduced_coarse(out, f, false, progress)?,
        None => [0, 0],
    };
    write_file_atomically(&out.join("layer.json"), layer.as_bytes(), replace_read_only)?;
    let frame_path = shard_frame_path(out, shards);
    for p in paths
        .iter()
        .chain(frame_path.is_file().then_some(&frame_path))
    {
        std::fs::remove_file(p).map_err(|source| PyramidError::Io {
            path: p.clone(),
            source,
        })?;
    }
    remove_coarse_files(out, shards)?;
    Ok(ReduceReport {
        shards,
        tiles: tiles + written + kept,
        coarse_written: written,
    })
}
