//! One tiling job: the settings that decide a pyramid's tiles, its inputs,
//! and the steps of a sharded run over them (the plan step's layout, its
//! parts and their merge, each shard's part, the reduce), as `cota tiles`,
//! `cota serve` and the Python bindings (`cota.tiles`, `cota.dask`) run
//! them. The front ends only parse their arguments into a [`TileJob`], call
//! its steps and print.
//!
//! A job's [`TileJob::key`] names its inputs, how they are read and the
//! settings, and no front end: a frame or a layout written by `cota tiles`
//! is taken by `cota.tiles(..., shard=(i, n))` and the other way round when
//! both read the same paths the same way.

use std::path::{Path, PathBuf};

use cota_core::tiles::plan::plan;
use cota_core::tiles::{BandCorners, ErrorSchedule, Lattice, LatticeOptions, TilerOptions};
use cota_core::{FillOptions, HeightGrid, MosaicOptions};

use super::frame::{read_shard_frame, ShardFrame};
use super::part::{frame_of, load_part, read_part_files, read_part_files_in_turn, Part, PartError};
use super::plan_frame::{mosaic_frame, plan_layout, summarize_files};
use super::plan_parts::{finish_plan, plan_layout_or, run_plan_part, PlanPartReport};
use super::shard::write_plan;
use super::PyramidError;
use cota_io::{DemSummary, RegionOptions};

/// The settings that decide the lattice, the plan and so every tile (the
/// options of a pyramid's bytes, gzip or extensions, are
/// [`super::PyramidOptions`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TileSettings {
    /// The coarsest zoom written. Default 0.
    pub min_zoom: u8,
    /// The finest zoom; `None`: the zoom whose tiles match the input's
    /// sample spacing. Default `None`.
    pub max_zoom: Option<u8>,
    /// Cells along a tile's side in the lattice. Default 64.
    pub tile_cells: u32,
    /// Each zoom's error bound. Default Cesium's, factor 1.
    pub error: ErrorSchedule,
}

impl TileSettings {
    /// The defaults of `cota tiles`.
    pub const DEFAULT: Self = Self {
        min_zoom: 0,
        max_zoom: None,
        tile_cells: 64,
        error: ErrorSchedule::Cesium { factor: 1.0 },
    };

    /// The error schedule of `cota tiles`' two flags: a bound at the finest
    /// zoom (`--max-error-m-at-max-zoom`) over Cesium's factor
    /// (`--error-factor`, default 1).
    pub fn schedule(factor: Option<f64>, at_max_zoom_m: Option<f64>) -> ErrorSchedule {
        match (factor, at_max_zoom_m) {
            (_, Some(e)) => ErrorSchedule::AtMaxZoom { max_error_m: e },
            (q, None) => ErrorSchedule::Cesium {
                factor: q.unwrap_or(1.0),
            },
        }
    }

    /// The lattice's options.
    pub fn lattice_options(&self) -> LatticeOptions {
        LatticeOptions::DEFAULT
            .with_max_zoom(self.max_zoom)
            .with_tile_cells(self.tile_cells)
            .with_error(self.error)
    }

    /// The tiler's options.
    pub fn tiler_options(&self) -> TilerOptions {
        TilerOptions::DEFAULT
            .with_min_zoom(self.min_zoom)
            .with_error(self.error)
    }
}

/// What one of a job's read steps gives: the mosaic of the files read
/// (voids filled) and their names.
pub type ReadPart = (HeightGrid, Vec<String>);

/// A job's inputs and how they are read.
pub trait JobInput {
    /// The error of reading (it holds the job's own errors too).
    type Error: From<PartError> + From<PyramidError>;

    /// What names the inputs and their reading in a job's key: the paths as
    /// given and the region options (see [`input_key`]).
    fn key(&self) -> String;

    /// Each input file alone (its shape, no samples kept) and how they
    /// join; `None` when a shard must read every file (standard input, a
    /// window of the inputs).
    ///
    /// # Errors
    /// The first file that cannot be read.
    fn summaries(&self) -> Result<Option<(Vec<DemSummary>, MosaicOptions)>, Self::Error>;

    /// The mosaic of `files` (`None`: every input), voids filled, with the
    /// names of the files read; one file after the other on this thread
    /// when `in_turn` (a process that reads parts in turn reuses the memory
    /// the last one freed).
    ///
    /// # Errors
    /// The files cannot be read or joined, or their voids filled.
    fn read(&self, files: Option<Vec<PathBuf>>, in_turn: bool) -> Result<ReadPart, Self::Error>;
}

/// The key of inputs `paths` read with `region` (and `extra`: what else
/// decides the mosaic, as `--src-crs` or a window; empty for none).
pub fn input_key(paths: &[PathBuf], region: &RegionOptions, extra: &str) -> String {
    format!("{paths:?} {region:?}{extra}")
}

/// DEM files read as `cota tiles` reads them by default: mosaicked, voids
/// filled harmonically.
#[derive(Debug, Clone)]
pub struct PathsInput {
    /// The files, in the order given.
    pub paths: Vec<PathBuf>,
}

impl PathsInput {
    /// How the files are read.
    pub fn region_options() -> RegionOptions {
        RegionOptions::DEFAULT.with_fill(Some(FillOptions::DEFAULT))
    }
}

impl JobInput for PathsInput {
    type Error = PartError;

    fn key(&self) -> String {
        input_key(&self.paths, &Self::region_options(), "")
    }

    fn summaries(&self) -> Result<Option<(Vec<DemSummary>, MosaicOptions)>, PartError> {
        let opts = Self::region_options();
        Ok(Some((
            summarize_files(&self.paths, &opts.read)?,
            opts.mosaic,
        )))
    }

    fn read(&self, files: Option<Vec<PathBuf>>, in_turn: bool) -> Result<ReadPart, PartError> {
        let opts = Self::region_options();
        if in_turn {
            read_part_files_in_turn(&self.paths, files, &opts)
        } else {
            read_part_files(&self.paths, files, &opts)
        }
    }
}

/// A sharded tiling job: `input` tiled with `settings` into `out` by
/// `shards` shards (1 for a whole run).
#[derive(Debug)]
pub struct TileJob<'a, I> {
    /// The inputs.
    pub input: &'a I,
    /// The settings that decide the tiles.
    pub settings: TileSettings,
    /// The pyramid's directory or archive.
    pub out: &'a Path,
    /// How many shards.
    pub shards: u32,
}

impl<I> Clone for TileJob<'_, I> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<I> Copy for TileJob<'_, I> {}

impl<I: JobInput> TileJob<'_, I> {
    /// What decides the lattice and the plan: a frame, a layout or a plan
    /// part of another key is refused.
    pub fn key(&self) -> String {
        let s = &self.settings;
        format!(
            "cota tiles {} {:?}",
            self.input.key(),
            (s.min_zoom, s.max_zoom, s.tile_cells, s.error)
        )
    }

    /// The plan step's frame under `out`, once the plan step is done.
    ///
    /// # Errors
    /// A damaged frame, or one that cannot be read.
    pub fn frame(&self) -> Result<Option<ShardFrame>, I::Error> {
        Ok(read_shard_frame(self.out, self.shards)?)
    }

    /// The plan step's layout (the frame before the statistics, from each
    /// file's shape), from `out` when a plan step in parts already wrote it,
    /// else made and written there; `None` when a shard must read every
    /// file (one file, voids, samples no file covers, a window): the plan
    /// step then reads the whole input ([`Self::plan_whole`]).
    ///
    /// # Errors
    /// A layout of another key, and what reading the files' shapes returns.
    pub fn layout(&self) -> Result<Option<ShardFrame>, I::Error> {
        let key = self.key();
        plan_layout_or(self.out, &key, self.shards, || {
            let Some((files, mosaic)) = self.input.summaries()? else {
                return Ok(None);
            };
            let lattice = self.settings.lattice_options();
            let Some(m) = mosaic_frame(&files, &lattice, &mosaic)? else {
                return Ok(None);
            };
            let tiler = self.settings.tiler_options();
            Ok(Some(plan_layout(key.clone(), self.shards, &m, &tiler)?))
        })
    }

    /// Part `index` of the plan step from `layout`: the part's files read
    /// and its statistics and band corners written under `out`; skipped when
    /// its file is there.
    ///
    /// # Errors
    /// What reading returns, a damaged part file or one of another key.
    pub fn plan_part(&self, layout: &ShardFrame, index: u32) -> Result<PlanPartReport, I::Error> {
        let read = |files| self.input.read(files, false);
        run_plan_part(
            self.out,
            layout,
            &self.settings.tiler_options(),
            index,
            read,
        )
    }

    /// The plan step from `layout`: the parts already written, the others
    /// read in turn; merged, the frame and the band corners written. Returns
    /// the frame, its corners and how many parts came from their files.
    ///
    /// # Errors
    /// What [`Self::plan_part`] returns.
    pub fn finish_plan(
        &self,
        layout: ShardFrame,
    ) -> Result<(ShardFrame, BandCorners, u32), I::Error> {
        let read = |files| self.input.read(files, true);
        finish_plan(self.out, layout, &self.settings.tiler_options(), read)
    }

    /// The plan step from the whole input's `lattice` (`files`: where each
    /// file lies in it, [`super::file_extents`]; empty when every shard must
    /// read every file): the frame and band corners written under `out`.
    ///
    /// # Errors
    /// A plan the settings refuse; the frame cannot be written.
    pub fn plan_whole(
        &self,
        lattice: &Lattice,
        files: Vec<(String, [usize; 4])>,
    ) -> Result<ShardFrame, I::Error> {
        let zooms = plan(lattice, &self.settings.tiler_options()).map_err(PyramidError::Tiles)?;
        let frame = frame_of(self.key(), self.shards, lattice, &zooms, files);
        let cells = lattice.scheme().cells_at(frame.band_zoom);
        let mut corners = BandCorners::new(lattice.window(), cells);
        corners.fill_from(lattice);
        write_plan(self.out, &frame, &corners)?;
        Ok(frame)
    }

    /// Shard `index`'s part after the plan step: only the files its part
    /// needs read, its part of the lattice resampled (`normals`: with the
    /// margin the normals need).
    ///
    /// # Errors
    /// A frame of another key, an index past the shards, what reading
    /// returns.
    pub fn load_part(
        &self,
        frame: &ShardFrame,
        index: u32,
        normals: bool,
    ) -> Result<Part, I::Error> {
        let tiler = self.settings.tiler_options();
        let read = |files| self.input.read(files, false);
        load_part(self.out, frame, &self.key(), &tiler, index, normals, read)
    }
}
