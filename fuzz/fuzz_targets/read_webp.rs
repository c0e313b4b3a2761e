//! Fuzz target for the WebP terrain-tile reader (Terrarium by default):
//! arbitrary bytes, named `x.webp`, through `cota_io::read_dem_bytes`. Any result is fine; a panic,
//! an abort or an out-of-memory is a bug. Seeds: `fuzz/corpus/read_webp/`,
//! written by the ignored test `write_reader_fuzz_seeds` in
//! crates/cota-io/tests/fuzz_corpus.rs.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = cota_io::read_dem_bytes(data, Path::new("x.webp"), &cota_io::ReadOptions::DEFAULT);
});
