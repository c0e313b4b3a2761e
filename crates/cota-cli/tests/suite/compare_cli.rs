//! `cota compare`: the documented JSON keys on the 65×65 crop of docs/compare.md,
//! and flag validation.
#![allow(clippy::unwrap_used, reason = "tests")]

use crate::common;
use common::*;

#[test]
fn json_on_the_65_crop_has_the_documented_keys() {
    let o = cota(&[
        "compare",
        "--crop",
        "824,792,65,65",
        "--tolerances",
        "0,2,50",
        "--modes",
        "conforming,faithful",
        "--check",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    for k in [
        "input", "crop", "width", "height", "min_m", "max_m", "range_m", "checked", "modes",
        "quadtree", "rows",
    ] {
        assert!(v.get(k).is_some(), "missing {k}");
    }
    assert_eq!(v["width"], 65);
    assert_eq!(v["crop"], serde_json::json!([824, 792, 65, 65]));
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 4);
    assert_eq!(rows[0]["label"], "full");
    let mut last_tris = usize::MAX;
    for row in rows {
        for k in [
            "label",
            "tolerance_pct",
            "tolerance_m",
            "entries",
            "savings",
        ] {
            assert!(row.get(k).is_some(), "missing row key {k}");
        }
        let entries = row["entries"].as_array().unwrap();
        // 2 bitree modes + 2 quadtree variants.
        assert_eq!(entries.len(), 4);
        for e in entries {
            for k in [
                "hierarchy",
                "mode",
                "vertices",
                "triangles",
                "added",
                "transmitted",
                "selected",
                "base",
                "fictitious",
                "added_by_forced_splits",
                "line_triangles",
                "separate_refs",
                "strip_refs",
                "max_error_m",
            ] {
                assert!(e.get(k).is_some(), "missing entry key {k}");
            }
            let t = e["triangles"].as_u64().unwrap();
            // One strip: at least one reference per triangle plus 2, and
            // well under 3 per triangle (cota_core::strip).
            let strip = e["strip_refs"].as_u64().unwrap();
            assert!(
                strip >= t + 2 && strip <= 3 * t,
                "strip refs {strip} for {t}"
            );
            assert_eq!(e["separate_refs"].as_u64().unwrap(), 3 * t);
            if let Some(tol) = row["tolerance_m"].as_f64() {
                assert!(e["max_error_m"].as_f64().unwrap() <= tol + 1e-6);
            }
        }
        for s in row["savings"].as_array().unwrap() {
            for k in [
                "mode",
                "quadtree",
                "added_pct",
                "transmitted_pct",
                "triangles_pct",
            ] {
                assert!(s.get(k).is_some(), "missing saving key {k}");
            }
        }
        // Tighter tolerance first after "full": the quadtree's triangles fall.
        let qt = entries
            .iter()
            .find(|e| e["hierarchy"] == "quadtree" && e["mode"] == "templates")
            .unwrap();
        let t = qt["triangles"].as_u64().unwrap() as usize;
        assert!(t <= last_tris);
        last_tris = t;
    }
}

#[test]
fn rejects_bad_crops_and_tolerances() {
    let o = cota(&["compare", "--crop", "1200,0,65,65"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--crop"), "{}", stderr(&o));
    let o = cota(&["compare", "--crop", "1,2,3"]);
    assert!(!o.status.success());
    let o = cota(&["compare", "--tolerances", "-1"]);
    assert!(!o.status.success());
}

#[test]
fn mesh_with_the_quadtree_hierarchy_is_checked() {
    for leaves in ["templates", "centre-when-needed"] {
        let o = cota(&[
            "mesh",
            "--hierarchy",
            "quadtree",
            "--quadtree-leaves",
            leaves,
            "--max-error",
            "20",
            "--check",
            "--json",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
        assert_eq!(v["hierarchy"], "quadtree");
        assert!(v["max_error_m"].as_f64().unwrap() <= 20.0);
    }
    let o = cota(&["mesh", "--hierarchy", "quadtree", "--max-triangles", "100"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--hierarchy quadtree"));
}
