//! Outputs (issue 23): a read-only existing file is refused unless `--force`;
//! a symbolic link is written through.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

mod common;

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
