//! Fuzz target for the USGS ASCII DEM reader: arbitrary bytes, named
//! `x.dem`, through `cota_io::read_dem_bytes`. Any result is fine; a panic,
//! an abort or an out-of-memory is a bug. Seeds: `fuzz/corpus/read_usgs_dem/`,
//! written by the ignored test `write_reader_fuzz_seeds` in
//! crates/cota-io/tests/fuzz_corpus.rs.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = cota_io::read_dem_bytes(data, Path::new("x.dem"), &cota_io::ReadOptions::DEFAULT);
});
