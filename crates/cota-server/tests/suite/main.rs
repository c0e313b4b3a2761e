//! The cota-server integration tests, one binary (one link instead of one per file).

mod bounds;
mod common;
mod demand;
mod golden;
mod imagery;
mod loopback;
mod mbtiles;
mod router;
mod texture;
