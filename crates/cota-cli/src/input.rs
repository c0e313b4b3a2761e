//! Reading the inputs of a command: each file, the mosaic of several, the
//! bundled sample when there is none.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use cota_core::grid::mosaic::{MosaicOptions, SeamPolicy, SeamReport};
use cota_core::grid::voids::{
    fill_voids, fill_voids_with_progress, FillMethod, FillOptions, FillReport, VoidPolicy,
};
use cota_core::HeightGrid;
use cota_io::{
    read_dem_bytes, read_dem_from, read_dems_counted, ArrayName, Dem, PngEncoding, ReadOptions,
    Region, RegionOptions, TileRequest,
};

use crate::args::{Encoding, InputArgs, ReadArgs, Seam, Voids};
use crate::progress;

/// The sample DEM bundled in the repository (SRTM 3", Chilean coast, public domain).
const SAMPLE: &[u8] = include_bytes!("../../../fixtures/S29W072.hgt.zip");
/// The name the bundled sample is reported under.
const SAMPLE_NAME: &str = "fixtures/S29W072.hgt.zip";

/// What one input file held, as read (before any mosaic or fill).
pub type FileInfo = cota_io::DemSummary;

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
    /// `--seam-tolerance`, metres.
    pub seam_tolerance_m: f64,
    /// Time spent reading and mosaicking, milliseconds.
    pub read_ms: f64,
    /// What reading warned of (each also said on standard error when it
    /// was found), one sentence each: `cota serve` shows them in the viewer.
    pub warnings: Vec<String>,
}

/// Says `msg` on standard error as a warning and keeps it in `kept`.
fn warn(kept: &mut Vec<String>, msg: String) {
    eprintln!("cota: warning: {msg}");
    kept.push(msg);
}

/// The input files joined with " + ", for reports.
pub fn name(files: &[FileInfo]) -> String {
    let names: Vec<String> = files.iter().map(|f| f.path.display().to_string()).collect();
    names.join(" + ")
}

/// Refuses `--voids hole` in a command that cannot leave holes.
pub fn refuse_hole(voids: Voids, command: &str) -> anyhow::Result<()> {
    if matches!(voids, Voids::Hole) {
        anyhow::bail!(
            "--voids hole: expected fill, idw or refuse for cota {command} (it needs a height at every sample); holes are for cota mesh"
        );
    }
    Ok(())
}

/// Applies the `--voids` policy to `grid` (`hole` fills with a constant: the
/// mesher then leaves the filled samples out, see `crate::hole`).
pub fn fill(grid: &mut HeightGrid, voids: Voids) -> anyhow::Result<FillReport> {
    if matches!(voids, Voids::Hole) {
        if grid.void_count() == grid.len() {
            anyhow::bail!("--voids hole: every sample is void, there is nothing to mesh");
        }
        let filled = cota_core::mesh::holes::fill_flat(grid);
        return Ok(FillReport {
            filled,
            converged: true,
            ..FillReport::default()
        });
    }
    let policy = match voids {
        Voids::Fill => VoidPolicy::Fill(FillMethod::Harmonic),
        Voids::Hole => VoidPolicy::Refuse,
        Voids::Idw => VoidPolicy::Fill(FillMethod::InverseDistance),
        Voids::Refuse => VoidPolicy::Refuse,
    };
    let opts = FillOptions::DEFAULT.with_policy(policy);
    if grid.void_count() == 0 || matches!(voids, Voids::Refuse) {
        return fill_voids(grid, &opts).context("void policy");
    }
    let pb = progress::bar(grid.void_count() as u64, "filling voids");
    let filled = fill_voids_with_progress(grid, &opts, &pb.report());
    filled.context("void policy")
}

pub fn read_options(a: &ReadArgs) -> anyhow::Result<ReadOptions> {
    warn_old_zoom_flag();
    let enc = a.encoding.map(|e| match e {
        Encoding::TerrainRgb => PngEncoding::TerrainRgb,
        Encoding::Terrarium => PngEncoding::Terrarium,
        Encoding::Gray16 => PngEncoding::Gray16,
    });
    let array = match &a.array {
        Some(name) => Some(ArrayName::new(name).with_context(|| {
            format!(
                "--array: expected a name of 1 to {} bytes, found {name:?}",
                ArrayName::MAX_LEN
            )
        })?),
        None => None,
    };
    let tiles = match (a.zoom, &a.bbox) {
        (Some(zoom), Some(b)) => {
            let [w, s, e, n] = b[..] else {
                anyhow::bail!("--bbox: expected W,S,E,N (4 numbers), found {}", b.len());
            };
            Some(TileRequest {
                zoom,
                bbox_deg: [w, s, e, n],
            })
        }
        _ => None,
    };
    Ok(ReadOptions::DEFAULT
        .with_png_encoding(enc)
        .with_gray(a.gray_scale_m, a.gray_offset_m)
        .with_cell_size_m(a.cell_size_m)
        .with_band(a.band)
        .with_max_samples(a.max_samples)
        .with_max_abs_height_m(if a.any_height {
            cota_io::MAX_ABS_HEIGHT_M
        } else {
            cota_io::DEFAULT_MAX_ABS_HEIGHT_M
        })
        .with_array(array)
        .with_tiles(tiles))
}

/// A number for a message: plain when of ordinary size, else in scientific
/// notation (never hundreds of digits).
pub fn num(v: f64) -> String {
    cota_core::criteria::plain(v)
}

/// A number for a report: three significant decimals at most, plainly.
pub fn num_short(v: f64) -> String {
    if v.abs() >= 100.0 {
        format!("{v:.0}")
    } else if v.abs() >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    }
}

/// Refuses non-finite and out-of-range reading options, by name.
fn check_options(a: &ReadArgs) -> anyhow::Result<()> {
    for (name, v) in [
        ("--gray-scale-m", a.gray_scale_m),
        ("--gray-offset-m", a.gray_offset_m),
        ("--cell-size-m", a.cell_size_m),
        ("--seam-tolerance", a.seam_tolerance_m),
    ] {
        if !v.is_finite() {
            anyhow::bail!(
                "{name}: expected a finite number of metres, found {}",
                num(v)
            );
        }
    }
    if a.seam_tolerance_m < 0.0 {
        anyhow::bail!(
            "--seam-tolerance: expected a number of metres >= 0, found {}",
            num(a.seam_tolerance_m)
        );
    }
    let cell = a.cell_size_m;
    if cell <= 0.0 || !(cell as f32).is_normal() || !((cell * 65536.0) as f32).is_finite() {
        anyhow::bail!(
            "--cell-size-m: expected a positive number of metres that f32 holds (about 1e-30 to 1e30), found {}",
            num(cell)
        );
    }
    Ok(())
}

/// Refuses a grid whose cell size (in metres) underflows or overflows f32,
/// naming the files.
fn check_cell_size(grid: &HeightGrid, files: &[FileInfo]) -> anyhow::Result<()> {
    let [cx, cy] = grid.cell_size_m();
    for c in [cx, cy] {
        if !(c as f32).is_normal()
            || !((c * grid.width().max(grid.height()) as f64) as f32).is_finite()
        {
            anyhow::bail!(
                "{}: expected a cell size f32 holds (about 1e-30 to 1e30 m), found {} m",
                name(files),
                num(c)
            );
        }
    }
    Ok(())
}

/// The cell size assumed for an input without georeference (PNG, a `.hgt`
/// without a position in its name), if any.
pub fn assumed_cell_m(files: &[FileInfo]) -> Option<f64> {
    files
        .iter()
        .find(|f| !f.georef.known)
        .map(|f| f.cell_size_m[0])
}

/// Warns (stderr) for each SRTM tile whose name gave no position.
/// `--zoom` (the PMTiles input's zoom) is `--input-zoom` now: `cota tiles`
/// has zooms of its own (`--min-zoom`, `--max-zoom`).
fn warn_old_zoom_flag() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    let old = std::env::args().any(|s| s == "--zoom" || s.starts_with("--zoom="));
    if old {
        ONCE.call_once(|| {
            eprintln!(
                "cota: warning: --zoom is deprecated: it is the PMTiles input's zoom, now --input-zoom \
                 (the output's zooms are --min-zoom/--max-zoom)"
            );
        });
    }
}

/// Warns (stderr) when heights are large enough (only with `--any-height`)
/// that f32 holds them to worse than a millimetre: errors and checks are
/// against the heights as held.
fn warn_storage_precision(grid: &HeightGrid, files: &[FileInfo], kept: &mut Vec<String>) {
    let Some((lo, hi)) = grid.valid_range() else {
        return;
    };
    let max_abs = f64::from(lo.abs().max(hi.abs()));
    let held = cota_io::f32_storage_error_m(max_abs);
    if held > 1e-3 {
        warn(
            kept,
            format!(
                "{}: heights up to {} m are held as f32, within {} m of the file's \
             values: errors and checks are against the heights as held, so a bound below \
             that says little (heights relative to an offset are not supported)",
                name(files),
                num(max_abs),
                num_short(held)
            ),
        );
    }
}

fn warn_unpositioned(files: &[FileInfo], kept: &mut Vec<String>) {
    for f in files {
        let srtm = matches!(
            f.format,
            cota_io::Format::SrtmHgt | cota_io::Format::SrtmHgtZip
        );
        if srtm && !f.georef.known {
            warn(
                kept,
                format!(
                    "{}: no position in the name (expected [NS]dd[EW]ddd, e.g. N45E006.hgt): \
                 read without georeference, at an assumed {} m cell",
                    f.path.display(),
                    num(f.cell_size_m[0])
                ),
            );
        }
    }
}

/// The path of input `index`, for messages.
fn path_of(files: &[FileInfo], index: usize) -> String {
    files
        .get(index)
        .map_or_else(|| format!("file {index}"), |f| f.path.display().to_string())
}

/// Warns on stderr (fails with `--strict`) when overlapping tiles disagree
/// by more than `--seam-tolerance`, naming the two files and the worst
/// disagreement.
fn check_seams(
    a: &ReadArgs,
    seams: Option<&SeamReport>,
    files: &[FileInfo],
    warned: &mut Vec<String>,
) -> anyhow::Result<()> {
    let Some(s) = seams.filter(|s| s.max_abs_diff_m > a.seam_tolerance_m) else {
        return Ok(());
    };
    let (pair, at) = match s.max_diff_at {
        Some(p) => (
            format!(
                "{} and {}",
                path_of(files, p.tiles[0]),
                path_of(files, p.tiles[1])
            ),
            format!(" at ({}, {})", num_short(p.x), num_short(p.y)),
        ),
        None => (name(files), String::new()),
    };
    let msg = format!(
        "{pair} disagree by up to {} m{at} where they overlap, more than --seam-tolerance {} m \
         (over all {} samples where the inputs overlap, the mean difference is {} m)",
        num(s.max_abs_diff_m),
        num(a.seam_tolerance_m),
        s.compared,
        num_short(s.mean_abs_diff_m)
    );
    if a.strict {
        anyhow::bail!("{msg} (--strict)");
    }
    let kept = match a.seam {
        Seam::Mean => "their mean",
        Seam::First => "the first file's value",
    };
    let used = format!("{msg}; {kept} is used there (--seam; --strict refuses)");
    warn(warned, used);
    Ok(())
}

/// The seam report as JSON, with the files of the largest disagreement
/// named; `null` for a single file.
pub fn seams_json(input: &Input) -> serde_json::Value {
    let tolerance_m = input.seam_tolerance_m;
    let Some(s) = &input.seams else {
        return serde_json::Value::Null;
    };
    serde_json::json!({
        "overlap_samples": s.overlap_samples,
        "compared": s.compared,
        "max_abs_diff_m": s.max_abs_diff_m,
        "mean_abs_diff_m": s.mean_abs_diff_m,
        "tolerance_m": tolerance_m,
        "within_tolerance": s.max_abs_diff_m <= tolerance_m,
        "max_diff_at": s.max_diff_at.map(|p| serde_json::json!({
            "col": p.col, "row": p.row, "x": p.x, "y": p.y, "tiles": p.tiles,
            "files": [path_of(&input.files, p.tiles[0]), path_of(&input.files, p.tiles[1])],
        })),
    })
}

/// `--bbox` as four numbers.
fn bbox4(b: &[f64]) -> anyhow::Result<[f64; 4]> {
    match b[..] {
        [w, s, e, n] => Ok([w, s, e, n]),
        _ => anyhow::bail!("--bbox: expected W,S,E,N (4 numbers), found {}", b.len()),
    }
}

/// The name standard input (`-`) is reported under.
pub const STDIN_NAME: &str = "<stdin>";

/// True for the path `-`: standard input or output.
pub fn is_dash(p: &Path) -> bool {
    p.as_os_str() == "-"
}

/// Reads the files (`-`: standard input, which must then be the only one;
/// none: the bundled sample), each on its own: in parallel,
/// or (`in_turn`) one after the other on this thread.
fn read_files(files: &[PathBuf], opts: &ReadOptions, in_turn: bool) -> anyhow::Result<Vec<Dem>> {
    match files {
        [] => Ok(vec![read_dem_bytes(SAMPLE, Path::new(SAMPLE_NAME), opts)?]),
        [f] if is_dash(f) => {
            let stdin = std::io::stdin();
            if stdin.is_terminal() {
                anyhow::bail!(
                    "-: expected a DEM on standard input, found a terminal (pipe or redirect one: cota info - < FILE)"
                );
            }
            let _spinner = progress::spinner("reading");
            Ok(vec![read_dem_from(
                stdin.lock(),
                Path::new(STDIN_NAME),
                opts,
            )?])
        }
        _ if files.iter().any(|f| is_dash(f)) => anyhow::bail!(
            "-: standard input must be the only FILE (it holds one DEM), found {} files",
            files.len()
        ),
        _ => {
            let pb = progress::bytes(0, "reading");
            Ok(read_dems_counted(files, opts, in_turn, &|done, total| {
                pb.set(done, total)
            })?)
        }
    }
}

/// How the files are joined (`--seam`).
pub fn mosaic_options(a: &ReadArgs) -> MosaicOptions {
    let policy = match a.seam {
        Seam::Mean => SeamPolicy::Mean,
        Seam::First => SeamPolicy::First,
    };
    MosaicOptions::DEFAULT.with_seam_policy(policy)
}

/// Each input file as [`load`] reports it, read one at a time and its
/// samples dropped (the peak is one file); no mosaic, no window.
pub fn summaries(a: &InputArgs) -> anyhow::Result<Vec<FileInfo>> {
    check_options(&a.read)?;
    let opts = read_options(&a.read)?;
    let mut files = cota_tiles::summarize_files(&a.files, &opts)?;
    if let Some(flag) = &a.read.src_crs {
        for f in &mut files {
            f.georef.crs = cota_io::crs::src_crs_for(&f.path, &f.georef, f.width, f.height, flag)?;
        }
    }
    Ok(files)
}

/// Reads every input (or the bundled sample), gives them `--src-crs` (see
/// [`cota_io::crs::assign_src_crs`]) and joins them into one region per
/// kind of grid ([`cota_io::read::join_groups`]); voids stay NaN (each
/// command applies its own policy, [`fill`]).
fn read_groups(a: &InputArgs, in_turn: bool) -> anyhow::Result<(Vec<Region>, RegionOptions)> {
    let opts = read_options(&a.read)?;
    check_options(&a.read)?;
    let region_opts = RegionOptions::DEFAULT
        .with_read(opts)
        .with_mosaic(mosaic_options(&a.read))
        .with_fill(None);
    let mut dems = read_files(&a.files, &opts, in_turn)?;
    if let Some(crs) = a.read.src_crs.as_ref() {
        for dem in &mut dems {
            cota_io::crs::assign_src_crs(dem, crs)?;
        }
    }
    Ok((cota_io::read::join_groups(dems, &region_opts)?, region_opts))
}

/// The window the reading flags keep of a region's grid: `--bbox` (in the
/// input's CRS units; with `--input-zoom` it chose the archive's tiles
/// instead) or `--crop` (samples); the whole grid otherwise.
fn window(a: &ReadArgs, grid: HeightGrid, files: &[FileInfo]) -> anyhow::Result<HeightGrid> {
    match (&a.bbox, a.zoom, &a.crop) {
        (Some(b), None, _) => crate::window::bbox(&grid, bbox4(b)?).with_context(|| name(files)),
        (_, _, Some(c)) => crate::window::crop(&grid, c).with_context(|| name(files)),
        _ => Ok(grid),
    }
}

/// A region as an [`Input`], after the seam check and the window.
fn input_of(
    a: &ReadArgs,
    region: Region,
    read_ms: f64,
    mut warnings: Vec<String>,
) -> anyhow::Result<Input> {
    warn_unpositioned(&region.files, &mut warnings);
    warn_storage_precision(&region.grid, &region.files, &mut warnings);
    check_seams(a, region.seams.as_ref(), &region.files, &mut warnings)?;
    check_cell_size(&region.grid, &region.files)?;
    let grid = window(a, region.grid, &region.files)?;
    Ok(Input {
        grid,
        files: region.files,
        seams: region.seams,
        hole_samples: region.hole_samples,
        seam_tolerance_m: a.seam_tolerance_m,
        read_ms,
        warnings,
    })
}

/// Reads every input (or the bundled sample) and joins it into one input
/// per kind of grid (CRS, pixel size): the files of each kind mosaicked, or
/// each alone where they do not mosaic ([`cota_io::read::join_groups`]);
/// what `cota tiles` takes as its sources. `--bbox` and `--crop` are
/// refused with several.
pub fn load_groups(a: &InputArgs) -> anyhow::Result<Vec<Input>> {
    let t0 = Instant::now();
    let (regions, _) = read_groups(a, false)?;
    let flag = match (&a.read.bbox, a.read.zoom, &a.read.crop) {
        (Some(_), None, _) => Some("--bbox"),
        (_, _, Some(_)) => Some("--crop"),
        _ => None,
    };
    if let (true, Some(flag)) = (regions.len() > 1, flag) {
        anyhow::bail!("{flag}: expected inputs on one grid (one CRS, one resolution), found {} kinds of grid; crop each file first", regions.len());
    }
    let read_ms = t0.elapsed().as_secs_f64() * 1e3;
    regions
        .into_iter()
        .map(|region| input_of(&a.read, region, read_ms, Vec::new()))
        .collect()
}

/// Reads every input (or the bundled sample) and mosaics them, then keeps
/// the window of `--bbox` (for inputs other than PMTiles archives) or
/// `--crop`.
pub fn load(a: &InputArgs) -> anyhow::Result<Input> {
    load_with(a, false)
}

/// [`load`], the files read in parallel or (`in_turn`) one after the other
/// on this thread (a sharded tiling part, which bounds its memory so). Inputs of several
/// resolutions (one CRS) are joined on the finest one's grid, each coarser
/// one resampled once ([`cota_io::read::resample_join`], its deviation at
/// its own samples said on stderr).
pub fn load_with(a: &InputArgs, in_turn: bool) -> anyhow::Result<Input> {
    let t0 = Instant::now();
    let (mut groups, region_opts) = read_groups(a, in_turn)?;
    let mut notes = Vec::new();
    let region = if groups.len() == 1 {
        groups.swap_remove(0)
    } else {
        let (region, resampled) = cota_io::read::resample_join(groups, &region_opts)?;
        for r in resampled {
            let note = format!(
                "{} resampled onto the finest input's grid (pixel {} to {}): it lies within {} m of its own samples",
                r.files,
                num(r.pixel),
                num(region.grid.georef().pixel_x.abs()),
                num_short(r.max_deviation_m)
            );
            eprintln!("cota: note: {note}");
            notes.push(note);
        }
        region
    };
    input_of(&a.read, region, t0.elapsed().as_secs_f64() * 1e3, notes)
}
