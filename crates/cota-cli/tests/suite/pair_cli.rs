//! `cota pair` (paper 004) and `cota mesh --texture` on the Olinda DEM +
//! Landsat pair of `fixtures/`: the chosen pair fits and is the optimum of
//! the two lists, the GLB is within the budget and textured; bad input is a
//! clear error naming the file, with no output file.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use crate::common;
use common::*;

use std::path::Path;

fn json(o: &std::process::Output) -> serde_json::Value {
    assert!(o.status.success(), "cota failed: {}", stderr(o));
    serde_json::from_str(&stdout(o)).expect("one JSON object")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `cota pair` on the fixture pair with true colour and `extra` flags.
fn pair(budget: u64, out: &Path, extra: &[&str]) -> std::process::Output {
    let (dem, img) = (fixture("olinda_dem_utm25s.tif"), fixture("L7_ETMs.tif"));
    let b = budget.to_string();
    let mut args = vec!["pair", s(&dem), s(&img), "--bands", "3,2,1"];
    args.extend(["--budget-bytes", &b, "--json", "-o", s(out)]);
    args.extend(extra);
    cota(&args)
}

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap()
}

fn u(v: &serde_json::Value) -> u64 {
    v.as_u64().unwrap()
}

/// The GLB's JSON chunk.
fn glb_json(bytes: &[u8]) -> serde_json::Value {
    let u32_at = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap()) as usize;
    assert_eq!(&bytes[0..4], b"glTF");
    assert_eq!(u32_at(8), bytes.len());
    serde_json::from_slice(&bytes[20..20 + u32_at(12)]).unwrap()
}

/// Checks one report: the optimum is the exhaustive minimum over the lists
/// within the room, the greedy pair fits and is no better, the file is
/// within the budget.
fn check_report(r: &serde_json::Value, budget: u64, out: &Path) {
    let room = budget - u(&r["frame_reserve_bytes"]);
    let (alpha, beta) = (f(&r["alpha"]), f(&r["beta"]));
    let (ms, ts) = (
        r["meshes"].as_array().unwrap(),
        r["textures"].as_array().unwrap(),
    );
    let mut best = f64::INFINITY;
    for m in ms {
        for t in ts {
            if u(&m["bytes"]) + u(&t["bytes"]) <= room {
                best = best.min(alpha * f(&m["d_mesh_m2"]) + beta * f(&t["d_texture"]));
            }
        }
    }
    let o = &r["optimum"];
    assert!(u(&o["bytes"]) <= room, "the optimum does not fit: {o}");
    assert_eq!(u(&o["bytes"]), u(&o["mesh_bytes"]) + u(&o["texture_bytes"]));
    assert!(
        (f(&o["distortion"]) - best).abs() <= 1e-9 * best.max(1.0),
        "{o} vs {best}"
    );
    let g = &r["greedy"];
    if !g.is_null() {
        assert!(u(&g["bytes"]) <= room);
        assert!(f(&g["distortion"]) >= f(&o["distortion"]));
    }
    let len = std::fs::metadata(out).unwrap().len();
    assert!(len == u(&r["glb_bytes"]) && len <= budget, "{len} bytes");
}

#[test]
fn the_chosen_pair_fits_is_optimal_and_is_written_textured() {
    let dir = tempfile::tempdir().unwrap();
    let mut last = f64::INFINITY;
    for budget in [60_000u64, 200_000, 600_000] {
        let out = dir.path().join(format!("p{budget}.glb"));
        let r = json(&pair(budget, &out, &[]));
        check_report(&r, budget, &out);
        // More budget, no more distortion.
        let d = f(&r["optimum"]["distortion"]);
        assert!(d <= last, "{d} after {last}");
        last = d;
        // The zero tolerance texture is lossless; more tolerance, fewer leaves.
        let ts = r["textures"].as_array().unwrap();
        assert_eq!((f(&ts[0]["tolerance"]), u(&ts[0]["d_texture"])), (0.0, 0));
        assert!(ts
            .windows(2)
            .all(|w| u(&w[1]["leaves"]) < u(&w[0]["leaves"])));
        let j = glb_json(&std::fs::read(&out).unwrap());
        assert_eq!(json_attr(&j, "TEXCOORD_0"), 1);
        assert_eq!(j["extensionsUsed"][0], "KHR_materials_unlit");
        assert_eq!(j["images"][0]["mimeType"], "image/png");
    }
    // Weighted: the optimum of alpha D(M) + beta D(T), and the greedy pick.
    let out = dir.path().join("w.glb");
    let r = json(&pair(200_000, &out, &["--alpha", "10", "--beta", "0.5"]));
    check_report(&r, 200_000, &out);
    let out = dir.path().join("g.glb");
    let r = json(&pair(200_000, &out, &["--pick", "greedy"]));
    check_report(&r, 200_000, &out);
    assert_eq!(r["picked"], "greedy");
}

fn json_attr(j: &serde_json::Value, name: &str) -> u64 {
    u(&j["meshes"][0]["primitives"][0]["attributes"][name])
}

/// `args` fail, stderr holds every one of `words`, and `out` is not there.
fn refused(args: &[&str], words: &[&str], out: &Path) {
    let o = cota(args);
    let e = stderr(&o);
    assert!(!o.status.success(), "{args:?} succeeded");
    assert!(words.iter().all(|w| e.contains(w)), "{args:?}: {e}");
    assert!(!e.contains("panicked"), "{e}");
    assert!(!out.exists(), "{} written", out.display());
}

#[test]
fn bad_input_is_a_clear_error_and_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.glb");
    let o = s(&out);
    let (dem, img) = (fixture("olinda_dem_utm25s.tif"), fixture("L7_ETMs.tif"));
    let srtm = fixture("S29W072.hgt.zip");
    let b = ["--bands", "3,2,1", "-o", o];
    // A mismatched image and DEM: UTM 25S imagery on a geographic SRTM tile.
    let mut args = vec!["pair", s(&srtm), s(&img), "--budget-bytes", "200000"];
    args.extend(b);
    refused(&args, &["L7_ETMs.tif", "EPSG:4326", "EPSG:31985"], &out);
    // A one-band image where three bands are asked for.
    let mut args = vec!["pair", s(&dem), s(&dem), "--budget-bytes", "200000"];
    args.extend(b);
    refused(&args, &["olinda_dem_utm25s.tif", "found 1 band"], &out);
    // A budget too small for any pair, and one under the GLB's frame.
    let mut args = vec!["pair", s(&dem), s(&img), "--budget-bytes", "6000"];
    args.extend(b);
    refused(
        &args,
        &["--budget-bytes", "no (mesh, texture) pair fits"],
        &out,
    );
    let mut args = vec!["pair", s(&dem), s(&img), "--budget-bytes", "100"];
    args.extend(b);
    refused(&args, &["--budget-bytes", "found 100"], &out);
    // Not a .glb; a missing image.
    let obj = dir.path().join("x.obj");
    let args = [
        "pair",
        s(&dem),
        s(&img),
        "--budget-bytes",
        "200000",
        "-o",
        s(&obj),
    ];
    refused(&args, &["x.obj", ".glb"], &obj);
    let none = dir.path().join("none.tif");
    let args = [
        "pair",
        s(&dem),
        s(&none),
        "--budget-bytes",
        "200000",
        "-o",
        o,
    ];
    refused(&args, &["none.tif"], &out);
    // cota mesh --texture: a .glb output and a three-band image.
    let args = ["mesh", s(&dem), "--texture", s(&img), "-o", s(&obj)];
    refused(&args, &["x.obj", ".glb"], &obj);
    let args = [
        "mesh",
        s(&dem),
        "--texture",
        s(&dem),
        "--bands",
        "3,2,1",
        "-o",
        o,
    ];
    refused(&args, &["olinda_dem_utm25s.tif", "found 1 band"], &out);
}

#[test]
fn mesh_texture_drapes_the_whole_image() {
    let dir = tempfile::tempdir().unwrap();
    let (dem, jpg) = (fixture("olinda_dem_utm25s.tif"), fixture("L7_ETMs_321.jpg"));
    for mode in ["bitree", "tin"] {
        let out = dir.path().join(format!("{mode}.glb"));
        let args = ["mesh", s(&dem), "--mesh", mode, "--max-error", "5"];
        let o = cota(&[&args[..], &["--texture", s(&jpg), "-o", s(&out)]].concat());
        assert!(o.status.success(), "{}", stderr(&o));
        let j = glb_json(&std::fs::read(&out).unwrap());
        assert_eq!(json_attr(&j, "TEXCOORD_0"), 1);
        assert!(j["materials"][0]["extensions"]["KHR_materials_unlit"].is_object());
    }
}
