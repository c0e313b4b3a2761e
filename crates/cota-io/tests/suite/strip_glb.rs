//! GLB with one TRIANGLE_STRIP primitive (`write_glb_strip`): mode 5, the
//! strip's indices, every drawn triangle facing up in both coordinate frames
//! (a mirrored frame gets one leading repeated index), a strip refused with
//! a mesh it does not encode, and the Khronos validator's verdict when
//! tools/gltf-validate is installed.
#![allow(clippy::unwrap_used, reason = "tests")]

use std::path::Path;
use std::process::Command;

use cota_core::strip::{drawn_triangles, stripify_bitree};
use cota_core::{Bitree, ExtractOptions, GeoRef, HeightGrid, Mesh};
use cota_io::export::{
    write_atomically, write_glb_strip, Coords, ExportError, ExportOptions, IndexWidth,
};

fn grid(w: usize, h: usize) -> HeightGrid {
    let heights: Vec<f32> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            500.0 + 40.0 * (0.3 * x).sin() * (0.2 * y).cos() + ((i * 7919) % 13) as f32
        })
        .collect();
    HeightGrid::new(w, h, heights, GeoRef::unreferenced(30.0)).unwrap()
}

fn mesh(g: &HeightGrid, e: f64) -> Mesh {
    Bitree::build(g)
        .unwrap()
        .extract(&ExtractOptions::max_error_m(e))
        .unwrap()
        .mesh
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_bits(u32_at(b, at))
}

/// (JSON, BIN) of a GLB.
fn split(bytes: &[u8]) -> (serde_json::Value, Vec<u8>) {
    assert_eq!(&bytes[..4], b"glTF");
    assert_eq!(u32_at(bytes, 8) as usize, bytes.len());
    let json_len = u32_at(bytes, 12) as usize;
    let text = std::str::from_utf8(&bytes[20..20 + json_len]).unwrap();
    let json: serde_json::Value = serde_json::from_str(text.trim_end()).unwrap();
    let at = 20 + json_len;
    assert_eq!(&bytes[at + 4..at + 8], b"BIN\0");
    (json, bytes[at + 8..].to_vec())
}

fn encode(m: &Mesh, strip: &[u32], g: &HeightGrid, o: &ExportOptions) -> Vec<u8> {
    let mut out = Vec::new();
    write_glb_strip(&mut out, m, strip, g, o).unwrap();
    out
}

/// The written indices and positions.
fn read_back(bytes: &[u8]) -> (Vec<u32>, Vec<[f32; 3]>) {
    let (json, bin) = split(bytes);
    let prim = &json["meshes"][0]["primitives"][0];
    assert_eq!(prim["mode"], 5, "TRIANGLE_STRIP");
    let span = |i: u64| {
        let a = &json["accessors"][i as usize];
        let v = &json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        (
            v["byteOffset"].as_u64().unwrap_or(0) as usize,
            a["count"].as_u64().unwrap() as usize,
            a["componentType"].as_u64().unwrap(),
        )
    };
    let (off, n, ty) = span(prim["indices"].as_u64().unwrap());
    let idx = (0..n)
        .map(|k| match ty {
            5123 => u16::from_le_bytes([bin[off + 2 * k], bin[off + 2 * k + 1]]) as u32,
            _ => u32_at(&bin, off + 4 * k),
        })
        .collect();
    let (off, n, _) = span(prim["attributes"]["POSITION"].as_u64().unwrap());
    let pos = (0..n)
        .map(|k| [0, 1, 2].map(|c| f32_at(&bin, off + 12 * k + 4 * c)))
        .collect();
    (idx, pos)
}

#[test]
fn strip_glb_faces_up_in_both_frames() {
    let g = grid(37, 23);
    for e in [0.0, 3.0] {
        let m0 = mesh(&g, e);
        let s = stripify_bitree(&m0).unwrap();
        let (m, strip) = (&*s.mesh, &s.strip);
        for coords in [Coords::LocalMetres, Coords::Grid] {
            for width in [IndexWidth::U16, IndexWidth::U32] {
                let o = ExportOptions::DEFAULT
                    .with_coords(coords)
                    .with_index_width(width);
                let (idx, pos) = read_back(&encode(m, &strip.indices, &g, &o));
                assert!(idx == strip.indices || idx[1..] == strip.indices[..]);
                let tris = drawn_triangles(&idx);
                assert_eq!(tris.len(), m.triangles.len());
                for t in tris {
                    let [a, b, c] = t.map(|i| pos[i as usize]);
                    let (u, v) = ([b[0] - a[0], b[1] - a[1]], [c[0] - a[0], c[1] - a[1]]);
                    assert!(
                        u[0] * v[1] - u[1] * v[0] > 0.0,
                        "{coords:?}: a triangle faces down"
                    );
                }
            }
        }
    }
}

/// A strip of re-triangulated cells written with the mesh it was made from
/// (not the one it encodes) is refused: its normals would be wrong.
#[test]
fn strip_glb_rejects_a_strip_of_another_mesh() {
    let g = grid(37, 23);
    let m = mesh(&g, 0.0);
    let s = stripify_bitree(&m).unwrap();
    assert!(s.retriangulated());
    let mut out = Vec::new();
    let err =
        write_glb_strip(&mut out, &m, &s.strip.indices, &g, &ExportOptions::DEFAULT).unwrap_err();
    match err {
        ExportError::StripMismatch {
            mesh_triangles,
            strip_triangles,
            foreign,
        } => {
            assert_eq!(mesh_triangles, m.triangles.len());
            assert_eq!(strip_triangles, m.triangles.len());
            assert_eq!(foreign, 2 * s.flipped_cells);
        }
        e => panic!("expected StripMismatch, found {e}"),
    }
    assert!(write_glb_strip(
        &mut out,
        &s.mesh,
        &s.strip.indices,
        &g,
        &ExportOptions::DEFAULT
    )
    .is_ok());
}

#[test]
fn strip_glb_rejects_bad_indices() {
    let g = grid(9, 9);
    let m = mesh(&g, 1.0);
    let mut out = Vec::new();
    let bad = [0, 1, m.vertices.len() as u32];
    assert!(write_glb_strip(&mut out, &m, &bad, &g, &ExportOptions::DEFAULT).is_err());
}

/// Runs tools/gltf-validate on strip GLBs, when its node_modules exists.
#[test]
fn strip_glb_passes_the_khronos_validator() {
    let tool = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/gltf-validate");
    if !tool.join("node_modules/gltf-validator").is_dir() {
        eprintln!(
            "skipped: {} has no node_modules (run `npm ci` there)",
            tool.display()
        );
        return;
    }
    if Command::new("node").arg("--version").output().is_err() {
        eprintln!("skipped: node is not installed");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    let small = grid(37, 23);
    let big = grid(300, 220);
    for (name, g, e, o) in [
        ("local.glb", &small, 2.0, ExportOptions::DEFAULT),
        (
            "grid-u16.glb",
            &small,
            0.0,
            ExportOptions::DEFAULT.with_coords(Coords::Grid),
        ),
        ("u32.glb", &big, 0.0, ExportOptions::DEFAULT),
    ] {
        let m = mesh(g, e);
        let s = stripify_bitree(&m).unwrap();
        let path = dir.path().join(name);
        write_atomically(&path, |w| {
            write_glb_strip(w, &s.mesh, &s.strip.indices, g, &o)
        })
        .unwrap();
        files.push(path);
    }
    let out = Command::new("node")
        .arg(tool.join("validate.mjs"))
        .args(&files)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    eprintln!("{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "validator failed:\n{text}");
    assert_eq!(
        text.matches("numErrors=0 numWarnings=0").count(),
        3,
        "{text}"
    );
}
