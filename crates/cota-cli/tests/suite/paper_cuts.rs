//! The newcomer's paper cuts (issue 33), each replayed on the bundled real
//! DEM (fixtures/S29W072.hgt.zip, SRTM, 29° S 72° W: every coordinate of its
//! box is negative) and on what `cota` writes from it.
#![allow(clippy::unwrap_used, reason = "tests")]

use crate::common;
use common::*;

/// A western and southern box given as `--bbox W,S,E,N` (no `=`): every
/// number starts with a minus sign, and clap must take it as the value.
#[test]
fn negative_numbers_are_values_not_flags() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("box.glb");
    let o = cota(&[
        "mesh",
        "--bbox",
        "-71.9,-28.9,-71.8,-28.8",
        "--max-error",
        "5",
        "--check",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.exists());
    // An observer and a direction below zero, as the view criterion takes them.
    let o = cota(&[
        "mesh",
        "--criterion",
        "view",
        "--observer",
        "-2000,-3000,4000",
        "--look",
        "1,1,-0.3",
        "--max-error-px",
        "3",
    ]);
    let e = stderr(&o);
    assert!(!e.contains("unexpected argument"), "{e}");
    assert!(o.status.success(), "{e}");
}

/// `--error-factor 0`: the message says what was expected in words, not
/// the option's Rust value.
#[test]
fn a_zero_error_factor_is_refused_in_words() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t");
    let o = cota(&["tiles", "--error-factor", "0", "-o", out.to_str().unwrap()]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(!e.contains("Cesium {") && !e.contains("factor:"), "{e}");
    assert!(
        e.contains("expected a positive, finite error factor, found 0"),
        "{e}"
    );
    assert!(!out.exists(), "nothing written");
}

/// `pair` names `--max-samples` when a DEM is over the sample limit: the
/// flag exists on `pair` and raises the limit.
#[test]
fn pair_has_the_flag_its_message_names() {
    let dem = fixture("olinda_dem_utm25s.tif");
    let img = fixture("L7_ETMs.tif");
    let (d, i) = (dem.to_str().unwrap(), img.to_str().unwrap());
    let small = ["pair", d, i, "--bands", "3,2,1", "--budget-bytes", "200000"];
    let o = cota(&[&small[..], &["--max-samples", "1000"]].concat());
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("olinda_dem_utm25s.tif") && e.contains("--max-samples"),
        "{e}"
    );
    let o = cota(&[&small[..], &["--max-samples", "20000"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
}

/// A stream cut inside a step frame (a partial download) decodes its
/// complete steps and says what is missing; `--strict` refuses it.
#[test]
fn a_cut_stream_decodes_its_complete_steps() {
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
    std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let mesh = dir.path().join("cut.obj");
    let c = cut.to_str().unwrap();
    let o = cota(&[
        "stream",
        "decode",
        c,
        "-o",
        mesh.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("warning") && e.contains("cut.cstream"), "{e}");
    assert!(e.contains("complete step") && e.contains("missing"), "{e}");
    assert!(mesh.exists());
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert!(
        v["truncated"].as_str().unwrap().contains("truncated"),
        "{v}"
    );
    let whole = cota(&["stream", "decode", cs.to_str().unwrap(), "--json"]);
    let w: serde_json::Value = serde_json::from_str(&stdout(&whole)).unwrap();
    assert!(w["truncated"].is_null());
    assert!(v["steps_used"].as_u64() < w["steps_used"].as_u64());
    let o = cota(&["stream", "decode", c, "--strict"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("truncated"), "{}", stderr(&o));
}

/// The PMTiles input's zoom is `--input-zoom`; `--zoom` still works and
/// warns that it is the input's zoom, not the output's.
#[test]
fn input_zoom_is_named_for_what_it_is() {
    let args = ["info", "--bbox=-72,-29,-71,-28", "--input-zoom", "3"];
    let o = cota(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("deprecated"), "{}", stderr(&o));
    let o = cota(&["info", "--bbox=-72,-29,-71,-28", "--zoom", "3"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("--zoom is deprecated") && e.contains("--input-zoom"),
        "{e}"
    );
}

/// Negative numbers in a crop are refused by the crop's own message, not by
/// clap's "unexpected argument" with its `-- -7` tip.
#[test]
fn negative_crop_is_refused_by_its_own_message() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.obj");
    let o = cota(&["mesh", "--crop", "-1,0,10,10", "-o", out.to_str().unwrap()]);
    let e = stderr(&o);
    assert!(!o.status.success());
    assert!(!e.contains("unexpected argument"), "{e}");
    assert!(e.contains("COL,ROW,W,H"), "{e}");
    assert!(!out.exists());
}

/// An output that cannot be made: the operating system's text once, not
/// once from the wrapping error and again from its cause.
#[test]
fn os_error_text_is_printed_once() {
    let o = cota(&[
        "tiles",
        "--max-zoom",
        "3",
        "-o",
        "/proc/cota-cannot-make-this",
    ]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("/proc/cota-cannot-make-this"), "{e}");
    assert_eq!(e.matches("(os error").count(), 1, "{e}");
}
