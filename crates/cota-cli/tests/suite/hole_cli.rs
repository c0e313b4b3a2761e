//! `cota mesh --voids hole`: a void-heavy window of a real tile is meshed
//! with holes, checked by the one checker and written in every format;
//! the reports say `voids: hole` with the area left out; STL with
//! `--base-m`, `cota stream` and `cota compare` refuse clearly and write
//! nothing.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use crate::common;
use common::*;

use std::fmt::Write;
use std::path::{Path, PathBuf};

/// A 129² window of the bundled real tile (SRTM 3", Andes) with a blanked
/// disc and its own voids, written as ESRI ASCII (NODATA -9999) in `dir`.
fn void_heavy_asc(dir: &Path) -> PathBuf {
    let s = cota_fixtures::bundled_tile().crop(850, 600, 129, 129);
    let mut text = String::from(
        "ncols 129\nnrows 129\nxllcorner 0\nyllcorner 0\ncellsize 90\nNODATA_value -9999\n",
    );
    for r in 0..129 {
        for c in 0..129 {
            let (x, y) = (c as f64 - 70.0, r as f64 - 60.0);
            let h = s.heights[r * 129 + c];
            let void = h.is_nan() || x * x + y * y < 25.0 * 25.0 || (r < 20 && c < 40);
            let v = if void { -9999.0 } else { h };
            write!(text, "{v} ").unwrap();
        }
        text.push('\n');
    }
    let p = dir.join("voids.asc");
    std::fs::write(&p, text).unwrap();
    p
}

fn json(o: &std::process::Output) -> serde_json::Value {
    assert!(o.status.success(), "cota failed: {}", stderr(o));
    serde_json::from_str(&stdout(o)).expect("one JSON object")
}

#[test]
fn every_writer_takes_a_checked_mesh_with_holes() {
    let dir = tempfile::tempdir().unwrap();
    let input = void_heavy_asc(dir.path());
    let mut triangles = None;
    for ext in ["obj", "ply", "stl", "glb"] {
        let out = dir.path().join(format!("m.{ext}"));
        let r = json(&cota(&[
            "mesh",
            input.to_str().unwrap(),
            "--voids",
            "hole",
            "--max-error",
            "3",
            "--check",
            "--json",
            "-o",
            out.to_str().unwrap(),
        ]));
        assert_eq!(r["voids"], "hole");
        assert!(r["nodata_count"].as_u64().unwrap() > 1500, "{r}");
        // At least the disc's area (π·25² cells of 90 m) is left out.
        let area = r["area_left_out_m2"].as_f64().unwrap();
        assert!(area > 1900.0 * 8100.0, "{r}");
        assert!(r["triangles_left_out"].as_u64().unwrap() > 0);
        assert!(r["max_error_m"].as_f64().unwrap() <= 3.0);
        assert!(std::fs::metadata(&out).unwrap().len() > 1000);
        let t = r["triangles"].as_u64().unwrap();
        assert_eq!(*triangles.get_or_insert(t), t);
    }
    // The text report.
    let o = cota(&[
        "mesh",
        input.to_str().unwrap(),
        "--voids",
        "hole",
        "--check",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(
        text.contains("voids       hole:") && text.contains("m2 left out"),
        "{text}"
    );
    assert!(text.contains("bound holds at every valid sample"), "{text}");
    // Quantized GLB too.
    let out = dir.path().join("q.glb");
    let r = json(&cota(&[
        "mesh",
        input.to_str().unwrap(),
        "--voids",
        "hole",
        "--quantize",
        "--check",
        "--json",
        "-o",
        out.to_str().unwrap(),
    ]));
    assert_eq!(r["voids"], "hole");
}

#[test]
fn what_cannot_leave_holes_refuses_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let input = void_heavy_asc(dir.path());
    let inp = input.to_str().unwrap();
    let stl = dir.path().join("solid.stl");
    let o = cota(&[
        "mesh",
        inp,
        "--voids",
        "hole",
        "--base-m",
        "10",
        "-o",
        stl.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--voids hole") && stderr(&o).contains("--base-m"));
    assert!(!stl.exists(), "nothing written");
    let s = dir.path().join("s.cota");
    let o = cota(&[
        "stream",
        "encode",
        inp,
        "--voids",
        "hole",
        "-o",
        s.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--voids hole"), "{}", stderr(&o));
    assert!(!s.exists());
    let o = cota(&["compare", inp, "--voids", "hole"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--voids hole"), "{}", stderr(&o));
    for extra in [
        ["--mesh", "tin"],
        ["--mode", "fictitious"],
        ["--max-triangles", "100"],
    ] {
        let mut args = vec!["mesh", inp, "--voids", "hole"];
        args.extend(extra);
        let o = cota(&args);
        assert!(!o.status.success(), "{extra:?}");
        assert!(stderr(&o).contains("--voids hole"), "{}", stderr(&o));
    }
}
