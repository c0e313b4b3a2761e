//! The cota-tiles integration tests, one binary (one link instead of one per file).

mod mbtiles;
mod tiles;
mod tiles3d;
