//! Shared by the server's tests: a small real grid and tile directories.
#![allow(dead_code, clippy::unwrap_used, reason = "test helpers")]

use std::io::Write;
use std::path::Path;

use cota_core::HeightGrid;
use cota_core::{fill_voids, FillOptions};
use cota_io::{read_dem, ReadOptions};
use cota_server::{ServerState, StreamAsset};

/// A 257 × 193 window of the bundled SRTM tile, voids filled, whole metres.
pub fn grid() -> HeightGrid {
    let path = cota_fixtures::fixture(cota_fixtures::BUNDLED_TILE);
    let mut g = read_dem(&path, &ReadOptions::DEFAULT).unwrap().grid;
    fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
    let (c0, r0, w, h) = (900, 300, 257, 193);
    let mut v = Vec::with_capacity(w * h);
    for r in r0..r0 + h {
        for c in c0..c0 + w {
            v.push(g.get(c, r).round());
        }
    }
    HeightGrid::new(w, h, v, g.georef().clone()).unwrap()
}

pub fn state() -> ServerState {
    ServerState::new(StreamAsset::from_grid(&grid(), "S29W072 window").unwrap())
}

/// A plausible raw quantized-mesh tile: header, 3 vertices, one triangle.
pub fn raw_tile(seed: u8) -> Vec<u8> {
    let mut b = vec![seed; 88];
    b.extend_from_slice(&3u32.to_le_bytes());
    b.extend_from_slice(&[0u8; 18]);
    b.extend_from_slice(&1u32.to_le_bytes());
    b.extend_from_slice(&[0, 0, 1, 0, 1, 0]);
    b.extend_from_slice(&[0u8; 16]);
    b
}

pub fn gzip(b: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    e.write_all(b).unwrap();
    e.finish().unwrap()
}

pub const LAYER: &str = r#"{
  "tilejson": "2.1.0", "format": "quantized-mesh-1.0", "version": "1.0.0",
  "scheme": "tms", "projection": "EPSG:4326",
  "tiles": ["{z}/{x}/{y}.terrain?v={version}"],
  "bounds": [-180, -90, 180, 90], "minzoom": 0, "maxzoom": 2,
  "available": [[{"startX": 0, "startY": 0, "endX": 1, "endY": 0}],
                [{"startX": 0, "startY": 0, "endX": 3, "endY": 1}],
                [{"startX": 0, "startY": 0, "endX": 7, "endY": 3}]]
}"#;

/// Levels 0–2 of raw and gzipped tiles, plus one corrupt tile (2/7/3).
pub fn tile_dir(dir: &Path) {
    std::fs::write(dir.join("layer.json"), LAYER).unwrap();
    for z in 0..3u32 {
        for x in 0..(2u32 << z) {
            for y in 0..(1u32 << z) {
                let d = dir.join(format!("{z}/{x}"));
                std::fs::create_dir_all(&d).unwrap();
                let t = raw_tile((x + y) as u8);
                let bytes = if (x + y) % 2 == 0 { t } else { gzip(&t) };
                std::fs::write(d.join(format!("{y}.terrain")), bytes).unwrap();
            }
        }
    }
    std::fs::write(dir.join("2/7/3.terrain"), b"not a tile").unwrap();
}
