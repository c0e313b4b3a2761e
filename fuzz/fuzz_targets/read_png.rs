//! Fuzz target for the PNG height reader (terrain-RGB by default): arbitrary bytes, named
//! `x.png`, through `cota_io::read_dem_bytes`. Any result is fine; a panic,
//! an abort or an out-of-memory is a bug. Seeds: `fuzz/corpus/read_png/`.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = cota_io::read_dem_bytes(data, Path::new("x.png"), &cota_io::ReadOptions::DEFAULT);
});
