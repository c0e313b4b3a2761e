//! The pure-Rust meshopt codecs (`cota_io::meshopt`) on real tile data and
//! edge cases: each stream decodes (independent decoder) to exactly the
//! input; the npm `meshoptimizer` decoder, the one CesiumJS loads, reads the
//! same streams when node and the viewer's node_modules are there.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::Path;

use cota_core::tiles::{Lattice, LatticeOptions, Prepared, TilerOptions};
use cota_core::{fill_voids, FillOptions};
use cota_io::meshopt::{
    decode_index_sequence, decode_triangles, decode_vertex_buffer, encode_index_sequence,
    encode_triangles, encode_triangles_rotated, encode_vertex_buffer,
};
use cota_io::{read_dem, ReadOptions};
use cota_tiles::{decode, make_tile, PyramidOptions};
use proptest::prelude::*;

/// A named case: mode, count, stride, input bytes, encoded stream.
struct Case {
    name: String,
    mode: &'static str,
    count: usize,
    stride: usize,
    raw: Vec<u8>,
    packed: Vec<u8>,
}

/// Indices as little-endian bytes.
type Bytes = fn(&[u32]) -> Vec<u8>;

fn le16(v: &[u32]) -> Vec<u8> {
    v.iter().flat_map(|&i| (i as u16).to_le_bytes()).collect()
}

fn le32(v: &[u32]) -> Vec<u8> {
    v.iter().flat_map(|&i| i.to_le_bytes()).collect()
}

/// Vertex, triangle and sequence cases, each checked here to round-trip.
fn cases_of(name: &str, vertices: &[u8], triangles: &[u32], sequence: &[u32]) -> Vec<Case> {
    let mut out = Vec::new();
    let packed = encode_vertex_buffer(vertices, 8).unwrap();
    assert_eq!(
        decode_vertex_buffer(&packed, vertices.len() / 8, 8).unwrap(),
        vertices,
        "{name}"
    );
    out.push(Case {
        name: format!("{name}-vertices"),
        mode: "ATTRIBUTES",
        count: vertices.len() / 8,
        stride: 8,
        raw: vertices.to_vec(),
        packed,
    });
    let wide = triangles.iter().chain(sequence).any(|&i| i > 65_535);
    let (stride, bytes): (usize, Bytes) = if wide { (4, le32) } else { (2, le16) };
    let packed = encode_triangles(triangles).unwrap();
    assert_eq!(
        decode_triangles(&packed, triangles.len()).unwrap(),
        triangles,
        "{name}"
    );
    out.push(Case {
        name: format!("{name}-triangles"),
        mode: "TRIANGLES",
        count: triangles.len(),
        stride,
        raw: bytes(triangles),
        packed,
    });
    let (packed, turned) = encode_triangles_rotated(triangles).unwrap();
    assert_eq!(
        decode_triangles(&packed, triangles.len()).unwrap(),
        turned,
        "{name}"
    );
    for (t, u) in triangles.chunks(3).zip(turned.chunks(3)) {
        let r = [[t[0], t[1], t[2]], [t[1], t[2], t[0]], [t[2], t[0], t[1]]];
        assert!(
            r.contains(&[u[0], u[1], u[2]]),
            "{name}: {t:?} turned to {u:?}"
        );
    }
    out.push(Case {
        name: format!("{name}-triangles-rotated"),
        mode: "TRIANGLES",
        count: turned.len(),
        stride,
        raw: bytes(&turned),
        packed,
    });
    let packed = encode_index_sequence(sequence).unwrap();
    assert_eq!(
        decode_index_sequence(&packed, sequence.len()).unwrap(),
        sequence,
        "{name}"
    );
    out.push(Case {
        name: format!("{name}-sequence"),
        mode: "INDICES",
        count: sequence.len(),
        stride,
        raw: bytes(sequence),
        packed,
    });
    out
}

/// Real tiles of the fixture's pyramid (zooms 0-9): u16 position-like
/// vertices (u, v, height, 0), triangles, edges.
fn fixture_cases() -> Vec<Case> {
    let mut g = read_dem(
        &cota_fixtures::fixture("S29W072.hgt.zip"),
        &ReadOptions::DEFAULT,
    )
    .unwrap()
    .grid;
    fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
    let lat = Lattice::resample(&g, &LatticeOptions::DEFAULT.with_max_zoom(Some(9))).unwrap();
    let prep = Prepared::new(&lat, &g, &TilerOptions::DEFAULT).unwrap();
    let mut out = Vec::new();
    for t in prep.tiles().filter(|t| t.z >= 7) {
        let qm = make_tile(&prep, t, &PyramidOptions::DEFAULT.with_check(false), None).unwrap();
        let d = decode(&qm.bytes).unwrap();
        let vertices: Vec<u8> = (0..d.u.len())
            .flat_map(|i| {
                [d.u[i], d.v[i], d.height[i], 0]
                    .into_iter()
                    .flat_map(u16::to_le_bytes)
            })
            .collect();
        let tris: Vec<u32> = d.triangles.iter().flatten().copied().collect();
        let edges: Vec<u32> = d.edges.iter().flatten().copied().collect();
        out.extend(cases_of(
            &format!("tile-{}-{}-{}", t.z, t.x, t.y),
            &vertices,
            &tris,
            &edges,
        ));
    }
    out
}

/// Edge cases: nothing, one vertex, more than 65,535 vertices (u32 indices),
/// a grid far from `next` order.
fn edge_cases() -> Vec<Case> {
    let mut out = cases_of("empty", &[], &[], &[]);
    out.extend(cases_of("one", &[1, 2, 3, 4, 5, 6, 7, 8], &[0, 0, 0], &[0]));
    let n = 300u32; // 90,000 vertices
    let vertices: Vec<u8> = (0..n * n)
        .flat_map(|i| {
            let (x, y) = (i % n, i / n);
            [
                x as u16 * 200,
                y as u16 * 200,
                ((x * 7 + y * 13) % 4000) as u16,
                0,
            ]
            .into_iter()
            .flat_map(u16::to_le_bytes)
        })
        .collect();
    let mut tris = Vec::new();
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            let i = y * n + x;
            tris.extend_from_slice(&[i, i + 1, i + n, i + 1, i + n + 1, i + n]);
        }
    }
    let seq: Vec<u32> = (0..n).map(|k| k * n).chain((0..n).rev()).collect();
    out.extend(cases_of("grid-90000", &vertices, &tris, &seq));
    // Triangles far from first-use order: every index explicit.
    let scattered: Vec<u32> = (0..3000u32).map(|k| (k * 7919) % 100_003).collect();
    out.extend(cases_of(
        "scattered",
        &vertices[..8 * 64],
        &scattered,
        &scattered,
    ));
    out
}

#[test]
fn codecs_round_trip_on_real_tiles_and_edge_cases() {
    let cases: Vec<Case> = fixture_cases().into_iter().chain(edge_cases()).collect();
    assert!(cases.len() > 40);
    let raw: usize = cases.iter().map(|c| c.raw.len()).sum();
    let packed: usize = cases.iter().map(|c| c.packed.len()).sum();
    eprintln!("{} buffers: {raw} bytes encoded to {packed}", cases.len());
    assert!(packed < raw);
}

#[test]
fn bad_layouts_are_errors_not_panics() {
    assert!(encode_vertex_buffer(&[0; 12], 6).is_err());
    assert!(encode_vertex_buffer(&[0; 10], 8).is_err());
    assert!(encode_vertex_buffer(&[0; 8], 0).is_err());
    assert!(encode_triangles(&[0, 1]).is_err());
    assert!(encode_index_sequence(&[0, 1 << 31]).is_err());
    assert!(decode_vertex_buffer(&[0xa0], 1, 8).is_err());
    assert!(decode_triangles(&[0xe1, 0x10], 3).is_err());
    assert!(decode_index_sequence(&[0xd1, 0xff, 0, 0, 0], 1).is_err());
    assert!(decode_vertex_buffer(&[0xa0; 40], usize::MAX / 2, 8).is_err());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn random_buffers_round_trip(
        bytes in proptest::collection::vec(any::<u8>(), 0..2000),
        ids in proptest::collection::vec(0u32..5000, 0..600),
    ) {
        let whole = &bytes[..bytes.len() / 16 * 16];
        let packed = encode_vertex_buffer(whole, 16).unwrap();
        prop_assert_eq!(decode_vertex_buffer(&packed, whole.len() / 16, 16).unwrap(), whole);
        let tris = &ids[..ids.len() / 3 * 3];
        let packed = encode_triangles(tris).unwrap();
        prop_assert_eq!(decode_triangles(&packed, tris.len()).unwrap(), tris);
        let (packed, turned) = encode_triangles_rotated(tris).unwrap();
        prop_assert_eq!(decode_triangles(&packed, tris.len()).unwrap(), turned);
        let packed = encode_index_sequence(&ids).unwrap();
        prop_assert_eq!(decode_index_sequence(&packed, ids.len()).unwrap(), ids);
        // Decoding junk is an error or some output, never a panic.
        let _ = decode_vertex_buffer(&bytes, 7, 8);
        let _ = decode_triangles(&bytes, 9);
        let _ = decode_index_sequence(&bytes, 5);
    }
}

#[test]
fn npm_decoder_reads_cota_buffers() {
    let viewer = Path::new(env!("CARGO_MANIFEST_DIR")).join("../cota-server/viewer");
    if !viewer.join("node_modules/meshoptimizer").is_dir() {
        eprintln!(
            "skipped: no {}",
            viewer.join("node_modules/meshoptimizer").display()
        );
        return;
    }
    if std::process::Command::new("node")
        .arg("--version")
        .output()
        .is_err()
    {
        eprintln!("skipped: no node on PATH");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for c in fixture_cases().into_iter().chain(edge_cases()) {
        let meta = serde_json::json!({"mode": c.mode, "count": c.count, "stride": c.stride});
        std::fs::write(
            dir.path().join(format!("{}.json", c.name)),
            meta.to_string(),
        )
        .unwrap();
        std::fs::write(dir.path().join(format!("{}.raw", c.name)), &c.raw).unwrap();
        std::fs::write(dir.path().join(format!("{}.bin", c.name)), &c.packed).unwrap();
    }
    let out = std::process::Command::new("node")
        .args(["--test", "test-tiles/meshopt.test.mjs"])
        .current_dir(&viewer)
        .env("COTA_MESHOPT_CASES", dir.path())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("decoded exactly"), "{text}");
}
