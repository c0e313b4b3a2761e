//! Quantized GLB (`ExportOptions::quantize`, `KHR_mesh_quantization`) on the
//! bundled real tile, read back by a decoder written here from the glTF
//! spec (accessors, strides, node translation and scale): every triangle of
//! the mesh comes back once with its own winding, every vertex at its sample
//! (x, y to f32 precision) with the height `GlbQuantization::written_heights`
//! says, within half the step of the sample's; the written mesh passes the
//! invariant checker with the bound plus half the step; normals decode close
//! to the float layout's; the file is at most 0.55 of the float one; and the
//! Khronos validator accepts it when tools/gltf-validate is installed.
#![allow(clippy::unwrap_used, reason = "tests")]

use crate::common;

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

use cota_core::grid::voids::{fill_voids, FillOptions};
use cota_core::{check_mesh, Bitree, CheckOptions, ExtractOptions, HeightGrid, Mesh};
use cota_io::export::{
    write_glb, write_glb_quantized, write_glb_strip, Coords, ExportError, ExportOptions,
    GlbQuantization,
};
use cota_io::{read_dem, ReadOptions};

/// The bundled tile, voids filled.
fn tile() -> HeightGrid {
    let mut g = read_dem(&common::fixture("S29W072.hgt.zip"), &ReadOptions::DEFAULT)
        .unwrap()
        .grid;
    fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
    g
}

fn mesh(g: &HeightGrid, e: f64) -> Mesh {
    Bitree::build(g)
        .unwrap()
        .extract(&ExtractOptions::max_error_m(e))
        .unwrap()
        .mesh
}

fn glb(m: &Mesh, g: &HeightGrid, o: &ExportOptions) -> Vec<u8> {
    let mut out = Vec::new();
    write_glb(&mut out, m, g, o).unwrap();
    out
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
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

/// One decoded primitive: positions in the node's parent frame (z up, f64
/// from the f32 transform), decoded normals (parent frame, unit), triangles.
struct Decoded {
    positions: Vec<[f64; 3]>,
    normals: Vec<[f64; 3]>,
    triangles: Vec<[usize; 3]>,
}

/// Decodes every primitive of a quantized GLB.
fn decode(bytes: &[u8]) -> (serde_json::Value, Vec<Decoded>) {
    let (json, bin) = split(bytes);
    assert_eq!(json["extensionsRequired"][0], "KHR_mesh_quantization");
    assert_eq!(json["extensionsUsed"][0], "KHR_mesh_quantization");
    let root = &json["nodes"][0];
    assert!(root["rotation"].is_array(), "the root turns z up to y up");
    let f = |v: &serde_json::Value| v.as_f64().unwrap();
    let mut out = Vec::new();
    for child in root["children"].as_array().unwrap() {
        let node = &json["nodes"][child.as_u64().unwrap() as usize];
        let t: Vec<f64> = node["translation"]
            .as_array()
            .unwrap()
            .iter()
            .map(f)
            .collect();
        let s: Vec<f64> = node["scale"].as_array().unwrap().iter().map(f).collect();
        let mesh = &json["meshes"][node["mesh"].as_u64().unwrap() as usize];
        let prim = &mesh["primitives"][0];
        assert!(prim.get("mode").is_none(), "TRIANGLES");
        let acc = |name: &serde_json::Value| {
            let a = &json["accessors"][name.as_u64().unwrap() as usize];
            let v = &json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
            let start =
                v["byteOffset"].as_u64().unwrap_or(0) + a["byteOffset"].as_u64().unwrap_or(0);
            (
                a.clone(),
                start as usize,
                v["byteStride"].as_u64().unwrap_or(0) as usize,
            )
        };
        let (pa, p0, ps) = acc(&prim["attributes"]["POSITION"]);
        assert_eq!(
            (pa["componentType"].as_u64(), ps),
            (Some(5123), 8),
            "u16, stride 8"
        );
        let (na, n0, ns) = acc(&prim["attributes"]["NORMAL"]);
        assert_eq!(
            (na["componentType"].as_u64(), ns),
            (Some(5120), 4),
            "i8, stride 4"
        );
        assert_eq!(na["normalized"], true);
        let (ia, i0, _) = acc(&prim["indices"]);
        assert_eq!(ia["componentType"].as_u64(), Some(5123), "u16 indices");
        let n = pa["count"].as_u64().unwrap() as usize;
        assert!(n <= 65_535);
        let u16_at = |at: usize| f64::from(u16::from_le_bytes([bin[at], bin[at + 1]]));
        let mut positions = Vec::with_capacity(n);
        let mut normals = Vec::with_capacity(n);
        let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
        for k in 0..n {
            let q = [0, 1, 2].map(|c| u16_at(p0 + ps * k + 2 * c));
            for c in 0..3 {
                lo[c] = lo[c].min(q[c]);
                hi[c] = hi[c].max(q[c]);
            }
            positions.push([0, 1, 2].map(|c| t[c] + s[c] * q[c]));
            let b = [0, 1, 2].map(|c| f64::from(bin[n0 + ns * k + c] as i8) / 127.0);
            let len = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt();
            assert!(
                (len - 1.0).abs() <= 0.00674,
                "validator's unit length: {len}"
            );
            // A normal maps by the inverse transpose of the node's scale.
            let d = [0, 1, 2].map(|c| b[c] / s[c]);
            let dl = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            normals.push(d.map(|x| x / dl));
        }
        let bounds =
            |v: &serde_json::Value| -> Vec<f64> { v.as_array().unwrap().iter().map(f).collect() };
        assert_eq!(bounds(&pa["min"]), lo.to_vec());
        assert_eq!(bounds(&pa["max"]), hi.to_vec());
        let m = ia["count"].as_u64().unwrap() as usize;
        let triangles = (0..m / 3)
            .map(|k| [0, 1, 2].map(|c| u16_at(i0 + 2 * (3 * k + c)) as usize))
            .collect();
        out.push(Decoded {
            positions,
            normals,
            triangles,
        });
    }
    (json, out)
}

/// The mesh vertex at each decoded position (grid frame: x = col, y = row;
/// local metres: x = col·dx, y = (H−1−row)·dy), found by its sample.
fn vertex_ids(g: &HeightGrid, m: &Mesh, coords: Coords, d: &Decoded) -> Vec<u32> {
    let at: HashMap<(u32, u32), u32> = m
        .vertices
        .iter()
        .enumerate()
        .map(|(k, v)| ((v.col, v.row), k as u32))
        .collect();
    let [dx, dy] = g.cell_size_m();
    let last = (g.height() - 1) as f64;
    d.positions
        .iter()
        .map(|p| {
            let (c, r) = match coords {
                Coords::Grid => (p[0], p[1]),
                _ => (p[0] / dx, last - p[1] / dy),
            };
            // f32 transforms: within a thousandth of a sample.
            assert!(
                (c - c.round()).abs() < 1e-3 && (r - r.round()).abs() < 1e-3,
                "{c} {r}"
            );
            at[&(c.round() as u32, r.round() as u32)]
        })
        .collect()
}

/// A triangle rotated to start at its smallest index (winding kept).
fn canonical(t: [u32; 3]) -> [u32; 3] {
    let k = (0..3).min_by_key(|&k| t[k]).unwrap();
    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
}

#[test]
fn quantized_glb_decodes_to_the_mesh_with_the_written_heights() {
    let g = tile();
    let e = 5.0;
    let m = mesh(&g, e);
    for coords in [Coords::LocalMetres, Coords::Grid] {
        let o = ExportOptions::DEFAULT
            .with_coords(coords)
            .with_quantize(true);
        let q = GlbQuantization::new(&m, &g, &o).unwrap();
        let s = q.z_step_m();
        assert_eq!(s, 2f64.powi(s.log2().round() as i32), "a power of two");
        assert!(s <= 0.125, "step {s} m");
        let written = q.written_heights(&m);
        let bytes = glb(&m, &g, &o);
        let mut again = Vec::new();
        write_glb_quantized(&mut again, &m, &g, &o, &q).unwrap();
        assert_eq!(bytes, again, "planned once or twice: the same file");
        let (json, parts) = decode(&bytes);
        assert_eq!(parts.len(), q.primitives());
        assert_eq!(json["meshes"].as_array().unwrap().len(), q.primitives());
        let mut tris = Vec::new();
        let mut seen = vec![false; m.vertices.len()];
        for d in &parts {
            let ids = vertex_ids(&g, &m, coords, d);
            for (p, &i) in d.positions.iter().zip(&ids) {
                assert_eq!(p[2], f64::from(written[i as usize]), "height as written");
                let z = f64::from(m.vertices[i as usize].z_m);
                assert!((p[2] - z).abs() <= s / 2.0, "moved {} > {s}/2", p[2] - z);
                seen[i as usize] = true;
            }
            for t in &d.triangles {
                let t = t.map(|k| ids[k]);
                // The grid frame is mirrored: the writer reverses it back.
                let t = match coords {
                    Coords::Grid => [t[0], t[2], t[1]],
                    _ => t,
                };
                tris.push(canonical(t));
            }
        }
        assert!(seen.iter().all(|&x| x), "every vertex written");
        let mut want: Vec<[u32; 3]> = m.triangles.iter().map(|&t| canonical(t)).collect();
        tris.sort_unstable();
        want.sort_unstable();
        assert_eq!(tris, want, "each triangle once, same winding");
    }
}

#[test]
fn the_written_mesh_meets_the_bound_plus_half_the_step() {
    let g = tile();
    for e in [1.0, 5.0] {
        let m = mesh(&g, e);
        let q = GlbQuantization::new(&m, &g, &ExportOptions::DEFAULT.with_quantize(true)).unwrap();
        let h = q.z_step_m() / 2.0;
        let mut w = m.clone();
        for (v, z) in w.vertices.iter_mut().zip(q.written_heights(&m)) {
            v.z_m = z;
        }
        let opts = CheckOptions::conforming(e + h).with_height_tolerance_m(h);
        let report = check_mesh(&g, &w, &opts).unwrap();
        assert!(report.metrics.max_error_m <= e + h);
        // The checker sees the moved heights: without the tolerance it refuses.
        assert!(check_mesh(&g, &w, &CheckOptions::conforming(e + h)).is_err());
    }
}

#[test]
fn normals_decode_close_to_the_float_layout() {
    let g = tile();
    let m = mesh(&g, 5.0);
    let (fj, fbin) = split(&glb(&m, &g, &ExportOptions::DEFAULT));
    let off = |a: u64| {
        let a = &fj["accessors"][a as usize];
        fj["bufferViews"][a["bufferView"].as_u64().unwrap() as usize]["byteOffset"]
            .as_u64()
            .unwrap_or(0) as usize
    };
    let prim = &fj["meshes"][0]["primitives"][0];
    let n0 = off(prim["attributes"]["NORMAL"].as_u64().unwrap());
    let float_normal =
        |i: usize| [0, 1, 2].map(|c| f64::from(f32::from_bits(u32_at(&fbin, n0 + 12 * i + 4 * c))));
    let o = ExportOptions::DEFAULT.with_quantize(true);
    let (_, parts) = decode(&glb(&m, &g, &o));
    let (mut worst, mut sum, mut n) = (0f64, 0f64, 0usize);
    for d in &parts {
        let ids = vertex_ids(&g, &m, Coords::LocalMetres, d);
        for (got, &i) in d.normals.iter().zip(&ids) {
            let want = float_normal(i as usize);
            let cos = got[0] * want[0] + got[1] * want[1] + got[2] * want[2];
            let deg = cos.clamp(-1.0, 1.0).acos().to_degrees();
            worst = worst.max(deg);
            sum += deg;
            n += 1;
        }
    }
    let mean = sum / n as f64;
    eprintln!("normals: mean {mean:.2}°, worst {worst:.2}° off the float layout's");
    assert!(mean < 1.0, "mean {mean}°");
    assert!(worst < 10.0, "worst {worst}°");
}

#[test]
fn quantized_glb_is_at_most_0_55_of_the_float_one() {
    let g = tile();
    let m = mesh(&g, 5.0);
    let plain = glb(&m, &g, &ExportOptions::DEFAULT).len();
    let small = glb(&m, &g, &ExportOptions::DEFAULT.with_quantize(true)).len();
    let ratio = small as f64 / plain as f64;
    eprintln!("quantized {small} / float {plain} bytes = {ratio:.3}");
    assert!(ratio <= 0.55, "{ratio}");
}

#[test]
fn a_quantized_strip_is_refused() {
    let g = tile();
    let m = mesh(&g, 50.0);
    let o = ExportOptions::DEFAULT.with_quantize(true);
    let err = write_glb_strip(Vec::new(), &m, &[0, 1, 2], &g, &o).unwrap_err();
    assert!(matches!(err, ExportError::Incompatible { .. }), "{err}");
    assert!(err.to_string().contains("quantized"), "{err}");
}

/// Runs tools/gltf-validate on quantized GLBs, when its node_modules exists.
#[test]
fn quantized_glb_passes_the_khronos_validator() {
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
    let g = tile();
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    for (name, e, coords) in [
        ("local-5.glb", 5.0, Coords::LocalMetres),
        ("grid-1.glb", 1.0, Coords::Grid),
        ("local-50.glb", 50.0, Coords::LocalMetres),
    ] {
        let path = dir.path().join(name);
        let o = ExportOptions::DEFAULT
            .with_coords(coords)
            .with_quantize(true);
        std::fs::write(&path, glb(&mesh(&g, e), &g, &o)).unwrap();
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
