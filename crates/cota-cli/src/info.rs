//! `cota info`: what the inputs hold, as read (before any void fill).

use std::path::PathBuf;
use std::process::ExitCode;

use cota_core::{GeoRef, PixelIs};
use cota_io::crs::{describe, FOOTPRINT_STEPS_PER_SIDE};
use cota_io::read::pmtiles::{self, is_pmtiles_file};
use serde_json::{json, Value};

use crate::args::InfoArgs;
use crate::input::{load, FileInfo, Input};

pub fn run(a: &InfoArgs) -> anyhow::Result<ExitCode> {
    let files = &a.input.files;
    if a.input.read.zoom.is_none() && !files.is_empty() && files.iter().all(|f| is_pmtiles_file(f))
    {
        return archives(files, a.json);
    }
    if a.each && files.len() > 1 {
        return run_each(a);
    }
    let input = load(&a.input)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&to_json(&input))?);
    } else {
        print_text(&input);
    }
    Ok(ExitCode::SUCCESS)
}

/// `--each`: every file read and described on its own, in order; the first
/// file that cannot be read stops the run (its error names it).
fn run_each(a: &InfoArgs) -> anyhow::Result<ExitCode> {
    let mut reports = Vec::new();
    for file in &a.input.files {
        let one = crate::args::InputArgs {
            files: vec![file.clone()],
            ..a.input.clone()
        };
        let input = load(&one)?;
        if a.json {
            reports.push(to_json(&input));
        } else {
            print_text(&input);
        }
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&reports)?);
    }
    Ok(ExitCode::SUCCESS)
}

/// `cota info ARCHIVE.pmtiles` without --zoom: what each archive holds.
fn archives(files: &[PathBuf], json: bool) -> anyhow::Result<ExitCode> {
    let mut all = Vec::new();
    for f in files {
        let s = pmtiles::summary(f)?;
        if json {
            all.push(json!({
                "path": f.display().to_string(),
                "format": "PMTiles",
                "tile_type": s.tile_type,
                "tile_compression": s.tile_compression,
                "min_zoom": s.min_zoom,
                "max_zoom": s.max_zoom,
                "bounds_deg": s.bounds_deg,
                "addressed_tiles": s.addressed_tiles,
            }));
            continue;
        }
        let [w, so, e, n] = s.bounds_deg;
        println!("{}", f.display());
        println!(
            "  format      PMTiles v3 ({} tiles, {} compression)",
            s.tile_type, s.tile_compression
        );
        println!("  zooms       {}..{}", s.min_zoom, s.max_zoom);
        println!("  bounds      {w},{so},{e},{n} (W,S,E,N degrees)");
        println!("  tiles       {}", s.addressed_tiles);
        println!("  read with   --input-zoom Z --bbox W,S,E,N");
    }
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&json!({ "archives": all }))?
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn units(g: &GeoRef) -> &'static str {
    if !g.known {
        "assumed metres (no georeference)"
    } else if g.crs.is_geographic() {
        "degrees"
    } else {
        "CRS units"
    }
}

fn pixel_is(p: PixelIs) -> &'static str {
    match p {
        PixelIs::Area => "area",
        PixelIs::Point => "point",
    }
}

/// The WGS 84 bounds (west, south, east, north, degrees) of the rectangle
/// through the outer samples' centres, its boundary densified and mapped
/// through the CRS; or why there are none (no georeference, no known CRS).
fn footprint(g: &GeoRef, width: usize, height: usize) -> Result<[f64; 4], String> {
    if !g.known {
        return Err("no georeference".to_string());
    }
    let t = cota_io::crs::transform_for(&g.crs).map_err(|e| e.to_string())?;
    cota_io::crs::footprint(g, width, height, t.as_ref(), FOOTPRINT_STEPS_PER_SIDE)
        .map_err(|e| e.to_string())
}

/// The CRS and footprint fields of a JSON report.
fn crs_json(v: &mut Value, g: &GeoRef, width: usize, height: usize) {
    let f = footprint(g, width, height);
    v["crs_name"] = json!(describe(&g.crs));
    v["crs_definition"] = json!(cota_io::crs::definition(&g.crs));
    v["footprint_deg"] = json!(f.as_ref().ok());
    v["footprint_note"] = json!(f.err());
}

/// The footprint line of the text report.
fn footprint_line(g: &GeoRef, width: usize, height: usize) -> String {
    match footprint(g, width, height) {
        Ok([w, s, e, n]) => {
            format!("  footprint   {w:.6},{s:.6},{e:.6},{n:.6} (W,S,E,N degrees, WGS 84)")
        }
        Err(why) => format!("  footprint   none: {why}"),
    }
}

fn file_json(f: &FileInfo) -> Value {
    let g = &f.georef;
    let mut v = json!({
        "path": f.path.display().to_string(),
        "format": f.format.to_string(),
        "data_type": f.data_type.to_string(),
        "width": f.width,
        "height": f.height,
        "min_m": f.range.map(|r| r.0),
        "max_m": f.range.map(|r| r.1),
        "nodata_count": f.nodata_count,
        "nodata_value": f.nodata,
        "crs": g.crs.to_string(),
        "georeferenced": g.known,
        "pixel_is": pixel_is(g.pixel_is),
        "origin": [g.origin_x, g.origin_y],
        "cell_size": [g.pixel_x.abs(), g.pixel_y.abs()],
        "cell_size_units": units(g),
        "cell_size_m": f.cell_size_m,
    });
    crs_json(&mut v, g, f.width, f.height);
    v
}

fn to_json(input: &Input) -> Value {
    let g = &input.grid;
    let geo = g.georef();
    let range = g.valid_range();
    let first = input.files.first();
    let mut v = json!({
        "format": first.map(|f| f.format.to_string()),
        "data_type": first.map(|f| f.data_type.to_string()),
        "width": g.width(),
        "height": g.height(),
        "min_m": range.map(|r| r.0),
        "max_m": range.map(|r| r.1),
        "nodata_count": g.void_count(),
        "crs": geo.crs.to_string(),
        "georeferenced": geo.known,
        "pixel_is": pixel_is(geo.pixel_is),
        "origin": [geo.origin_x, geo.origin_y],
        "cell_size": [geo.pixel_x.abs(), geo.pixel_y.abs()],
        "cell_size_units": units(geo),
        "cell_size_m": g.cell_size_m(),
        "files": input.files.iter().map(file_json).collect::<Vec<_>>(),
    });
    crs_json(&mut v, geo, g.width(), g.height());
    if input.seams.is_some() {
        v["seams"] = crate::input::seams_json(input);
        v["hole_samples"] = json!(input.hole_samples);
    }
    v
}

fn print_text(input: &Input) {
    for f in &input.files {
        let g = &f.georef;
        println!("{}", f.path.display());
        println!("  format      {} ({})", f.format, f.data_type);
        println!("  size        {} x {}", f.width, f.height);
        println!("  crs         {}", describe(&g.crs));
        println!("{}", footprint_line(g, f.width, f.height));
        println!(
            "  cell size   {} x {} {}  =  {:.3} x {:.3} m",
            g.pixel_x.abs(),
            g.pixel_y.abs(),
            units(g),
            f.cell_size_m[0],
            f.cell_size_m[1]
        );
        let (ox, oy) = g.sample_xy(0.0, 0.0);
        println!(
            "  first sample ({ox}, {oy}), pixel is {}",
            pixel_is(g.pixel_is)
        );
        match f.range {
            Some((lo, hi)) => println!("  heights     {lo} .. {hi} m"),
            None => println!("  heights     none (every sample is void)"),
        }
        let nd = f
            .nodata
            .map(|v| format!(" (nodata value {})", crate::input::num(v)))
            .unwrap_or_default();
        println!("  voids       {}{nd}", f.nodata_count);
    }
    if let Some(s) = &input.seams {
        let g = &input.grid;
        println!("mosaic");
        println!("  size        {} x {}", g.width(), g.height());
        println!("{}", footprint_line(g.georef(), g.width(), g.height()));
        println!(
            "  voids       {} ({} in coverage holes)",
            g.void_count(),
            input.hole_samples
        );
        println!(
            "  seams       {} overlapping samples, largest difference {} m, mean {:.3} m",
            s.overlap_samples, s.max_abs_diff_m, s.mean_abs_diff_m
        );
        if let Some(p) = s.max_diff_at {
            println!(
                "              largest at ({}, {}) between files {} and {}",
                p.x, p.y, p.tiles[0], p.tiles[1]
            );
        }
    }
}
