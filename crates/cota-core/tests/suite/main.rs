//! The cota-core integration tests, one binary (one link instead of one per file).

mod checker_catches;
mod common;
mod criteria;
mod extract_prop;
mod fictitious;
mod golden;
mod holes;
mod mosaic_real;
mod paper002;
mod paper004;
mod quadtree;
mod strip;
mod tiles_parts;
mod tin;
mod void_fill_real;
mod web_tiles;
