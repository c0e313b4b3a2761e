//! The `cota` binary end to end: the default run, JSON reports, bad arguments
//! and bad outputs.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use crate::common;
use common::*;

fn json(o: &std::process::Output) -> serde_json::Value {
    assert!(o.status.success(), "cota failed: {}", stderr(o));
    serde_json::from_str(&stdout(o)).expect("one JSON object")
}

#[test]
fn default_run_meshes_the_bundled_sample_within_bound() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.glb");
    let o = cota(&[
        "mesh",
        "--max-error",
        "5",
        "--check",
        "--json",
        "-o",
        out.to_str().unwrap(),
    ]);
    let r = json(&o);
    for k in [
        "vertices",
        "triangles",
        "max_error_m",
        "rmse_m",
        "build_ms",
        "extract_ms",
    ] {
        assert!(r.get(k).is_some(), "missing key {k}");
    }
    assert_eq!(r["width"], 1201);
    assert!(r["max_error_m"].as_f64().unwrap() <= 5.0);
    assert!(r["triangles"].as_u64().unwrap() < 2 * 1200 * 1200 / 4);
    assert_eq!(r["voids_filled"], 21);
    let bytes = std::fs::read(&out).unwrap();
    assert_eq!(&bytes[..4], b"glTF");
}

/// The default report measures while it writes (the writer on its own
/// thread); `--check` measures first, then writes. Both must give the same
/// bytes and the same figures, with and without a strip.
#[test]
fn measuring_while_writing_changes_neither_bytes_nor_figures() {
    let dir = tempfile::tempdir().unwrap();
    for (name, extra) in [("m.glb", None), ("s.glb", Some("--strip")), ("m.ply", None)] {
        let run = |check: bool| {
            let out = dir.path().join(format!("{check}-{name}"));
            let mut args = vec![
                "mesh",
                "--max-error",
                "5",
                "--json",
                "-o",
                out.to_str().unwrap(),
            ];
            args.extend(extra);
            if check {
                args.push("--check");
            }
            (json(&cota(&args)), std::fs::read(&out).unwrap())
        };
        let ((overlapped, a), (sequential, b)) = (run(false), run(true));
        assert!(a == b, "{name}: the bytes differ");
        for k in [
            "max_error_m",
            "rmse_m",
            "mean_abs_error_m",
            "sse_m2",
            "volume_m3",
        ] {
            assert_eq!(overlapped[k], sequential[k], "{name}: {k}");
        }
        assert_eq!(overlapped["checked"], false);
        let total = overlapped["total_ms"].as_f64().unwrap();
        assert!(total >= overlapped["write_ms"].as_f64().unwrap());
        assert!(total >= overlapped["measure_ms"].as_f64().unwrap());
    }
}

#[test]
fn budget_mode_uses_most_of_the_budget() {
    let o = cota(&["mesh", "--max-triangles", "50000", "--json"]);
    let r = json(&o);
    let n = r["triangles"].as_u64().unwrap();
    assert!(
        (45_000..=50_000).contains(&n),
        "{n} triangles for a 50000 budget"
    );
    assert!(r["max_error_m"].as_f64().unwrap() <= r["threshold_m"].as_f64().unwrap());
}

#[test]
fn info_json_has_the_documented_keys() {
    let f = fixture("hugo_site.asc");
    let r = json(&cota(&["info", "--json", f.to_str().unwrap()]));
    assert_eq!(r["width"], 76);
    assert_eq!(r["height"], 55);
    assert_eq!(r["nodata_count"], 2028);
    assert_eq!(r["min_m"], 1660.0);
    assert_eq!(r["max_m"], 1711.0);
    assert!(r["crs"].is_string());
    assert_eq!(r["cell_size_m"].as_array().unwrap().len(), 2);
}

#[test]
fn negative_error_zero_budget_and_conflicts_are_refused() {
    let o = cota(&["mesh", "--max-error", "-1"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("expected 0 m or more, found -1"),
        "{}",
        stderr(&o)
    );
    let o = cota(&["mesh", "--max-triangles", "0"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--max-triangles"), "{}", stderr(&o));
    let o = cota(&["mesh", "--max-triangles", "1"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("budget of at least"), "{}", stderr(&o));
    let o = cota(&["mesh", "--max-error", "1", "--max-triangles", "10"]);
    assert!(!o.status.success());
}

#[test]
fn unwritable_outputs_fail_cleanly_and_leave_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no/such/dir/out.glb");
    let o = cota(&["mesh", "-o", missing.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("out.glb"), "{}", stderr(&o));
    assert!(!missing.exists());
    let bad = dir.path().join("out.xyz");
    let o = cota(&["mesh", "-o", bad.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains(".obj"), "{}", stderr(&o));
    let o = cota(&["mesh", "-o", dir.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "nothing left behind"
    );
}

#[test]
fn missing_and_garbage_inputs_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let o = cota(&["info", "/no/such/N00E010.hgt"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("/no/such/N00E010.hgt"),
        "{}",
        stderr(&o)
    );
    let g = dir.path().join("x.png");
    std::fs::write(&g, "hello, I am text").unwrap();
    let o = cota(&["mesh", g.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("x.png") && e.contains("expected"), "{e}");
    assert_eq!(e.lines().count(), 1, "one-line error: {e}");
}

#[test]
fn all_four_formats_and_both_frames_are_written() {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["obj", "ply", "stl", "glb"] {
        for coords in ["local", "grid"] {
            let out = dir.path().join(format!("m-{coords}.{ext}"));
            let o = cota(&[
                "mesh",
                "--max-triangles",
                "2000",
                "--coords",
                coords,
                "-o",
                out.to_str().unwrap(),
            ]);
            assert!(o.status.success(), "{ext} {coords}: {}", stderr(&o));
            assert!(std::fs::metadata(&out).unwrap().len() > 1000);
        }
    }
    let out = dir.path().join("solid.stl");
    let o = cota(&[
        "mesh",
        "--max-triangles",
        "2000",
        "--base-m",
        "-100",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = cota(&[
        "mesh",
        "--base-m",
        "-100",
        "-o",
        dir.path().join("x.glb").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
}

#[test]
fn refuse_policy_rejects_voids() {
    let o = cota(&["mesh", "--voids", "refuse"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("void"), "{}", stderr(&o));
}

#[test]
fn quadtree_takes_every_criterion() {
    let r = json(&cota(&[
        "mesh",
        "--hierarchy",
        "quadtree",
        "--max-error",
        "5",
        "--check",
        "--json",
    ]));
    assert!(r["max_error_m"].as_f64().unwrap() <= 5.0);
    let fine = r["triangles"].as_u64().unwrap();
    let r = json(&cota(&[
        "mesh",
        "--hierarchy",
        "quadtree",
        "--criterion",
        "curvature",
        "--check",
        "--json",
    ]));
    assert!(r["criterion"].as_str().unwrap().contains("curvature"));
    let n = r["triangles"].as_u64().unwrap();
    assert!(n > 100 && n != fine, "{n} vs {fine}");
    let o = cota(&["mesh", "--hierarchy", "quadtree", "--mode", "fictitious"]);
    assert_eq!(o.status.code(), Some(1));
}
