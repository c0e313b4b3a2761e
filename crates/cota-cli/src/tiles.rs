//! `cota tiles`: a Cesium quantized-mesh-1.0 pyramid with an error bound per
//! zoom and no seams; with `--check`, every tile decoded again and checked
//! after quantization.

use std::time::Instant;

use anyhow::Context;
use cota_core::tiles::{
    resampling_deviation, Deviation, ErrorSchedule, Lattice, LatticeOptions, Prepared, TilerOptions,
};
use cota_io::tiles::{write_pyramid, PyramidOptions, PyramidReport, TileExtensions};
use serde_json::json;

use crate::args::TilesArgs;
use crate::{input, progress};

/// Runs `cota tiles`.
pub fn run(a: &TilesArgs) -> anyhow::Result<std::process::ExitCode> {
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
    let t_prep = Instant::now();
    let opts = TilerOptions::DEFAULT
        .with_min_zoom(a.min_zoom)
        .with_error(error);
    let prepared = Prepared::new(&lattice, &opts).with_context(|| format!("tiling {name}"))?;
    let prep_s = t_prep.elapsed().as_secs_f64();
    let pyramid = PyramidOptions::DEFAULT
        .with_extensions(TileExtensions::with(a.normals, a.watermask, a.metadata))
        .with_gzip(a.gzip)
        .with_force(a.force)
        .with_check(a.check);
    let pb = progress::bar(prepared.tile_count(), "tiles");
    let report = write_pyramid(&prepared, &a.output, &pyramid, &|n| pb.set_position(n))
        .with_context(|| format!("writing {}", a.output.display()))?;
    pb.finish_and_clear();
    let total_s = t0.elapsed().as_secs_f64();
    if a.json {
        println!(
            "{}",
            report_json(
                &name,
                &prepared,
                &deviation,
                &report,
                [prep_s, total_s],
                a.check
            )
        );
    } else {
        print_report(
            &name,
            &prepared,
            &deviation,
            &report,
            [prep_s, total_s],
            &a.output,
            a.check,
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
