//! Helpers shared by the CLI tests: running the binary, finding the shared data.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Command, Output};

/// Runs `cota` with `args`.
pub fn cota(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cota"))
        .args(args)
        .output()
        .expect("run the cota binary")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The repository's fixtures folder.
pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures")
        .join(name)
}

/// `../shared/data` (or `$COTA_SHARED_DATA`), when present.
pub fn shared(rel: &str) -> Option<PathBuf> {
    let root = std::env::var_os("COTA_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"));
    let p = root.join(rel);
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skipped: shared data not found at {}", p.display());
        None
    }
}
