//! `cota tiles --plan` and `--shard I/N` over parts of the lattice: the
//! arguments' side of `cota_io::tiles::part` (the settings' key, which files
//! a shard may read alone, and reading them as `cota tiles` reads its input).

use cota_core::tiles::{Lattice, TilerOptions, ZoomPlan};
use cota_io::tiles::{Part, ShardFrame};

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
/// `--bbox` or `--zoom` crop.
pub fn file_extents(a: &TilesArgs, inp: &input::Input, voids: usize) -> Vec<(String, [usize; 4])> {
    let crop = a.input.bbox.is_some() || a.input.zoom.is_some();
    if voids > 0 || inp.hole_samples > 0 || crop {
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

/// Reads the files shard `index` needs (with the input flags) and
/// resamples its part.
pub fn load_part(
    a: &TilesArgs,
    f: &ShardFrame,
    opts: &TilerOptions,
    index: u32,
) -> anyhow::Result<Part> {
    let read = |files: Option<Vec<std::path::PathBuf>>| -> anyhow::Result<_> {
        let mut args = a.input.clone();
        if let Some(files) = files {
            args.files = files;
        }
        let mut inp = input::load(&args)?;
        input::fill(&mut inp.grid, a.voids)?;
        let names = inp
            .files
            .iter()
            .map(|f| f.path.display().to_string())
            .collect();
        Ok((inp.grid, names))
    };
    cota_io::tiles::load_part(&a.output, f, &frame_key(a), opts, index, a.normals, read)
}
