//! A pyramid as one MBTiles archive (`cota tiles … -o OUT.mbtiles`): the
//! same tile bytes as the directory output, tile for tile, in one SQLite
//! file that a static host, `cota serve --tiles` or any MBTiles reader
//! holds as a single object.
//!
//! Layout (MBTiles 1.3, mapbox/mbtiles-spec): `tiles(zoom_level,
//! tile_column, tile_row, tile_data)` with a unique index, rows in TMS
//! order, which is the order quantized-mesh tiles are already named in
//! (row 0 at the south); `metadata(name, value)` with `name`, `format`
//! (`application/vnd.quantized-mesh`), `bounds`, `minzoom`, `maxzoom`,
//! `json` (the pyramid's `layer.json`, byte for byte what the directory
//! output writes) and `cota_manifest` (what decides the tiles' content, as
//! `.cota-tiles.json`).
//!
//! * **Why MBTiles, not PMTiles.** PMTiles numbers tiles along a Hilbert
//!   curve over one root tile per zoom (Web Mercator's `2^z × 2^z`); the
//!   geographic scheme of quantized-mesh has two roots (`2^(z+1) × 2^z`),
//!   which its tile IDs cannot address without remapping every tile.
//!   MBTiles stores `(z, x, y)` as they are.
//! * **Atomic, resumable.** The archive is built as `OUT.mbtiles.partial`
//!   and renamed to `OUT.mbtiles` only after its metadata is written and
//!   its last transaction committed: an interrupted run never leaves a file
//!   that looks complete. A re-run with the same settings resumes the
//!   partial archive (tiles present are skipped), with other settings it is
//!   refused unless `force` (which starts afresh).
//! * **Parallel.** Tiles are made on the rayon pool as for a directory; one
//!   writer thread owns the connection and inserts them, a transaction per
//!   [`BATCH`] tiles, through a bounded channel (memory: at most
//!   [`IN_FLIGHT`] tiles' bytes beyond those being made).

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{sync_channel, Receiver};
use std::time::Instant;

use cota_core::tiles::{Prepared, TileId};
use rayon::prelude::*;
use rusqlite::{params, Connection, OptionalExtension};

use super::drawn::Against;
use super::layer::run_manifest;
use super::pyramid::{
    fold, layer_text, make_tile, Outcome, PyramidError, PyramidOptions, PyramidReport,
};

/// Tiles per transaction.
pub const BATCH: usize = 512;

/// Tiles made but not yet inserted, at most.
pub const IN_FLIGHT: usize = 1024;

/// The `format` metadata value of a quantized-mesh archive.
pub const FORMAT: &str = "application/vnd.quantized-mesh";

/// Whether `out` names an archive rather than a directory.
pub fn is_mbtiles(out: &Path) -> bool {
    out.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mbtiles"))
}

/// The archive under construction beside `out`.
pub fn partial_path(out: &Path) -> PathBuf {
    let mut name = out.file_name().unwrap_or_default().to_os_string();
    name.push(".partial");
    out.with_file_name(name)
}

fn sql(path: &Path) -> impl Fn(rusqlite::Error) -> PyramidError + '_ {
    move |e| PyramidError::Archive {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Writes every tile of `prep` into the archive `out` (`….mbtiles`), then
/// its metadata, then renames it into place; `progress(done)` after each
/// tile.
///
/// # Errors
/// [`PyramidError`]: the first tile that failed, an unwritable archive, or
/// one made with other settings ([`PyramidError::Changed`]).
pub fn write_mbtiles(
    prep: &Prepared<'_>,
    out: &Path,
    opts: &PyramidOptions,
    source: Option<&Against<'_>>,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<PyramidReport, PyramidError> {
    let t0 = Instant::now();
    let tiles: Vec<TileId> = prep.tiles().collect();
    let manifest = run_manifest(prep, &opts.extensions, opts.gzip).to_string();
    if out.is_file() && !opts.force {
        // A finished archive: the same settings skip every tile.
        check_manifest(&open(out)?, out, &manifest)?;
        let outcomes: Vec<Outcome> = tiles.iter().map(|&t| Outcome::skipped(t)).collect();
        return Ok(PyramidReport {
            zooms: fold(prep, &outcomes),
            seconds: t0.elapsed().as_secs_f64(),
        });
    }
    let partial = partial_path(out);
    if opts.force {
        remove_if_present(&partial)?;
    }
    let conn = open(&partial)?;
    create(&conn, &partial)?;
    check_manifest(&conn, &partial, &manifest)?;
    set_meta(&conn, &partial, "cota_manifest", &manifest)?;
    let present = present(&conn, &partial)?;
    let outcomes = make_and_insert(
        prep, opts, source, &tiles, &present, conn, &partial, progress,
    )?;
    let conn = open(&partial)?;
    write_metadata(&conn, &partial, prep, opts)?;
    conn.close().map_err(|(_, e)| sql(&partial)(e))?;
    std::fs::rename(&partial, out).map_err(|e| PyramidError::Io {
        path: out.to_path_buf(),
        source: e,
    })?;
    Ok(PyramidReport {
        zooms: fold(prep, &outcomes),
        seconds: t0.elapsed().as_secs_f64(),
    })
}

fn remove_if_present(path: &Path) -> Result<(), PyramidError> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(PyramidError::Io {
            path: path.to_path_buf(),
            source: e,
        }),
        _ => Ok(()),
    }
}

/// Opens (or creates) the archive at `path`.
fn open(path: &Path) -> Result<Connection, PyramidError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| PyramidError::Io {
            path: dir.to_path_buf(),
            source: e,
        })?;
    }
    Connection::open(path).map_err(sql(path))
}

/// The tables and index of MBTiles 1.3, if absent.
fn create(conn: &Connection, path: &Path) -> Result<(), PyramidError> {
    conn.execute_batch(
        "PRAGMA journal_mode = DELETE;
         CREATE TABLE IF NOT EXISTS metadata (name TEXT PRIMARY KEY, value TEXT);
         CREATE TABLE IF NOT EXISTS tiles (zoom_level INTEGER, tile_column INTEGER,
             tile_row INTEGER, tile_data BLOB);
         CREATE UNIQUE INDEX IF NOT EXISTS tile_index ON tiles (zoom_level, tile_column, tile_row);",
    )
    .map_err(sql(path))
}

/// Refuses an archive whose recorded settings differ from `want`.
fn check_manifest(conn: &Connection, path: &Path, want: &str) -> Result<(), PyramidError> {
    let found: Option<String> = conn
        .query_row(
            "SELECT value FROM metadata WHERE name = 'cota_manifest'",
            [],
            |r| r.get(0),
        )
        .optional()
        .or_else(|e| match e {
            // A file that is not an archive of ours (no metadata table).
            rusqlite::Error::SqliteFailure(..) => Ok(Some(String::from("no cota manifest"))),
            e => Err(e),
        })
        .map_err(sql(path))?;
    match found {
        Some(text) if text != want => Err(PyramidError::Changed {
            path: path.to_path_buf(),
            found: text,
            expected: want.to_string(),
        }),
        _ => Ok(()),
    }
}

fn set_meta(conn: &Connection, path: &Path, name: &str, value: &str) -> Result<(), PyramidError> {
    conn.execute(
        "INSERT OR REPLACE INTO metadata (name, value) VALUES (?1, ?2)",
        params![name, value],
    )
    .map(drop)
    .map_err(sql(path))
}

/// The tiles already in the archive.
fn present(conn: &Connection, path: &Path) -> Result<HashSet<(u8, u32, u32)>, PyramidError> {
    let mut st = conn
        .prepare("SELECT zoom_level, tile_column, tile_row FROM tiles")
        .map_err(sql(path))?;
    let rows = st
        .query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))
        .map_err(sql(path))?;
    rows.collect::<Result<_, _>>().map_err(sql(path))
}

/// Makes the tiles not `present` on the pool and inserts them from one
/// writer thread, which owns (and closes) `conn`.
#[allow(clippy::too_many_arguments)]
fn make_and_insert(
    prep: &Prepared<'_>,
    opts: &PyramidOptions,
    source: Option<&Against<'_>>,
    tiles: &[TileId],
    present: &HashSet<(u8, u32, u32)>,
    conn: Connection,
    path: &Path,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<Outcome>, PyramidError> {
    let (tx, rx) = sync_channel::<(TileId, Vec<u8>)>(IN_FLIGHT);
    let done = AtomicU64::new(0);
    std::thread::scope(|scope| {
        let writer = scope.spawn(move || insert_all(conn, path, rx));
        let made: Result<Vec<Outcome>, PyramidError> = tiles
            .par_iter()
            .map(|&t| {
                let o = if present.contains(&(t.z, t.x, t.y)) {
                    Outcome::skipped(t)
                } else {
                    let mut m = make_tile(prep, t, opts, source)?;
                    let o = Outcome::made(t, &m);
                    // The writer has stopped only on an error, returned below.
                    let _ = tx.send((t, std::mem::take(&mut m.bytes)));
                    o
                };
                progress(done.fetch_add(1, Ordering::Relaxed) + 1);
                Ok(o)
            })
            .collect();
        drop(tx);
        let wrote = writer.join().unwrap_or_else(|_| {
            Err(PyramidError::Archive {
                path: path.to_path_buf(),
                message: "the archive's writer thread stopped".into(),
            })
        });
        let outcomes = made?;
        wrote.map(|()| outcomes)
    })
}

/// Inserts what arrives on `rx`, a transaction per [`BATCH`] tiles.
fn insert_all(
    mut conn: Connection,
    path: &Path,
    rx: Receiver<(TileId, Vec<u8>)>,
) -> Result<(), PyramidError> {
    let mut batch = Vec::with_capacity(BATCH);
    let flush = |conn: &mut Connection, batch: &mut Vec<(TileId, Vec<u8>)>| {
        let tx = conn.transaction().map_err(sql(path))?;
        {
            let mut st = tx
                .prepare_cached(
                    "INSERT OR REPLACE INTO tiles (zoom_level, tile_column, tile_row, tile_data)
                     VALUES (?1, ?2, ?3, ?4)",
                )
                .map_err(sql(path))?;
            for (t, bytes) in batch.drain(..) {
                st.execute(params![t.z, t.x, t.y, bytes])
                    .map_err(sql(path))?;
            }
        }
        tx.commit().map_err(sql(path))
    };
    for item in rx {
        batch.push(item);
        if batch.len() == BATCH {
            flush(&mut conn, &mut batch)?;
        }
    }
    flush(&mut conn, &mut batch)?;
    conn.close().map_err(|(_, e)| sql(path)(e))
}

/// The metadata an MBTiles reader looks for, and the layer.
fn write_metadata(
    conn: &Connection,
    path: &Path,
    prep: &Prepared<'_>,
    opts: &PyramidOptions,
) -> Result<(), PyramidError> {
    let layer = layer_text(prep, opts);
    let v: serde_json::Value = serde_json::from_str(&layer).unwrap_or_default();
    let bounds = v["bounds"]
        .as_array()
        .map(|b| {
            b.iter()
                .map(|x| x.as_f64().unwrap_or(0.0).to_string())
                .collect::<Vec<_>>()
                .join(",")
        })
        .unwrap_or_else(|| "-180,-90,180,90".into());
    let zooms = prep.zooms();
    let minzoom = zooms.first().map_or(0, |p| p.zoom).to_string();
    let maxzoom = zooms.last().map_or(0, |p| p.zoom).to_string();
    let name = v["name"].as_str().unwrap_or("cota").to_string();
    for (k, val) in [
        ("name", name.as_str()),
        ("format", FORMAT),
        ("type", "baselayer"),
        ("bounds", bounds.as_str()),
        ("minzoom", minzoom.as_str()),
        ("maxzoom", maxzoom.as_str()),
        ("json", layer.as_str()),
    ] {
        set_meta(conn, path, k, val)?;
    }
    Ok(())
}

/// Reads an archive's `layer.json` (its `json` metadata) and tiles: what
/// `cota serve --tiles` and the tests use.
#[derive(Debug)]
pub struct MbtilesReader {
    conn: Connection,
    path: PathBuf,
}

impl MbtilesReader {
    /// Opens `path` read-only.
    ///
    /// # Errors
    /// [`PyramidError::Io`] for a missing file, [`PyramidError::Archive`]
    /// for one SQLite cannot open.
    pub fn open(path: &Path) -> Result<Self, PyramidError> {
        std::fs::metadata(path).map_err(|e| PyramidError::Io {
            path: path.to_path_buf(),
            source: e,
        })?;
        let conn = Connection::open_with_flags(path, rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY)
            .map_err(sql(path))?;
        Ok(MbtilesReader {
            conn,
            path: path.to_path_buf(),
        })
    }

    /// The `json` metadata (the pyramid's `layer.json`).
    ///
    /// # Errors
    /// [`PyramidError::Archive`]: not an MBTiles archive, or no `json`.
    pub fn layer_json(&self) -> Result<String, PyramidError> {
        let format: Option<String> = self.meta("format")?;
        if format.as_deref() != Some(FORMAT) {
            return Err(PyramidError::Archive {
                path: self.path.clone(),
                message: format!(
                    "expected an MBTiles archive of format {FORMAT}, found format {}",
                    format.as_deref().unwrap_or("none")
                ),
            });
        }
        self.meta("json")?.ok_or_else(|| PyramidError::Archive {
            path: self.path.clone(),
            message: "expected a `json` metadata entry (the layer.json), found none".into(),
        })
    }

    fn meta(&self, name: &str) -> Result<Option<String>, PyramidError> {
        self.conn
            .query_row("SELECT value FROM metadata WHERE name = ?1", [name], |r| {
                r.get(0)
            })
            .optional()
            .map_err(sql(&self.path))
    }

    /// The bytes of tile `(z, x, y)` (TMS rows), if present.
    ///
    /// # Errors
    /// [`PyramidError::Archive`].
    pub fn tile(&self, z: u32, x: u32, y: u32) -> Result<Option<Vec<u8>>, PyramidError> {
        self.conn
            .query_row(
                "SELECT tile_data FROM tiles WHERE zoom_level = ?1 AND tile_column = ?2 AND tile_row = ?3",
                params![z, x, y],
                |r| r.get(0),
            )
            .optional()
            .map_err(sql(&self.path))
    }

    /// Every tile's `(z, x, y)`.
    ///
    /// # Errors
    /// [`PyramidError::Archive`].
    pub fn tile_ids(&self) -> Result<Vec<(u32, u32, u32)>, PyramidError> {
        let mut st = self
            .conn
            .prepare("SELECT zoom_level, tile_column, tile_row FROM tiles")
            .map_err(sql(&self.path))?;
        let rows = st
            .query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))
            .map_err(sql(&self.path))?;
        rows.collect::<Result<_, _>>().map_err(sql(&self.path))
    }
}
