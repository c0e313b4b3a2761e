//! `cota tiles`: a Cesium quantized-mesh-1.0 pyramid with an error bound per
//! zoom and no seams; with `--check`, every tile decoded again and checked
//! after quantization.

use std::time::Instant;

use anyhow::Context;
use cota_core::tiles::plan::plan;
use cota_core::tiles::{
    resampling_deviation, shard_plan, Deviation, ErrorSchedule, Lattice, LatticeOptions, Prepared,
    Shard, TilerOptions, ZoomPlan,
};
use cota_io::tiles::{
    reduce_shards, write_pyramid, write_shard, PyramidOptions, PyramidReport, TileExtensions,
};
use serde_json::json;

use crate::args::TilesArgs;
use crate::{input, progress};

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
    let spinner = progress::spinner("resampling");
    let lattice =
        Lattice::resample(&inp.grid, &lattice_opts).with_context(|| format!("tiling {name}"))?;
    let deviation = resampling_deviation(&inp.grid, &lattice);
    drop((spinner, inp.grid));
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
    let spinner = progress::spinner("preparing");
    let prepared = Prepared::new(&lattice, &opts).with_context(|| format!("tiling {name}"))?;
    drop(spinner);
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
    let r = reduce_shards(&a.output, a.shards, a.force)
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
