//! Writing a pyramid: `OUT/layer.json` and `OUT/{z}/{x}/{y}.terrain`, every
//! tile cut and encoded, and with [`PyramidOptions::check`] (the default)
//! decoded again and checked before it is written.
//!
//! * **Parallel**: all tiles of all zooms go to the rayon pool at once; each
//!   is independent (the prepared hierarchy is shared, read-only).
//! * **Bounded memory**: a tile lives from its cut to its write; nothing of
//!   the pyramid is kept but per-zoom counters.
//! * **No corrupt tile left**: tiles are written in place, each begun and
//!   ended in the run's journal ([`super::journal`]: a rename per tile was
//!   most of the writing time), so an interrupted run leaves at most one
//!   unfinished tile per thread, named in its journal and made again by the
//!   next run over the same tiles; `layer.json` is written last (not
//!   `fsync`ed: a power cut may lose recent tiles, never mix them).
//! * **Resumable, shardable**: `OUT/.cota-tiles.json` records what decides
//!   the tiles' content; a run into a directory whose manifest matches skips
//!   the tiles already there (`force` redoes them), one whose manifest
//!   differs is refused unless `force`. Runs over disjoint sets of tiles can
//!   share a directory.
//! * **Verified** (with [`PyramidOptions::check`]): [`make_tile`] decodes the
//!   bytes with the independent decoder and checks the decoded tile with
//!   [`cota_core::mesh::check::check_placed_mesh`] against its zoom's bound at
//!   every sample of its square of the lattice, and its edge lists.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use cota_core::mesh::check::{check_placed_mesh, CheckError, Region};
use cota_core::tiles::{Prepared, TileId, TileMesh, TilesError};
use rayon::prelude::*;

use super::decode::{decode, DecodeError};
use super::drawn::{check_random, check_samples, Against, DrawnTile};
use super::glb_tile::SKIRT_LEVELS;
use super::journal::{make_dirs, Journal, PathIo};
use super::layer::{layer_json, run_manifest};
use super::quantized_mesh::{encode_tile, EncodeError, TileExtensions};
use super::seams::edge_lists_match;

/// Why a pyramid or a tile could not be made.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PyramidError {
    /// A file or directory could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The path.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// The tiling could not be prepared or cut.
    #[error(transparent)]
    Tiles(#[from] TilesError),
    /// A tile could not be encoded.
    #[error("tile {tile}: {source}")]
    Encode {
        /// The tile.
        tile: TileId,
        /// The error.
        source: EncodeError,
    },
    /// A tile's bytes did not decode: an encoder bug.
    #[error("tile {tile} does not decode: {source}")]
    Decode {
        /// The tile.
        tile: TileId,
        /// The error.
        source: DecodeError,
    },
    /// A decoded tile broke an invariant: a bug, reported rather than written.
    #[error("tile {tile} fails its check after quantization: {source}")]
    Check {
        /// The tile.
        tile: TileId,
        /// The violations.
        source: CheckError,
    },
    /// A decoded tile, drawn as the client draws it, is farther from the
    /// source than its bound: a bug, reported rather than written.
    #[error("tile {tile} as drawn is {got_m} m from the source at longitude {lon}, latitude {lat}, beyond its bound of {bound_m} m")]
    Drawn {
        /// The tile.
        tile: TileId,
        /// The error found, metres.
        got_m: f64,
        /// The bound, metres.
        bound_m: f64,
        /// Where, degrees.
        lon: f64,
        /// Where, degrees.
        lat: f64,
    },
    /// A shard's record is missing or does not match the others.
    #[error("{path}: {message}")]
    Shard {
        /// The directory or record.
        path: PathBuf,
        /// What was expected and found.
        message: String,
    },
    /// An MBTiles archive could not be read or written (SQLite's words).
    #[error("{path}: {message}")]
    Archive {
        /// The archive.
        path: PathBuf,
        /// What SQLite said, or what was expected and found.
        message: String,
    },
    /// The output holds tiles made with other settings.
    #[error("{path} was made with other settings (found {found}, expected {expected}); use --force to redo every tile, or another directory")]
    Changed {
        /// The manifest.
        path: PathBuf,
        /// Its content.
        found: String,
        /// This run's.
        expected: String,
    },
}

/// How to write a pyramid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub struct PyramidOptions {
    /// Extensions to write. Default: none.
    pub extensions: TileExtensions,
    /// Gzip each tile (the server then sends `Content-Encoding: gzip`). Default: false.
    pub gzip: bool,
    /// Redo tiles that exist, and ignore another run's manifest. Default: false.
    pub force: bool,
    /// Decode every tile again and check it (the one checker's placed mode,
    /// every lattice sample of its square, and its edge lists) before it is
    /// written. Default: true (`cota tiles` turns it on with `--check`).
    pub check: bool,
    /// The tile format. Default: quantized-mesh.
    pub format: TileFormat,
    /// With [`TileFormat::Tiles3d`]: `KHR_mesh_quantization` positions and
    /// `EXT_meshopt_compression` geometry ([`super::glb_tile::GlbGeometry`]).
    /// Default: false (float32 positions, plain indices).
    pub meshopt: bool,
    /// With [`TileFormat::Tiles3d`]: a skirt in each GLB, for clients that
    /// build none ([`super::glb_tile::skirt`], as deep as
    /// [`super::glb_tile::skirt_depth_m`]). Default: true.
    pub skirts: bool,
}

/// The format of a pyramid's tiles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum TileFormat {
    /// Cesium quantized-mesh-1.0: `layer.json` and `{z}/{x}/{y}.terrain`.
    #[default]
    QuantizedMesh,
    /// 3D Tiles 1.1 terrain: `tileset.json`, subtrees and GLB tiles
    /// ([`super::pyramid3d`]).
    Tiles3d,
}

impl PyramidOptions {
    /// The defaults, as documented on each field.
    pub const DEFAULT: PyramidOptions = PyramidOptions {
        extensions: TileExtensions::NONE,
        gzip: false,
        force: false,
        check: true,
        format: TileFormat::QuantizedMesh,
        meshopt: false,
        skirts: true,
    };

    /// Sets [`PyramidOptions::skirts`].
    pub const fn with_skirts(mut self, on: bool) -> Self {
        self.skirts = on;
        self
    }

    /// Sets [`PyramidOptions::meshopt`].
    pub const fn with_meshopt(mut self, on: bool) -> Self {
        self.meshopt = on;
        self
    }

    /// Sets [`PyramidOptions::extensions`].
    pub const fn with_extensions(mut self, e: TileExtensions) -> Self {
        self.extensions = e;
        self
    }

    /// Sets [`PyramidOptions::gzip`].
    pub const fn with_gzip(mut self, yes: bool) -> Self {
        self.gzip = yes;
        self
    }

    /// Sets [`PyramidOptions::force`].
    pub const fn with_force(mut self, yes: bool) -> Self {
        self.force = yes;
        self
    }

    /// Sets [`PyramidOptions::format`].
    pub const fn with_format(mut self, f: TileFormat) -> Self {
        self.format = f;
        self
    }

    /// Sets [`PyramidOptions::check`].
    pub const fn with_check(mut self, yes: bool) -> Self {
        self.check = yes;
        self
    }
}

/// One tile, encoded and verified.
#[derive(Debug, Clone)]
pub struct MadeTile {
    /// The tile.
    pub tile: TileId,
    /// Its bytes, gzipped when asked.
    pub bytes: Vec<u8>,
    /// Triangles.
    pub triangles: usize,
    /// Vertices.
    pub vertices: usize,
    /// The bound it meets, metres.
    pub max_error_m: f64,
    /// The largest error measured on the decoded tile at its lattice's
    /// samples, metres; NaN when [`PyramidOptions::check`] is off.
    pub measured_error_m: f64,
    /// The largest error of the tile as drawn (flat ECEF triangles, along
    /// the normal) at the source's samples and on the ellipsoid far from
    /// the data, metres; NaN when not checked against a source.
    pub drawn_error_m: f64,
    /// The largest deviation as drawn from the source's bilinear surface
    /// at random points inside the data (between samples: reported, not
    /// bounded), metres; NaN when not checked against a source.
    pub between_m: f64,
}

/// Cuts, encodes and (with [`PyramidOptions::check`]) verifies one tile: the
/// entry point for making tiles on demand from a prepared hierarchy. With
/// `source` the check also draws the tile as a client does and measures it
/// against the source's samples ([`super::drawn`]).
///
/// # Errors
/// [`PyramidError::Tiles`] for a tile outside the pyramid, and
/// [`PyramidError::Encode`], [`PyramidError::Decode`],
/// [`PyramidError::Check`] or [`PyramidError::Drawn`] when the tile is
/// wrong (a bug: never written).
pub fn make_tile(
    prep: &Prepared<'_>,
    t: TileId,
    opts: &PyramidOptions,
    source: Option<&Against<'_>>,
) -> Result<MadeTile, PyramidError> {
    let ext = opts.extensions;
    let tile = prep.cut(t, ext.normals, ext.watermask)?;
    finish_tile(tile, opts, Some(&prep.region(t)), source)
}

/// Encodes a cut tile and (with [`PyramidOptions::check`]) verifies it:
/// decoded independently, its edge lists, with `region` the one checker at
/// every lattice sample of its square, and with `source` as drawn against
/// the source's samples.
///
/// # Errors
/// As [`make_tile`].
pub fn finish_tile(
    tile: TileMesh,
    opts: &PyramidOptions,
    region: Option<&Region<'_>>,
    source: Option<&Against<'_>>,
) -> Result<MadeTile, PyramidError> {
    let (t, ext) = (tile.tile, opts.extensions);
    let raw =
        encode_tile(&tile, &ext).map_err(|source| PyramidError::Encode { tile: t, source })?;
    let bytes = if opts.gzip { gzip(&raw) } else { raw };
    let unchecked = MadeTile {
        tile: t,
        triangles: tile.mesh.triangles.len(),
        vertices: tile.mesh.vertices.len(),
        max_error_m: tile.max_error_m,
        measured_error_m: f64::NAN,
        drawn_error_m: f64::NAN,
        between_m: f64::NAN,
        bytes,
    };
    if !opts.check {
        return Ok(unchecked);
    }
    let decoded =
        decode(&unchecked.bytes).map_err(|source| PyramidError::Decode { tile: t, source })?;
    if !edge_lists_match(&decoded) {
        return Err(PyramidError::Decode {
            tile: t,
            source: DecodeError::Invalid("the edge lists do not hold the edges' vertices".into()),
        });
    }
    let mut made = MadeTile {
        triangles: decoded.triangles.len(),
        vertices: decoded.u.len(),
        ..unchecked
    };
    if let Some(region) = region {
        let report = check_placed_mesh(
            region,
            &decoded.to_placed(tile.cells),
            Some(tile.max_error_m),
        )
        .map_err(|source| PyramidError::Check { tile: t, source })?;
        made.measured_error_m = report.metrics.max_error_m;
    }
    if let Some(against) = source {
        let drawn = DrawnTile::new(&decoded, tile.rect_deg);
        let bounds = [tile.max_error_m, tile.source_bound_m];
        let [drawn, between] = check_drawn(&drawn, t, bounds, against)?;
        made.drawn_error_m = drawn;
        made.between_m = between;
    }
    Ok(made)
}

/// The decoded tile drawn as a client draws it, against the source's
/// samples and, at random points, the ellipsoid far from the data, within
/// `[bound, bound at the source's samples]`:
/// `[largest error, largest deviation between samples]`.
pub(crate) fn check_drawn(
    drawn: &DrawnTile<'_>,
    t: TileId,
    [bound, at_source]: [f64; 2],
    against: &Against<'_>,
) -> Result<[f64; 2], PyramidError> {
    let at_samples = check_samples(drawn, &against.samples);
    let seed = (u64::from(t.z) << 48) ^ (u64::from(t.x) << 24) ^ u64::from(t.y);
    let random = check_random(drawn, 4, seed, &*against.reference);
    // Rounding slack relative to the heights and the Earth's radius.
    let slack = 1e-6 * at_source.max(1.0) + 1e-6;
    if at_samples.max_error_m > at_source + slack {
        return Err(PyramidError::Drawn {
            tile: t,
            got_m: at_samples.max_error_m,
            bound_m: at_source,
            lon: at_samples.at[0],
            lat: at_samples.at[1],
        });
    }
    if random.ellipsoid_m > bound + slack {
        return Err(PyramidError::Drawn {
            tile: t,
            got_m: random.ellipsoid_m,
            bound_m: bound,
            lon: f64::NAN,
            lat: f64::NAN,
        });
    }
    Ok([
        at_samples.max_error_m.max(random.ellipsoid_m),
        random.data_m,
    ])
}

fn gzip(raw: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(
        Vec::with_capacity(raw.len() / 2),
        flate2::Compression::default(),
    );
    // Writing to a Vec cannot fail.
    let _ = e.write_all(raw);
    e.finish().unwrap_or_default()
}

/// What one zoom of a written pyramid holds.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct ZoomReport {
    /// The zoom.
    pub zoom: u8,
    /// Tiles written.
    pub written: u64,
    /// Tiles kept from a previous run.
    pub skipped: u64,
    /// Of the tiles written or kept, the fill tiles (3D Tiles: the
    /// quadrants beyond the data of a refined tile,
    /// [`cota_core::tiles::Prepared::is_fill`]; 0 for quantized-mesh).
    pub fill: u64,
    /// Bytes written.
    pub bytes: u64,
    /// Triangles written.
    pub triangles: u64,
    /// Vertices written.
    pub vertices: u64,
    /// The zoom's bound, metres.
    pub max_error_m: f64,
    /// The margin left for quantization, metres.
    pub margin_m: f64,
    /// The bound its tiles meet at the source's own samples, as drawn (the
    /// zoom's bound unless the lattice cannot hold the source), metres.
    pub source_bound_m: f64,
    /// The largest error measured over its written tiles at their
    /// lattice's samples, metres; NaN when they were not checked
    /// ([`PyramidOptions::check`] off).
    pub measured_error_m: f64,
    /// The largest error as drawn against the source's samples (and the
    /// ellipsoid far from the data), metres; NaN when not measured.
    pub drawn_error_m: f64,
    /// The largest deviation as drawn from the source's bilinear surface
    /// between its samples, metres; NaN when not measured.
    pub between_m: f64,
}

/// What [`write_pyramid`] did.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct PyramidReport {
    /// Per zoom, coarse to fine.
    pub zooms: Vec<ZoomReport>,
    /// Seconds the tiles took (cut, encode, verify, write, in parallel).
    pub seconds: f64,
}

impl PyramidReport {
    /// Tiles written.
    pub fn written(&self) -> u64 {
        self.zooms.iter().map(|z| z.written).sum()
    }

    /// Tiles skipped.
    pub fn skipped(&self) -> u64 {
        self.zooms.iter().map(|z| z.skipped).sum()
    }

    /// Fill tiles written or kept ([`ZoomReport::fill`]).
    pub fn fill(&self) -> u64 {
        self.zooms.iter().map(|z| z.fill).sum()
    }

    /// Bytes written.
    pub fn bytes(&self) -> u64 {
        self.zooms.iter().map(|z| z.bytes).sum()
    }
}

impl From<PathIo> for PyramidError {
    fn from(PathIo(path, source): PathIo) -> Self {
        PyramidError::Io { path, source }
    }
}

pub(crate) fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> PyramidError + '_ {
    move |source| PyramidError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes `bytes` to `path` atomically: a temporary file beside it, renamed.
/// An existing read-only `path` is refused unless `replace_read_only` (the
/// CLI's `--force`), as the mesh writers do.
///
/// # Errors
/// [`PyramidError::Io`] naming the path.
pub fn write_file_atomically(
    path: &Path,
    bytes: &[u8],
    replace_read_only: bool,
) -> Result<(), PyramidError> {
    let read_only = std::fs::metadata(path).is_ok_and(|m| m.permissions().readonly());
    if read_only && !replace_read_only {
        return Err(io_err(path)(std::io::Error::new(
            std::io::ErrorKind::PermissionDenied,
            "the existing file is read-only; use --force to replace it",
        )));
    }
    let dir = path.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(io_err(dir))?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let done = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path));
    if let Err(e) = done {
        let _ = std::fs::remove_file(&tmp);
        return Err(io_err(path)(e));
    }
    Ok(())
}

/// The path of a tile under `out`.
pub fn tile_path(out: &Path, t: TileId) -> PathBuf {
    out.join(t.z.to_string())
        .join(t.x.to_string())
        .join(format!("{}.terrain", t.y))
}

/// Checks or writes the run manifest: `true` when it was written now (a new
/// output, or `force`), `false` when an earlier run's matched.
pub(crate) fn manifest(
    prep: &Prepared<'_>,
    out: &Path,
    opts: &PyramidOptions,
) -> Result<bool, PyramidError> {
    std::fs::create_dir_all(out).map_err(io_err(out))?;
    let path = out.join(".cota-tiles.json");
    let mut want = run_manifest(prep, &opts.extensions, opts.gzip);
    if opts.format == TileFormat::Tiles3d {
        want["format"] = "3dtiles".into();
        if opts.meshopt {
            want["compression"] = "meshopt".into();
        }
        if opts.skirts {
            want["skirts"] = SKIRT_LEVELS.into();
        }
    }
    let want = want.to_string();
    if !opts.force && path.exists() {
        let text = std::fs::read_to_string(&path).map_err(io_err(&path))?;
        // Compared as text: serde_json's parser does not round-trip every
        // f64 exactly, so parsed values of the same text could differ.
        if text != want {
            return Err(PyramidError::Changed {
                path,
                found: text,
                expected: want,
            });
        }
        return Ok(false);
    }
    write_file_atomically(&path, want.as_bytes(), opts.force)?;
    Ok(true)
}

/// Per-tile outcome folded into the report.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Outcome {
    zoom: u8,
    written: bool,
    /// A fill tile ([`ZoomReport::fill`]).
    pub(crate) fill: bool,
    bytes: u64,
    triangles: u64,
    vertices: u64,
    measured: f64,
    drawn: f64,
    between: f64,
}

/// Writes every tile of `prep` under `out`, then `layer.json`;
/// `progress(done)` after each tile.
///
/// # Errors
/// [`PyramidError`]: the first tile that failed, an unwritable output, or
/// an output made with other settings.
pub fn write_pyramid(
    prep: &Prepared<'_>,
    out: &Path,
    opts: &PyramidOptions,
    source: Option<&Against<'_>>,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<PyramidReport, PyramidError> {
    let t0 = Instant::now();
    let tiles: Vec<TileId> = prep.tiles().collect();
    let outcomes = write_tiles(prep, out, opts, source, &tiles, progress)?;
    write_file_atomically(
        &out.join("layer.json"),
        layer_text(prep, opts).as_bytes(),
        opts.force,
    )?;
    Ok(PyramidReport {
        zooms: fold(prep, &outcomes),
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// The bytes of `layer.json`.
pub(crate) fn layer_text(prep: &Prepared<'_>, opts: &PyramidOptions) -> String {
    let layer = layer_json(prep, &opts.extensions);
    format!("{layer:#}\n")
}

/// Checks or writes the run manifest, then writes `tiles` (those not yet
/// there unless `force`) in parallel; `progress(done)` after each.
pub(crate) fn write_tiles(
    prep: &Prepared<'_>,
    out: &Path,
    opts: &PyramidOptions,
    source: Option<&Against<'_>>,
    tiles: &[TileId],
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<Outcome>, PyramidError> {
    // A new output has no tile to skip: no look at each tile's name.
    let fresh = manifest(prep, out, opts)?;
    let journal = Journal::open(out, tiles, |t| tile_path(out, t))?;
    make_dirs(tiles, |t| tile_path(out, t))?;
    let done = AtomicU64::new(0);
    let outcomes = tiles
        .par_iter()
        .map(|&t| {
            let path = tile_path(out, t);
            let o = if !fresh && !opts.force && path.is_file() {
                Outcome::skipped(t)
            } else {
                let m = make_tile(prep, t, opts, source)?;
                journal.write_tile(t, &path, &m.bytes)?;
                Outcome::made(t, &m)
            };
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            Ok(o)
        })
        .collect::<Result<Vec<_>, PyramidError>>()?;
    journal.finish()?;
    Ok(outcomes)
}

impl Outcome {
    /// A tile already in the output.
    pub(crate) fn skipped(t: TileId) -> Outcome {
        Outcome {
            zoom: t.z,
            ..Outcome::default()
        }
    }

    /// A tile made and written.
    pub(crate) fn made(t: TileId, m: &MadeTile) -> Outcome {
        Outcome {
            zoom: t.z,
            written: true,
            fill: false,
            bytes: m.bytes.len() as u64,
            triangles: m.triangles as u64,
            vertices: m.vertices as u64,
            measured: m.measured_error_m,
            drawn: m.drawn_error_m,
            between: m.between_m,
        }
    }
}

/// The larger of two measures; NaN (not measured) when either is.
fn nan_max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// The per-zoom report of the tiles' outcomes.
pub(crate) fn fold(prep: &Prepared<'_>, outcomes: &[Outcome]) -> Vec<ZoomReport> {
    prep.zooms()
        .iter()
        .map(|p| {
            let mut r = ZoomReport {
                zoom: p.zoom,
                max_error_m: p.max_error_m,
                margin_m: p.margin_m,
                source_bound_m: prep.source_bound_m(p.zoom),
                ..ZoomReport::default()
            };
            for o in outcomes.iter().filter(|o| o.zoom == p.zoom) {
                r.fill += u64::from(o.fill);
                if o.written {
                    r.written += 1;
                    r.bytes += o.bytes;
                    r.triangles += o.triangles;
                    r.vertices += o.vertices;
                    // NaN (not checked) stays NaN: `f64::max` would drop it.
                    r.measured_error_m = nan_max(r.measured_error_m, o.measured);
                    r.drawn_error_m = nan_max(r.drawn_error_m, o.drawn);
                    r.between_m = nan_max(r.between_m, o.between);
                } else {
                    r.skipped += 1;
                }
            }
            r
        })
        .collect()
}
