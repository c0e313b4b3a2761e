//! Outputs (issue 23): a read-only existing file is refused unless `--force`;
//! a symbolic link is written through.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use crate::common;

use common::{cota, stderr};

#[test]
fn read_only_output_needs_force() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("kept.obj");
    std::fs::write(&out, b"old").unwrap();
    let mut perms = std::fs::metadata(&out).unwrap().permissions();
    perms.set_readonly(true);
    std::fs::set_permissions(&out, perms).unwrap();
    let o = out.to_str().unwrap();
    let r = cota(&["mesh", "--max-error", "50", "-o", o]);
    let err = stderr(&r);
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(
        err.contains("kept.obj") && err.contains("read-only"),
        "{err}"
    );
    assert_eq!(std::fs::read(&out).unwrap(), b"old");
    let r = cota(&["mesh", "--max-error", "50", "-o", o, "--force"]);
    assert!(r.status.success(), "{}", stderr(&r));
    assert!(std::fs::read(&out).unwrap().starts_with(b"# "));
}

#[cfg(unix)]
#[test]
fn symlink_output_is_written_through() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("real.obj");
    let link = dir.path().join("link.obj");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let r = cota(&["mesh", "--max-error", "50", "-o", link.to_str().unwrap()]);
    assert!(r.status.success(), "{}", stderr(&r));
    let meta = std::fs::symlink_metadata(&link).unwrap();
    assert!(meta.file_type().is_symlink());
    assert!(std::fs::metadata(&target).unwrap().len() > 1000);
}

/// Makes `path` an existing read-only file holding `old`.
fn read_only_file(path: &std::path::Path) {
    std::fs::write(path, b"old").unwrap();
    let mut perms = std::fs::metadata(path).unwrap().permissions();
    perms.set_readonly(true);
    std::fs::set_permissions(path, perms).unwrap();
}

/// Runs `args` without and then with `--force` over the read-only `out`:
/// refused by name (saying --force, which the command must then take),
/// then replaced.
fn refused_then_forced(args: &[&str], out: &std::path::Path) {
    read_only_file(out);
    let r = cota(args);
    let err = stderr(&r);
    let name = out.file_name().unwrap().to_str().unwrap();
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(
        err.contains(name) && err.contains("read-only") && err.contains("--force"),
        "{err}"
    );
    assert_eq!(std::fs::read(out).unwrap(), b"old");
    let r = cota(&[args, &["--force"]].concat());
    assert!(r.status.success(), "{args:?} --force: {}", stderr(&r));
    assert_ne!(std::fs::read(out).unwrap(), b"old");
}

#[test]
fn every_command_that_writes_takes_force() {
    let dir = tempfile::tempdir().unwrap();
    let stream = dir.path().join("s.cstream");
    let s = stream.to_str().unwrap();
    refused_then_forced(&["stream", "encode", "--max-error", "20", "-o", s], &stream);
    let decoded = dir.path().join("d.ply");
    let d = decoded.to_str().unwrap();
    refused_then_forced(&["stream", "decode", s, "-o", d], &decoded);
    let tiles = dir.path().join("tiles");
    let t = tiles.to_str().unwrap();
    let r = cota(&["tiles", "--max-zoom", "6", "-o", t]);
    assert!(r.status.success(), "{}", stderr(&r));
    refused_then_forced(
        &["tiles", "--max-zoom", "6", "-o", t],
        &tiles.join("layer.json"),
    );
    let pair = dir.path().join("p.glb");
    let dem = common::fixture("olinda_dem_utm25s.tif");
    let img = common::fixture("L7_ETMs.tif");
    let args = [
        "pair",
        dem.to_str().unwrap(),
        img.to_str().unwrap(),
        "--bands",
        "3,2,1",
        "--budget-bytes",
        "100000",
        "-o",
        pair.to_str().unwrap(),
    ];
    refused_then_forced(&args, &pair);
}
