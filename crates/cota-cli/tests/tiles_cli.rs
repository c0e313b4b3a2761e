//! `cota tiles` end to end: the bundled sample into a pyramid, the report,
//! a resumed run, and a projected input refused with its CRS named.
#![allow(clippy::unwrap_used, clippy::panic)]

mod common;

use common::{cota, stderr, stdout};

#[test]
fn sample_pyramid_report_and_resume() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tiles");
    let o = out.to_str().unwrap();
    let r = cota(&[
        "tiles",
        "--max-zoom",
        "7",
        "--normals",
        "--metadata",
        "--check",
        "--json",
        "-o",
        o,
    ]);
    assert!(r.status.success(), "{}", stderr(&r));
    let v: serde_json::Value = serde_json::from_str(&stdout(&r)).unwrap();
    let tiles = v["tiles"].as_u64().unwrap();
    assert!(tiles > 5 && v["written"].as_u64() == Some(tiles), "{v}");
    for z in v["zooms"].as_array().unwrap() {
        assert!(
            z["measured_error_m"].as_f64().unwrap() <= z["max_error_m"].as_f64().unwrap(),
            "{z}"
        );
    }
    assert!(v["check"].as_str().unwrap().starts_with("passed"), "{v}");
    assert!(out.join("layer.json").is_file() && out.join("0/0/0.terrain").is_file());
    let again = cota(&[
        "tiles",
        "--max-zoom",
        "7",
        "--normals",
        "--metadata",
        "-o",
        o,
    ]);
    assert!(again.status.success(), "{}", stderr(&again));
    assert!(
        stdout(&again).contains(&format!("0 written, {tiles} skipped")),
        "{}",
        stdout(&again)
    );
    let changed = cota(&["tiles", "--max-zoom", "7", "-o", o]);
    assert!(!changed.status.success());
    assert!(stderr(&changed).contains("--force"), "{}", stderr(&changed));
}

#[test]
fn projected_input_is_refused_naming_its_crs() {
    let Some(f) = common::shared("texture/olinda_dem_utm25s.tif") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let r = cota(&[
        "tiles",
        f.to_str().unwrap(),
        "-o",
        dir.path().join("t").to_str().unwrap(),
    ]);
    assert!(!r.status.success());
    let e = stderr(&r);
    assert!(
        e.contains("geographic") && e.to_lowercase().contains("utm"),
        "{e}"
    );
}
