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
    cota_fixtures::fixture(name)
}

/// `../shared/data/REL` (or `$COTA_SHARED_DATA/REL`), when present; else
/// `None` after printing "skipped: …".
pub fn shared(rel: &str) -> Option<PathBuf> {
    cota_fixtures::shared(rel)
}
