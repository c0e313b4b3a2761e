//! STL print scale (issue 23, item 7): `--scale 1:N` and `--size-mm W` write
//! the STL in millimetres, heights (times `--z-scale`) at the same scale;
//! combinations that make no sense are refused by name.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use crate::common;

use std::path::Path;

use common::{cota, stderr, stdout};

/// Every vertex of a binary STL, in file order.
fn stl_vertices(path: &Path) -> Vec<[f32; 3]> {
    let b = std::fs::read(path).unwrap();
    let n = u32::from_le_bytes(b[80..84].try_into().unwrap()) as usize;
    assert_eq!(b.len(), 84 + 50 * n);
    let f = |at: usize| f32::from_le_bytes(b[at..at + 4].try_into().unwrap());
    (0..n)
        .flat_map(|t| (1..4).map(move |v| 84 + 50 * t + 12 * v))
        .map(|at| [f(at), f(at + 4), f(at + 8)])
        .collect()
}

/// Meshes the bundled sample to `out` with `extra` flags; the JSON report.
fn mesh(out: &Path, extra: &[&str]) -> serde_json::Value {
    let args = [
        &[
            "mesh",
            "--max-error",
            "30",
            "--json",
            "-o",
            out.to_str().unwrap(),
        ],
        extra,
    ]
    .concat();
    let o = cota(&args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    serde_json::from_str(&stdout(&o)).unwrap()
}

/// True when `a` is `b` times `k`, to f32 precision.
fn scaled(a: &[[f32; 3]], b: &[[f32; 3]], k: [f64; 3]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(p, q)| {
            (0..3).all(|i| {
                let want = f64::from(q[i]) * k[i];
                (f64::from(p[i]) - want).abs() <= 1e-5 * want.abs().max(1.0)
            })
        })
}

#[test]
fn scale_writes_millimetres() {
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("plain.stl");
    let print = dir.path().join("print.stl");
    mesh(&plain, &[]);
    let r = mesh(&print, &["--scale", "1:100000"]);
    let (p, q) = (stl_vertices(&print), stl_vertices(&plain));
    // 1:100000: one metre of terrain is 0.01 mm of model.
    assert!(scaled(&p, &q, [0.01; 3]), "not 0.01 times the metres");
    assert_eq!(r["print_scale"], "1:100000");
    assert_eq!(r["print_mm_per_m"], 0.01);
    let size = r["print_size_mm"].as_array().unwrap();
    let max_x = p.iter().map(|v| v[0]).fold(0.0f32, f32::max);
    assert!(
        (size[0].as_f64().unwrap() - f64::from(max_x)).abs() < 1e-3,
        "{size:?} vs {max_x}"
    );
    let header = std::fs::read(&print).unwrap();
    assert!(String::from_utf8_lossy(&header[..80]).contains("x0.01"));
    // The factor as a number, and the text report's line.
    let same = dir.path().join("same.stl");
    mesh(&same, &["--scale", "0.00001"]);
    assert_eq!(
        std::fs::read(&same).unwrap(),
        std::fs::read(&print).unwrap()
    );
    let o = cota(&[
        "mesh",
        "--max-error",
        "30",
        "-o",
        same.to_str().unwrap(),
        "--scale",
        "1:100000",
    ]);
    assert!(
        stdout(&o).contains("print       1:100000"),
        "{}",
        stdout(&o)
    );
}

#[test]
fn size_mm_sets_the_longer_side_and_follows_z_scale() {
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("plain.stl");
    let print = dir.path().join("print.stl");
    mesh(&plain, &[]);
    let r = mesh(
        &print,
        &["--size-mm", "150", "--z-scale", "2", "--base-m", "-100"],
    );
    let p = stl_vertices(&print);
    let side = |i: usize| {
        let lo = p.iter().map(|v| v[i]).fold(f32::INFINITY, f32::min);
        let hi = p.iter().map(|v| v[i]).fold(f32::NEG_INFINITY, f32::max);
        f64::from(hi - lo)
    };
    assert!(
        (side(0).max(side(1)) - 150.0).abs() < 1e-3,
        "{} {}",
        side(0),
        side(1)
    );
    let k = r["print_mm_per_m"].as_f64().unwrap();
    let q = stl_vertices(&plain);
    // The surface facets come first: heights are twice the metres, times k.
    let surface = q.len();
    assert!(scaled(&p[..surface], &q, [k, k, 2.0 * k]));
    // The base of the solid is at -100 m, times 2, times k.
    let bottom = p.iter().map(|v| v[2]).fold(f32::INFINITY, f32::min);
    assert!((f64::from(bottom) + 200.0 * k).abs() < 1e-3, "{bottom}");
    let size = r["print_size_mm"].as_array().unwrap();
    assert!(
        (size[2].as_f64().unwrap() - side(2)).abs() < 1e-2,
        "{size:?} vs {}",
        side(2)
    );
}

#[test]
fn print_scales_that_make_no_sense_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let stl = dir.path().join("m.stl");
    let glb = dir.path().join("m.glb");
    let (s, g) = (stl.to_str().unwrap(), glb.to_str().unwrap());
    let cases: [(&[&str], &[&str]); 7] = [
        (&["--scale", "1:1000", "-o", g], &["--scale", ".stl"]),
        (&["--size-mm", "100", "-o", g], &["--size-mm", ".stl"]),
        (&["--scale", "1:1000"], &["--scale", "no output"]),
        (&["--size-mm", "0", "-o", s], &["--size-mm", "positive"]),
        (&["--size-mm", "nan", "-o", s], &["--size-mm", "positive"]),
        (&["--scale", "1:0", "-o", s], &["--scale", "1:N"]),
        (
            &["--scale", "1:1000", "--coords", "grid", "-o", s],
            &["--scale", "--coords"],
        ),
    ];
    for (flags, words) in cases {
        let o = cota(&[&["mesh", "--max-error", "30"], flags].concat());
        let err = stderr(&o);
        assert_ne!(o.status.code(), Some(0), "{flags:?} accepted");
        for w in words {
            assert!(err.contains(w), "{flags:?}: {w:?} not in {err}");
        }
    }
    let o = cota(&["mesh", "--scale", "1:1000", "--size-mm", "100", "-o", s]);
    let err = stderr(&o);
    assert!(
        err.contains("--scale") && err.contains("--size-mm"),
        "{err}"
    );
    assert!(!stl.exists() && !glb.exists());
}
