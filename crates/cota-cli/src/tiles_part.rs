//! `cota tiles --plan` and `--shard I/N` over parts of the lattice: the plan
//! step's frame of the whole, and a shard that reads only the input files
//! its part of the lattice needs (see `cota_io::tiles::shard`).

use std::path::PathBuf;

use anyhow::Context;
use cota_core::tiles::plan::plan_with;
use cota_core::tiles::{
    band_zoom, part_region, resampling_deviation, shard_plan, Deviation, Lattice, LatticeStats,
    Shard, SourcePart, TilerOptions, ZoomPlan,
};
use cota_core::{GeoRef, HeightGrid};
use cota_io::tiles::ShardFrame;

use crate::args::TilesArgs;
use crate::input;

/// What decides the lattice and the plan: a shard refuses a frame made with
/// other settings.
pub fn frame_key(a: &TilesArgs) -> String {
    format!(
        "{:?}",
        (
            &a.input,
            a.min_zoom,
            a.max_zoom,
            a.tile_cells,
            a.error_factor,
            a.max_error_m_at_max_zoom,
            a.voids,
        )
    )
}

/// Where each file's samples lie in the mosaic `whole`, `[c0, r0, c1, r1]`;
/// empty when a shard must read every file: a single file, voids to fill,
/// samples no file covers, or a `--bbox` or `--zoom` crop.
pub fn file_extents(a: &TilesArgs, inp: &input::Input, voids: usize) -> Vec<(String, [usize; 4])> {
    let whole = inp.grid.georef();
    let crop = a.input.bbox.is_some() || a.input.zoom.is_some();
    if inp.files.len() < 2 || voids > 0 || inp.hole_samples > 0 || crop {
        return Vec::new();
    }
    let mut out = Vec::new();
    for f in &inp.files {
        let Some([c0, r0]) = offset_in(&f.georef, whole) else {
            return Vec::new();
        };
        let e = [c0, r0, c0 + f.width - 1, r0 + f.height - 1];
        out.push((f.path.display().to_string(), e));
    }
    out
}

/// The column and row of `part`'s sample (0, 0) in the grid of `whole`.
fn offset_in(part: &GeoRef, whole: &GeoRef) -> Option<[usize; 2]> {
    let (px, py) = part.sample_xy(0.0, 0.0);
    let (wx, wy) = whole.sample_xy(0.0, 0.0);
    let c = ((px - wx) / whole.pixel_x).round();
    let r = ((py - wy) / whole.pixel_y).round();
    (c >= 0.0 && r >= 0.0 && c.is_finite() && r.is_finite()).then_some([c as usize, r as usize])
}

/// The plan step's frame for `shards` shards.
pub fn frame_of(
    a: &TilesArgs,
    lattice: &Lattice,
    zooms: &[ZoomPlan],
    files: Vec<(String, [usize; 4])>,
) -> ShardFrame {
    ShardFrame {
        key: frame_key(a),
        shards: a.shards,
        band_zoom: band_zoom(zooms, lattice.align_zoom(), a.shards),
        frame: lattice.frame().clone(),
        stats: LatticeStats::of(lattice),
        files,
    }
}

/// One shard's part: its lattice, plan and tiles.
pub struct Part {
    /// The part of the lattice.
    pub lattice: Lattice,
    /// Every zoom's plan (the whole pyramid's).
    pub zooms: Vec<ZoomPlan>,
    /// The shard's tiles of the band zoom and finer.
    pub shard: Shard,
    /// The resampling's deviation over the source samples in the part.
    pub deviation: Deviation,
    /// The input files read.
    pub files_read: Vec<String>,
}

/// Reads the files shard `index` needs and resamples its part.
pub fn load_part(
    a: &TilesArgs,
    f: &ShardFrame,
    opts: &TilerOptions,
    index: u32,
) -> anyhow::Result<Part> {
    if f.key != frame_key(a) {
        anyhow::bail!(
            "{}: expected the plan step's frame of these settings, found one of other settings; run --plan again with them",
            cota_io::tiles::shard_frame_path(&a.output, f.shards).display()
        );
    }
    let fr = &f.frame;
    let zooms = plan_with(&fr.scheme, fr.window, &f.stats, opts)?;
    let shard = shard_plan(&zooms, f.shards)?.swap_remove(index as usize);
    let shard = shard.from_zoom(f.band_zoom);
    let t = fr.scheme.cells_at(f.band_zoom);
    let w = fr.window;
    let region =
        part_region(&shard, &fr.scheme, w, f.band_zoom).unwrap_or([w[0], w[1], w[0] + t, w[1] + t]);
    let (grid, offset, files_read) = read_span(a, f, fr.source_span(region))?;
    let part = SourcePart {
        grid: &grid,
        offset,
    };
    let lattice =
        Lattice::resample_part(fr, part, region).context("resampling the shard's part")?;
    let deviation = resampling_deviation(&grid, &lattice);
    Ok(Part {
        lattice,
        zooms,
        shard,
        deviation,
        files_read,
    })
}

/// The source samples `span` (`[c0, r0, c1, r1]` of the whole source): the
/// files that meet it (every file when the frame lists none), their offset
/// in the whole source, and their names.
fn read_span(
    a: &TilesArgs,
    f: &ShardFrame,
    span: Option<[usize; 4]>,
) -> anyhow::Result<(HeightGrid, [usize; 2], Vec<String>)> {
    let Some(s) = span else {
        // All 0 m: nothing is read.
        let g = HeightGrid::new(2, 2, vec![0.0; 4], f.frame.source_georef.clone())?;
        return Ok((g, [0, 0], Vec::new()));
    };
    let meets = |e: &[usize; 4]| e[0] <= s[2] && e[2] >= s[0] && e[1] <= s[3] && e[3] >= s[1];
    let subset: Vec<PathBuf> = f
        .files
        .iter()
        .filter(|(_, e)| meets(e))
        .map(|(p, _)| PathBuf::from(p))
        .collect();
    let mut args = a.input.clone();
    if !f.files.is_empty() {
        if subset.is_empty() {
            anyhow::bail!(
                "expected input files covering samples {s:?} of the mosaic, found none in the plan step's frame; run --plan again"
            );
        }
        args.files = subset;
    }
    let mut inp = input::load(&args)?;
    input::fill(&mut inp.grid, a.voids)?;
    let names = inp
        .files
        .iter()
        .map(|f| f.path.display().to_string())
        .collect();
    let whole = &f.frame.source_georef;
    let offset = if f.files.is_empty() {
        [0, 0]
    } else {
        same_grid(inp.grid.georef(), whole)?;
        offset_in(inp.grid.georef(), whole).context("placing the shard's files in the mosaic")?
    };
    Ok((inp.grid, offset, names))
}

/// Refuses files whose samples are not on the whole mosaic's grid.
fn same_grid(part: &GeoRef, whole: &GeoRef) -> anyhow::Result<()> {
    let same = part.pixel_x == whole.pixel_x
        && part.pixel_y == whole.pixel_y
        && part.pixel_is == whole.pixel_is;
    if !same {
        anyhow::bail!(
            "expected the shard's files on the plan step's grid (pixel {} x {}), found pixel {} x {}; run --plan again",
            whole.pixel_x,
            whole.pixel_y,
            part.pixel_x,
            part.pixel_y
        );
    }
    Ok(())
}
