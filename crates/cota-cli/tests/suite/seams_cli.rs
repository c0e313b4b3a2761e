//! Seams between adjacent tiles (issue 23, item 5): a disagreement above
//! `--seam-tolerance` warns naming both files, fails with `--strict`, and the
//! seam statistics appear in `cota mesh --json`.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use crate::common;

use std::path::{Path, PathBuf};

use common::{cota, shared, stderr, stdout};

/// Samples per side of a 3" SRTM tile.
const N: usize = 1201;
/// SRTM's void value.
const VOID: i16 = -32768;

/// Writes `dir/N00E010.hgt` (the real tile) and `dir/N00E011.hgt`, the same
/// bytes except its west column, which is the real tile's east column plus
/// `offset_m` (voids kept): the two overlap on that column and disagree there
/// by exactly `offset_m` wherever both are valid.
fn offset_pair(dir: &Path, offset_m: i16) -> Option<(PathBuf, PathBuf)> {
    let real = shared("srtm/N00E010.hgt")?;
    let bytes = std::fs::read(real).unwrap();
    assert_eq!(bytes.len(), 2 * N * N);
    let mut east = bytes.clone();
    for row in 0..N {
        let at = |col: usize| 2 * (row * N + col);
        let h = i16::from_be_bytes([bytes[at(N - 1)], bytes[at(N - 1) + 1]]);
        let moved = if h == VOID { VOID } else { h + offset_m };
        east[at(0)..at(0) + 2].copy_from_slice(&moved.to_be_bytes());
    }
    let (w, e) = (dir.join("N00E010.hgt"), dir.join("N00E011.hgt"));
    std::fs::write(&w, bytes).unwrap();
    std::fs::write(&e, east).unwrap();
    Some((w, e))
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn a_seam_over_the_tolerance_warns_naming_both_files() {
    let dir = tempfile::tempdir().unwrap();
    let Some((w, e)) = offset_pair(dir.path(), 50) else {
        return;
    };
    let o = cota(&["info", s(&w), s(&e)]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("warning"), "{err}");
    assert!(err.contains(s(&w)) && err.contains(s(&e)), "{err}");
    assert!(err.contains("up to 50 m"), "{err}");
    assert!(err.contains("--seam-tolerance 5 m"), "{err}");
}

#[test]
fn strict_refuses_a_seam_over_the_tolerance() {
    let dir = tempfile::tempdir().unwrap();
    let Some((w, e)) = offset_pair(dir.path(), 50) else {
        return;
    };
    let o = cota(&["info", "--strict", s(&w), s(&e)]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains(s(&w)) && err.contains(s(&e)), "{err}");
    assert!(
        err.contains("up to 50 m") && err.contains("--strict"),
        "{err}"
    );
    let out = dir.path().join("m.obj");
    let o = cota(&["mesh", "--strict", s(&w), s(&e), "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(!out.exists(), "no output after a refused seam");
}

#[test]
fn a_seam_within_the_tolerance_is_silent_even_when_strict() {
    let dir = tempfile::tempdir().unwrap();
    let Some((w, e)) = offset_pair(dir.path(), 50) else {
        return;
    };
    let o = cota(&["info", "--strict", "--seam-tolerance", "50", s(&w), s(&e)]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(!err.contains("seam"), "{err}");
}

#[test]
fn mesh_json_reports_the_seams() {
    let dir = tempfile::tempdir().unwrap();
    let Some((w, e)) = offset_pair(dir.path(), 50) else {
        return;
    };
    let o = cota(&["mesh", "--json", "--max-error", "100", s(&w), s(&e)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let seams = &v["seams"];
    assert_eq!(seams["overlap_samples"], N, "{seams}");
    assert_eq!(seams["max_abs_diff_m"].as_f64(), Some(50.0), "{seams}");
    assert_eq!(seams["tolerance_m"].as_f64(), Some(5.0), "{seams}");
    assert_eq!(seams["within_tolerance"], false, "{seams}");
    let files = &seams["max_diff_at"]["files"];
    assert_eq!(files[0].as_str(), Some(s(&w)), "{seams}");
    assert_eq!(files[1].as_str(), Some(s(&e)), "{seams}");
    // One file: no seams.
    let o = cota(&["mesh", "--json", "--max-error", "100", s(&w)]);
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert!(v["seams"].is_null(), "{}", v["seams"]);
}

#[test]
fn the_real_adjacent_tiles_agree_on_their_seam() {
    let (Some(w), Some(e)) = (shared("srtm/N00E010.hgt"), shared("srtm/N00E011.hgt.zip")) else {
        return;
    };
    // The two real tiles hold the same values on their shared column: even a
    // zero tolerance passes, strictly.
    let args = ["info", "--json", "--strict", "--seam-tolerance", "0"];
    let o = cota(&[&args[..], &[s(&w), s(&e)]].concat());
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(!err.contains("warning"), "{err}");
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let seams = &v["seams"];
    assert_eq!(seams["compared"], N, "{seams}");
    assert_eq!(seams["max_abs_diff_m"].as_f64(), Some(0.0), "{seams}");
    assert_eq!(seams["within_tolerance"], true, "{seams}");
}

#[test]
fn a_negative_or_nan_seam_tolerance_is_refused_by_name() {
    for bad in ["-1", "nan"] {
        let o = cota(&["info", "--seam-tolerance", bad]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{bad}: {err}");
        assert!(err.contains("--seam-tolerance"), "{bad}: {err}");
    }
}
