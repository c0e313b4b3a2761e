//! Issue 33, "the newcomer's paper cuts": each case replayed on the real
//! `cota` binary and the bundled sample (S29W072, a western and southern tile).

mod common;
use common::{cota, stderr};

/// A western/southern `--bbox` written with a space (`--bbox -71.6,…`), not
/// only as `--bbox=-71.6,…`, is read as the box, not as an unknown flag.
#[test]
fn negative_bbox_with_a_space_is_a_box() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("box.obj");
    let o = cota(&[
        "mesh",
        "--bbox",
        "-71.6,-28.9,-71.4,-28.7",
        "-o",
        out.to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(!e.contains("unexpected argument"), "{e}");
    assert!(out.exists());
}

/// Negative numbers in a crop are refused by the crop's own message, not by
/// clap's "unexpected argument" with its `-- -7` tip.
#[test]
fn negative_crop_is_refused_by_its_own_message() {
    let o = cota(&["mesh", "--crop", "-1,0,10,10", "-o", "x.obj"]);
    let e = stderr(&o);
    assert!(!o.status.success());
    assert!(!e.contains("unexpected argument"), "{e}");
    assert!(e.contains("COL,ROW,W,H"), "{e}");
}
