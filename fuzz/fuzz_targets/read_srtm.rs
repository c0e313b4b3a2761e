//! Fuzz target for the SRTM .hgt / .hgt.zip reader: arbitrary bytes, named
//! `N10E010.hgt`, through `cota_io::read_dem_bytes`. Any result is fine; a panic,
//! an abort or an out-of-memory is a bug. Seeds: `fuzz/corpus/read_srtm/`.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = cota_io::read_dem_bytes(
        data,
        Path::new("N10E010.hgt"),
        &cota_io::ReadOptions::DEFAULT,
    );
});
