//! `cota tiles --plan` and `--shard I/N` over parts of the lattice: the
//! arguments' side of `cota_io::tiles::part` (the settings' key, which files
//! a shard may read alone, and reading them as `cota tiles` reads its input).

use std::path::PathBuf;

use cota_core::tiles::{
    BandCorners, ErrorSchedule, Lattice, LatticeOptions, TilerOptions, ZoomPlan,
};
use cota_core::HeightGrid;
use cota_io::tiles::{
    finish_plan, plan_layout, plan_layout_or, run_plan_part, Part, PlanPartReport, ShardFrame,
};

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

/// Where each file's samples lie in the mosaic; empty when a shard must read
/// every file: a single file, voids to fill, samples no file covers, or a
/// window (`--bbox`, `--crop`, `--input-zoom`).
pub fn file_extents(a: &TilesArgs, inp: &input::Input, voids: usize) -> Vec<(String, [usize; 4])> {
    if voids > 0 || inp.hole_samples > 0 || a.input.read.windowed() {
        return Vec::new();
    }
    cota_io::tiles::file_extents(&inp.files, inp.grid.georef())
}

/// The plan step's frame for `--shards`.
pub fn frame_of(
    a: &TilesArgs,
    lattice: &Lattice,
    zooms: &[ZoomPlan],
    files: Vec<(String, [usize; 4])>,
) -> ShardFrame {
    cota_io::tiles::frame_of(frame_key(a), a.shards, lattice, zooms, files)
}

/// The lattice's options of the arguments.
pub fn lattice_options(a: &TilesArgs) -> LatticeOptions {
    LatticeOptions::DEFAULT
        .with_max_zoom(a.max_zoom)
        .with_tile_cells(a.tile_cells)
        .with_error(error_schedule(a))
}

/// The error schedule of the arguments.
pub fn error_schedule(a: &TilesArgs) -> ErrorSchedule {
    match (a.error_factor, a.max_error_m_at_max_zoom) {
        (_, Some(e)) => ErrorSchedule::AtMaxZoom { max_error_m: e },
        (q, None) => ErrorSchedule::Cesium {
            factor: q.unwrap_or(1.0),
        },
    }
}

/// A reader of the input files a part needs (`None`: every input), as
/// `cota tiles` reads its input (the input flags, the void policy); the
/// files one after the other when `in_turn` (see [`input::load_with`]).
fn part_reader(
    a: &TilesArgs,
    in_turn: bool,
) -> impl Fn(Option<Vec<PathBuf>>) -> anyhow::Result<(HeightGrid, Vec<String>)> + '_ {
    move |files: Option<Vec<PathBuf>>| {
        let mut args = a.input.clone();
        if let Some(files) = files {
            args.files = files;
        }
        let mut inp = input::load_with(&args, in_turn)?;
        input::fill(&mut inp.grid, a.voids)?;
        let names = inp
            .files
            .iter()
            .map(|f| f.path.display().to_string())
            .collect();
        Ok((inp.grid, names))
    }
}

/// Reads the files shard `index` needs (with the input flags) and
/// resamples its part.
pub fn load_part(
    a: &TilesArgs,
    f: &ShardFrame,
    opts: &TilerOptions,
    index: u32,
) -> anyhow::Result<Part> {
    cota_io::tiles::load_part(
        &a.output,
        f,
        &frame_key(a),
        opts,
        index,
        a.normals,
        part_reader(a, false),
    )
}

/// The plan step's layout (the frame before the statistics: each file read
/// alone for the mosaic's frame), from OUT when a plan step in parts already
/// wrote it, else made and written there. `None` where a shard would read
/// every file (see [`file_extents`]; also standard input or the bundled
/// sample): the plan step must then read the whole input, and has no parts.
pub fn layout(a: &TilesArgs, opts: &TilerOptions) -> anyhow::Result<Option<ShardFrame>> {
    let make = || -> anyhow::Result<Option<ShardFrame>> {
        let inp = &a.input;
        if inp.read.windowed() || inp.files.len() < 2 || inp.files.iter().any(|f| input::is_dash(f))
        {
            return Ok(None);
        }
        let files = input::summaries(inp)?;
        let lattice = lattice_options(a);
        let mosaic = input::mosaic_options(&inp.read);
        let Some(m) = cota_io::tiles::mosaic_frame(&files, &lattice, &mosaic)? else {
            return Ok(None);
        };
        Ok(Some(plan_layout(frame_key(a), a.shards, &m, opts)?))
    };
    plan_layout_or(&a.output, &frame_key(a), a.shards, make)
}

/// The plan step from its layout (the same frame as [`frame_of`] of the
/// whole lattice): the parts a `--plan --part I` already wrote, the others
/// read in turn, each file on this thread so each part reuses the memory
/// the last one freed; written to OUT. Returns the frame, its corners and
/// how many parts came from their files.
pub fn finish(
    a: &TilesArgs,
    layout: ShardFrame,
    opts: &TilerOptions,
) -> anyhow::Result<(ShardFrame, BandCorners, u32)> {
    finish_plan(&a.output, layout, opts, part_reader(a, true))
}

/// `--plan --part I`: part I of the plan step, into its file.
pub fn plan_part(
    a: &TilesArgs,
    layout: &ShardFrame,
    opts: &TilerOptions,
    index: u32,
) -> anyhow::Result<PlanPartReport> {
    run_plan_part(&a.output, layout, opts, index, part_reader(a, false))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::panic)]
    use super::*;
    use crate::args::{Cli, Command};
    use clap::Parser;
    use cota_core::tiles::Prepared;

    fn tiles_args(args: &[&str]) -> TilesArgs {
        match Cli::try_parse_from([&["cota", "tiles"], args].concat())
            .unwrap()
            .command
        {
            Command::Tiles(t) => t,
            _ => panic!("not tiles"),
        }
    }

    /// `cota tiles W E --plan --shards 3`: the streamed frame is the one the
    /// whole input gives; one file, or a `--bbox` crop, has no layout.
    #[test]
    fn streamed_frame_is_the_whole_inputs() {
        let (Some(w), Some(e)) = (
            cota_fixtures::shared("srtm/N00E010.hgt"),
            cota_fixtures::shared("srtm/N00E011.hgt.zip"),
        ) else {
            return;
        };
        let (w, e) = (w.to_str().unwrap(), e.to_str().unwrap());
        let a = tiles_args(&[
            w,
            e,
            "-o",
            "out",
            "--plan",
            "--shards",
            "3",
            "--max-zoom",
            "10",
        ]);
        let opts = TilerOptions::DEFAULT;
        let dir = tempfile::tempdir().unwrap();
        let mut a = a;
        a.output = dir.path().join("out");
        let lay = layout(&a, &opts).unwrap().unwrap();
        let (streamed, corners, _) = finish(&a, lay, &opts).unwrap();
        assert_eq!(corners.missing(), 0);
        let inp = input::load(&a.input).unwrap();
        let lat = Lattice::resample(&inp.grid, &lattice_options(&a)).unwrap();
        let prep = Prepared::new(&lat, &inp.grid, &opts).unwrap();
        let whole = frame_of(&a, &lat, prep.zooms(), file_extents(&a, &inp, 0));
        assert_eq!(format!("{streamed:?}"), format!("{whole:?}"));
        assert_eq!(streamed.stats.hi_m.to_bits(), whole.stats.hi_m.to_bits());
        let one = tiles_args(&[w, "-o", "out", "--plan", "--shards", "3"]);
        assert!(layout(&one, &opts).unwrap().is_none());
        let crop = [
            w,
            e,
            "-o",
            "out",
            "--plan",
            "--shards",
            "3",
            "--bbox",
            "10.2,0.2,11.5,0.8",
        ];
        assert!(layout(&tiles_args(&crop), &opts).unwrap().is_none());
    }
}
