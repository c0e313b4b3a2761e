//! `cota tiles --plan` and `--shard I/N` over parts of the lattice: the
//! arguments as a [`TileJob`] (`cota_tiles::job`): its settings, and its
//! input read as `cota tiles` reads it (the input flags, the void policy).

use std::path::PathBuf;

use cota_core::tiles::{ErrorSchedule, LatticeOptions};
use cota_core::{FillMethod, FillOptions, MosaicOptions, VoidPolicy};
use cota_io::{DemSummary, RegionOptions};
use cota_tiles::{input_key, JobInput, ReadPart, TileJob, TileSettings};

use crate::args::{TilesArgs, Voids};
use crate::input;

/// `cota tiles`' input as a job's.
pub struct CliInput<'a> {
    args: &'a TilesArgs,
    key: String,
}

impl<'a> CliInput<'a> {
    /// The input of `a` (its reading flags checked).
    pub fn new(a: &'a TilesArgs) -> anyhow::Result<Self> {
        let read = &a.input.read;
        let region = RegionOptions::DEFAULT
            .with_read(input::read_options(read)?)
            .with_mosaic(input::mosaic_options(read))
            .with_fill(fill_options(a.voids));
        // What else decides the mosaic: a CRS given, a window.
        let extra = if read.windowed() || read.src_crs.is_some() {
            format!(" {read:?}")
        } else {
            String::new()
        };
        Ok(Self {
            args: a,
            key: input_key(&a.input.files, &region, &extra),
        })
    }
}

/// The void fill of `--voids` (`None` for holes, refused by `cota tiles`).
fn fill_options(voids: Voids) -> Option<FillOptions> {
    let policy = match voids {
        Voids::Fill => VoidPolicy::Fill(FillMethod::Harmonic),
        Voids::Idw => VoidPolicy::Fill(FillMethod::InverseDistance),
        Voids::Refuse => VoidPolicy::Refuse,
        Voids::Hole => return None,
    };
    Some(FillOptions::DEFAULT.with_policy(policy))
}

impl JobInput for CliInput<'_> {
    type Error = anyhow::Error;

    fn key(&self) -> String {
        self.key.clone()
    }

    /// `None` for a window, one file, standard input or the bundled sample.
    fn summaries(&self) -> anyhow::Result<Option<(Vec<DemSummary>, MosaicOptions)>> {
        let inp = &self.args.input;
        if inp.read.windowed() || inp.files.len() < 2 || inp.files.iter().any(|f| input::is_dash(f))
        {
            return Ok(None);
        }
        Ok(Some((
            input::summaries(inp)?,
            input::mosaic_options(&inp.read),
        )))
    }

    fn read(&self, files: Option<Vec<PathBuf>>, in_turn: bool) -> anyhow::Result<ReadPart> {
        let mut args = self.args.input.clone();
        if let Some(files) = files {
            args.files = files;
        }
        let mut inp = input::load_with(&args, in_turn)?;
        input::fill(&mut inp.grid, self.args.voids)?;
        let names = inp
            .files
            .iter()
            .map(|f| f.path.display().to_string())
            .collect();
        Ok((inp.grid, names))
    }
}

/// The settings of the arguments.
pub fn settings(a: &TilesArgs) -> TileSettings {
    TileSettings {
        min_zoom: a.min_zoom,
        max_zoom: a.max_zoom,
        tile_cells: a.tile_cells,
        error: error_schedule(a),
    }
}

/// The job of the arguments over `input` (see [`CliInput::new`]).
pub fn job<'a>(a: &'a TilesArgs, input: &'a CliInput<'a>) -> TileJob<'a, CliInput<'a>> {
    TileJob {
        input,
        settings: settings(a),
        out: &a.output,
        shards: a.shards,
    }
}

/// Where each file's samples lie in the mosaic; empty when a shard must read
/// every file: a single file, voids to fill, samples no file covers, or a
/// window (`--bbox`, `--crop`, `--input-zoom`).
pub fn file_extents(a: &TilesArgs, inp: &input::Input, voids: usize) -> Vec<(String, [usize; 4])> {
    if voids > 0 || inp.hole_samples > 0 || a.input.read.windowed() {
        return Vec::new();
    }
    cota_tiles::file_extents(&inp.files, inp.grid.georef())
}

/// The lattice's options of the arguments.
pub fn lattice_options(a: &TilesArgs) -> LatticeOptions {
    settings(a).lattice_options()
}

/// The error schedule of the arguments.
pub fn error_schedule(a: &TilesArgs) -> ErrorSchedule {
    TileSettings::schedule(a.error_factor, a.max_error_m_at_max_zoom)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::panic)]
    use super::*;
    use crate::args::{Cli, Command};
    use clap::Parser;
    use cota_core::tiles::Lattice;
    use cota_tiles::PathsInput;

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
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        let out = out.to_str().unwrap();
        let plan = ["--plan", "--shards", "3"];
        let a = tiles_args(&[&[w, e, "-o", out, "--max-zoom", "10"][..], &plan].concat());
        let input = CliInput::new(&a).unwrap();
        let job = job(&a, &input);
        let lay = job.layout().unwrap().unwrap();
        let (streamed, corners, _) = job.finish_plan(lay).unwrap();
        assert_eq!(corners.missing(), 0);
        let inp = input::load(&a.input).unwrap();
        let lat = Lattice::resample(&inp.grid, &lattice_options(&a)).unwrap();
        let whole_dir = tempfile::tempdir().unwrap();
        let whole = TileJob {
            out: whole_dir.path(),
            ..job
        };
        let frame = whole.plan_whole(&lat, file_extents(&a, &inp, 0)).unwrap();
        assert_eq!(format!("{streamed:?}"), format!("{frame:?}"));
        assert_eq!(streamed.stats.hi_m.to_bits(), frame.stats.hi_m.to_bits());
        let one = tiles_args(&[&[w, "-o", out][..], &plan].concat());
        let one_input = CliInput::new(&one).unwrap();
        assert!(super::job(&one, &one_input).layout().unwrap().is_none());
        let crop =
            tiles_args(&[&[w, e, "-o", out, "--bbox", "10.2,0.2,11.5,0.8"][..], &plan].concat());
        let crop_input = CliInput::new(&crop).unwrap();
        assert!(super::job(&crop, &crop_input).layout().unwrap().is_none());
    }

    /// With the default reading flags `cota tiles` and `cota.tiles` (a job
    /// of [`PathsInput`]) have one key, so each takes the other's frames;
    /// another void policy or a window makes another key.
    #[test]
    fn the_cli_and_the_library_share_a_key_by_default() {
        let paths = ["a.hgt", "b.hgt"];
        let a = tiles_args(&[paths[0], paths[1], "-o", "out", "--max-zoom", "9"]);
        let cli = CliInput::new(&a).unwrap();
        let lib = PathsInput {
            paths: paths.iter().map(PathBuf::from).collect(),
        };
        let cli_job = job(&a, &cli);
        let lib_job = TileJob {
            input: &lib,
            settings: cli_job.settings,
            out: cli_job.out,
            shards: 1,
        };
        assert_eq!(cli_job.key(), lib_job.key());
        for other in [&["--voids", "idw"][..], &["--crop", "0,0,10,10"]] {
            let b = tiles_args(
                &[
                    &[paths[0], paths[1], "-o", "out", "--max-zoom", "9"][..],
                    other,
                ]
                .concat(),
            );
            let input = CliInput::new(&b).unwrap();
            assert_ne!(job(&b, &input).key(), lib_job.key(), "{other:?}");
        }
    }
}
