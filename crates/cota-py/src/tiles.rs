//! `cota.tiles`, `cota.tiles_plan`, `cota.tiles_plan_step` and
//! `cota.tiles_reduce`: a quantized-mesh pyramid (`cota_io::tiles`), whole or
//! one shard of it, as `cota tiles` writes it (a shard after the plan step
//! reads only the files of its part, `cota_io::tiles::part`); the GIL is
//! released while reading and tiling.

use std::path::{Path, PathBuf};

use cota_core::tiles::plan::plan;
use cota_core::tiles::{
    addressed, shard_plan, BandCorners, ErrorSchedule, Lattice, LatticeOptions, Prepared,
    TilerOptions,
};
use cota_core::{FillOptions, HeightGrid};
use cota_io::tiles::{
    check_output, file_extents, finish_plan, frame_of, load_part, mosaic_frame, plan_layout,
    plan_layout_or, read_part_files, read_part_files_in_turn, read_shard_frame, reduce_shards,
    run_plan_part, shard_frame_path, shard_record_path, summarize_files, write_output, write_plan,
    write_shard, PartError, PlanPartReport, PyramidOptions, PyramidReport, ShardFrame,
    TileExtensions, TileFormat,
};
use cota_io::{read_region, RegionOptions};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::errors;

/// The settings that decide the tiles (as `cota tiles`' flags).
#[derive(Clone, Copy)]
struct Settings {
    min_zoom: u8,
    max_zoom: Option<u8>,
    tile_cells: u32,
    error: ErrorSchedule,
}

fn paths_of(paths: &Bound<'_, PyAny>) -> PyResult<Vec<PathBuf>> {
    match paths.extract::<PathBuf>() {
        Ok(p) => Ok(vec![p]),
        Err(_) => paths.extract(),
    }
}

fn schedule(factor: Option<f64>, at_max: Option<f64>) -> ErrorSchedule {
    match (factor, at_max) {
        (_, Some(e)) => ErrorSchedule::AtMaxZoom { max_error_m: e },
        (q, None) => ErrorSchedule::Cesium {
            factor: q.unwrap_or(1.0),
        },
    }
}

/// How the inputs are read: voids filled (harmonic, as `cota tiles`).
fn region_options() -> RegionOptions {
    RegionOptions::DEFAULT.with_fill(Some(FillOptions::DEFAULT))
}

/// Each input file and its samples in the mosaic (`file_extents`).
type FileExtents = Vec<(String, [usize; 4])>;

/// The lattice's options of the settings.
fn lattice_options(s: &Settings) -> LatticeOptions {
    LatticeOptions::DEFAULT
        .with_max_zoom(s.max_zoom)
        .with_tile_cells(s.tile_cells)
        .with_error(s.error)
}

/// The plan step's layout under `out` (the frame before the statistics,
/// from the files' shapes), made and written there when missing; `None`
/// when a shard must read every file (one file, voids, holes).
fn layout_of(
    paths: &[PathBuf],
    s: &Settings,
    out: &Path,
    shards: u32,
) -> Result<Option<ShardFrame>, PartError> {
    let key = frame_key(paths, s);
    plan_layout_or(out, &key, shards, || {
        let ro = region_options();
        let files = summarize_files(paths, &ro.read)?;
        let Some(m) = mosaic_frame(&files, &lattice_options(s), &ro.mosaic)? else {
            return Ok(None);
        };
        Ok(Some(plan_layout(key.clone(), shards, &m, &tiler(s))?))
    })
}

/// A part's error as Python's.
fn part_error(e: PartError) -> PyErr {
    match e {
        PartError::Read(e) => errors::read(e),
        PartError::Frame(e) => errors::write(e),
    }
}

/// Reads, fills the voids and resamples; with where each file lies in the
/// mosaic (empty when a shard must read every file: one file, voids, holes).
fn lattice_and_files(
    paths: &[PathBuf],
    s: &Settings,
) -> PyResult<(HeightGrid, Lattice, FileExtents)> {
    let region = read_region(paths, &region_options()).map_err(errors::read)?;
    let lat = Lattice::resample(&region.grid, &lattice_options(s)).map_err(errors::mesh)?;
    let files = if region.voids > 0 || region.hole_samples > 0 {
        Vec::new()
    } else {
        file_extents(&region.files, region.grid.georef())
    };
    Ok((region.grid, lat, files))
}

/// Reads, fills the voids and resamples: the source and its lattice.
fn lattice(paths: &[PathBuf], s: &Settings) -> PyResult<(HeightGrid, Lattice)> {
    lattice_and_files(paths, s).map(|(grid, lat, _)| (grid, lat))
}

/// What decides the lattice and the plan: a shard refuses a plan step's
/// frame made with other settings (or by the `cota` CLI).
fn frame_key(paths: &[PathBuf], s: &Settings) -> String {
    format!(
        "cota-py {:?}",
        (paths, s.min_zoom, s.max_zoom, s.tile_cells, s.error)
    )
}

/// Shard `i` after the plan step: reads only the files of its part.
fn write_part(
    paths: &[PathBuf],
    s: &Settings,
    out: &std::path::Path,
    opts: &PyramidOptions,
    f: &ShardFrame,
    i: u32,
) -> PyResult<(u64, PyramidReport, Vec<String>)> {
    let read = |files| read_part_files(paths, files, &region_options());
    let normals = opts.extensions.normals;
    let part =
        load_part(out, f, &frame_key(paths, s), &tiler(s), i, normals, read).map_err(part_error)?;
    let prep = Prepared::new_part(
        &part.lattice,
        part.source_part(),
        part.zooms.clone(),
        &part.stats,
    )
    .map_err(errors::mesh)?;
    let frame = Some((f, part.source_part()));
    let report =
        write_shard(&prep, out, opts, &part.shard, frame, &|_| {}).map_err(errors::write)?;
    Ok((part.shard.tile_count(), report, part.files_read))
}

/// The tile format named `name`: "quantized-mesh" or "3dtiles".
fn format_of(name: &str) -> PyResult<TileFormat> {
    match name {
        "quantized-mesh" => Ok(TileFormat::QuantizedMesh),
        "3dtiles" => Ok(TileFormat::Tiles3d),
        other => Err(errors::value(format!(
            "expected format \"quantized-mesh\" or \"3dtiles\", found {other:?}"
        ))),
    }
}

fn tiler(s: &Settings) -> TilerOptions {
    TilerOptions::DEFAULT
        .with_min_zoom(s.min_zoom)
        .with_error(s.error)
}

/// Writes a pyramid of the DEM file(s) `paths` under `out`
/// (`out/layer.json`, `out/{z}/{x}/{y}.terrain`), byte for byte as
/// `cota tiles` with the same settings: into one MBTiles archive when `out`
/// ends in `.mbtiles`; with `format="3dtiles"` (`meshopt`, `skirts`) as 3D
/// Tiles terrain, into one 3D Tiles Archive when `out` ends in `.3tz`. With `shard=(i, n)` only shard `i`
/// of `n` (see `tiles_plan`) and its record; `tiles_reduce(out, n)` then
/// writes `layer.json`. Returns a dict: `tiles`, `written`, `skipped`,
/// `bytes`. Raises `ReadError`, `MeshError` or `WriteError`.
#[pyfunction]
#[pyo3(signature = (paths, out, *, min_zoom = 0, max_zoom = None, tile_cells = 64,
    error_factor = None, max_error_m_at_max_zoom = None, normals = false, watermask = false,
    metadata = false, gzip = false, force = false, check = false, shard = None,
    format = "quantized-mesh", meshopt = false, skirts = true))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn tiles<'py>(
    py: Python<'py>,
    paths: &Bound<'py, PyAny>,
    out: PathBuf,
    min_zoom: u8,
    max_zoom: Option<u8>,
    tile_cells: u32,
    error_factor: Option<f64>,
    max_error_m_at_max_zoom: Option<f64>,
    normals: bool,
    watermask: bool,
    metadata: bool,
    gzip: bool,
    force: bool,
    check: bool,
    shard: Option<(u32, u32)>,
    format: &str,
    meshopt: bool,
    skirts: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let paths = paths_of(paths)?;
    let s = settings(
        min_zoom,
        max_zoom,
        tile_cells,
        error_factor,
        max_error_m_at_max_zoom,
    );
    let opts = PyramidOptions::DEFAULT
        .with_extensions(TileExtensions::with(normals, watermask, metadata))
        .with_gzip(gzip)
        .with_force(force)
        .with_check(check)
        .with_meshopt(meshopt)
        .with_skirts(skirts)
        .with_format(format_of(format)?);
    check_output(&out, &opts).map_err(errors::value)?;
    if let Some((i, n)) = shard {
        if opts.format == TileFormat::Tiles3d {
            return Err(errors::value(
                "shards write quantized-mesh pyramids: expected format=\"quantized-mesh\" with shard",
            ));
        }
        if i >= n {
            return Err(errors::value(format!(
                "expected shard (i, n) with 0 <= i < n, found ({i}, {n})"
            )));
        }
    }
    let (total, report, files_read) = py.detach(|| -> PyResult<_> {
        if let Some((i, n)) = shard {
            if let Some(f) = read_shard_frame(&out, n).map_err(errors::write)? {
                let (t, r, files) = write_part(&paths, &s, &out, &opts, &f, i)?;
                return Ok((t, r, Some(files)));
            }
        }
        let (grid, lat) = lattice(&paths, &s)?;
        let prep = Prepared::new(&lat, &grid, &tiler(&s)).map_err(errors::mesh)?;
        let report = match shard {
            Some((i, n)) => {
                let part = shard_plan(prep.zooms(), n)
                    .map_err(errors::value)?
                    .swap_remove(i as usize);
                write_shard(&prep, &out, &opts, &part, None, &|_| {})
            }
            None => write_output(&prep, &out, &opts, None, &|_| {}),
        }
        .map_err(errors::write)?;
        Ok((prep.tile_count(), report, None))
    })?;
    let d = PyDict::new(py);
    d.set_item("tiles", total)?;
    d.set_item("written", report.written())?;
    d.set_item("skipped", report.skipped())?;
    d.set_item("bytes", report.bytes())?;
    d.set_item("files_read", files_read)?;
    Ok(d)
}

/// The plan step of `cota tiles --plan --shards n`: reads the inputs one
/// shard's part at a time (parts that `tiles_plan_part` already wrote are not
/// read again; the whole input when every shard must read every file), and
/// writes the frame `out/.cota-shards-n.json` and the band corners; each
/// `tiles(..., shard=(i, n))` then reads only the files its part of the
/// lattice needs. Writes no tile. Returns a dict: `band_zoom`,
/// `coarse_tiles`, `written`, `skipped` (both 0), `files` (each input's
/// samples in the mosaic; empty when every shard must read every file: one
/// file, voids or holes).
#[pyfunction]
#[pyo3(signature = (paths, out, shards, *, min_zoom = 0, max_zoom = None, tile_cells = 64,
    error_factor = None, max_error_m_at_max_zoom = None, normals = false, watermask = false,
    metadata = false, gzip = false, force = false, check = false))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn tiles_plan_step<'py>(
    py: Python<'py>,
    paths: &Bound<'py, PyAny>,
    out: PathBuf,
    shards: u32,
    min_zoom: u8,
    max_zoom: Option<u8>,
    tile_cells: u32,
    error_factor: Option<f64>,
    max_error_m_at_max_zoom: Option<f64>,
    normals: bool,
    watermask: bool,
    metadata: bool,
    gzip: bool,
    force: bool,
    check: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let paths = paths_of(paths)?;
    let s = settings(
        min_zoom,
        max_zoom,
        tile_cells,
        error_factor,
        max_error_m_at_max_zoom,
    );
    // The tiles' settings are the shards' (each records them with its
    // partial maxima, and the reduce cuts the coarse tiles with them).
    let _ = (normals, watermask, metadata, gzip, force, check);
    let shards = at_least_one(shards)?;
    let (frame, coarse) = py.detach(|| -> PyResult<_> {
        // Without the whole input where the files allow it: the parts
        // `tiles_plan_part` already wrote, the others in turn.
        if let Some(layout) = layout_of(&paths, &s, &out, shards).map_err(part_error)? {
            let read = |files| read_part_files_in_turn(&paths, files, &region_options());
            let (frame, _, _) = finish_plan(&out, layout, &tiler(&s), read).map_err(part_error)?;
            let coarse = frame.coarse_tiles;
            return Ok((frame, coarse));
        }
        let (_, lat, files) = lattice_and_files(&paths, &s)?;
        let zooms = plan(&lat, &tiler(&s)).map_err(errors::mesh)?;
        let frame = frame_of(frame_key(&paths, &s), shards, &lat, &zooms, files);
        let mut corners = BandCorners::new(lat.window(), lat.scheme().cells_at(frame.band_zoom));
        corners.fill_from(&lat);
        write_plan(&out, &frame, &corners).map_err(errors::write)?;
        let coarse = frame.coarse_tiles;
        Ok((frame, coarse))
    })?;
    let d = PyDict::new(py);
    d.set_item("band_zoom", frame.band_zoom)?;
    d.set_item("coarse_tiles", coarse)?;
    d.set_item("written", 0)?;
    d.set_item("skipped", 0)?;
    d.set_item("files", frame.files)?;
    Ok(d)
}

/// The plan step's layout (`cota tiles --plan --layout`): each input read
/// alone for its shape, `out/.cota-layout-n.json` written (kept when there).
/// Returns a dict: `streamed` (False when every shard must read every file:
/// then the plan step reads the whole input and has no parts), `files`.
#[pyfunction]
#[pyo3(signature = (paths, out, shards, *, min_zoom = 0, max_zoom = None, tile_cells = 64,
    error_factor = None, max_error_m_at_max_zoom = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn tiles_plan_layout<'py>(
    py: Python<'py>,
    paths: &Bound<'py, PyAny>,
    out: PathBuf,
    shards: u32,
    min_zoom: u8,
    max_zoom: Option<u8>,
    tile_cells: u32,
    error_factor: Option<f64>,
    max_error_m_at_max_zoom: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let paths = paths_of(paths)?;
    let s = settings(
        min_zoom,
        max_zoom,
        tile_cells,
        error_factor,
        max_error_m_at_max_zoom,
    );
    let shards = at_least_one(shards)?;
    let layout = py.detach(|| layout_of(&paths, &s, &out, shards).map_err(part_error))?;
    let d = PyDict::new(py);
    d.set_item("streamed", layout.is_some())?;
    d.set_item("files", layout.map_or(0, |l| l.files.len()))?;
    Ok(d)
}

/// Part `part` of the plan step (`cota tiles --plan --part i`): shard
/// `part`'s files read and its part resampled for the statistics and band
/// corners, into `out/.cota-plan-i-of-n.bin`, after the layout (made when
/// missing). Idempotent; `tiles_plan_step` then merges the parts. Returns a
/// dict: `streamed` (False: nothing to do, the plan step reads the whole
/// input), `skipped` (its file, or the plan step's frame, was there),
/// `files_read`.
#[pyfunction]
#[pyo3(signature = (paths, out, shards, part, *, min_zoom = 0, max_zoom = None,
    tile_cells = 64, error_factor = None, max_error_m_at_max_zoom = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn tiles_plan_part<'py>(
    py: Python<'py>,
    paths: &Bound<'py, PyAny>,
    out: PathBuf,
    shards: u32,
    part: u32,
    min_zoom: u8,
    max_zoom: Option<u8>,
    tile_cells: u32,
    error_factor: Option<f64>,
    max_error_m_at_max_zoom: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let paths = paths_of(paths)?;
    let s = settings(
        min_zoom,
        max_zoom,
        tile_cells,
        error_factor,
        max_error_m_at_max_zoom,
    );
    let shards = at_least_one(shards)?;
    if part >= shards {
        return Err(errors::value(format!(
            "expected a part 0 <= part < {shards}, found {part}"
        )));
    }
    let report = py.detach(|| -> Result<_, PartError> {
        if shard_frame_path(&out, shards).is_file() {
            // The plan step is done.
            return Ok(Some(PlanPartReport {
                skipped: true,
                files_read: Vec::new(),
            }));
        }
        let Some(layout) = layout_of(&paths, &s, &out, shards)? else {
            return Ok(None);
        };
        let read = |files| read_part_files(&paths, files, &region_options());
        run_plan_part(&out, &layout, &tiler(&s), part, read).map(Some)
    });
    let report = report.map_err(part_error)?;
    let d = PyDict::new(py);
    d.set_item("streamed", report.is_some())?;
    d.set_item("skipped", report.as_ref().is_some_and(|r| r.skipped))?;
    d.set_item(
        "files_read",
        report.map(|r| r.files_read).unwrap_or_default(),
    )?;
    Ok(d)
}

fn settings(
    min_zoom: u8,
    max_zoom: Option<u8>,
    tile_cells: u32,
    error_factor: Option<f64>,
    at_max: Option<f64>,
) -> Settings {
    Settings {
        min_zoom,
        max_zoom,
        tile_cells,
        error: schedule(error_factor, at_max),
    }
}

fn at_least_one(shards: u32) -> PyResult<u32> {
    if shards == 0 {
        return Err(errors::value("expected at least 1 shard, found 0"));
    }
    Ok(shards)
}

/// The shard plan of `cota tiles --plan --shards n`: a list of `n` dicts
/// (`shard`, `shards`, `tiles`, `ranges`: a list of `(zoom, x0, x1, y0, y1)`,
/// tile addresses, TMS, inclusive; a range across the antimeridian is given
/// as its two parts). Deterministic: every process computes the same.
#[pyfunction]
#[pyo3(signature = (paths, shards, *, min_zoom = 0, max_zoom = None, tile_cells = 64,
    error_factor = None, max_error_m_at_max_zoom = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn tiles_plan<'py>(
    py: Python<'py>,
    paths: &Bound<'py, PyAny>,
    shards: u32,
    min_zoom: u8,
    max_zoom: Option<u8>,
    tile_cells: u32,
    error_factor: Option<f64>,
    max_error_m_at_max_zoom: Option<f64>,
) -> PyResult<Bound<'py, PyList>> {
    let paths = paths_of(paths)?;
    let s = settings(
        min_zoom,
        max_zoom,
        tile_cells,
        error_factor,
        max_error_m_at_max_zoom,
    );
    let (parts, scheme) = py.detach(|| -> PyResult<_> {
        let (_, lat) = lattice(&paths, &s)?;
        let zooms = plan(&lat, &tiler(&s)).map_err(errors::mesh)?;
        let parts = shard_plan(&zooms, shards).map_err(errors::value)?;
        Ok((parts, *lat.scheme()))
    })?;
    let list = PyList::empty(py);
    for p in parts {
        let d = PyDict::new(py);
        d.set_item("shard", p.index)?;
        d.set_item("shards", p.shards)?;
        d.set_item("tiles", p.tile_count())?;
        let ranges: Vec<(u8, u32, u32, u32, u32)> = p
            .ranges
            .iter()
            .flat_map(|&(z, r)| addressed(&scheme, z, r).into_iter().map(move |r| (z, r)))
            .map(|(z, r)| (z, r.x0, r.x1, r.y0, r.y1))
            .collect();
        d.set_item("ranges", ranges)?;
        list.append(d)?;
    }
    Ok(list)
}

/// Checks the records of the `shards` shards written under `out`, after a
/// plan step cuts the tiles coarser than the band zoom from the shards'
/// partial maxima, writes `layer.json` and removes the records
/// (`cota tiles --reduce`). Returns the pyramid's tile count. Raises `WriteError` naming a
/// missing or disagreeing shard.
#[pyfunction]
pub(crate) fn tiles_reduce(py: Python<'_>, out: PathBuf, shards: u32) -> PyResult<u64> {
    py.detach(|| reduce_shards(&out, shards, false, &|_| {}))
        .map(|r| r.tiles)
        .map_err(errors::write)
}

/// The path of the plan step's frame of `shards` shards under `out`: it
/// exists once the plan step is done (and until
/// `tiles_reduce` removes it).
#[pyfunction]
pub(crate) fn shard_frame(out: PathBuf, shards: u32) -> PathBuf {
    shard_frame_path(&out, shards)
}

/// The path of shard `index`'s record under `out`: it exists once the shard
/// has written all its tiles (and until `tiles_reduce` removes it).
#[pyfunction]
pub(crate) fn shard_record(out: PathBuf, index: u32, shards: u32) -> PathBuf {
    shard_record_path(&out, index, shards)
}
