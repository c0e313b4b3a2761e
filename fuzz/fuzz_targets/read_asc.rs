//! Fuzz target for the ESRI ASCII grid reader: arbitrary bytes, named
//! `x.asc`, through `cota_io::read_dem_bytes`. Any result is fine; a panic,
//! an abort or an out-of-memory is a bug. Seeds: `fuzz/corpus/read_asc/`.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = cota_io::read_dem_bytes(data, Path::new("x.asc"), &cota_io::ReadOptions::DEFAULT);
});
