//! Test support shared by the unit tests: the bundled real tiles, as plain
//! data from `cota-fixtures` (a dev-dependency that does not depend on this
//! crate), put into this crate's grid type and filled.

use crate::grid::voids::{fill_voids, FillOptions};
use crate::grid::{GeoRef, HeightGrid};

/// The bundled fixture `name` as an unreferenced grid (1 m cells), voids
/// filled.
pub(crate) fn fixture(name: &str) -> HeightGrid {
    let s = cota_fixtures::bundled(name);
    let mut g = HeightGrid::new(s.width, s.height, s.heights, GeoRef::unreferenced(1.0)).unwrap();
    fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
    g
}
