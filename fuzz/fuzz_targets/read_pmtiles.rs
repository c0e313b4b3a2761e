//! Fuzz target for the PMTiles v3 reader (header, gzipped directories, PNG
//! or WebP tiles): arbitrary bytes, named `x.pmtiles`, through
//! `cota_io::read_dem_bytes`, asking for every tile of zoom 2 (the seeds'
//! zoom). Any result is fine; a panic, an abort or an out-of-memory is a bug.
//! Seeds: `fuzz/corpus/read_pmtiles/`, written by the ignored test
//! `write_reader_fuzz_seeds` in crates/cota-io/tests/fuzz_corpus.rs.
#![no_main]

use std::path::Path;

use cota_io::{ReadOptions, TileRequest};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let tiles = TileRequest {
        zoom: 2,
        bbox_deg: [-180.0, -85.0, 180.0, 85.0],
    };
    let opts = ReadOptions::DEFAULT.with_tiles(Some(tiles));
    let _ = cota_io::read_dem_bytes(data, Path::new("x.pmtiles"), &opts);
});
