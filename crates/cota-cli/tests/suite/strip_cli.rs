//! `cota mesh --strip`: a TRIANGLE_STRIP GLB and the strip counts in the
//! JSON report; refusals for non-GLB output and the quadtree.
#![allow(clippy::unwrap_used, reason = "tests")]

use crate::common;

use common::{cota, fixture, stderr, stdout};

#[test]
fn mesh_strip_writes_a_strip_glb_and_reports_refs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.glb");
    let sample = fixture("S29W072.hgt.zip");
    let o = cota(&[
        "mesh",
        sample.to_str().unwrap(),
        "--max-error",
        "20",
        "--mode",
        "fictitious-faithful",
        "--strip",
        "--json",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let tris = r["triangles"].as_f64().unwrap();
    let refs = r["strip_refs"].as_f64().unwrap();
    let per = r["strip_refs_per_triangle"].as_f64().unwrap();
    assert!((refs / tris - per).abs() < 1e-12);
    assert!(per > 1.0 && per < 1.5, "{per}");
    let bytes = std::fs::read(&out).unwrap();
    let json_len = u32::from_le_bytes([bytes[12], bytes[13], bytes[14], bytes[15]]) as usize;
    let text = std::str::from_utf8(&bytes[20..20 + json_len]).unwrap();
    assert!(text.contains("\"mode\":5"), "{text}");
}

#[test]
fn mesh_strip_refuses_other_formats_and_the_quadtree() {
    let dir = tempfile::tempdir().unwrap();
    let sample = fixture("S29W072.hgt.zip");
    let obj = dir.path().join("s.obj");
    let o = cota(&[
        "mesh",
        sample.to_str().unwrap(),
        "--strip",
        "-o",
        obj.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains(".glb"), "{}", stderr(&o));
    let o = cota(&[
        "mesh",
        sample.to_str().unwrap(),
        "--strip",
        "--hierarchy",
        "quadtree",
    ]);
    assert!(!o.status.success());
}

/// `--strip-method`: the default (cells) re-triangulates unit cells, says so
/// in the report, passes `--check` and needs fewer references than guided,
/// which needs fewer than the papers' traversal; the GLB holds the strip.
#[test]
fn mesh_strip_methods() {
    let dir = tempfile::tempdir().unwrap();
    let sample = fixture("S29W072.hgt.zip");
    let run = |method: Option<&str>| -> serde_json::Value {
        let out = dir
            .path()
            .join(format!("{}.glb", method.unwrap_or("default")));
        let mut args = vec![
            "mesh",
            sample.to_str().unwrap(),
            "--max-error",
            "1",
            "--strip",
            "--check",
            "--json",
            "-o",
            out.to_str().unwrap(),
        ];
        if let Some(m) = method {
            args.extend(["--strip-method", m]);
        }
        let o = cota(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(std::fs::metadata(&out).unwrap().len() > 0);
        serde_json::from_str(&stdout(&o)).unwrap()
    };
    let cells = run(None);
    let guided = run(Some("guided"));
    let traversal = run(Some("traversal"));
    assert_eq!(cells["strip_method"], "cells");
    assert_eq!(guided["strip_method"], "guided");
    assert_eq!(traversal["strip_method"], "traversal");
    assert_eq!(cells["strip_retriangulated"], true);
    assert!(cells["strip_flipped_cells"].as_u64().unwrap() > 0);
    assert_eq!(guided["strip_retriangulated"], false);
    assert_eq!(guided["strip_flipped_cells"], 0);
    // Same mesh, same error: the flip is exact.
    assert_eq!(cells["triangles"], guided["triangles"]);
    assert_eq!(cells["max_error_m"], guided["max_error_m"]);
    let per = |r: &serde_json::Value| r["strip_refs_per_triangle"].as_f64().unwrap();
    // Measured 1.33, 1.44, 1.63.
    assert!(
        per(&cells) < per(&guided) - 0.05,
        "{} {}",
        per(&cells),
        per(&guided)
    );
    assert!(per(&guided) < per(&traversal));
}

#[test]
fn mesh_strip_method_rejects_unknown_names() {
    let sample = fixture("S29W072.hgt.zip");
    let o = cota(&["mesh", sample.to_str().unwrap(), "--strip-method", "zigzag"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("cells"), "{}", stderr(&o));
}
