//! `cota mesh --crop` and `--bbox` (issue 23, item 7): a window of the input,
//! in samples or in the input's CRS units.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use crate::common;

use common::{cota, shared, stderr, stdout};

/// `cota mesh --json --check ARGS`, expected to succeed: its report.
fn mesh_json(args: &[&str]) -> serde_json::Value {
    let o = cota(&[&["mesh", "--json", "--check", "--max-error", "2"], args].concat());
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    serde_json::from_str(&stdout(&o)).unwrap()
}

#[test]
fn bbox_in_degrees_is_the_same_window_as_crop_in_samples() {
    let Some(tile) = shared("srtm/N00E010.hgt") else {
        return;
    };
    let tile = tile.to_str().unwrap();
    // N00E010 spans 10..11°E, 0..1°N at 1/1200°: the box's sample centres
    // are columns 300..=600 and rows (from the north) 600..=900.
    let b = mesh_json(&[tile, "--bbox", "10.25,0.25,10.5,0.5"]);
    let c = mesh_json(&[tile, "--crop", "300,600,301,301"]);
    assert_eq!(
        (b["width"].as_u64(), b["height"].as_u64()),
        (Some(301), Some(301))
    );
    for k in [
        "width",
        "height",
        "triangles",
        "vertices",
        "max_error_m",
        "volume_m3",
    ] {
        assert_eq!(b[k], c[k], "{k}");
    }
    // --bbox belongs to every command reading DEMs: `info` describes the window.
    let o = cota(&["info", "--json", tile, "--bbox", "10.25,0.25,10.5,0.5"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let i: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(
        (i["width"].as_u64(), i["height"].as_u64()),
        (Some(301), Some(301))
    );
    let whole = mesh_json(&[tile]);
    assert!(b["triangles"].as_u64() < whole["triangles"].as_u64());
}

#[test]
fn bbox_across_a_mosaic_seam() {
    let (Some(w), Some(e)) = (shared("srtm/N00E010.hgt"), shared("srtm/N00E011.hgt.zip")) else {
        return;
    };
    let (w, e) = (w.to_str().unwrap(), e.to_str().unwrap());
    let v = mesh_json(&[w, e, "--bbox=10.9,0.1,11.1,0.2"]);
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(241), Some(121))
    );
}

#[test]
fn bad_windows_are_refused_by_name() {
    for (args, want) in [
        (vec!["--bbox=-10,0,-9,1"], "--bbox"),
        (vec!["--bbox", "11,0,10,1"], "WEST < EAST"),
        (vec!["--bbox", "1,2,3"], "W,S,E,N"),
        (vec!["--bbox", "1,2,nan,4"], "W,S,E,N"),
        (vec!["--crop", "0,0,1,5"], "--crop"),
        (vec!["--crop", "1200,0,2,2"], "--crop"),
    ] {
        let o = cota(&[&["mesh"], &args[..]].concat());
        let err = stderr(&o);
        assert!(matches!(o.status.code(), Some(1 | 2)), "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {err}");
    }
    let o = cota(&["mesh", "--crop", "0,0,2,2", "--bbox", "1,2,3,4"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

/// `cota info --each` (issue 23, item 7): unrelated files, each on its own.
#[test]
fn info_each_describes_unrelated_files_without_mosaicking_them() {
    let (Some(a), Some(b)) = (shared("srtm/N00E010.hgt"), shared("srtm/N49E011.hgt.zip")) else {
        return;
    };
    let (a, b) = (a.to_str().unwrap(), b.to_str().unwrap());
    // Mosaicked, they are far apart: refused.
    let o = cota(&["info", a, b]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let o = cota(&["info", "--each", "--json", a, b]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let each = v.as_array().unwrap();
    assert_eq!(each.len(), 2);
    for (r, f) in each.iter().zip([a, b]) {
        assert_eq!(r["files"][0]["path"].as_str(), Some(f), "{r}");
        assert_eq!(r["width"].as_u64(), Some(1201), "{r}");
        assert!(r["seams"].is_null(), "{r}");
    }
    let o = cota(&["info", "--each", a, b]);
    let text = stdout(&o);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        text.contains(a) && text.contains(b) && !text.contains("mosaic"),
        "{text}"
    );
}

/// The `v x y z` lines of an OBJ file.
fn obj_vertices(path: &std::path::Path) -> Vec<[f64; 3]> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|p| p.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}

/// `cota mesh --z-scale` (issue 23, item 7): written heights (and the STL
/// base) are exaggerated, the report stays in true metres.
#[test]
fn z_scale_multiplies_the_written_heights_only() {
    let dir = tempfile::tempdir().unwrap();
    let (one, two) = (dir.path().join("one.obj"), dir.path().join("two.obj"));
    let run = |out: &std::path::Path, z: &str| {
        let o = cota(&[
            "mesh",
            "--json",
            "--max-error",
            "5",
            "--z-scale",
            z,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        serde_json::from_str::<serde_json::Value>(&stdout(&o)).unwrap()
    };
    let (r1, r2) = (run(&one, "1"), run(&two, "2.5"));
    assert_eq!(r2["z_scale"].as_f64(), Some(2.5));
    assert_eq!(
        r1["max_error_m"], r2["max_error_m"],
        "errors stay in true metres"
    );
    let (v1, v2) = (obj_vertices(&one), obj_vertices(&two));
    assert_eq!(v1.len(), v2.len());
    assert!(v1.iter().any(|v| v[2] > 100.0));
    for (a, b) in v1.iter().zip(&v2) {
        assert_eq!((a[0], a[1]), (b[0], b[1]));
        assert!(
            (b[2] - 2.5 * a[2]).abs() <= 1e-3 * a[2].abs().max(1.0),
            "{a:?} {b:?}"
        );
    }
    for bad in ["0", "-1", "nan", "inf"] {
        let o = cota(&["mesh", "--z-scale", bad]);
        assert_eq!(o.status.code(), Some(1), "{bad}");
        assert!(stderr(&o).contains("--z-scale"), "{bad}: {}", stderr(&o));
    }
    let glb = dir.path().join("q.glb");
    let o = cota(&[
        "mesh",
        "--quantize",
        "--z-scale",
        "2",
        "-o",
        glb.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
}
