//! `cota tiles`: a Cesium quantized-mesh-1.0 pyramid with an error bound per
//! zoom and no seams; with `--check`, every tile decoded again and checked
//! after quantization.

use std::time::Instant;

use anyhow::Context;
use cota_core::tiles::plan::plan_with;
use cota_core::tiles::sources::deviation_of_with_progress;
use cota_core::tiles::{
    addressed, resampling_deviation_with_progress, shard_plan, Deviation, GeographicScheme,
    Lattice, LatticeFrame, Prepared, Shard, Source, SourcePart, TileRange, TilerOptions, ZoomPlan,
};
use cota_core::{HeightGrid, LonLat};
use cota_tiles::drawn::{Against, SourceGrid};
use cota_tiles::{
    is_3tz, is_mbtiles, plan_layout_path, plan_part_path, read_shard_frame, reduce_shards,
    shard_frame_path, write_output, write_shard, PyramidOptions, PyramidReport, ShardFrame,
    TileExtensions, TileFormat, TileJob,
};
use serde_json::json;

use crate::args::{TileFormatArg, TilesArgs, Voids};
use crate::{input, progress, tiles_estimate, tiles_part};

/// The job of `cota tiles`' arguments.
type Job<'a> = TileJob<'a, tiles_part::CliInput<'a>>;

/// Runs `cota tiles`.
pub fn run(a: &TilesArgs) -> anyhow::Result<std::process::ExitCode> {
    if a.reduce {
        return reduce(a);
    }
    if matches!(a.voids, Voids::Hole) {
        anyhow::bail!("{}", HOLES_REFUSED);
    }
    refuse_archive_mismatch(a)?;
    let input = tiles_part::CliInput::new(a)?;
    let job = tiles_part::job(a, &input);
    let opts = job.settings.tiler_options();
    if let Some((i, n)) = a.shard {
        let frame = read_shard_frame(&a.output, n)
            .with_context(|| format!("reading the plan step's frame in {}", a.output.display()))?;
        if let Some(f) = frame {
            return run_part(a, &job, &f, i);
        }
    }
    if a.plan {
        if a.layout || a.part.is_some() {
            if let Some(code) = plan_part_not_needed(a)? {
                return Ok(code);
            }
        }
        // Without the whole input where the files allow it (each file
        // alone, then each shard's part: in turn, or as --part processes).
        if let Some(layout) = job.layout()? {
            return plan_in_parts(a, &job, &opts, layout);
        }
        if a.layout || a.part.is_some() {
            return whole_input_plan(a);
        }
    }
    let t0 = Instant::now();
    let mut inp = match one_lonlat(input::load_groups(&a.input)?) {
        Ok(one) => one,
        Err(groups) => return run_sources(a, groups, &opts, t0),
    };
    let lattice_opts = tiles_part::lattice_options(a);
    if let Ok(frame) = LatticeFrame::of(&inp.grid, &lattice_opts) {
        tiles_estimate::check(a, &frame, inp.grid.len() as u64)?;
    }
    let voids = inp.grid.void_count();
    input::fill(&mut inp.grid, a.voids)?;
    if a.imagery {
        crate::imagery::write(&inp.grid, &a.output)?;
    }
    let name = input::name(&inp.files);
    let (lattice, deviation) = resample(a, &inp.grid, &name)?;
    let files = if a.plan {
        tiles_part::file_extents(a, &inp, voids)
    } else {
        Vec::new()
    };
    if a.plan {
        drop(inp.grid);
        return plan_step(a, &job, &lattice, files);
    }
    let t_prep = Instant::now();
    let pb = progress::bar(0, "preparing");
    let prepared = Prepared::new_with_progress(&lattice, &inp.grid, &opts, &pb.report())
        .with_context(|| format!("tiling {name}"))?;
    drop(pb);
    warn_source_floor(&prepared);
    // With --check, the source stays to check every tile against it as drawn.
    let source = a.check.then_some(inp.grid);
    let prep_s = t_prep.elapsed().as_secs_f64();
    let against = source.as_ref().map(|g| against(g, &lattice));
    let report = write(a, &prepared, None, against.as_ref())?;
    let times = [prep_s, t0.elapsed().as_secs_f64()];
    finish(a, &name, &prepared, &deviation, &report, times, json!(null));
    Ok(std::process::ExitCode::SUCCESS)
}

/// The lattice of one geographic grid and its deviation from the grid's
/// samples, each with a bar.
fn resample(a: &TilesArgs, grid: &HeightGrid, name: &str) -> anyhow::Result<(Lattice, Deviation)> {
    let pb = progress::bar(0, "resampling");
    let lattice =
        Lattice::resample_with_progress(grid, &tiles_part::lattice_options(a), &pb.report())
            .with_context(|| format!("tiling {name}"))?;
    drop(pb);
    let pb = progress::bar(0, "deviation");
    let deviation = resampling_deviation_with_progress(grid, &lattice, &pb.report());
    Ok((lattice, deviation))
}

/// An `.mbtiles` output with what only a directory takes, or --meshopt
/// without --format 3dtiles: refused in words; an output that cannot be
/// written: refused before any work.
fn refuse_archive_mismatch(a: &TilesArgs) -> anyhow::Result<()> {
    if a.meshopt && a.format != TileFormatArg::Tiles3d {
        anyhow::bail!("--meshopt compresses 3D Tiles GLBs: expected --format 3dtiles with it");
    }
    if a.no_skirts && a.format != TileFormatArg::Tiles3d {
        anyhow::bail!("--no-skirts leaves the skirts out of 3D Tiles GLBs: expected --format 3dtiles with it (quantized-mesh clients build their own)");
    }
    if is_mbtiles(&a.output) && a.format == TileFormatArg::Tiles3d {
        anyhow::bail!(
            "{}: expected a directory or a .3tz archive for --format 3dtiles, found an .mbtiles name",
            a.output.display()
        );
    }
    if is_3tz(&a.output) && a.format != TileFormatArg::Tiles3d {
        anyhow::bail!(
            "{}: a .3tz archive holds 3D Tiles: expected --format 3dtiles with it (quantized-mesh archives: .mbtiles)",
            a.output.display()
        );
    }
    let archive = is_mbtiles(&a.output) || is_3tz(&a.output);
    if archive && (a.plan || a.shard.is_some() || a.imagery) {
        anyhow::bail!(
            "{}: expected a directory for --plan, --shard and --imagery, found an archive name; write the archive in one run",
            a.output.display()
        );
    }
    crate::output::check_output_dir(&a.output, archive)
}

/// The one input when it is a single grid in WGS 84 longitude/latitude
/// (the lattice then follows its axes, and shards can split it); the
/// inputs otherwise.
fn one_lonlat(mut groups: Vec<input::Input>) -> Result<input::Input, Vec<input::Input>> {
    let lonlat = |g: &HeightGrid| {
        g.georef().known
            && g.georef().crs.is_geographic()
            && cota_io::crs::transform_for(&g.georef().crs).is_ok_and(|t| t.is_identity())
    };
    match groups.as_slice() {
        [one] if lonlat(&one.grid) => Ok(groups.swap_remove(0)),
        _ => Err(groups),
    }
}

/// `cota tiles` over inputs in other CRSs or of several resolutions: each
/// input (the files of one kind of grid mosaicked) a source of the lattice
/// ([`cota_core::tiles::sources`]), finest first.
fn run_sources(
    a: &TilesArgs,
    mut groups: Vec<input::Input>,
    opts: &TilerOptions,
    t0: Instant,
) -> anyhow::Result<std::process::ExitCode> {
    if a.plan || a.shard.is_some() {
        anyhow::bail!("--plan/--shard: expected one input in longitude/latitude (WGS 84) on one grid, found {} inputs of other CRSs or resolutions; tile them in one run without --shard", groups.len());
    }
    for g in &mut groups {
        input::fill(&mut g.grid, a.voids)?;
    }
    let mins = |g: &input::Input| g.grid.cell_size_m()[0].min(g.grid.cell_size_m()[1]);
    groups.sort_by(|p, q| mins(p).total_cmp(&mins(q)));
    let transforms = groups
        .iter()
        .map(|g| {
            let (r, n) = (g.grid.georef(), input::name(&g.files));
            cota_io::crs::transform_for_grid(r, g.grid.width(), g.grid.height())
                .with_context(|| format!("{n}: placing it on the Earth"))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let sources: Vec<Source<'_>> = groups
        .iter()
        .zip(&transforms)
        .map(|(g, t)| Source {
            grid: &g.grid,
            transform: t.as_ref(),
        })
        .collect();
    let files: Vec<input::FileInfo> = groups.iter().flat_map(|g| g.files.clone()).collect();
    let name = input::name(&files);
    let lattice_opts = tiles_part::lattice_options(a);
    if let Ok(frame) = LatticeFrame::for_sources(&sources, &lattice_opts) {
        let samples = groups.iter().map(|g| g.grid.len() as u64).sum();
        tiles_estimate::check(a, &frame, samples)?;
    }
    let pb = progress::bar(0, "resampling");
    let r = Lattice::resample_sources_with_progress(&sources, &lattice_opts, &pb.report())
        .with_context(|| format!("tiling {name}"))?;
    drop(pb);
    let pb = progress::bar(0, "deviation");
    let deviation = deviation_of_with_progress(&r.lattice, &r.samples, &pb.report());
    drop(pb);
    let t_prep = Instant::now();
    let pb = progress::bar(0, "preparing");
    let prepared = Prepared::new_sampled_with_progress(&r.lattice, &r.samples, opts, &pb.report())
        .with_context(|| format!("tiling {name}"))?;
    drop(pb);
    warn_source_floor(&prepared);
    let prep_s = t_prep.elapsed().as_secs_f64();
    let against = a.check.then(|| against_sources(&sources, &r.lattice));
    let report = write(a, &prepared, None, against.as_ref())?;
    let times = [prep_s, t0.elapsed().as_secs_f64()];
    finish(a, &name, &prepared, &deviation, &report, times, json!(null));
    Ok(std::process::ExitCode::SUCCESS)
}

/// What `--check` measures tiles of several sources against: their
/// samples, their bilinear surfaces, and the ellipsoid farther than two
/// finest tiles from their footprints.
fn against_sources<'a>(sources: &[Source<'a>], lattice: &Lattice) -> Against<'a> {
    let s = lattice.scheme();
    let grids = sources
        .iter()
        .map(|src| SourceGrid {
            grid: src.grid,
            transform: src.transform,
        })
        .collect();
    let rects = lattice
        .coverage()
        .map(|c| {
            c.polygons
                .iter()
                .map(|p| {
                    let xs = p.iter().map(|q| q[0]);
                    let ys = p.iter().map(|q| q[1]);
                    let (x0, x1) = (
                        xs.clone().fold(f64::INFINITY, f64::min),
                        xs.fold(f64::NEG_INFINITY, f64::max),
                    );
                    let (y0, y1) = (
                        ys.clone().fold(f64::INFINITY, f64::min),
                        ys.fold(f64::NEG_INFINITY, f64::max),
                    );
                    [s.lon_of(x0), s.lat_of(y1), s.lon_of(x1), s.lat_of(y0)]
                })
                .collect()
        })
        .unwrap_or_default();
    let margin = 2.0 * f64::from(s.tile_cells) * s.cell_deg();
    against_on(s, grids, rects, margin)
}

/// [`Against`] the sources, across the antimeridian when the lattice is
/// (its rectangles' longitudes then run past 180°).
fn against_on<'a>(
    s: &GeographicScheme,
    grids: Vec<SourceGrid<'a>>,
    rects: Vec<[f64; 4]>,
    margin: f64,
) -> Against<'a> {
    if s.from_greenwich {
        Against::across_antimeridian(grids, rects, margin)
    } else {
        Against::new(grids, rects, margin)
    }
}

/// Says, before the tiles are made, at which zooms the lattice cannot hold
/// the source's own samples within the zoom's bound (a `--max-zoom` below
/// the source's resolution), and what bound those tiles meet there.
fn warn_source_floor(p: &Prepared<'_>) {
    let short: Vec<String> = p
        .zooms()
        .iter()
        .filter(|z| p.source_bound_m(z.zoom) > z.max_error_m)
        .map(|z| {
            format!(
                "{} ({} m, not {} m)",
                z.zoom,
                input::num_short(p.source_bound_m(z.zoom)),
                input::num_short(z.max_error_m)
            )
        })
        .collect();
    if short.is_empty() {
        return;
    }
    let s = p.lattice().scheme();
    eprintln!(
        "cota: warning: the lattice ({}\" a cell at zoom {}) cannot hold the source's samples within the bound at zooms {}: \
         its points cut the peaks and pits between them by up to {} m; tiles there meet the bound at the lattice's points and the figure given at the source's samples; \
         leave --max-zoom out (the source's own resolution) to meet the bound everywhere",
        input::num_short(s.cell_deg() * 3600.0),
        s.max_zoom,
        short.join(", "),
        input::num_short(p.lattice().residual_m()),
    );
}

/// Why `--voids hole` makes no tiles.
pub const HOLES_REFUSED: &str = "--voids hole: expected a void policy that gives every tile terrain (fill, idw or refuse), found hole; a terrain client draws a hole in a tile as a hole through the globe, so tiles fill voids (the default, --voids fill)";

/// What `--check` measures the tiles against as drawn: the source's
/// samples, its bilinear surface, and the ellipsoid farther than two
/// finest tiles from its footprint.
fn against<'a>(source: &'a HeightGrid, lattice: &Lattice) -> Against<'a> {
    let s = lattice.scheme();
    let fp = lattice.footprint();
    let rect = [
        s.lon_of(fp[0]),
        s.lat_of(fp[3]),
        s.lon_of(fp[2]),
        s.lat_of(fp[1]),
    ];
    let margin = 2.0 * f64::from(s.tile_cells) * s.cell_deg();
    let grid = SourceGrid {
        grid: source,
        transform: &LonLat,
    };
    against_on(s, vec![grid], vec![rect], margin)
}

/// Prints the report (`part`: what a shard over a part read, or null).
fn finish(
    a: &TilesArgs,
    name: &str,
    prepared: &Prepared<'_>,
    deviation: &Deviation,
    report: &PyramidReport,
    times: [f64; 2],
    part: serde_json::Value,
) {
    if a.json {
        let mut v = report_json(name, prepared, deviation, report, times, a.check);
        if let Some((i, n)) = a.shard {
            v["shard"] = json!([i, n]);
        }
        if !part.is_null() {
            v["part"] = part;
        }
        println!("{v}");
    } else if !crate::progress::quiet() {
        print_report(name, prepared, deviation, report, times, &a.output, a.check);
    }
}

/// `--shard I/N` after the plan step: only the shard's part of the lattice.
fn run_part(
    a: &TilesArgs,
    job: &Job<'_>,
    f: &ShardFrame,
    index: u32,
) -> anyhow::Result<std::process::ExitCode> {
    let t0 = Instant::now();
    let part = job.load_part(f, index, a.normals)?;
    let name = part.files_read.join(" + ");
    let t_prep = Instant::now();
    let source = part.source_part();
    let pb = progress::bar(0, "preparing");
    let prepared = Prepared::new_part_with_progress(
        &part.lattice,
        source,
        part.zooms.clone(),
        &part.stats,
        &pb.report(),
    )
    .with_context(|| format!("tiling {name}"))?;
    drop(pb);
    let prep_s = t_prep.elapsed().as_secs_f64();
    let report = write(a, &prepared, Some((part.shard.clone(), f, source)), None)?;
    let times = [prep_s, t0.elapsed().as_secs_f64()];
    let info = json!({
        "band_zoom": f.band_zoom,
        "region": part.lattice.stored(),
        "files_read": part.files_read,
    });
    finish(a, &name, &prepared, &part.deviation, &report, times, info);
    Ok(std::process::ExitCode::SUCCESS)
}

/// `--plan` from the whole lattice: the frame and the band corners (the
/// reduce cuts the tiles coarser than the band zoom from the shards' partial
/// maxima), the plan.
fn plan_step(
    a: &TilesArgs,
    job: &Job<'_>,
    lattice: &Lattice,
    files: Vec<(String, [usize; 4])>,
) -> anyhow::Result<std::process::ExitCode> {
    let frame = job
        .plan_whole(lattice, files)
        .with_context(|| format!("writing {}", a.output.display()))?;
    print_plan_step(a, &job.settings.tiler_options(), &frame)
}

/// `--plan` with a layout: `--layout` alone, `--part I`, or the whole plan
/// step from the parts already done and the others in turn.
fn plan_in_parts(
    a: &TilesArgs,
    job: &Job<'_>,
    opts: &TilerOptions,
    layout: ShardFrame,
) -> anyhow::Result<std::process::ExitCode> {
    let n = a.shards;
    if a.layout {
        let path = plan_layout_path(&a.output, n);
        if a.json {
            println!(
                "{}",
                json!({"layout": path, "shards": n, "files": layout.files.len()})
            );
        } else {
            println!(
                "layout      {} ({} files, {n} parts)",
                path.display(),
                layout.files.len()
            );
        }
        return Ok(std::process::ExitCode::SUCCESS);
    }
    if let Some(i) = a.part {
        let r = job.plan_part(&layout, i)?;
        let path = plan_part_path(&a.output, i, n);
        if a.json {
            let v = json!({"part": i, "shards": n, "skipped": r.skipped, "files_read": r.files_read, "wrote": path});
            println!("{v}");
        } else if r.skipped {
            println!("plan part   {i} of {n} already done ({})", path.display());
        } else {
            println!(
                "plan part   {i} of {n}: read {}; wrote {}",
                r.files_read.join(" + "),
                path.display()
            );
        }
        return Ok(std::process::ExitCode::SUCCESS);
    }
    let (frame, _, _) = job
        .finish_plan(layout)
        .with_context(|| format!("writing the plan step in {}", a.output.display()))?;
    print_plan_step(a, opts, &frame)
}

/// `--plan --part I` past the last part (an error), or `--layout`/`--part`
/// once the plan step is done (nothing to do: `Some`).
fn plan_part_not_needed(a: &TilesArgs) -> anyhow::Result<Option<std::process::ExitCode>> {
    if let Some(i) = a.part.filter(|&i| i >= a.shards) {
        anyhow::bail!(
            "--part: expected a part below {} (--shards), found {i}",
            a.shards
        );
    }
    let frame = shard_frame_path(&a.output, a.shards);
    if !frame.is_file() {
        return Ok(None);
    }
    if a.json {
        println!("{}", json!({"done": true, "frame": frame}));
    } else {
        println!("plan        already done ({})", frame.display());
    }
    Ok(Some(std::process::ExitCode::SUCCESS))
}

/// `--plan --layout` or `--part I` for an input whose shards read every file.
fn whole_input_plan(a: &TilesArgs) -> anyhow::Result<std::process::ExitCode> {
    let why = "the plan step reads the whole input here (one file, voids, samples no file covers, a crop or standard input): nothing to do in parts; run --plan --shards N alone";
    if a.json {
        println!("{}", json!({"whole_input": true, "message": why}));
    } else {
        println!("plan        {why}");
    }
    Ok(std::process::ExitCode::SUCCESS)
}

/// Prints the plan of the plan step's frame.
fn print_plan_step(
    a: &TilesArgs,
    opts: &TilerOptions,
    frame: &ShardFrame,
) -> anyhow::Result<std::process::ExitCode> {
    let f = &frame.frame;
    let zooms = plan_with(f, &frame.stats, opts)?;
    print_plan(
        &zooms,
        &f.scheme,
        a.shards,
        frame.band_zoom,
        frame.coarse_tiles,
        a.json,
    )
}

fn pyramid_options(a: &TilesArgs) -> PyramidOptions {
    PyramidOptions::DEFAULT
        .with_extensions(TileExtensions::with(a.normals, a.watermask, a.metadata))
        .with_gzip(a.gzip)
        .with_force(a.force)
        .with_check(a.check)
        .with_meshopt(a.meshopt)
        .with_skirts(!a.no_skirts)
        .with_format(match a.format {
            TileFormatArg::QuantizedMesh => TileFormat::QuantizedMesh,
            TileFormatArg::Tiles3d => TileFormat::Tiles3d,
        })
}

/// Writes the pyramid, or with --shard one shard of it (`part`: the shard's
/// tiles when it holds only its part of the lattice).
fn write(
    a: &TilesArgs,
    prepared: &Prepared<'_>,
    part: Option<(Shard, &ShardFrame, SourcePart<'_>)>,
    against: Option<&Against<'_>>,
) -> anyhow::Result<PyramidReport> {
    let pyramid = pyramid_options(a);
    let frame = part.as_ref().map(|p| (p.1, p.2));
    let shard = match (part.as_ref(), a.shard) {
        (Some((s, _, _)), _) => Some(s.clone()),
        (None, Some((i, n))) => Some(shard_plan(prepared.zooms(), n)?.swap_remove(i as usize)),
        (None, None) => None,
    };
    let fills = match (&shard, a.format) {
        (None, TileFormatArg::Tiles3d) => prepared.fills().count() as u64,
        _ => 0,
    };
    let total = shard
        .as_ref()
        .map_or(prepared.tile_count() + fills, Shard::tile_count);
    let pb = progress::bar(total, "tiles");
    let pb = &pb;
    let report = match &shard {
        Some(s) => write_shard(prepared, &a.output, &pyramid, s, frame, &|n| {
            pb.set_position(n)
        }),
        None => write_output(prepared, &a.output, &pyramid, against, &|n| {
            pb.set_position(n)
        }),
    }
    .with_context(|| format!("writing {}", a.output.display()))?;
    Ok(report)
}

/// `--reduce`: the shards' records into layer.json.
fn reduce(a: &TilesArgs) -> anyhow::Result<std::process::ExitCode> {
    let coarse = read_shard_frame(&a.output, a.shards)
        .ok()
        .flatten()
        .map_or(0, |f| f.coarse_tiles);
    let pb = progress::bar(coarse, "coarse tiles");
    let r = reduce_shards(&a.output, a.shards, a.force, &|n| pb.set_position(n))
        .with_context(|| format!("reducing {}", a.output.display()))?;
    drop(pb);
    if a.json {
        println!(
            "{}",
            json!({"reduced": r.shards, "tiles": r.tiles, "coarse_written": r.coarse_written})
        );
    } else {
        println!(
            "reduced     {} shards, {} tiles ({} coarser than the band zoom cut here); wrote {}",
            r.shards,
            r.tiles,
            r.coarse_written,
            a.output.join("layer.json").display()
        );
    }
    Ok(std::process::ExitCode::SUCCESS)
}

/// `--plan`: each shard's tiles, zoom by zoom (the band zoom and finer; the
/// reduce cuts the `coarse` tiles above it), as addresses (a range split
/// in two where it crosses the antimeridian).
fn print_plan(
    zooms: &[ZoomPlan],
    scheme: &GeographicScheme,
    shards: u32,
    band: u8,
    coarse: u64,
    as_json: bool,
) -> anyhow::Result<std::process::ExitCode> {
    let plan: Vec<Shard> = shard_plan(zooms, shards)?
        .iter()
        .map(|s| s.from_zoom(band))
        .collect();
    let addressed = |s: &Shard| -> Vec<(u8, TileRange)> {
        s.ranges
            .iter()
            .flat_map(|&(z, r)| addressed(scheme, z, r).into_iter().map(move |r| (z, r)))
            .collect()
    };
    if as_json {
        let v: Vec<serde_json::Value> = plan
            .iter()
            .map(|s| {
                let ranges: Vec<serde_json::Value> = addressed(s)
                    .iter()
                    .map(|(z, r)| json!({"zoom": z, "x0": r.x0, "x1": r.x1, "y0": r.y0, "y1": r.y1}))
                    .collect();
                json!({"shard": s.index, "shards": s.shards, "tiles": s.tile_count(), "ranges": ranges})
            })
            .collect();
        println!(
            "{}",
            json!({"shards": shards, "band_zoom": band, "coarse_tiles": coarse, "plan": v})
        );
        return Ok(std::process::ExitCode::SUCCESS);
    }
    println!("reduce     {coarse:>6}  zooms below {band} (from the shards' partial maxima)");
    println!("shard       tiles  zoom: columns x rows (TMS)");
    for s in &plan {
        let parts: Vec<String> = addressed(s)
            .iter()
            .map(|(z, r)| format!("{z}: {}..={} x {}..={}", r.x0, r.x1, r.y0, r.y1))
            .collect();
        println!(
            "{:>2}/{:<2} {:>10}  {}",
            s.index,
            s.shards,
            s.tile_count(),
            parts.join("; ")
        );
    }
    Ok(std::process::ExitCode::SUCCESS)
}

/// What the report says of the check.
fn check_line(checked: bool) -> &'static str {
    if checked {
        "passed: every written tile decoded, conforming, within its zoom's bound at every lattice sample and, drawn as flat triangles on the globe, at every source sample"
    } else {
        "not run (--check decodes every tile again and checks it before writing)"
    }
}

/// The report as one JSON object.
fn report_json(
    name: &str,
    prep: &Prepared<'_>,
    dev: &Deviation,
    r: &PyramidReport,
    [prep_s, total_s]: [f64; 2],
    checked: bool,
) -> serde_json::Value {
    let lat = prep.lattice();
    let s = lat.scheme();
    json!({
        "input": name,
        "lattice": {
            "method": "bilinear",
            "cell_arcsec": s.cell_deg() * 3600.0,
            "tile_cells": s.tile_cells,
            "window": [lat.grid().width(), lat.grid().height()],
            "align_zoom": lat.align_zoom(),
            "deviation_max_m": dev.max_m,
            "deviation_rms_m": dev.rms_m,
        },
        "min_zoom": prep.zooms().first().map_or(0, |p| p.zoom),
        "max_zoom": s.max_zoom,
        "tiles": prep.tile_count(),
        "written": r.written(),
        "skipped": r.skipped(),
        "fill": r.fill(),
        "bytes": r.bytes(),
        "zooms": r.zooms,
        "check": check_line(checked),
        "seconds": {"prepare": prep_s, "tiles": r.seconds, "total": total_s},
    })
}

fn print_report(
    name: &str,
    prep: &Prepared<'_>,
    dev: &Deviation,
    r: &PyramidReport,
    [prep_s, total_s]: [f64; 2],
    out: &std::path::Path,
    checked: bool,
) {
    let lat = prep.lattice();
    let s = lat.scheme();
    println!("input       {name}");
    println!(
        "lattice     {:.3}\" bilinear, {}x{} window, deviation from the source max {:.3} m, RMS {:.3} m",
        s.cell_deg() * 3600.0,
        lat.grid().width(),
        lat.grid().height(),
        dev.max_m,
        dev.rms_m
    );
    println!("zoom        tiles  skipped   triangles      bytes  bound (m)  as drawn (m)");
    for z in &r.zooms {
        let measured = if z.drawn_error_m.is_nan() {
            "-".to_string()
        } else {
            format!("{:.3}", z.drawn_error_m)
        };
        println!(
            "{:>4} {:>12} {:>8} {:>11} {:>10} {:>10.3} {:>13}",
            z.zoom, z.written, z.skipped, z.triangles, z.bytes, z.max_error_m, measured
        );
    }
    println!(
        "tiles       {} written, {} skipped, {} bytes",
        r.written(),
        r.skipped(),
        r.bytes()
    );
    if r.fill() > 0 {
        println!(
            "fill        {} of them beyond the data (3D Tiles: every refined tile's four children)",
            r.fill()
        );
    }
    println!("check       {}", check_line(checked));
    println!(
        "time        prepare {prep_s:.3} s, tiles {:.3} s, total {total_s:.3} s",
        r.seconds
    );
    println!("wrote       {}", out.display());
}
