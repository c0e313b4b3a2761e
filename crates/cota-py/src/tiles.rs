//! `cota.tiles`, `cota.tiles_plan`, `cota.tiles_plan_step` and
//! `cota.tiles_reduce`: a quantized-mesh pyramid (`cota_tiles`), whole or
//! one shard of it, as `cota tiles` writes it (a shard after the plan step
//! reads only the files of its part, `cota_tiles::part`); the GIL is
//! released while reading and tiling.

use std::path::{Path, PathBuf};

use cota_core::tiles::{addressed, shard_plan, Lattice, Prepared};
use cota_core::HeightGrid;
use cota_io::read_region;
use cota_tiles::{
    check_output, file_extents, reduce_shards, shard_frame_path, shard_record_path, write_output,
    write_shard, PartError, PathsInput, PlanPartReport, PyramidError, PyramidOptions,
    PyramidReport, ShardFrame, TileExtensions, TileFormat, TileJob, TileSettings,
};
use pyo3::conversion::FromPyObjectOwned;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::errors;

/// The keyword arguments that decide the tiles (`cota tiles`' flags), with
/// every tiling function; [`PYRAMID`]'s too with `tiles` and
/// `tiles_plan_step`.
const SETTINGS: [&str; 5] = [
    "min_zoom",
    "max_zoom",
    "tile_cells",
    "error_factor",
    "max_error_m_at_max_zoom",
];

/// The keyword arguments of a pyramid's bytes.
const PYRAMID: [&str; 9] = [
    "normals",
    "watermask",
    "metadata",
    "gzip",
    "force",
    "check",
    "format",
    "meshopt",
    "skirts",
];

/// A tiling function's keyword arguments.
struct Keywords<'a, 'py> {
    func: &'static str,
    given: Option<&'a Bound<'py, PyDict>>,
}

impl<'a, 'py> Keywords<'a, 'py> {
    /// The keywords `given` to `func`; a keyword none of `allowed` names is
    /// refused, as Python would.
    fn of(
        func: &'static str,
        given: Option<&'a Bound<'py, PyDict>>,
        allowed: &[&[&str]],
    ) -> PyResult<Self> {
        for k in given.iter().flat_map(|d| d.keys()) {
            let k: String = k.extract()?;
            if !allowed.iter().any(|names| names.contains(&k.as_str())) {
                return Err(PyTypeError::new_err(format!(
                    "{func}() got an unexpected keyword argument '{k}'"
                )));
            }
        }
        Ok(Self { func, given })
    }

    /// The value of `name`, or `default` when not given (or `None`).
    fn get<T: FromPyObjectOwned<'py>>(&self, name: &str, default: T) -> PyResult<T> {
        match self.given.map(|d| d.get_item(name)).transpose()?.flatten() {
            Some(v) if !v.is_none() => v.extract::<T>().map_err(|e| {
                let e: PyErr = e.into();
                PyTypeError::new_err(format!("{}(): argument '{name}': {e}", self.func))
            }),
            _ => Ok(default),
        }
    }

    /// The settings that decide the tiles.
    fn settings(&self) -> PyResult<TileSettings> {
        let d = TileSettings::DEFAULT;
        Ok(TileSettings {
            min_zoom: self.get("min_zoom", d.min_zoom)?,
            max_zoom: self.get("max_zoom", None)?,
            tile_cells: self.get("tile_cells", d.tile_cells)?,
            error: TileSettings::schedule(
                self.get("error_factor", None)?,
                self.get("max_error_m_at_max_zoom", None)?,
            ),
        })
    }

    /// The options of the pyramid's bytes.
    fn pyramid(&self) -> PyResult<PyramidOptions> {
        let ext = TileExtensions::with(
            self.get("normals", false)?,
            self.get("watermask", false)?,
            self.get("metadata", false)?,
        );
        let format: String = self.get("format", "quantized-mesh".to_string())?;
        Ok(PyramidOptions::DEFAULT
            .with_extensions(ext)
            .with_gzip(self.get("gzip", false)?)
            .with_force(self.get("force", false)?)
            .with_check(self.get("check", false)?)
            .with_meshopt(self.get("meshopt", false)?)
            .with_skirts(self.get("skirts", true)?)
            .with_format(format_of(&format)?))
    }
}

/// One path or a list of them.
fn paths_of(paths: &Bound<'_, PyAny>) -> PyResult<Vec<PathBuf>> {
    match paths.extract::<PathBuf>() {
        Ok(p) => Ok(vec![p]),
        Err(_) => paths.extract(),
    }
}

/// The input files `paths` (one path or a list of them).
fn input_of(paths: &Bound<'_, PyAny>) -> PyResult<PathsInput> {
    Ok(PathsInput {
        paths: paths_of(paths)?,
    })
}

/// Each input file and its samples in the mosaic (`file_extents`).
type FileExtents = Vec<(String, [usize; 4])>;

/// A part's error as Python's.
fn part_error(e: PartError) -> PyErr {
    match e {
        PartError::Read(e) => errors::read(e),
        PartError::Frame(PyramidError::Tiles(e)) => errors::mesh(e),
        PartError::Frame(e) => errors::write(e),
    }
}

/// Reads, fills the voids and resamples: the source, its lattice, and
/// where each file lies in the mosaic (empty when a shard must read every
/// file: one file, voids, holes).
fn lattice_and_files(
    paths: &[PathBuf],
    s: &TileSettings,
) -> PyResult<(HeightGrid, Lattice, FileExtents)> {
    let region = read_region(paths, &PathsInput::region_options()).map_err(errors::read)?;
    let lat = Lattice::resample(&region.grid, &s.lattice_options()).map_err(errors::mesh)?;
    let files = if region.voids > 0 || region.hole_samples > 0 {
        Vec::new()
    } else {
        file_extents(&region.files, region.grid.georef())
    };
    Ok((region.grid, lat, files))
}

/// Shard `i` after the plan step: reads only the files of its part.
fn write_part(
    job: &TileJob<'_, PathsInput>,
    opts: &PyramidOptions,
    f: &ShardFrame,
    i: u32,
) -> PyResult<(u64, PyramidReport, Vec<String>)> {
    let normals = opts.extensions.normals;
    let part = job.load_part(f, i, normals).map_err(part_error)?;
    let prep = Prepared::new_part(
        &part.lattice,
        part.source_part(),
        part.zooms.clone(),
        &part.stats,
    )
    .map_err(errors::mesh)?;
    let frame = Some((f, part.source_part()));
    let report =
        write_shard(&prep, job.out, opts, &part.shard, frame, &|_| {}).map_err(errors::write)?;
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

/// Refuses a shard `(i, n)` of a 3D Tiles pyramid or past the shards.
fn check_shard(shard: Option<(u32, u32)>, opts: &PyramidOptions) -> PyResult<()> {
    let Some((i, n)) = shard else {
        return Ok(());
    };
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
    Ok(())
}

/// The job of `paths` into `out` with the keywords' settings.
fn job<'a>(
    input: &'a PathsInput,
    out: &'a Path,
    shards: u32,
    kw: &Keywords<'_, '_>,
) -> PyResult<TileJob<'a, PathsInput>> {
    Ok(TileJob {
        input,
        settings: kw.settings()?,
        out,
        shards: at_least_one(shards)?,
    })
}

/// The whole pyramid, or shard `(i, n)` of it without a plan step (every
/// shard reads the whole input): tiles in it and the report.
fn write_whole(
    job: &TileJob<'_, PathsInput>,
    opts: &PyramidOptions,
    shard: Option<u32>,
) -> PyResult<(u64, PyramidReport)> {
    let (grid, lat, _) = lattice_and_files(&job.input.paths, &job.settings)?;
    let prep = Prepared::new(&lat, &grid, &job.settings.tiler_options()).map_err(errors::mesh)?;
    let report = match shard {
        Some(i) => {
            let part = shard_plan(prep.zooms(), job.shards)
                .map_err(errors::value)?
                .swap_remove(i as usize);
            write_shard(&prep, job.out, opts, &part, None, &|_| {})
        }
        None => write_output(&prep, job.out, opts, None, &|_| {}),
    }
    .map_err(errors::write)?;
    Ok((prep.tile_count(), report))
}

/// Writes a pyramid of the DEM file(s) `paths` under `out`
/// (`out/layer.json`, `out/{z}/{x}/{y}.terrain`), byte for byte as
/// `cota tiles` with the same settings: into one MBTiles archive when `out`
/// ends in `.mbtiles`; with `format="3dtiles"` (`meshopt`, `skirts`) as 3D
/// Tiles terrain, into one 3D Tiles Archive when `out` ends in `.3tz`. With
/// `shard=(i, n)` only shard `i` of `n` (see `tiles_plan`) and its record;
/// `tiles_reduce(out, n)` then writes `layer.json`. Keywords: `min_zoom`,
/// `max_zoom`, `tile_cells`, `error_factor`, `max_error_m_at_max_zoom`,
/// `normals`, `watermask`, `metadata`, `gzip`, `force`, `check`, `shard`,
/// `format`, `meshopt`, `skirts` (see `cota/__init__.pyi`). Returns a dict:
/// `tiles`, `written`, `skipped`, `bytes`, `files_read`. Raises `ReadError`,
/// `MeshError` or `WriteError`.
#[pyfunction]
#[pyo3(signature = (paths, out, **keywords))]
pub(crate) fn tiles<'py>(
    py: Python<'py>,
    paths: &Bound<'py, PyAny>,
    out: PathBuf,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let kw = Keywords::of("tiles", keywords, &[&SETTINGS, &PYRAMID, &["shard"]])?;
    let input = input_of(paths)?;
    let opts = kw.pyramid()?;
    check_output(&out, &opts).map_err(errors::value)?;
    let shard: Option<(u32, u32)> = kw.get("shard", None)?;
    check_shard(shard, &opts)?;
    let job = job(&input, &out, shard.map_or(1, |s| s.1), &kw)?;
    let (total, report, files_read) = py.detach(|| -> PyResult<_> {
        if let Some((i, _)) = shard {
            if let Some(f) = job.frame().map_err(part_error)? {
                let (t, r, files) = write_part(&job, &opts, &f, i)?;
                return Ok((t, r, Some(files)));
            }
        }
        let (t, r) = write_whole(&job, &opts, shard.map(|s| s.0))?;
        Ok((t, r, None))
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
/// lattice needs. Writes no tile. Takes `tiles`' keywords (those of the
/// tiles' bytes are the shards'). Returns a dict: `band_zoom`,
/// `coarse_tiles`, `written`, `skipped` (both 0), `files` (each input's
/// samples in the mosaic; empty when every shard must read every file: one
/// file, voids or holes).
#[pyfunction]
#[pyo3(signature = (paths, out, shards, **keywords))]
pub(crate) fn tiles_plan_step<'py>(
    py: Python<'py>,
    paths: &Bound<'py, PyAny>,
    out: PathBuf,
    shards: u32,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let kw = Keywords::of("tiles_plan_step", keywords, &[&SETTINGS, &PYRAMID])?;
    let input = input_of(paths)?;
    let job = job(&input, &out, shards, &kw)?;
    let frame = py.detach(|| -> PyResult<_> {
        // Without the whole input where the files allow it: the parts
        // `tiles_plan_part` already wrote, the others in turn.
        if let Some(layout) = job.layout().map_err(part_error)? {
            return Ok(job.finish_plan(layout).map_err(part_error)?.0);
        }
        let (_, lat, files) = lattice_and_files(&input.paths, &job.settings)?;
        job.plan_whole(&lat, files).map_err(part_error)
    })?;
    let d = PyDict::new(py);
    d.set_item("band_zoom", frame.band_zoom)?;
    d.set_item("coarse_tiles", frame.coarse_tiles)?;
    d.set_item("written", 0)?;
    d.set_item("skipped", 0)?;
    d.set_item("files", frame.files)?;
    Ok(d)
}

/// The plan step's layout (`cota tiles --plan --layout`): each input read
/// alone for its shape, `out/.cota-layout-n.json` written (kept when there).
/// Takes the keywords that decide the tiles. Returns a dict: `streamed`
/// (False when every shard must read every file: then the plan step reads
/// the whole input and has no parts), `files`.
#[pyfunction]
#[pyo3(signature = (paths, out, shards, **keywords))]
pub(crate) fn tiles_plan_layout<'py>(
    py: Python<'py>,
    paths: &Bound<'py, PyAny>,
    out: PathBuf,
    shards: u32,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let kw = Keywords::of("tiles_plan_layout", keywords, &[&SETTINGS])?;
    let input = input_of(paths)?;
    let job = job(&input, &out, shards, &kw)?;
    let layout = py.detach(|| job.layout().map_err(part_error))?;
    let d = PyDict::new(py);
    d.set_item("streamed", layout.is_some())?;
    d.set_item("files", layout.map_or(0, |l| l.files.len()))?;
    Ok(d)
}

/// Part `part` of the plan step (`cota tiles --plan --part i`): shard
/// `part`'s files read and its part resampled for the statistics and band
/// corners, into `out/.cota-plan-i-of-n.bin`, after the layout (made when
/// missing). Idempotent; `tiles_plan_step` then merges the parts. Takes the
/// keywords that decide the tiles. Returns a dict: `streamed` (False:
/// nothing to do, the plan step reads the whole input), `skipped` (its
/// file, or the plan step's frame, was there), `files_read`.
#[pyfunction]
#[pyo3(signature = (paths, out, shards, part, **keywords))]
pub(crate) fn tiles_plan_part<'py>(
    py: Python<'py>,
    paths: &Bound<'py, PyAny>,
    out: PathBuf,
    shards: u32,
    part: u32,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let kw = Keywords::of("tiles_plan_part", keywords, &[&SETTINGS])?;
    let input = input_of(paths)?;
    let job = job(&input, &out, shards, &kw)?;
    if part >= job.shards {
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
        match job.layout()? {
            Some(layout) => job.plan_part(&layout, part).map(Some),
            None => Ok(None),
        }
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

fn at_least_one(shards: u32) -> PyResult<u32> {
    if shards == 0 {
        return Err(errors::value("expected at least 1 shard, found 0"));
    }
    Ok(shards)
}

/// The shard plan of `cota tiles --plan --shards n`: a list of `n` dicts
/// (`shard`, `shards`, `tiles`, `ranges`: a list of `(zoom, x0, x1, y0, y1)`,
/// tile addresses, TMS, inclusive; a range across the antimeridian is given
/// as its two parts). Takes the keywords that decide the tiles.
/// Deterministic: every process computes the same.
#[pyfunction]
#[pyo3(signature = (paths, shards, **keywords))]
pub(crate) fn tiles_plan<'py>(
    py: Python<'py>,
    paths: &Bound<'py, PyAny>,
    shards: u32,
    keywords: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    let kw = Keywords::of("tiles_plan", keywords, &[&SETTINGS])?;
    let settings = kw.settings()?;
    let paths = paths_of(paths)?;
    let (parts, scheme) = py.detach(|| -> PyResult<_> {
        let (_, lat, _) = lattice_and_files(&paths, &settings)?;
        let zooms =
            cota_core::tiles::plan::plan(&lat, &settings.tiler_options()).map_err(errors::mesh)?;
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
