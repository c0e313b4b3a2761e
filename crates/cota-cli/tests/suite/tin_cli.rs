//! `cota mesh --mesh tin`: the TIN goes through the same check, report and
//! write path as the bitree's mesh, with fewer triangles; `--lock-border`
//! makes real adjacent tiles share their border vertices; bad flag mixes are
//! refused.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use crate::common;
use common::*;

use std::collections::BTreeSet;
use std::path::Path;

fn json(o: &std::process::Output) -> serde_json::Value {
    assert!(o.status.success(), "cota failed: {}", stderr(o));
    serde_json::from_str(&stdout(o)).expect("one JSON object")
}

/// The `(column, row)` of the vertices of an OBJ written with
/// `--coords grid` (x = column, y = row from the north).
fn obj_vertices(p: &Path) -> Vec<(u32, u32)> {
    std::fs::read_to_string(p)
        .unwrap()
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let mut it = l.split_whitespace().map(|x| x.parse::<f64>().unwrap());
            let (x, y) = (it.next().unwrap(), it.next().unwrap());
            (x.round() as u32, y.round() as u32)
        })
        .collect()
}

#[test]
fn tin_is_checked_and_smaller_than_the_bitree_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.ply");
    let tin = json(&cota(&[
        "mesh",
        "--mesh",
        "tin",
        "--max-error",
        "5",
        "--check",
        "--json",
        "-o",
        out.to_str().unwrap(),
    ]));
    let bitree = json(&cota(&["mesh", "--max-error", "5", "--json"]));
    assert_eq!(tin["mesh"], "tin");
    assert_eq!(tin["checked"], true);
    // Within the bound up to the checker's floating-point slack (ties at
    // exactly 5 m are decided exactly; a plane evaluated in another
    // triangle may round 1e-13 m above).
    assert!(tin["max_error_m"].as_f64().unwrap() <= 5.0 + 1e-9 * 1899.0);
    let (t, b) = (
        tin["triangles"].as_u64().unwrap(),
        bitree["triangles"].as_u64().unwrap(),
    );
    assert!((t as f64) < 0.7 * b as f64, "tin {t} vs bitree {b}");
    assert!(std::fs::metadata(&out).unwrap().len() > 0);
    // The text report names the TIN.
    let o = cota(&["mesh", "--mesh", "tin", "--max-error", "20", "--check"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("refinement  tin, conforming"),
        "{}",
        stdout(&o)
    );
}

#[test]
fn tin_budget() {
    let r = json(&cota(&[
        "mesh",
        "--mesh",
        "tin",
        "--max-triangles",
        "30000",
        "--check",
        "--json",
    ]));
    let n = r["triangles"].as_u64().unwrap();
    assert!((25_000..=30_000).contains(&n), "{n} triangles for 30000");
    assert!(r["max_error_m"].as_f64().unwrap() <= r["threshold_m"].as_f64().unwrap() + 1e-6);
}

#[test]
fn locked_borders_of_real_adjacent_tiles_match() {
    let (Some(west), Some(east)) = (shared("srtm/N00E010.hgt"), shared("srtm/N00E011.hgt.zip"))
    else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let mut cols = Vec::new();
    for (tile, name, col) in [(&west, "w.obj", 1200), (&east, "e.obj", 0)] {
        let out = dir.path().join(name);
        let o = cota(&[
            "mesh",
            tile.to_str().unwrap(),
            "--mesh",
            "tin",
            "--lock-border",
            "--max-error",
            "10",
            "--check",
            "--coords",
            "grid",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let rows: BTreeSet<u32> = obj_vertices(&out)
            .into_iter()
            .filter(|v| v.0 == col)
            .map(|v| v.1)
            .collect();
        cols.push(rows);
    }
    assert!(cols[0].len() > 2, "the shared column is not flat");
    assert_eq!(cols[0], cols[1]);
}

#[test]
fn tin_refuses_what_it_cannot_do() {
    for args in [
        &["mesh", "--lock-border", "--max-error", "5"][..],
        &["mesh", "--mesh", "tin", "--strip", "-o", "x.glb"],
        &["mesh", "--mesh", "tin", "--hierarchy", "quadtree"],
        &["mesh", "--mesh", "tin", "--mode", "fictitious"],
        &["mesh", "--mesh", "tin", "--max-error", "-1"],
    ] {
        let o = cota(args);
        assert!(!o.status.success(), "{args:?} was accepted");
        assert!(stderr(&o).contains("expected"), "{args:?}: {}", stderr(&o));
    }
}
