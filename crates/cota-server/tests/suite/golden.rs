//! Golden streams for the viewer's JavaScript decoder (`viewer/src/decoder.js`,
//! tested by `viewer/test/decoder.test.mjs` under node): each `.cstream` in
//! `viewer/test/golden/` is written by the Rust encoder, and its `.json`
//! holds what the Rust decoder makes of every step (stated error, counts,
//! FNV-1a of the mesh and of the decoded heights; the whole mesh for the
//! smallest). This test fails when the files drift from the Rust side;
//! `COTA_BLESS=1 cargo test -p cota-server --test golden` rewrites them.
#![allow(clippy::unwrap_used, clippy::panic, reason = "tests")]

use std::path::{Path, PathBuf};

use cota_core::stream::{encode, StreamOptions};
use cota_core::{fill_voids, FillOptions};
use cota_core::{GeoRef, HeightGrid, Mesh};
use cota_io::stream_file::{stream_bytes, StreamReader};
use cota_io::{read_dem, ReadOptions};
use serde_json::{json, Value};

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("viewer/test/golden")
}

fn fnv(bytes: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &x in bytes {
        h ^= x as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// Vertices (col u32, row u32, z f32 bits), then triangles (u32), little-endian.
fn mesh_hash(m: &Mesh) -> String {
    let mut b = Vec::new();
    for v in &m.vertices {
        b.extend_from_slice(&v.col.to_le_bytes());
        b.extend_from_slice(&v.row.to_le_bytes());
        b.extend_from_slice(&v.z_m.to_le_bytes());
    }
    for t in &m.triangles {
        for i in t {
            b.extend_from_slice(&i.to_le_bytes());
        }
    }
    fnv(&b)
}

fn synthetic(w: usize, h: usize) -> HeightGrid {
    let v = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            (300.0 + 60.0 * (x * 0.23).sin() * (y * 0.19).cos()).round() + ((i * 7919) % 7) as f32
        })
        .collect();
    HeightGrid::new(w, h, v, GeoRef::unreferenced(30.0)).unwrap()
}

/// A window of the bundled SRTM tile, voids filled, whole metres, with its
/// geographic georeference moved to the window.
fn srtm_window(c0: usize, r0: usize, w: usize, h: usize) -> HeightGrid {
    let path = cota_fixtures::fixture(cota_fixtures::BUNDLED_TILE);
    let mut g = read_dem(&path, &ReadOptions::DEFAULT).unwrap().grid;
    fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
    let mut v = Vec::with_capacity(w * h);
    for r in r0..r0 + h {
        for c in c0..c0 + w {
            v.push(g.get(c, r).round());
        }
    }
    let mut geo = g.georef().clone();
    let (x, y) = geo.sample_xy(c0 as f64, r0 as f64);
    geo.origin_x = x;
    geo.origin_y = y;
    geo.pixel_is = cota_core::PixelIs::Point;
    HeightGrid::new(w, h, v, geo).unwrap()
}

/// What the Rust decoder makes of `bytes`, step by step.
fn expected(bytes: &[u8], full_mesh: bool) -> Value {
    let mut r = StreamReader::new();
    let frames = r.push(bytes).unwrap();
    r.finish().unwrap();
    // Decode again step by step to see every prefix.
    let mut steps = Vec::new();
    let mut r2 = StreamReader::new();
    let mut at = 0usize;
    for f in &frames {
        let end = f.end_offset as usize;
        r2.push(&bytes[at..end]).unwrap();
        at = end;
        let d = r2.decoder().unwrap();
        let m = d.mesh();
        let z = d.heights_m().unwrap();
        let zb: Vec<u8> = z.iter().flat_map(|h| h.to_le_bytes()).collect();
        let mut s = json!({
            "index": f.info.index,
            "end_offset": f.end_offset,
            "max_error_m": f.info.max_error_m,
            "new_points": f.info.new_points,
            "triangles": m.triangle_count(),
            "vertices": m.vertex_count(),
            "mesh_fnv": mesh_hash(&m),
            "heights_fnv": fnv(&zb),
        });
        if full_mesh {
            let verts: Vec<[f64; 3]> = m
                .vertices
                .iter()
                .map(|v| [v.col as f64, v.row as f64, v.z_m as f64])
                .collect();
            s["mesh"] = json!({ "vertices": verts, "triangles": m.triangles });
        }
        steps.push(s);
    }
    let d = r.decoder().unwrap();
    json!({
        "width": d.header().width,
        "height": d.header().height,
        "quantum_m": d.header().quantum_m,
        "bytes": bytes.len(),
        "steps": steps,
    })
}

fn check_or_bless(name: &str, grid: &HeightGrid, opts: &StreamOptions, full_mesh: bool) {
    let enc = encode(grid, opts).unwrap();
    let bytes = stream_bytes(&enc, grid.georef());
    let want = expected(&bytes, full_mesh);
    let text = serde_json::to_string_pretty(&want).unwrap() + "\n";
    let dir = golden_dir();
    let (bp, jp) = (
        dir.join(format!("{name}.cstream")),
        dir.join(format!("{name}.json")),
    );
    if std::env::var_os("COTA_BLESS").is_some() {
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(&bp, &bytes).unwrap();
        std::fs::write(&jp, &text).unwrap();
        return;
    }
    let hint = "run `COTA_BLESS=1 cargo test -p cota-server --test golden` and commit the files";
    let have = std::fs::read(&bp).unwrap_or_else(|e| panic!("{}: {e}; {hint}", bp.display()));
    assert!(
        have == bytes,
        "{} differs from the encoder's output; {hint}",
        bp.display()
    );
    let have = std::fs::read_to_string(&jp).unwrap();
    let have: Value = serde_json::from_str(&have).unwrap();
    assert_eq!(
        have,
        want,
        "{} differs from the decoder's; {hint}",
        jp.display()
    );
}

#[test]
fn golden_synthetic_small() {
    check_or_bless(
        "synthetic-2x9",
        &synthetic(2, 9),
        &StreamOptions::default(),
        true,
    );
    check_or_bless(
        "synthetic-13x11",
        &synthetic(13, 11),
        &StreamOptions::default(),
        true,
    );
    check_or_bless(
        "synthetic-37x23",
        &synthetic(37, 23),
        &StreamOptions::default(),
        false,
    );
    check_or_bless(
        "synthetic-33x33",
        &synthetic(33, 33),
        &StreamOptions::default(),
        false,
    );
}

#[test]
fn golden_srtm_windows() {
    check_or_bless(
        "s29w072-129x97",
        &srtm_window(1000, 300, 129, 97),
        &StreamOptions::default(),
        false,
    );
    // Decimetre quantum and explicit thresholds: other contexts and residuals.
    let o = StreamOptions::default()
        .with_quantum_m(0.1)
        .with_thresholds_m(Some(vec![200.0, 50.0, 12.5, 3.0]))
        .with_max_error_m(0.5);
    check_or_bless(
        "s29w072-200x150-dm",
        &srtm_window(900, 900, 200, 150),
        &o,
        false,
    );
}
