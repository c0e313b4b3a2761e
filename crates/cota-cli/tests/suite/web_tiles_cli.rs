//! `cota mesh` on web-tile sizes (issue 22, item 3): a grid whose span is odd
//! is meshed on its extended grid and clipped back (`--odd-spans extend`, the
//! default), far leaner than its own hierarchy (`--odd-spans keep`), and
//! `--check` proves both on the real samples.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use crate::common;

use common::{cota, fixture, shared, stderr, stdout};

/// `cota mesh --json --check ARGS`, expected to succeed: its report.
fn mesh_json(args: &[&str]) -> serde_json::Value {
    let o = cota(&[&["mesh", "--json", "--check"], args].concat());
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    serde_json::from_str(&stdout(&o)).unwrap()
}

fn triangles(r: &serde_json::Value) -> u64 {
    r["triangles"].as_u64().unwrap()
}

#[test]
fn terrarium_fixture_256_is_extended_to_257() {
    let png = fixture("terrarium.png");
    let png = png.to_str().unwrap();
    let new = mesh_json(&[png, "--max-error", "50"]);
    let old = mesh_json(&[png, "--max-error", "50", "--odd-spans", "keep"]);
    assert_eq!(new["extended_to"], serde_json::json!([257, 257]));
    assert_eq!(old["extended_to"], serde_json::Value::Null);
    assert!(triangles(&new) * 2 < triangles(&old), "{new} {old}");
    assert_eq!(new["checked"], true);
    // The text report says so.
    let o = cota(&["mesh", png, "--max-error", "50"]);
    assert!(
        stdout(&o).contains("extended to 257 x 257"),
        "{}",
        stdout(&o)
    );
}

#[test]
fn strips_keep_the_grids_own_hierarchy() {
    let png = fixture("terrarium.png");
    let out = tempfile::tempdir().unwrap();
    let glb = out.path().join("t.glb");
    let r = mesh_json(&[
        png.to_str().unwrap(),
        "--max-error",
        "20",
        "--strip",
        "-o",
        glb.to_str().unwrap(),
    ]);
    assert_eq!(r["extended_to"], serde_json::Value::Null);
}

#[test]
fn real_512_web_tile_and_srtm_window() {
    let Some(tif) = shared("geotiff/mapzen-geotiff-14-10348-7801.tif") else {
        return;
    };
    let tif = tif.to_str().unwrap();
    let new = mesh_json(&[tif, "--max-error", "5"]);
    let old = mesh_json(&[tif, "--max-error", "5", "--odd-spans", "keep"]);
    assert_eq!(new["extended_to"], serde_json::json!([513, 513]));
    assert!(triangles(&new) * 3 < triangles(&old), "{new} {old}");
    let Some(hgt) = shared("srtm/N49E011.hgt.zip") else {
        return;
    };
    let hgt = hgt.to_str().unwrap();
    let crop = ["--crop", "600,600,256,256", "--max-error", "100"];
    let new = mesh_json(&[&[hgt][..], &crop].concat());
    let old = mesh_json(&[&[hgt][..], &crop, &["--odd-spans", "keep"]].concat());
    assert!(triangles(&new) * 3 < triangles(&old), "{new} {old}");
}
