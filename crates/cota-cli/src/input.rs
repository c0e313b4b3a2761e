//! Reading the inputs of a command: each file, the mosaic of several, the
//! bundled sample when there is none.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use cota_core::grid::mosaic::{mosaic, MosaicOptions, SeamPolicy, SeamReport};
use cota_core::grid::voids::{fill_voids, FillMethod, FillOptions, FillReport, VoidPolicy};
use cota_core::HeightGrid;
use cota_io::{read_dem, read_dem_bytes, DataType, Dem, Format, PngEncoding, ReadOptions};

use crate::args::{Encoding, InputArgs, Seam, Voids};
use crate::progress;

/// The sample DEM bundled in the repository (SRTM 3", Chilean coast, public domain).
const SAMPLE: &[u8] = include_bytes!("../../../fixtures/S29W072.hgt.zip");
/// The name the bundled sample is reported under.
const SAMPLE_NAME: &str = "fixtures/S29W072.hgt.zip";

/// What one input file held, as read (before any mosaic or fill).
#[derive(Debug, Clone)]
pub struct FileInfo {
    pub path: PathBuf,
    pub format: Format,
    pub data_type: DataType,
    pub nodata: Option<f64>,
    pub width: usize,
    pub height: usize,
    pub nodata_count: usize,
    pub range: Option<(f32, f32)>,
    pub grid_georef: cota_core::GeoRef,
    pub cell_size_m: [f64; 2],
}

/// The grid to work on and how it was obtained.
pub struct Input {
    /// The grid (mosaicked when several files); voids still NaN.
    pub grid: HeightGrid,
    /// Each file as read.
    pub files: Vec<FileInfo>,
    /// Seam report when several files were mosaicked.
    pub seams: Option<SeamReport>,
    /// Mosaic samples covered by no file.
    pub hole_samples: usize,
    /// Time spent reading and mosaicking, milliseconds.
    pub read_ms: f64,
}

/// The input files joined with " + ", for reports.
pub fn name(files: &[FileInfo]) -> String {
    let names: Vec<String> = files.iter().map(|f| f.path.display().to_string()).collect();
    names.join(" + ")
}

/// Applies the `--voids` policy to `grid`.
pub fn fill(grid: &mut HeightGrid, voids: Voids) -> anyhow::Result<FillReport> {
    let policy = match voids {
        Voids::Fill => VoidPolicy::Fill(FillMethod::Harmonic),
        Voids::Idw => VoidPolicy::Fill(FillMethod::InverseDistance),
        Voids::Refuse => VoidPolicy::Refuse,
    };
    fill_voids(grid, &FillOptions::DEFAULT.with_policy(policy)).context("void policy")
}

fn read_options(a: &InputArgs) -> ReadOptions {
    let enc = a.encoding.map(|e| match e {
        Encoding::TerrainRgb => PngEncoding::TerrainRgb,
        Encoding::Terrarium => PngEncoding::Terrarium,
        Encoding::Gray16 => PngEncoding::Gray16,
    });
    ReadOptions::DEFAULT
        .with_png_encoding(enc)
        .with_gray(a.gray_scale_m, a.gray_offset_m)
        .with_cell_size_m(a.cell_size_m)
        .with_band(a.band)
}

fn describe(dem: &Dem) -> FileInfo {
    FileInfo {
        path: dem.path.clone(),
        format: dem.format,
        data_type: dem.data_type,
        nodata: dem.nodata,
        width: dem.grid.width(),
        height: dem.grid.height(),
        nodata_count: dem.grid.void_count(),
        range: dem.grid.valid_range(),
        grid_georef: dem.grid.georef().clone(),
        cell_size_m: dem.grid.cell_size_m(),
    }
}

/// Reads every input (or the bundled sample) and mosaics them.
pub fn load(a: &InputArgs) -> anyhow::Result<Input> {
    let t0 = Instant::now();
    let opts = read_options(a);
    if a.cell_size_m.is_nan() || a.cell_size_m <= 0.0 {
        anyhow::bail!(
            "--cell-size-m: expected a positive number of metres, found {}",
            a.cell_size_m
        );
    }
    let mut dems = Vec::new();
    if a.files.is_empty() {
        dems.push(read_dem_bytes(SAMPLE, Path::new(SAMPLE_NAME), &opts)?);
    } else {
        let pb = progress::bar(a.files.len() as u64, "reading");
        for f in &a.files {
            dems.push(read_dem(f, &opts)?);
            pb.inc(1);
        }
        pb.finish_and_clear();
    }
    let files: Vec<FileInfo> = dems.iter().map(describe).collect();
    let names: Vec<String> = files.iter().map(|f| f.path.display().to_string()).collect();
    let grids: Vec<HeightGrid> = dems.into_iter().map(|d| d.grid).collect();
    let several = grids.len() > 1;
    let policy = match a.seam {
        Seam::Mean => SeamPolicy::Mean,
        Seam::First => SeamPolicy::First,
    };
    let m = mosaic(grids, &MosaicOptions::DEFAULT.with_seam_policy(policy))
        .with_context(|| format!("mosaicking {}", names.join(", ")))?;
    Ok(Input {
        grid: m.grid,
        files,
        seams: several.then_some(m.seams),
        hole_samples: m.hole_samples,
        read_ms: t0.elapsed().as_secs_f64() * 1e3,
    })
}
