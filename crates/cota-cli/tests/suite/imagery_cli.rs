//! `cota tiles --imagery` writes shaded-relief PNG tiles beside the terrain
//! (`OUT/imagery/{z}/{x}/{y}.png`, `OUT/imagery/imagery.json`); `cota serve
//! --addr` refuses what is not HOST:PORT, naming it.
#![allow(clippy::unwrap_used, reason = "tests")]

use crate::common;

use common::{cota, stderr};

#[test]
fn tiles_with_imagery_writes_relief_pngs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t");
    let o = cota(&["tiles", "-o", out.to_str().unwrap(), "--imagery"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("layer.json").is_file());
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("imagery/imagery.json")).unwrap()).unwrap();
    assert_eq!(meta["scheme"], "tms");
    let z = meta["maxzoom"].as_u64().unwrap();
    assert!(z >= 9, "{meta}");
    // Zoom 0: the western half of the world holds S29W072.
    let png = std::fs::read(out.join("imagery/0/0/0.png")).unwrap();
    assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"));
    let deepest = std::fs::read_dir(out.join(format!("imagery/{z}")))
        .unwrap()
        .count();
    assert!(deepest > 4, "{deepest} columns at zoom {z}");
    assert!(stderr(&o).contains("shaded-relief tiles"), "{}", stderr(&o));
}

#[test]
fn serve_refuses_a_bad_address() {
    let o = cota(&["serve", "--addr", "no-port-here"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--addr no-port-here"), "{}", stderr(&o));
}
