//! `cota stream encode|decode` end to end on the bundled SRTM tile: reports,
//! prefixes by bytes and by error, mesh output, and clear errors on truncated
//! or corrupted files.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use crate::common;
use common::*;

fn json(o: &std::process::Output) -> serde_json::Value {
    assert!(o.status.success(), "cota failed: {}", stderr(o));
    serde_json::from_str(&stdout(o)).expect("one JSON object")
}

#[test]
fn encode_then_decode_prefixes() {
    let dir = tempfile::tempdir().unwrap();
    let cs = dir.path().join("s.cstream");
    let cs_s = cs.to_str().unwrap();
    let r = json(&cota(&["stream", "encode", "-o", cs_s, "--json"]));
    let steps = r["steps"].as_array().unwrap();
    assert!(steps.len() >= 5);
    let total = r["bytes"].as_u64().unwrap();
    assert_eq!(std::fs::metadata(&cs).unwrap().len(), total);
    assert!(r["bytes_per_final_triangle"].as_f64().unwrap() <= 1.0);
    // The whole stream.
    let obj = dir.path().join("full.obj");
    let d = json(&cota(&[
        "stream",
        "decode",
        cs_s,
        "--json",
        "-o",
        obj.to_str().unwrap(),
    ]));
    assert_eq!(d["max_error_m"].as_f64(), Some(0.0));
    assert_eq!(d["triangles"], steps.last().unwrap()["triangles"]);
    assert!(obj.exists());
    // A prefix by bytes, written as GLB in grid coordinates.
    let cut = steps[4]["total_bytes"].as_u64().unwrap();
    let glb = dir.path().join("p.glb");
    let d = json(&cota(&[
        "stream",
        "decode",
        cs_s,
        "--max-bytes",
        &cut.to_string(),
        "--coords",
        "grid",
        "--json",
        "-o",
        glb.to_str().unwrap(),
    ]));
    assert_eq!(d["steps_used"], 5);
    assert_eq!(d["triangles"], steps[4]["triangles"]);
    assert!(glb.exists());
    // A prefix by error.
    let d = json(&cota(&[
        "stream",
        "decode",
        cs_s,
        "--max-error",
        "8",
        "--json",
    ]));
    assert!(d["max_error_m"].as_f64().unwrap() <= 8.0);
}

#[test]
fn truncated_and_corrupted_files_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let cs = dir.path().join("s.cstream");
    let o = cota(&[
        "stream",
        "encode",
        "-o",
        cs.to_str().unwrap(),
        "--max-error",
        "20",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&cs).unwrap();
    let cut = dir.path().join("cut.cstream");
    std::fs::write(&cut, &bytes[..bytes.len() - 5]).unwrap();
    let o = cota(&["stream", "decode", cut.to_str().unwrap(), "--strict"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("cut.cstream") && e.contains("truncated"), "{e}");
    assert!(e.contains("expected") && e.contains("found"), "{e}");
    let bad = dir.path().join("bad.cstream");
    let mut b = bytes.clone();
    let k = b.len() / 2;
    b[k] ^= 0x40;
    std::fs::write(&bad, &b).unwrap();
    let o = cota(&["stream", "decode", bad.to_str().unwrap()]);
    let e = stderr(&o);
    assert!(!o.status.success());
    assert!(e.contains("bad.cstream") && e.contains("CRC-32"), "{e}");
    let o = cota(&["stream", "decode", cota_missing(&dir).as_str()]);
    assert!(stderr(&o).contains("missing.cstream"), "{}", stderr(&o));
}

fn cota_missing(dir: &tempfile::TempDir) -> String {
    dir.path().join("missing.cstream").display().to_string()
}

#[test]
fn fictitious_mode_streams_progressively() {
    let dir = tempfile::tempdir().unwrap();
    let cs = dir.path().join("f.cstream");
    let cs_s = cs.to_str().unwrap();
    let r = json(&cota(&[
        "stream",
        "encode",
        "-o",
        cs_s,
        "--mode",
        "fictitious",
        "--max-error",
        "5",
        "--json",
    ]));
    assert_eq!(r["mode"], "fictitious");
    let steps = r["steps"].as_array().unwrap();
    assert!(steps.len() >= 6, "{} steps", steps.len());
    let mut heights = 0;
    for (k, st) in steps.iter().enumerate() {
        let e = st["max_error_m"].as_f64().unwrap();
        if k > 0 {
            assert!(e <= st["threshold_m"].as_f64().unwrap(), "step {k}");
        }
        heights += st["new_points"].as_u64().unwrap();
        assert!(st["bytes_per_triangle"].as_f64().unwrap() > 0.0);
    }
    assert!(heights < steps.last().unwrap()["vertices"].as_u64().unwrap());
    assert!(steps.last().unwrap()["max_error_m"].as_f64().unwrap() <= 5.0);
    let ply = dir.path().join("f.ply");
    let d = json(&cota(&[
        "stream",
        "decode",
        cs_s,
        "--json",
        "-o",
        ply.to_str().unwrap(),
    ]));
    assert_eq!(d["triangles"], steps.last().unwrap()["triangles"]);
    assert!(d["max_error_m"].as_f64().unwrap() <= 5.0);
    assert!(ply.exists());
    // Cut at a step by error: the report has every step used, with its size.
    let d = json(&cota(&[
        "stream",
        "decode",
        cs_s,
        "--max-error",
        "40",
        "--json",
    ]));
    let used = d["steps"].as_array().unwrap();
    assert!(used.len() < steps.len() && used.len() >= 2);
    for (u, st) in used.iter().zip(steps) {
        assert_eq!(u["triangles"], st["triangles"]);
        assert_eq!(u["vertices"], st["vertices"]);
        assert_eq!(u["total_bytes"], st["total_bytes"]);
        assert_eq!(u["bytes_per_triangle"], st["bytes_per_triangle"]);
    }
    assert!(d["max_error_m"].as_f64().unwrap() <= 40.0);
    // The text report prints a line per step.
    let o = cota(&["stream", "decode", cs_s, "--max-error", "40"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(
        text.contains("B/tri") && text.lines().count() >= used.len() + 3,
        "{text}"
    );
}
