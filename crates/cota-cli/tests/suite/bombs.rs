//! Hostile inputs (issue 23): a gzip bomb and a PNG dimension bomb are
//! refused at once with a "too large" message naming the file and the limit,
//! never read into memory. The bombs are written into a temporary directory.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use crate::common;

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use common::stderr;

/// Runs `cota info FILE` under an address-space limit of 2 GiB (where `sh`
/// has `ulimit -v`): a reader that allocated the bomb's size would abort.
fn info_limited(file: &Path) -> (std::process::Output, Duration) {
    let t0 = Instant::now();
    let out = Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 2097152 2>/dev/null; exec \"$0\" info \"$1\"")
        .arg(env!("CARGO_BIN_EXE_cota"))
        .arg(file)
        .output()
        .expect("run cota under sh");
    (out, t0.elapsed())
}

fn assert_refused(file: &Path, limit_words: &[&str]) {
    let (out, took) = info_limited(file);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains(&file.display().to_string()), "{err}");
    assert!(err.contains("too large"), "{err}");
    for w in limit_words {
        assert!(err.contains(w), "{w:?} not in {err}");
    }
    assert!(!err.contains("broken"), "{err}");
    assert!(took < Duration::from_secs(5), "took {took:?}: {err}");
}

#[test]
fn gzip_bomb_stops_at_one_tile() {
    let dir = tempfile::tempdir().unwrap();
    let bomb = dir.path().join("N10E010.hgt.gz");
    cota_fixtures::bombs::gzip_zeros(&bomb, 8, 1).unwrap();
    // The cap is 2·3601² bytes, the largest standard tile.
    assert_refused(&bomb, &["25934402 bytes", "--max-samples"]);
}

#[test]
fn png_dimension_bomb_is_refused_from_its_header() {
    let dir = tempfile::tempdir().unwrap();
    let bomb = dir.path().join("bomb.png");
    cota_fixtures::bombs::png_gray16_zeros(&bomb, 46340, 4_250_000).unwrap();
    assert!(std::fs::metadata(&bomb).unwrap().len() < 4_400_000);
    assert_refused(
        &bomb,
        &["46340x46340", "over the limit of", "--max-samples"],
    );
}

#[test]
fn max_samples_sets_the_limit() {
    let tile = common::fixture("S29W072.hgt.zip");
    let out = common::cota(&["info", tile.to_str().unwrap(), "--max-samples", "1000000"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("1201x1201"), "{err}");
    assert!(err.contains("over the limit of 1000000 samples"), "{err}");
    let out = common::cota(&["info", tile.to_str().unwrap(), "--max-samples", "1442401"]);
    assert!(out.status.success(), "{}", stderr(&out));
}
