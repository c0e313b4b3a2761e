//! `tiles-codec`: `cota tiles` against the per-tile Rust pipeline a developer
//! writes today with the `terrain-codec` crate (issue 29), on the same DEM
//! files, the same tiles and the same bound per zoom.
//!
//! The peer, as its documentation shows it: for each tile, bilinear samples of
//! the source on a 65 × 65 grid over the tile's rectangle (north row first),
//! martini's RTIN at the zoom's bound e_z and terrain-codec's quantized-mesh
//! encoder with gzip level 6 (`terrain::encode_terrain_from_fn`), rayon over
//! the tiles, then `create_dir_all` and `fs::write` per tile. cota: the
//! prepared hierarchy (its preparation timed apart), then
//! [`cota_tiles::make_tile`] (gzip, no check) per tile, written by
//! [`write_pyramid`] (a temporary file and a rename per tile) or
//! [`write_mbtiles`].
//!
//! Both make exactly cota's tiles (those that meet the data). Phases, run in
//! turn each repetition (interleaved) after one warm-up round:
//! `compute` (tiles made in memory, nothing written), `dir` (into a fresh
//! directory), `dir-atomic` (the peer's tiles written as cota writes them: a
//! temporary file and a rename, the per-tile tax of atomicity), `mbtiles`
//! (cota only). Reading the DEM and removing the previous run's output are
//! outside every timing.
//!
//! Usage: `tiles-codec OUT REPS FILE...`; prints one JSON line per run and a
//! Markdown table of medians, and leaves `OUT/cota-dir` and `OUT/codec-dir`
//! for `tiles-peers measure` (true error and seams of both pyramids).
#![allow(clippy::unwrap_used)]

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use cota_core::grid::PixelIs;
use cota_core::tiles::{Lattice, LatticeOptions, Prepared, TileId, TilerOptions};
use cota_core::HeightGrid;
use cota_tiles::{
    make_tile, tile_path, write_file_atomically, write_mbtiles, write_pyramid, PyramidOptions,
};
use rayon::prelude::*;
use serde_json::json;
use terrain_codec::quantized_mesh::TileBounds;
use terrain_codec::terrain::{encode_terrain_from_fn, TerrainOptions};

/// Posts along a side of the peer's per-tile grid (2⁶ + 1, martini's size).
const GRID: u32 = 65;

/// Bilinear height of the source at (lon, lat); 0 m beyond its samples
/// (where cota shows the ellipsoid, so that both are measured alike).
fn bilinear(g: &HeightGrid, lon: f64, lat: f64) -> f64 {
    let r = g.georef();
    let half = if r.pixel_is == PixelIs::Area {
        0.5
    } else {
        0.0
    };
    let (w, h) = (g.width(), g.height());
    let col = (lon - r.origin_x) / r.pixel_x - half;
    let row = (lat - r.origin_y) / r.pixel_y - half;
    let inside = |v: f64, n: usize| (-1e-9..=(n - 1) as f64 + 1e-9).contains(&v);
    if !inside(col, w) || !inside(row, h) {
        return 0.0;
    }
    let (col, row) = (
        col.clamp(0.0, (w - 1) as f64),
        row.clamp(0.0, (h - 1) as f64),
    );
    let (c0, r0) = ((col as usize).min(w - 2), (row as usize).min(h - 2));
    let (fx, fy) = (col - c0 as f64, row - r0 as f64);
    let z = |c: usize, r: usize| f64::from(g.get(c, r));
    let top = z(c0, r0) * (1.0 - fx) + z(c0 + 1, r0) * fx;
    let bottom = z(c0, r0 + 1) * (1.0 - fx) + z(c0 + 1, r0 + 1) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// The peer's tile: sampled, meshed at `max_error_m`, encoded, gzipped.
fn codec_tile(g: &HeightGrid, prep: &Prepared<'_>, t: TileId) -> Vec<u8> {
    let [west, south, east, north] = prep.lattice().scheme().tile_rect_deg(t);
    let step = f64::from(GRID - 1);
    let at = |x: u32, y: u32| {
        let lon = west + (east - west) * f64::from(x) / step;
        let lat = north - (north - south) * f64::from(y) / step;
        bilinear(g, lon, lat)
    };
    let options = TerrainOptions {
        max_error: prep.zoom(t.z).map_or(0.0, |p| p.max_error_m),
        ..TerrainOptions::default()
    };
    encode_terrain_from_fn(
        GRID,
        &TileBounds::new(west, south, east, north),
        at,
        &options,
    )
}

fn write_plain(path: &Path, bytes: &[u8]) -> Result<()> {
    std::fs::create_dir_all(path.parent().unwrap())?;
    std::fs::write(path, bytes).with_context(|| format!("writing {}", path.display()))
}

/// One run: (tiles, bytes).
fn run(phase: &str, who: &str, g: &HeightGrid, prep: &Prepared<'_>, out: &Path) -> Result<u64> {
    let tiles: Vec<TileId> = prep.tiles().collect();
    let opts = PyramidOptions::DEFAULT.with_gzip(true).with_check(false);
    let none = |_: u64| {};
    let bytes: u64 = match (who, phase) {
        ("cota", "compute") => tiles
            .par_iter()
            .map(|&t| Ok(make_tile(prep, t, &opts, None)?.bytes.len() as u64))
            .sum::<Result<u64>>()?,
        ("cota", "dir") => write_pyramid(prep, out, &opts, None, &none)?.bytes(),
        ("cota", "mbtiles") => {
            write_mbtiles(prep, &out.with_extension("mbtiles"), &opts, None, &none)?.bytes()
        }
        ("codec", "compute") => tiles
            .par_iter()
            .map(|&t| codec_tile(g, prep, t).len() as u64)
            .sum(),
        ("codec", "dir") => tiles
            .par_iter()
            .map(|&t| {
                let b = codec_tile(g, prep, t);
                write_plain(&tile_path(out, t), &b)?;
                Ok(b.len() as u64)
            })
            .sum::<Result<u64>>()?,
        ("codec", "dir-atomic") => tiles
            .par_iter()
            .map(|&t| {
                let b = codec_tile(g, prep, t);
                write_file_atomically(&tile_path(out, t), &b, false)?;
                Ok(b.len() as u64)
            })
            .sum::<Result<u64>>()?,
        _ => bail!("no such run: {who} {phase}"),
    };
    Ok(bytes)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

const RUNS: [(&str, &str); 6] = [
    ("cota", "compute"),
    ("codec", "compute"),
    ("cota", "dir"),
    ("codec", "dir"),
    ("codec", "dir-atomic"),
    ("cota", "mbtiles"),
];

/// Removes what a run of `phase` into `out` writes (outside its timing).
fn clear(phase: &str, out: &Path) {
    match phase {
        "mbtiles" => drop(std::fs::remove_file(out.with_extension("mbtiles"))),
        "compute" => {}
        _ => drop(std::fs::remove_dir_all(out)),
    }
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        bail!("usage: tiles-codec OUT REPS FILE...");
    }
    let (out, reps): (PathBuf, usize) = (args[0].clone().into(), args[1].parse()?);
    let files: Vec<PathBuf> = args[2..].iter().map(PathBuf::from).collect();
    let grid = cota_bench::load_mosaic(&files)?;
    let t0 = Instant::now();
    let lattice = Lattice::resample(&grid, &LatticeOptions::DEFAULT)?;
    let prep = Prepared::new(&lattice, &grid, &TilerOptions::DEFAULT)?;
    let prepare_s = t0.elapsed().as_secs_f64();
    let tiles = prep.tiles().count() as f64;
    let mut times = vec![Vec::new(); RUNS.len()];
    let mut sizes = vec![0u64; RUNS.len()];
    for rep in 0..=reps {
        for (k, (who, phase)) in RUNS.iter().enumerate() {
            let dir = out.join(format!("{who}-{phase}"));
            clear(phase, &dir);
            let t = Instant::now();
            let bytes = run(phase, who, &grid, &prep, &dir)?;
            let s = t.elapsed().as_secs_f64();
            println!(
                "{}",
                json!({"pipeline": who, "phase": phase, "rep": rep, "seconds": s, "tiles": tiles, "bytes": bytes})
            );
            if rep > 0 {
                times[k].push(s);
            }
            sizes[k] = bytes;
        }
    }
    println!("\ncota's preparation (lattice, hierarchy, errors): {prepare_s:.2} s; {tiles} tiles; {} threads\n", rayon::current_num_threads());
    println!("| pipeline | phase | median s | tiles/s | tiles/s with cota's preparation | bytes |");
    println!("|---|---|---:|---:|---:|---:|");
    for (k, (who, phase)) in RUNS.iter().enumerate() {
        let m = median(times[k].clone());
        let prep_s = if *who == "cota" { prepare_s } else { 0.0 };
        println!(
            "| {who} | {phase} | {m:.3} | {:.0} | {:.0} | {} |",
            tiles / m,
            tiles / (m + prep_s),
            sizes[k]
        );
    }
    Ok(())
}
