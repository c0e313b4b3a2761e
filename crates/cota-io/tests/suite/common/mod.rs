//! Helpers shared by the cota-io integration tests: where the shared real
//! DEMs and the bundled fixtures are (from `cota-fixtures`), and small
//! builders of test files.
//!
//! The shared data directory is `$COTA_SHARED_DATA` when set, else
//! `<workspace root>/../shared/data`. Tests that need it call
//! [`shared_data`] and return early (printing "skipped: …") when it is absent;
//! tests on `/fixtures` always run.
#![allow(dead_code, clippy::unwrap_used, clippy::panic)]

use std::io::Write;
use std::path::{Path, PathBuf};

/// The cargo workspace root.
pub fn workspace_root() -> PathBuf {
    cota_fixtures::workspace_root()
}

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

/// Big-endian int16 bytes of an SRTM tile.
pub fn hgt_bytes(samples: &[i16]) -> Vec<u8> {
    samples.iter().flat_map(|v| v.to_be_bytes()).collect()
}

/// A deflated ZIP archive of the given (name, content) members.
pub fn zip_bytes(members: &[(&str, &[u8])]) -> Vec<u8> {
    let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    for (name, data) in members {
        w.start_file(*name, opts).unwrap();
        w.write_all(data).unwrap();
    }
    w.finish().unwrap().into_inner()
}

/// A PNG of the given colour type and bit depth holding `data` (packed rows).
pub fn png_bytes(
    width: u32,
    height: u32,
    color: png::ColorType,
    depth: png::BitDepth,
    data: &[u8],
) -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, width, height);
        enc.set_color(color);
        enc.set_depth(depth);
        let mut w = enc.write_header().unwrap();
        w.write_image_data(data).unwrap();
    }
    out
}

/// Asserts that `text` contains every one of `needles`.
pub fn assert_contains(text: &str, needles: &[&str]) {
    for n in needles {
        assert!(text.contains(n), "{text:?} does not contain {n:?}");
    }
}
