//! The cota-io integration tests, one binary (one link instead of one per file).

mod bad_input;
mod common;
mod crs;
mod derived_inputs;
mod export;
mod fuzz_corpus;
mod image;
mod quantized_glb;
mod read_asc;
mod read_formats;
mod read_geotiff;
mod read_gzip;
mod read_png;
mod read_srtm;
mod stream;
mod strip_glb;
mod voids_real;
