//! `tiles-peers`: the Rust half of `bench/tiles-peers.sh`.
//!
//! * `tiles-peers export DIR FILE...` writes the tiling lattice of the DEM
//!   files (`DIR/lattice.f32`, little-endian f32 rows of the window, and
//!   `DIR/lattice.json`: the window, the scheme and every zoom's tiles and
//!   bound) so that the Python peers mesh exactly the samples cota meshes.
//! * `tiles-peers measure PYRAMID FILE...` decodes every tile of a pyramid
//!   with cota's decoder, measures its true largest error at every sample of
//!   its square of the same lattice ([`check_placed_mesh`], triangles turned
//!   counter-clockwise first, since the winding is not what is measured),
//!   and counts seam mismatches between same-zoom neighbours
//!   ([`compare_border`]); prints one JSON object, with the worst error per
//!   zoom over every tile and over the tiles inside the data's samples.
#![allow(clippy::unwrap_used)]

use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use cota_core::mesh::check::check_placed_mesh;
use cota_core::tiles::{Lattice, LatticeOptions, Prepared, TileId, TilerOptions};
use cota_core::HeightGrid;
use cota_tiles::{compare_border, decode, tile_path, DecodedTile, Neighbour};
use serde_json::json;

fn export(dir: &Path, prep: &Prepared<'_>) -> Result<()> {
    std::fs::create_dir_all(dir)?;
    let lat = prep.lattice();
    let mut f = std::io::BufWriter::new(std::fs::File::create(dir.join("lattice.f32"))?);
    for h in lat.grid().heights() {
        f.write_all(&h.to_le_bytes())?;
    }
    f.flush()?;
    let zooms: Vec<_> = prep
        .zooms()
        .iter()
        .map(|p| {
            json!({"zoom": p.zoom, "x0": p.range.x0, "x1": p.range.x1, "y0": p.range.y0,
                   "y1": p.range.y1, "max_error_m": p.max_error_m})
        })
        .collect();
    let s = lat.scheme();
    let meta = json!({
        "origin": lat.origin(), "width": lat.grid().width(), "height": lat.grid().height(),
        "max_zoom": s.max_zoom, "tile_cells": s.tile_cells, "zooms": zooms,
    });
    std::fs::write(dir.join("lattice.json"), meta.to_string())?;
    Ok(())
}

/// Turns every triangle counter-clockwise seen from above; returns how many
/// were clockwise.
fn counter_clockwise(d: &mut DecodedTile) -> usize {
    let mut flipped = 0;
    for t in &mut d.triangles {
        let p = |i: u32| (i64::from(d.u[i as usize]), i64::from(d.v[i as usize]));
        let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
        if (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0) < 0 {
            t.swap(1, 2);
            flipped += 1;
        }
    }
    flipped
}

fn gzip_len(bytes: &[u8]) -> usize {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    e.write_all(bytes).unwrap();
    e.finish().unwrap().len()
}

/// Whether tile `t`'s rectangle lies inside the samples of `g` (a
/// geographic grid): there both pyramids are measured against the data
/// alone, not against what each shows beyond its edge.
fn inside(g: &HeightGrid, prep: &Prepared<'_>, t: TileId) -> bool {
    let [w, s, e, n] = prep.lattice().scheme().tile_rect_deg(t);
    let (x0, y0) = g.georef().sample_xy(0.0, 0.0);
    let (x1, y1) = g
        .georef()
        .sample_xy((g.width() - 1) as f64, (g.height() - 1) as f64);
    let (lo_x, hi_x, lo_y, hi_y) = (x0.min(x1), x0.max(x1), y0.min(y1), y0.max(y1));
    w >= lo_x && e <= hi_x && s >= lo_y && n <= hi_y
}

fn measure(out: &Path, prep: &Prepared<'_>, g: &HeightGrid) -> Result<serde_json::Value> {
    let mut tiles: HashMap<TileId, DecodedTile> = HashMap::new();
    let (mut bytes, mut gz, mut flipped, mut invalid, mut over) =
        (0usize, 0usize, 0usize, 0usize, 0usize);
    let mut worst: Vec<f64> = vec![0.0; 64];
    let mut worst_inside: Vec<f64> = vec![0.0; 64];
    for t in prep.tiles() {
        let raw = std::fs::read(tile_path(out, t)).with_context(|| format!("tile {t}"))?;
        let mut d = decode(&raw).with_context(|| format!("tile {t}"))?;
        bytes += raw.len();
        gz += if raw.starts_with(&[0x1f, 0x8b]) {
            raw.len()
        } else {
            gzip_len(&raw)
        };
        flipped += counter_clockwise(&mut d);
        let cells = prep.lattice().scheme().cells_at(t.z);
        let bound = prep.zoom(t.z).map_or(0.0, |p| p.max_error_m);
        match check_placed_mesh(&prep.region(t), &d.to_placed(cells), None) {
            Ok(r) => {
                let ratio = r.metrics.max_error_m / bound;
                worst[t.z as usize] = worst[t.z as usize].max(ratio);
                if inside(g, prep, t) {
                    worst_inside[t.z as usize] = worst_inside[t.z as usize].max(ratio);
                }
                over += usize::from(ratio > 1.0);
            }
            Err(_) => invalid += 1,
        }
        tiles.insert(t, d);
    }
    let (mut borders, mut mismatched_borders, mut mismatches) = (0usize, 0usize, 0usize);
    for (t, a) in &tiles {
        for (dx, dy, side) in [(1, 0, Neighbour::East), (0, 1, Neighbour::North)] {
            let n = TileId {
                z: t.z,
                x: t.x + dx,
                y: t.y + dy,
            };
            if let Some(b) = tiles.get(&n) {
                let c = compare_border(a, b, side);
                borders += 1;
                mismatches += c.mismatches();
                mismatched_borders += usize::from(c.mismatches() > 0);
            }
        }
    }
    let per_zoom: Vec<_> = prep
        .zooms()
        .iter()
        .map(|p| json!([p.zoom, worst[p.zoom as usize]]))
        .collect();
    let inside_per_zoom: Vec<_> = prep
        .zooms()
        .iter()
        .map(|p| json!([p.zoom, worst_inside[p.zoom as usize]]))
        .collect();
    Ok(json!({
        "tiles": tiles.len(), "bytes": bytes, "gzip_bytes": gz,
        "max_error_ratio": worst.iter().cloned().fold(0.0, f64::max),
        "tiles_over_bound": over, "invalid_tiles": invalid, "clockwise_triangles": flipped,
        "worst_ratio_per_zoom": per_zoom,
        "worst_ratio_per_zoom_inside_the_data": inside_per_zoom,
        "borders": borders, "borders_with_mismatches": mismatched_borders, "seam_mismatches": mismatches,
    }))
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        bail!("usage: tiles-peers export DIR FILE... | tiles-peers measure PYRAMID FILE...");
    }
    let files: Vec<PathBuf> = args[2..].iter().map(PathBuf::from).collect();
    let grid = cota_bench::load_mosaic(&files)?;
    let lattice = Lattice::resample(&grid, &LatticeOptions::DEFAULT)?;
    let prep = Prepared::new(&lattice, &grid, &TilerOptions::DEFAULT)?;
    match args[0].as_str() {
        "export" => export(Path::new(&args[1]), &prep),
        "measure" => {
            println!("{}", measure(Path::new(&args[1]), &prep, &grid)?);
            Ok(())
        }
        other => bail!("expected export or measure, found {other}"),
    }
}
