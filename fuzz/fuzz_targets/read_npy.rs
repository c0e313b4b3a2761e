//! Fuzz target for the NumPy .npy/.npz reader: arbitrary bytes, named
//! `x.npy`, through `cota_io::read_dem_bytes`. Any result is fine; a panic,
//! an abort or an out-of-memory is a bug. Seeds: `fuzz/corpus/read_npy/`,
//! written by the ignored test `write_reader_fuzz_seeds` in
//! crates/cota-io/tests/fuzz_corpus.rs.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = cota_io::read_dem_bytes(data, Path::new("x.npy"), &cota_io::ReadOptions::DEFAULT);
});
