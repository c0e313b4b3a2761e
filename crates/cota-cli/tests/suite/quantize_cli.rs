//! `cota mesh --quantize`: a quantized GLB about half the size of the float
//! one, the report measuring the mesh as written against the bound plus half
//! the height step (proved by --check); refusals for non-GLB output, strips
//! and fictitious modes.
#![allow(clippy::unwrap_used, reason = "tests")]

use crate::common;

use common::{cota, stderr, stdout};

fn mesh_json(args: &[&str]) -> serde_json::Value {
    let mut all = vec!["mesh", "--max-error", "5", "--json"];
    all.extend_from_slice(args);
    let o = cota(&all);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_str(&stdout(&o)).unwrap()
}

#[test]
fn quantize_writes_half_the_bytes_within_the_bound_plus_half_a_step() {
    let dir = tempfile::tempdir().unwrap();
    let (plain, small) = (dir.path().join("p.glb"), dir.path().join("q.glb"));
    let p = mesh_json(&["-o", plain.to_str().unwrap()]);
    let q = mesh_json(&["--quantize", "--check", "-o", small.to_str().unwrap()]);
    let step = q["z_step_m"].as_f64().unwrap();
    assert!(step > 0.0 && step <= 0.125, "{step}");
    assert_eq!(q["written_bound_m"].as_f64(), Some(5.0 + step / 2.0));
    assert_eq!(q["quantized"], true);
    assert_eq!(p["quantized"], false);
    assert!(p["z_step_m"].is_null());
    // Same mesh; the error measured is the written mesh's.
    assert_eq!(q["triangles"], p["triangles"]);
    let (ep, eq) = (
        p["max_error_m"].as_f64().unwrap(),
        q["max_error_m"].as_f64().unwrap(),
    );
    assert!(ep <= 5.0 && eq <= 5.0 + step / 2.0, "{ep} {eq}");
    assert!((eq - ep).abs() <= step / 2.0);
    assert_ne!(q["volume_m3"], p["volume_m3"], "the heights moved");
    let ratio = std::fs::metadata(&small).unwrap().len() as f64
        / std::fs::metadata(&plain).unwrap().len() as f64;
    assert!(ratio <= 0.55, "{ratio}");
    // The text report states the bound as written.
    let o = cota(&[
        "mesh",
        "--max-error",
        "5",
        "--quantize",
        "-o",
        small.to_str().unwrap(),
    ]);
    let text = stdout(&o);
    assert!(
        text.contains("as written") && text.contains("KHR_mesh_quantization"),
        "{text}"
    );
}

#[test]
fn quantize_refuses_other_formats_strips_and_fictitious_modes() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("q.obj");
    let glb = dir.path().join("q.glb");
    for (args, says) in [
        (vec!["--quantize", "-o", obj.to_str().unwrap()], ".glb"),
        (
            vec!["--quantize", "--strip", "-o", glb.to_str().unwrap()],
            "--strip",
        ),
        (
            vec!["--quantize", "--mode", "fictitious"],
            "--mode conforming",
        ),
    ] {
        let mut all = vec!["mesh", "--max-error", "20"];
        all.extend_from_slice(&args);
        let o = cota(&all);
        assert!(!o.status.success(), "{args:?}");
        assert!(stderr(&o).contains(says), "{args:?}: {}", stderr(&o));
        assert!(!obj.exists() && !glb.exists());
    }
}
