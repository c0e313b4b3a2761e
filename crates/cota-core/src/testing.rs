//! Test support shared by the unit tests: the bundled real tiles, read with
//! `cota-io` (a dev-dependency; a different build of this crate, so the
//! heights are copied into this crate's own grid type) and filled.

use crate::grid::voids::{fill_voids, FillOptions};
use crate::grid::{GeoRef, HeightGrid};

/// The bundled fixture `name` as an unreferenced grid (1 m cells), voids
/// filled.
pub(crate) fn fixture(name: &str) -> HeightGrid {
    let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures")
        .join(name);
    let g = cota_io::read_dem(&p, &cota_io::ReadOptions::DEFAULT)
        .unwrap()
        .grid;
    let (w, h) = (g.width(), g.height());
    let mut g = HeightGrid::new(w, h, g.heights().to_vec(), GeoRef::unreferenced(1.0)).unwrap();
    fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
    g
}
