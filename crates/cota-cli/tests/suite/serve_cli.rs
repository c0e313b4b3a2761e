//! `cota serve` refuses bad inputs at start, naming them, with a non-zero
//! exit (the server itself is tested in cota-server's tests and, end to end
//! with a browser, by crates/cota-server/viewer/test-browser/run.mjs).
#![allow(clippy::unwrap_used, reason = "tests")]

use crate::common;

use common::cota;

#[test]
fn a_missing_or_corrupt_tile_set_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nowhere");
    let out = cota(&[
        "serve",
        "--tiles",
        missing.to_str().unwrap(),
        "--addr",
        "127.0.0.1:0",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--tiles") && err.contains("nowhere"), "{err}");
    std::fs::write(dir.path().join("layer.json"), "{ not json").unwrap();
    let out = cota(&[
        "serve",
        "--tiles",
        dir.path().to_str().unwrap(),
        "--addr",
        "127.0.0.1:0",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("layer.json") && err.contains("JSON"), "{err}");
}

#[test]
fn a_corrupt_stream_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("bad.cstream");
    let mut b = b"COTASTRM".to_vec();
    b.extend_from_slice(&[1, 0, 200, 0, 0, 0, 7, 7]);
    std::fs::write(&f, b).unwrap();
    let out = cota(&["serve", f.to_str().unwrap(), "--addr", "127.0.0.1:0"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.cstream") && err.contains("truncated"),
        "{err}"
    );
}
