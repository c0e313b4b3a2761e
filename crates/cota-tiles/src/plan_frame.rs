//! The plan step's frame without the whole input: the mosaic's frame from
//! the files' shapes (each file read alone and dropped), and the lattice's
//! statistics merged from each shard's part in turn (only its files read,
//! only its part resampled). The frame is the one [`super::frame_of`] makes
//! of the whole lattice, field for field, so the peak memory of the plan
//! step is about one shard's, not the whole mosaic's. Shared by
//! `cota tiles --plan` and `cota.tiles_plan_step`.
//!
//! Why the statistics are exact: a part's heights are the whole lattice's
//! bit for bit ([`Lattice::resample_part`]); the finest zoom's tiles cover
//! the window and every shard's region covers the closed squares of its
//! tiles, so every pair of neighbouring samples lies in one region; and the
//! statistics are minima and maxima ([`PartStats`]), which do not depend on
//! the order they are taken in.

use std::path::{Path, PathBuf};

use cota_core::grid::mosaic::{layout, MosaicOptions, TileShape};
use cota_core::tiles::plan::plan_with;
use cota_core::tiles::{
    coarse_level_stats_in, part_region, shard_plan, BandCorners, Lattice, LatticeFrame,
    LatticeOptions, LatticeStats, LevelStats, PartStats, SourcePart, TilerOptions,
};
use cota_core::HeightGrid;

use super::frame::{shard_frame_path, ShardFrame};
use super::part::{file_extents, frame_with, read_span, PartError};
use super::PyramidError;
use cota_io::{read_dem, DemSummary, ReadOptions, RegionError};

/// The mosaic of several files, framed from their shapes alone.
#[derive(Debug, Clone, PartialEq)]
pub struct MosaicFrame {
    /// The lattice's frame (the mosaic's georeference and size).
    pub frame: LatticeFrame,
    /// Where each file's samples lie in the mosaic ([`file_extents`]).
    pub files: Vec<(String, [usize; 4])>,
}

/// Reads each of `paths` in turn, keeping only what it holds beside its
/// samples: the peak is one file.
///
/// # Errors
/// [`RegionError::NoFiles`], or [`RegionError::Read`] for the first file
/// that cannot be read.
pub fn summarize_files(
    paths: &[PathBuf],
    opts: &ReadOptions,
) -> Result<Vec<DemSummary>, RegionError> {
    if paths.is_empty() {
        return Err(RegionError::NoFiles);
    }
    paths
        .iter()
        .map(|p| Ok(read_dem(p, opts)?.summary()))
        .collect()
}

/// The frame of the mosaic of `files` (in input order) under `lattice`, as
/// the whole input's lattice would have it; `None` when a shard must read
/// every file (then so must the plan step): fewer than two files, a file
/// with voids, samples no file covers, or a file off the mosaic's grid.
///
/// # Errors
/// [`RegionError::Mosaic`] when the files cannot be joined, and
/// [`PyramidError::Tiles`] when the mosaic cannot be tiled.
pub fn mosaic_frame(
    files: &[DemSummary],
    lattice: &LatticeOptions,
    mosaic: &MosaicOptions,
) -> Result<Option<MosaicFrame>, PartError> {
    if files.len() < 2 || files.iter().any(|f| f.nodata_count > 0) {
        return Ok(None);
    }
    let shapes: Vec<TileShape> = files
        .iter()
        .map(|f| TileShape {
            georef: f.georef.clone(),
            width: f.width,
            height: f.height,
        })
        .collect();
    let names: Vec<String> = files.iter().map(|f| f.path.display().to_string()).collect();
    let m = layout(&shapes, mosaic).map_err(|source| RegionError::Mosaic {
        files: names.join(", "),
        source,
    })?;
    if m.hole_samples > 0 {
        return Ok(None);
    }
    let frame = LatticeFrame::for_source(&m.georef, [m.width, m.height], lattice)
        .map_err(PyramidError::Tiles)?;
    let files = file_extents(files, &m.georef);
    Ok((!files.is_empty()).then_some(MosaicFrame { frame, files }))
}

/// The plan step's *layout* of `shards` shards of the mosaic `m` (`key`:
/// the settings): the frame with zero statistics. The zooms' ranges, hence
/// the band zoom, the coarse tiles and the shards' parts, do not depend on
/// the statistics, so the plan parts ([`plan_part`]) work from it alone.
///
/// # Errors
/// [`PyramidError::Tiles`] for a plan the settings refuse.
pub fn plan_layout(
    key: String,
    shards: u32,
    m: &MosaicFrame,
    opts: &TilerOptions,
) -> Result<ShardFrame, PyramidError> {
    let fr = &m.frame;
    let zooms = plan_with(fr, &ZERO, opts)?;
    Ok(frame_with(
        key,
        shards,
        fr.clone(),
        ZERO,
        &zooms,
        m.files.clone(),
    ))
}

const ZERO: LatticeStats = LatticeStats {
    lo_m: 0.0,
    hi_m: 0.0,
    max_step_m: 0.0,
    levels: LevelStats {
        slope: Vec::new(),
        span_m: Vec::new(),
    },
    residual_m: 0.0,
};

/// What one part of the plan step gives: its part's statistics and the band
/// corners it holds.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanPart {
    /// The statistics of the part's lattice.
    pub stats: PartStats,
    /// The band zoom's tile corners inside the part (a sub-window of the
    /// whole corners' grid, every corner known).
    pub corners: BandCorners,
    /// The input files read.
    pub files_read: Vec<String>,
}

/// Part `index` of the plan step of `layout` (from [`plan_layout`]): reads
/// the files of shard `index`'s part at the band zoom and finer
/// (`read(files)`, as [`super::load_part`]'s reader), resamples it and
/// keeps its statistics and band corners; `None` when the shard has no
/// tile there. `out`: where the frame goes, for messages.
///
/// # Errors
/// [`PyramidError::Tiles`], [`PyramidError::Shard`] for files off the
/// layout's grid, and what `read` returns.
pub fn plan_part<E: From<PyramidError>>(
    out: &Path,
    layout: &ShardFrame,
    opts: &TilerOptions,
    index: u32,
    read: impl FnOnce(Option<Vec<PathBuf>>) -> Result<(HeightGrid, Vec<String>), E>,
) -> Result<Option<PlanPart>, E> {
    let tiles = |e| E::from(PyramidError::Tiles(e));
    let fr = &layout.frame;
    let zooms = plan_with(fr, &ZERO, opts).map_err(tiles)?;
    let band = layout.band_zoom;
    let shards = shard_plan(&zooms, layout.shards).map_err(tiles)?;
    let Some(shard) = shards.into_iter().nth(index as usize) else {
        let message = format!("expected a part below {}, found {index}", layout.shards);
        return Err(refusal(out, layout.shards, message).into());
    };
    let shard = shard.from_zoom(band);
    let Some(region) = part_region(&shard, &fr.scheme, fr.window, band, false) else {
        return Ok(None);
    };
    let refuse = |m: String| refusal(out, layout.shards, m);
    let (grid, offset, files_read) = read_span(layout, fr.source_span(region), read, &refuse)?;
    let part = SourcePart {
        grid: &grid,
        offset,
    };
    let lattice = Lattice::resample_part(fr, part, region).map_err(tiles)?;
    let mut corners = corners_within(fr.window, fr.scheme.cells_at(band), lattice.stored());
    corners.fill_from(&lattice);
    Ok(Some(PlanPart {
        stats: PartStats::of(&lattice, fr.scheme.cells_at(band)),
        corners,
        files_read,
    }))
}

fn refusal(out: &Path, shards: u32, message: String) -> PyramidError {
    PyramidError::Shard {
        path: shard_frame_path(out, shards),
        message,
    }
}

/// The corners of the whole window's grid (every `cells` cells) inside
/// `stored`, as a sub-window of that grid (empty: a 0 × 0 window at its
/// origin, when none is inside).
fn corners_within(window: [u64; 4], cells: u64, stored: [u64; 4]) -> BandCorners {
    let c = cells.max(1);
    let first = |lo: u64, w0: u64| lo.saturating_sub(w0).div_ceil(c);
    let last = |hi: u64, w0: u64, w1: u64| (hi.min(w1).saturating_sub(w0)) / c;
    let (i0, j0) = (first(stored[0], window[0]), first(stored[1], window[1]));
    let (i1, j1) = (
        last(stored[2], window[0], window[2]),
        last(stored[3], window[1], window[3]),
    );
    if i0 > i1 || j0 > j1 || stored[2] < window[0] || stored[3] < window[1] {
        return BandCorners {
            cells: c,
            window: [window[0], window[1], window[0], window[1]],
            heights_m: Vec::new(),
        };
    }
    let at = |i: u64, j: u64| [window[0] + i * c, window[1] + j * c];
    let ([x0, y0], [x1, y1]) = (at(i0, j0), at(i1, j1));
    BandCorners::new([x0, y0, x1, y1], c)
}

/// The plan step's frame and band corners from `layout` and every part's
/// [`PlanPart`] (in any order): the statistics merged, the corners set.
///
/// # Errors
/// [`PyramidError::Tiles`] for a plan the settings refuse,
/// [`PyramidError::Shard`] for a part's corners off the layout's grid.
pub fn merge_plan(
    layout: ShardFrame,
    parts: impl IntoIterator<Item = PlanPart>,
    opts: &TilerOptions,
    out: &Path,
) -> Result<(ShardFrame, BandCorners), PyramidError> {
    let fr = &layout.frame;
    let mut corners = BandCorners::new(fr.window, fr.scheme.cells_at(layout.band_zoom));
    let mut merged = PartStats::default();
    for p in parts {
        merged = merged.merge(p.stats);
        if !set_corners(&mut corners, &p.corners) {
            let message = format!(
                "expected a plan part's corners on the band zoom's grid (every {} cells over {:?}), found every {} over {:?}",
                corners.cells, corners.window, p.corners.cells, p.corners.window
            );
            return Err(refusal(out, layout.shards, message));
        }
    }
    // The levels above the band squares, from the band corners.
    let t = fr.scheme.cells_at(layout.band_zoom);
    let height = |x: u64, y: u64| corners.height(x, y).unwrap_or(0.0);
    let coarse = coarse_level_stats_in(&fr.scheme, fr.window, fr.align_zoom, 2 * t, &height);
    merged.levels = merged.levels.merge(&coarse);
    let stats = merged.stats();
    let zooms = plan_with(fr, &stats, opts)?;
    let ShardFrame {
        key,
        shards,
        frame,
        files,
        ..
    } = layout;
    Ok((
        frame_with(key, shards, frame, stats, &zooms, files),
        corners,
    ))
}

/// Sets `part`'s known corners in `whole`; false when `part` is not a
/// sub-window of `whole`'s grid.
fn set_corners(whole: &mut BandCorners, part: &BandCorners) -> bool {
    let (w, p, c) = (whole.window, part.window, whole.cells);
    let aligned = |v: u64, o: u64| v >= o && (v - o).is_multiple_of(c);
    let inside = p[0] <= p[2] && p[1] <= p[3] && p[2] <= w[2] && p[3] <= w[3];
    if part.heights_m.is_empty() {
        return true;
    }
    if part.cells != c || !inside || !aligned(p[0], w[0]) || !aligned(p[1], w[1]) {
        return false;
    }
    let [nx, _] = BandCorners::dims(w, c);
    let [px, py] = BandCorners::dims(p, c);
    if part.heights_m.len() != px * py {
        return false;
    }
    let (i0, j0) = (((p[0] - w[0]) / c) as usize, ((p[1] - w[1]) / c) as usize);
    for j in 0..py {
        for i in 0..px {
            let h = part.heights_m[j * px + i];
            if !h.is_nan() {
                whole.heights_m[(j0 + j) * nx + i0 + i] = h;
            }
        }
    }
    true
}

/// The plan step's frame of `shards` shards of the mosaic `m` (`key`: the
/// settings; `out`: where it goes, for messages), its statistics merged
/// from each shard's part in turn, and the band zoom's tile corners read
/// from those parts. `read(files)` reads and joins the mosaic
/// of `files` (as [`super::load_part`]'s reader); at most one part is held
/// at a time. The same as [`plan_layout`], each [`plan_part`] and
/// [`merge_plan`].
///
/// # Errors
/// [`PyramidError::Tiles`] for a plan the settings refuse, and what `read`
/// returns.
pub fn stream_frame<E: From<PyramidError>>(
    out: &Path,
    key: String,
    shards: u32,
    m: &MosaicFrame,
    opts: &TilerOptions,
    mut read: impl FnMut(Option<Vec<PathBuf>>) -> Result<(HeightGrid, Vec<String>), E>,
) -> Result<(ShardFrame, BandCorners), E> {
    let layout = plan_layout(key, shards, m, opts)?;
    let mut parts = Vec::new();
    for i in 0..shards {
        parts.extend(plan_part(out, &layout, opts, i, &mut read)?);
    }
    Ok(merge_plan(layout, parts, opts, out)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{frame_of, read_part_files_in_turn, write_shard_frame};
    use cota_core::tiles::plan::plan;
    use cota_io::{read_region, RegionOptions};

    /// The whole-input frame and the streamed one of `inputs`, as JSON text.
    fn both(inputs: &[PathBuf], lo: &LatticeOptions, shards: u32) -> (String, String) {
        let region = read_region(inputs, &RegionOptions::DEFAULT).unwrap();
        let files = file_extents(&region.files, region.grid.georef());
        let lat = Lattice::resample(&region.grid, lo).unwrap();
        let opts = TilerOptions::DEFAULT;
        let whole = frame_of("k".into(), shards, &lat, &plan(&lat, &opts).unwrap(), files);
        let mut corners = BandCorners::new(lat.window(), lat.scheme().cells_at(whole.band_zoom));
        corners.fill_from(&lat);
        drop((lat, region));
        let sums = summarize_files(inputs, &ReadOptions::DEFAULT).unwrap();
        let m = mosaic_frame(&sums, lo, &MosaicOptions::DEFAULT)
            .unwrap()
            .unwrap();
        let read = |f| read_part_files_in_turn(inputs, f, &RegionOptions::DEFAULT);
        let out = Path::new("out");
        let (streamed, got) = stream_frame(out, "k".into(), shards, &m, &opts, read).unwrap();
        // The band corners too, bit for bit.
        let bits = |c: &BandCorners| c.heights_m.iter().map(|h| h.to_bits()).collect::<Vec<_>>();
        assert_eq!(got.missing(), 0);
        assert_eq!(bits(&got), bits(&corners));
        (text(&whole), text(&streamed))
    }

    /// The frame's file as the plan step writes it.
    fn text(f: &ShardFrame) -> String {
        let dir = tempfile::tempdir().unwrap();
        write_shard_frame(dir.path(), f).unwrap();
        std::fs::read_to_string(shard_frame_path(dir.path(), f.shards)).unwrap()
    }

    /// The two-tile mosaic: the streamed frame is the whole input's, same
    /// text, for 1 to 4 shards; a single file is not streamed.
    #[test]
    fn streamed_frame_is_the_whole_inputs_on_two_tiles() {
        let (Some(w), Some(e)) = (
            cota_fixtures::shared("srtm/N00E010.hgt"),
            cota_fixtures::shared("srtm/N00E011.hgt.zip"),
        ) else {
            return;
        };
        let inputs = vec![w, e];
        for (n, z) in [(1, 10), (2, 11), (3, 10), (4, 12)] {
            let lo = LatticeOptions::DEFAULT.with_max_zoom(Some(z));
            let (whole, streamed) = both(&inputs, &lo, n);
            assert_eq!(whole, streamed, "n={n} z={z}");
        }
        let one = summarize_files(&inputs[..1], &ReadOptions::DEFAULT).unwrap();
        let m = mosaic_frame(&one, &LatticeOptions::DEFAULT, &MosaicOptions::DEFAULT);
        assert!(m.unwrap().is_none());
    }

    /// A relabelled 4×2 block of copies of the two tiles (real samples at
    /// false positions, seams that disagree and are averaged): the streamed
    /// frame is the whole input's for 2 and 4 shards.
    #[test]
    fn streamed_frame_is_the_whole_inputs_on_eight_files() {
        let (Some(w), Some(e)) = (
            cota_fixtures::shared("srtm/N00E010.hgt"),
            cota_fixtures::shared("srtm/N00E011.hgt.zip"),
        ) else {
            return;
        };
        let dir = tempfile::tempdir().unwrap();
        let inputs = relabelled_block(&[w, e], dir.path());
        for n in [2, 4] {
            let lo = LatticeOptions::DEFAULT.with_max_zoom(Some(10));
            let (whole, streamed) = both(&inputs, &lo, n);
            assert_eq!(whole, streamed, "n={n}");
        }
    }

    /// Not streamed (a shard would read every file): an L of three files
    /// (samples no file covers), and a file with a void.
    #[test]
    fn holes_and_voids_are_not_streamed() {
        let (Some(w), Some(e)) = (
            cota_fixtures::shared("srtm/N00E010.hgt"),
            cota_fixtures::shared("srtm/N00E011.hgt.zip"),
        ) else {
            return;
        };
        let dir = tempfile::tempdir().unwrap();
        let block = relabelled_block(&[w, e], dir.path());
        let (lo, mo) = (LatticeOptions::DEFAULT, MosaicOptions::DEFAULT);
        let frame = |paths: &[PathBuf]| {
            let sums = summarize_files(paths, &ReadOptions::DEFAULT).unwrap();
            mosaic_frame(&sums, &lo, &mo).unwrap()
        };
        assert!(frame(&block[..2]).is_some());
        let l = [block[0].clone(), block[1].clone(), block[4].clone()];
        assert!(frame(&l).is_none());
        let mut bytes = std::fs::read(&block[1]).unwrap();
        bytes[2000..2002].copy_from_slice(&i16::MIN.to_be_bytes());
        std::fs::write(&block[1], bytes).unwrap();
        assert!(frame(&block[..2]).is_none());
    }

    /// Copies of `tiles` (alternating) as raw SRTM tiles N10E020…N09E023.
    fn relabelled_block(tiles: &[PathBuf], dir: &Path) -> Vec<PathBuf> {
        let bytes: Vec<Vec<u8>> = tiles
            .iter()
            .map(|t| {
                let dem = read_dem(t, &ReadOptions::DEFAULT).unwrap();
                let hs = dem.grid.heights();
                hs.iter().flat_map(|h| (*h as i16).to_be_bytes()).collect()
            })
            .collect();
        let mut out = Vec::new();
        for lat in [10usize, 9] {
            for lon in 20usize..24 {
                let p = dir.join(format!("N{lat:02}E{lon:03}.hgt"));
                std::fs::write(&p, &bytes[(lat + lon) % 2]).unwrap();
                out.push(p);
            }
        }
        out
    }
}
