//! Helpers shared by the cota-tiles integration tests: where the shared real
//! DEMs and the bundled fixtures are (from `cota-fixtures`).
#![allow(dead_code, clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};

/// The shared data directory, or `None` (after printing why) when absent.
pub fn shared_data() -> Option<PathBuf> {
    cota_fixtures::shared_data()
}

/// A file of the bundled fixtures directory.
pub fn fixture(name: &str) -> PathBuf {
    cota_fixtures::fixture(name)
}

/// Writes `bytes` to `dir/name` and returns the path.
pub fn write_file(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}
