//! Bytes per triangle of cota's progressive stream against Cesium
//! quantized-mesh-1.0 + gzip and meshoptimizer's codecs + deflate, on the same
//! meshes (`Bitree::extract(E)` of each DEM).
//!
//! Usage: `cargo run --release -p cota-bench --bin stream-compare -- [--json]
//! [--errors 0,1,2,5,10,20] FILE...` (default file: the bundled
//! `fixtures/S29W072.hgt.zip`). Voids are filled and heights rounded to whole
//! metres (SRTM's lattice), so the `E = 0` stream is lossless.
//!
//! For each DEM and error `E`:
//! 1. the mesh `M = Bitree::extract(E)`;
//! 2. cota: the whole progressive stream from the coarse mesh down to `E`
//!    (every step, framing and checksums included), quantum 1 m;
//! 3. quantized-mesh-1.0 of `M` (`cota_tiles::encode`, the whole grid as
//!    one tile over its sample rectangle), raw and gzipped (best);
//! 4. meshopt: vertex-cache and vertex-fetch optimised, vertices as four
//!    `u16` (column, row, height − min, 0), `encode_vertex_buffer` +
//!    `encode_index_buffer`, then deflate (best).

use std::error::Error;
use std::io::Write;
use std::path::{Path, PathBuf};

use cota_core::grid::voids::{fill_voids, FillOptions};
use cota_core::stream::{encode, StreamOptions};
use cota_core::{Bitree, ExtractOptions, HeightGrid, Mesh};
use cota_io::stream_file::stream_bytes;
use cota_io::{read_dem, ReadOptions};
use flate2::write::{DeflateEncoder, GzEncoder};
use flate2::Compression;
use serde_json::json;

fn gzip(b: &[u8]) -> Result<usize, Box<dyn Error>> {
    let mut e = GzEncoder::new(Vec::new(), Compression::best());
    e.write_all(b)?;
    Ok(e.finish()?.len())
}

fn meshopt_bytes(mesh: &Mesh) -> Result<usize, Box<dyn Error>> {
    let zmin = mesh.vertices.iter().fold(f32::MAX, |a, v| a.min(v.z_m));
    let verts: Vec<[u16; 4]> = mesh
        .vertices
        .iter()
        .map(|v| [v.col as u16, v.row as u16, (v.z_m - zmin).round() as u16, 0])
        .collect();
    let idx: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    let mut idx = meshopt::optimize_vertex_cache(&idx, verts.len());
    let verts = meshopt::optimize_vertex_fetch(&mut idx, &verts);
    let vb = meshopt::encode_vertex_buffer(&verts)?;
    let ib = meshopt::encode_index_buffer(&idx, verts.len())?;
    let mut e = DeflateEncoder::new(Vec::new(), Compression::best());
    e.write_all(&vb)?;
    e.write_all(&ib)?;
    Ok(e.finish()?.len())
}

fn load(path: &Path) -> Result<HeightGrid, Box<dyn Error>> {
    let mut g = read_dem(path, &ReadOptions::DEFAULT)?.grid;
    fill_voids(&mut g, &FillOptions::DEFAULT)?;
    for h in g.heights_mut() {
        *h = h.round();
    }
    Ok(g)
}

fn main() -> Result<(), Box<dyn Error>> {
    let mut json_out = false;
    let mut errors = vec![20.0, 10.0, 5.0, 2.0, 1.0, 0.0];
    let mut files = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--json" => json_out = true,
            "--errors" => {
                let v = args.next().ok_or("--errors needs a list such as 0,1,5")?;
                errors = v
                    .split(',')
                    .map(|s| s.trim().parse::<f64>())
                    .collect::<Result<_, _>>()?;
            }
            _ => files.push(PathBuf::from(a)),
        }
    }
    if files.is_empty() {
        files.push(cota_fixtures::fixture(cota_fixtures::BUNDLED_TILE));
    }
    let mut rows = Vec::new();
    if !json_out {
        println!("| DEM | E (m) | triangles | cota stream B/tri | B/point | quantized-mesh B/tri | QM + gzip B/tri | meshopt + deflate B/tri |");
        println!("|---|---:|---:|---:|---:|---:|---:|---:|");
    }
    for f in &files {
        let grid = load(f)?;
        let tree = Bitree::build(&grid)?;
        let name = f
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        for &e in &errors {
            let mesh = tree.extract(&ExtractOptions::max_error_m(e))?.mesh;
            let s = encode(&grid, &StreamOptions::default().with_max_error_m(e))?;
            let cota = stream_bytes(&s, grid.georef()).len();
            let qm = quantized_mesh(&mesh, &grid)?;
            let qmz = gzip(&qm)?;
            let mo = meshopt_bytes(&mesh)?;
            let t = mesh.triangle_count() as f64;
            let row = json!({
                "dem": name,
                "max_error_m": e,
                "triangles": mesh.triangle_count(),
                "vertices": mesh.vertex_count(),
                "cota_bytes": cota,
                "cota_b_per_tri": cota as f64 / t,
                "cota_b_per_point": cota as f64 / mesh.vertex_count() as f64,
                "qm_bytes": qm.len(),
                "qm_gzip_bytes": qmz,
                "meshopt_deflate_bytes": mo,
            });
            if !json_out {
                println!(
                    "| {name} | {e} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} |",
                    mesh.triangle_count(),
                    cota as f64 / t,
                    cota as f64 / mesh.vertex_count() as f64,
                    qm.len() as f64 / t,
                    qmz as f64 / t,
                    mo as f64 / t
                );
            }
            rows.push(row);
        }
    }
    if json_out {
        println!("{}", serde_json::to_string_pretty(&rows)?);
    }
    Ok(())
}

/// The quantized-mesh-1.0 bytes of `mesh` with the whole grid as one tile
/// over its sample rectangle (no extensions).
fn quantized_mesh(mesh: &Mesh, grid: &HeightGrid) -> Result<Vec<u8>, Box<dyn Error>> {
    let (w, h) = (grid.width() as f64 - 1.0, grid.height() as f64 - 1.0);
    let g = grid.georef();
    let (x0, y0) = g.sample_xy(0.0, 0.0);
    let (x1, y1) = g.sample_xy(w, h);
    let frame = cota_tiles::TileFrame {
        cells: [w as u64, h as u64],
        rect_deg: [x0.min(x1), y0.min(y1), x0.max(x1), y0.max(y1)],
    };
    Ok(cota_tiles::encode(
        mesh,
        &frame,
        &cota_tiles::Extensions::default(),
    )?)
}
