//! `cota mesh --crop` and `--bbox` (issue 23, item 7): a window of the input,
//! in samples or in the input's CRS units.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

mod common;

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
