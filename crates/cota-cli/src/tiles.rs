//! `cota tiles`: a Cesium quantized-mesh-1.0 pyramid with an error bound per
//! zoom and no seams; with `--check`, every tile decoded again and checked
//! after quantization.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use cota_core::tiles::plan::plan;
use cota_core::tiles::{
    resampling_deviation, shard_plan, Deviation, ErrorSchedule, Lattice, LatticeOptions, Prepared,
    Shard, TilerOptions, ZoomPlan,
};
use cota_io::tiles::{
    reduce_shards, write_pyramid, write_shard, PyramidOptions, PyramidReport, TileExtensions,
};
use serde_json::json;

use crate::args::{InputArgs, Voids};
use crate::{input, progress};

/// Flags of `cota tiles`.
#[derive(Debug, Args)]
pub struct TilesArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Output directory: OUT/layer.json and OUT/{z}/{x}/{y}.terrain.
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// Coarsest zoom written (0: the two root tiles).
    #[arg(long, default_value_t = 0, value_name = "A")]
    pub min_zoom: u8,
    /// Finest zoom. Default: the zoom whose lattice is as fine as the source.
    #[arg(long, value_name = "B")]
    pub max_zoom: Option<u8>,
    /// cesium-terrain-builder's error per zoom times Q: 6378137·2π·0.25·Q/(65·2)/2^z metres.
    #[arg(long, value_name = "Q", conflicts_with = "max_error_m_at_max_zoom")]
    pub error_factor: Option<f64>,
    /// The error bound at the finest zoom in metres, doubled at each zoom above.
    #[arg(long, value_name = "E")]
    pub max_error_m_at_max_zoom: Option<f64>,
    /// Lattice cells across a tile at the finest zoom (a power of two).
    #[arg(long, default_value_t = 64, value_name = "S")]
    pub tile_cells: u32,
    /// Write oct-encoded vertex normals (extension 1).
    #[arg(long)]
    pub normals: bool,
    /// Write a water mask, water at or below 0 m (extension 2).
    #[arg(long)]
    pub watermask: bool,
    /// Write metadata: child availability and the geometric error (extension 4).
    #[arg(long)]
    pub metadata: bool,
    /// Gzip every tile (serve with Content-Encoding: gzip).
    #[arg(long)]
    pub gzip: bool,
    /// Redo tiles already in OUT.
    #[arg(long)]
    pub force: bool,
    /// Decode every tile again and check it (bound at every lattice sample,
    /// conformity, edge lists) before writing it.
    #[arg(long)]
    pub check: bool,
    /// What to do with voids.
    #[arg(long, value_enum, default_value_t = Voids::Fill)]
    pub voids: Voids,
    /// Print the report as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Print the shard plan (each shard's tiles, zoom by zoom) for --shards N and exit.
    #[arg(long, conflicts_with_all = ["shard", "reduce"])]
    pub plan: bool,
    /// Number of shards for --plan and --reduce.
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub shards: u32,
    /// Write only shard I of N (0-based) and its record OUT/.cota-shard-I-of-N.json;
    /// idempotent. Then --reduce --shards N writes layer.json.
    #[arg(long, value_name = "I/N", value_parser = parse_shard, conflicts_with = "reduce")]
    pub shard: Option<(u32, u32)>,
    /// Check the records of --shards N shards in OUT, write layer.json, remove
    /// the records (reads no input: the shards recorded it).
    #[arg(long)]
    pub reduce: bool,
}

/// `I/N` with `I < N`.
fn parse_shard(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("expected I/N with 0 <= I < N (e.g. 0/4), found {s:?}");
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let (i, n): (u32, u32) = (
        i.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if i >= n {
        return Err(bad());
    }
    Ok((i, n))
}

/// Runs `cota tiles`.
pub fn run(a: &TilesArgs) -> anyhow::Result<std::process::ExitCode> {
    if a.reduce {
        return reduce(a);
    }
    let t0 = Instant::now();
    let mut inp = input::load(&a.input)?;
    input::fill(&mut inp.grid, a.voids)?;
    let name = input::name(&inp.files);
    let lattice_opts = LatticeOptions::DEFAULT
        .with_max_zoom(a.max_zoom)
        .with_tile_cells(a.tile_cells);
    let lattice =
        Lattice::resample(&inp.grid, &lattice_opts).with_context(|| format!("tiling {name}"))?;
    let deviation = resampling_deviation(&inp.grid, &lattice);
    drop(inp.grid);
    let error = match (a.error_factor, a.max_error_m_at_max_zoom) {
        (_, Some(e)) => ErrorSchedule::AtMaxZoom { max_error_m: e },
        (q, None) => ErrorSchedule::Cesium {
            factor: q.unwrap_or(1.0),
        },
    };
    let opts = TilerOptions::DEFAULT
        .with_min_zoom(a.min_zoom)
        .with_error(error);
    if a.plan {
        let zooms = plan(&lattice, &opts).with_context(|| format!("tiling {name}"))?;
        return print_plan(&zooms, a.shards, a.json);
    }
    let t_prep = Instant::now();
    let prepared = Prepared::new(&lattice, &opts).with_context(|| format!("tiling {name}"))?;
    let prep_s = t_prep.elapsed().as_secs_f64();
    let report = write(a, &prepared)?;
    let total_s = t0.elapsed().as_secs_f64();
    let times = [prep_s, total_s];
    if a.json {
        let mut v = report_json(&name, &prepared, &deviation, &report, times, a.check);
        if let Some((i, n)) = a.shard {
            v["shard"] = json!([i, n]);
        }
        println!("{v}");
    } else {
        print_report(
            &name, &prepared, &deviation, &report, times, &a.output, a.check,
        );
    }
    Ok(std::process::ExitCode::SUCCESS)
}

/// Writes the pyramid, or with --shard one shard of it.
fn write(a: &TilesArgs, prepared: &Prepared<'_>) -> anyhow::Result<PyramidReport> {
    let pyramid = PyramidOptions::DEFAULT
        .with_extensions(TileExtensions::with(a.normals, a.watermask, a.metadata))
        .with_gzip(a.gzip)
        .with_force(a.force)
        .with_check(a.check);
    let shard = match a.shard {
        Some((i, n)) => Some(shard_plan(prepared.zooms(), n)?.swap_remove(i as usize)),
        None => None,
    };
    let total = shard
        .as_ref()
        .map_or(prepared.tile_count(), Shard::tile_count);
    let pb = progress::bar(total, "tiles");
    let report = match &shard {
        Some(s) => write_shard(prepared, &a.output, &pyramid, s, &|n| pb.set_position(n)),
        None => write_pyramid(prepared, &a.output, &pyramid, &|n| pb.set_position(n)),
    }
    .with_context(|| format!("writing {}", a.output.display()))?;
    pb.finish_and_clear();
    Ok(report)
}

/// `--reduce`: the shards' records into layer.json.
fn reduce(a: &TilesArgs) -> anyhow::Result<std::process::ExitCode> {
    let r = reduce_shards(&a.output, a.shards)
        .with_context(|| format!("reducing {}", a.output.display()))?;
    if a.json {
        println!("{}", json!({"reduced": r.shards, "tiles": r.tiles}));
    } else {
        println!(
            "reduced     {} shards, {} tiles; wrote {}",
            r.shards,
            r.tiles,
            a.output.join("layer.json").display()
        );
    }
    Ok(std::process::ExitCode::SUCCESS)
}

/// `--plan`: each shard's tiles, zoom by zoom.
fn print_plan(
    zooms: &[ZoomPlan],
    shards: u32,
    as_json: bool,
) -> anyhow::Result<std::process::ExitCode> {
    let plan = shard_plan(zooms, shards)?;
    if as_json {
        let v: Vec<serde_json::Value> = plan
            .iter()
            .map(|s| {
                let ranges: Vec<serde_json::Value> = s
                    .ranges
                    .iter()
                    .map(|(z, r)| json!({"zoom": z, "x0": r.x0, "x1": r.x1, "y0": r.y0, "y1": r.y1}))
                    .collect();
                json!({"shard": s.index, "shards": s.shards, "tiles": s.tile_count(), "ranges": ranges})
            })
            .collect();
        println!("{}", json!({"shards": shards, "plan": v}));
        return Ok(std::process::ExitCode::SUCCESS);
    }
    println!("shard       tiles  zoom: columns x rows (TMS)");
    for s in &plan {
        let parts: Vec<String> = s
            .ranges
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
        "passed: every written tile decoded, conforming, within its zoom's bound at every lattice sample"
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
    println!("zoom        tiles  skipped   triangles      bytes  bound (m)  measured (m)");
    for z in &r.zooms {
        println!(
            "{:>4} {:>12} {:>8} {:>11} {:>10} {:>10.3} {:>13.3}",
            z.zoom, z.written, z.skipped, z.triangles, z.bytes, z.max_error_m, z.measured_error_m
        );
    }
    println!(
        "tiles       {} written, {} skipped, {} bytes",
        r.written(),
        r.skipped(),
        r.bytes()
    );
    println!("check       {}", check_line(checked));
    println!(
        "time        prepare {prep_s:.3} s, tiles {:.3} s, total {total_s:.3} s",
        r.seconds
    );
    println!("wrote       {}", out.display());
}
