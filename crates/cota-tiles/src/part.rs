//! Shards over parts of the lattice: the plan step's frame of the whole
//! (where each input file's samples lie in the mosaic), and a shard's part,
//! read from only the input files it needs. Shared by `cota tiles --plan` /
//! `--shard I/N` and `cota.tiles_plan_step` / `cota.tiles(shard=…)`.

use std::path::{Path, PathBuf};

use cota_core::tiles::plan::plan_with;
use cota_core::tiles::{
    band_zoom, part_region, resampling_deviation, shard_plan, Deviation, Lattice, LatticeFrame,
    LatticeStats, Shard, SourcePart, TilerOptions, ZoomPlan,
};
use cota_core::{GeoRef, HeightGrid};

use super::frame::{shard_frame_path, ShardFrame};
use super::PyramidError;
use cota_io::{read_region, read_region_in_turn, DemSummary, Region, RegionError, RegionOptions};

/// A shard's part could not be made: a frame that does not fit, or input
/// files that could not be read.
#[derive(Debug, thiserror::Error)]
pub enum PartError {
    /// The frame does not fit the settings or the files.
    #[error(transparent)]
    Frame(#[from] PyramidError),
    /// The files could not be read.
    #[error(transparent)]
    Read(#[from] RegionError),
}

/// Where each file's samples lie in the mosaic `whole`, `[c0, r0, c1, r1]`
/// inclusive; empty (a shard then reads every file) for fewer than two files
/// or a file off the mosaic's grid origin. The caller also passes none when
/// the mosaic has voids to fill, holes or a crop.
pub fn file_extents(files: &[DemSummary], whole: &GeoRef) -> Vec<(String, [usize; 4])> {
    if files.len() < 2 {
        return Vec::new();
    }
    let mut out = Vec::new();
    for f in files {
        let Some([c0, r0]) = offset_in(&f.georef, whole) else {
            return Vec::new();
        };
        let e = [c0, r0, c0 + f.width - 1, r0 + f.height - 1];
        out.push((f.path.display().to_string(), e));
    }
    out
}

/// The column and row of `part`'s sample (0, 0) in the grid of `whole`; in
/// a geographic grid whose turn (360°) is a whole number of columns, the
/// column modulo a turn, as the mosaic places a file across the
/// antimeridian (`W180` one turn east of `E179`, `cota_core::grid::mosaic`).
fn offset_in(part: &GeoRef, whole: &GeoRef) -> Option<[usize; 2]> {
    let (px, py) = part.sample_xy(0.0, 0.0);
    let (wx, wy) = whole.sample_xy(0.0, 0.0);
    let mut c = ((px - wx) / whole.pixel_x).round();
    let r = ((py - wy) / whole.pixel_y).round();
    let turn = 360.0 / whole.pixel_x;
    if whole.crs.is_geographic() && whole.pixel_x > 0.0 && (turn - turn.round()).abs() < 1e-6 {
        c = c.rem_euclid(turn.round());
    }
    (c >= 0.0 && r >= 0.0 && c.is_finite() && r.is_finite()).then_some([c as usize, r as usize])
}

/// The plan step's frame for `shards` shards of `lattice` (`key`: the
/// settings; `files`: [`file_extents`]).
pub fn frame_of(
    key: String,
    shards: u32,
    lattice: &Lattice,
    zooms: &[ZoomPlan],
    files: Vec<(String, [usize; 4])>,
) -> ShardFrame {
    let stats = LatticeStats::of(lattice);
    frame_with(key, shards, lattice.frame().clone(), stats, zooms, files)
}

/// The plan step's frame for `shards` shards of a lattice of frame `frame`
/// and statistics `stats` (`zooms`: its plan).
pub(super) fn frame_with(
    key: String,
    shards: u32,
    frame: LatticeFrame,
    stats: LatticeStats,
    zooms: &[ZoomPlan],
    files: Vec<(String, [usize; 4])>,
) -> ShardFrame {
    let band = band_zoom(zooms, frame.align_zoom, shards);
    let coarse_tiles = zooms
        .iter()
        .filter(|z| z.zoom < band)
        .map(|z| z.range.count())
        .sum();
    ShardFrame {
        key,
        shards,
        band_zoom: band,
        coarse_tiles,
        frame,
        stats,
        files,
    }
}

/// One shard's part: its lattice, plan and tiles.
#[derive(Debug)]
pub struct Part {
    /// The part of the lattice.
    pub lattice: Lattice,
    /// Every zoom's plan (the whole pyramid's).
    pub zooms: Vec<ZoomPlan>,
    /// The whole lattice's statistics (the plan's and the drawn bound's).
    pub stats: LatticeStats,
    /// The source samples the part was resampled from.
    pub source: HeightGrid,
    /// Where they sit in the whole source, `[column, row]`.
    pub source_offset: [usize; 2],
    /// The shard's tiles of the band zoom and finer.
    pub shard: Shard,
    /// The resampling's deviation over the source samples in the part.
    pub deviation: Deviation,
    /// The input files read.
    pub files_read: Vec<String>,
}

impl Part {
    /// The source samples of the part, as the tiler takes them.
    pub fn source_part(&self) -> SourcePart<'_> {
        SourcePart {
            grid: &self.source,
            offset: self.source_offset,
        }
    }
}

/// Reads the files shard `index` of the frame `f` (found under `out`) needs
/// and resamples its part (with `normals`, grown by what the normals of its
/// coarse vertices read). `key` must be the frame's. `read(files)` reads
/// and fills the mosaic of `files` (`None`: every input, when the frame
/// lists no files) and returns it with the names of the files read.
///
/// # Errors
/// [`PyramidError::Shard`] for a frame of other settings or files off its
/// grid, [`PyramidError::Tiles`], and what `read` returns.
pub fn load_part<E: From<PyramidError>>(
    out: &Path,
    f: &ShardFrame,
    key: &str,
    opts: &TilerOptions,
    index: u32,
    normals: bool,
    read: impl FnOnce(Option<Vec<PathBuf>>) -> Result<(HeightGrid, Vec<String>), E>,
) -> Result<Part, E> {
    let refuse = |message: String| PyramidError::Shard {
        path: shard_frame_path(out, f.shards),
        message,
    };
    if f.key != key {
        return Err(refuse("expected the plan step's frame of these settings, found one of other settings; run the plan step again with them".into()).into());
    }
    let fr = &f.frame;
    let tiles = |e| E::from(PyramidError::Tiles(e));
    let zooms = plan_with(fr, &f.stats, opts).map_err(tiles)?;
    let shard = shard_plan(&zooms, f.shards).map_err(tiles)?;
    let Some(shard) = shard.into_iter().nth(index as usize) else {
        return Err(refuse(format!(
            "expected a shard index below {}, found {index}",
            f.shards
        ))
        .into());
    };
    let shard = shard.from_zoom(f.band_zoom);
    let t = fr.scheme.cells_at(f.band_zoom);
    let w = fr.window;
    let region = part_region(&shard, &fr.scheme, w, f.band_zoom, normals).unwrap_or([
        w[0],
        w[1],
        w[0] + t,
        w[1] + t,
    ]);
    let (grid, offset, files_read) = read_span(f, fr.source_span(region), read, &refuse)?;
    let part = SourcePart {
        grid: &grid,
        offset,
    };
    let lattice = Lattice::resample_part(fr, part, region).map_err(tiles)?;
    let deviation = resampling_deviation(&grid, &lattice);
    Ok(Part {
        lattice,
        zooms,
        stats: f.stats.clone(),
        source: grid,
        source_offset: offset,
        shard,
        deviation,
        files_read,
    })
}

/// The source samples `span` (`[c0, r0, c1, r1]` of the whole source): the
/// files that meet it (every file when the frame lists none), their offset
/// in the whole source, and their names.
pub(super) fn read_span<E: From<PyramidError>>(
    f: &ShardFrame,
    span: Option<[usize; 4]>,
    read: impl FnOnce(Option<Vec<PathBuf>>) -> Result<(HeightGrid, Vec<String>), E>,
    refuse: &dyn Fn(String) -> PyramidError,
) -> Result<(HeightGrid, [usize; 2], Vec<String>), E> {
    let Some(s) = span else {
        // All 0 m: nothing is read.
        let g = HeightGrid::new(2, 2, vec![0.0; 4], f.frame.source_georef.clone())
            .map_err(|e| refuse(e.to_string()))?;
        return Ok((g, [0, 0], Vec::new()));
    };
    if f.files.is_empty() {
        let (grid, names) = read(None)?;
        return Ok((grid, [0, 0], names));
    }
    let meets = |e: &[usize; 4]| e[0] <= s[2] && e[2] >= s[0] && e[1] <= s[3] && e[3] >= s[1];
    let subset: Vec<PathBuf> = f
        .files
        .iter()
        .filter(|(_, e)| meets(e))
        .map(|(p, _)| PathBuf::from(p))
        .collect();
    if subset.is_empty() {
        return Err(refuse(format!("expected input files covering samples {s:?} of the mosaic, found none in the plan step's frame; run the plan step again")).into());
    }
    let (grid, names) = read(Some(subset))?;
    let whole = &f.frame.source_georef;
    let (part, w) = (grid.georef(), whole);
    if part.pixel_x != w.pixel_x || part.pixel_y != w.pixel_y || part.pixel_is != w.pixel_is {
        return Err(refuse(format!(
            "expected the shard's files on the plan step's grid (pixel {} x {}), found pixel {} x {}; run the plan step again",
            w.pixel_x, w.pixel_y, part.pixel_x, part.pixel_y
        )).into());
    }
    let offset = offset_in(part, whole)
        .ok_or_else(|| refuse("expected the shard's files inside the mosaic, found them before its first sample; run the plan step again".into()))?;
    Ok((grid, offset, names))
}

/// A reader for [`load_part`]: reads `files` (every one of `inputs` for
/// `None`) with `opts` and returns the mosaic and the names of the files.
///
/// # Errors
/// [`RegionError`] from [`read_region`].
pub fn read_part_files(
    inputs: &[PathBuf],
    files: Option<Vec<PathBuf>>,
    opts: &RegionOptions,
) -> Result<(HeightGrid, Vec<String>), PartError> {
    let paths = files.unwrap_or_else(|| inputs.to_vec());
    Ok(named(read_region(&paths, opts)?))
}

/// [`read_part_files`] reading the files one after the other on this
/// thread ([`read_region_in_turn`]): for a process that reads parts in
/// turn, so that each reuses the memory the last one freed.
///
/// # Errors
/// [`RegionError`] from [`read_region_in_turn`].
pub fn read_part_files_in_turn(
    inputs: &[PathBuf],
    files: Option<Vec<PathBuf>>,
    opts: &RegionOptions,
) -> Result<(HeightGrid, Vec<String>), PartError> {
    let paths = files.unwrap_or_else(|| inputs.to_vec());
    Ok(named(read_region_in_turn(&paths, opts)?))
}

/// The region's grid and the names of its files.
fn named(region: Region) -> (HeightGrid, Vec<String>) {
    let names = region
        .files
        .iter()
        .map(|f| f.path.display().to_string())
        .collect();
    (region.grid, names)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::write_shard_frame;
    use cota_core::tiles::{LatticeOptions, Prepared};

    /// The two-tile mosaic: each file placed in it, the westmost of 4 shards
    /// reads only the western file, and a frame of other settings is refused.
    #[test]
    fn part_reads_only_its_files_and_refuses_other_settings() {
        let (Some(w), Some(e)) = (
            cota_fixtures::shared("srtm/N00E010.hgt"),
            cota_fixtures::shared("srtm/N00E011.hgt.zip"),
        ) else {
            return;
        };
        let inputs = vec![w.clone(), e.clone()];
        let region = read_region(&inputs, &RegionOptions::DEFAULT).unwrap();
        let files = file_extents(&region.files, region.grid.georef());
        assert_eq!(files[0].1, [0, 0, 1200, 1200]);
        assert_eq!(files[1].1, [1200, 0, 2400, 1200]);
        assert!(file_extents(&region.files[..1], region.grid.georef()).is_empty());
        let lo = LatticeOptions::DEFAULT.with_max_zoom(Some(10));
        let lat = Lattice::resample(&region.grid, &lo).unwrap();
        let opts = TilerOptions::DEFAULT;
        let prep = Prepared::new(&lat, &region.grid, &opts).unwrap();
        let frame = frame_of("k".into(), 4, &lat, prep.zooms(), files);
        let out = tempfile::tempdir().unwrap();
        write_shard_frame(out.path(), &frame).unwrap();
        let read = |f: Option<Vec<PathBuf>>| read_part_files(&inputs, f, &RegionOptions::DEFAULT);
        let part = load_part(out.path(), &frame, "k", &opts, 0, false, read).unwrap();
        assert_eq!(part.files_read, vec![w.display().to_string()]);
        assert!(part.lattice.grid().width() * 2 < lat.grid().width());
        let other = load_part(out.path(), &frame, "other", &opts, 0, false, read);
        let msg = other.unwrap_err().to_string();
        assert!(
            msg.contains("other settings") && msg.contains(".cota-shards-4.json"),
            "{msg}"
        );
        let past = load_part(out.path(), &frame, "k", &opts, 4, false, read);
        assert!(past.unwrap_err().to_string().contains("below 4"));
    }
}
