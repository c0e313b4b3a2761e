//! Helpers shared by cota-core's integration tests: the real test data of
//! `cota-fixtures` (plain heights) as this crate's grids.
#![allow(dead_code, clippy::unwrap_used)]

use cota_core::grid::voids::{fill_voids, FillOptions};
use cota_core::{Crs, GeoRef, HeightGrid, PixelIs};
use cota_fixtures::{Place, Samples};

/// `s` as a grid, voids still NaN. An SRTM tile gets the georeference its
/// reader gives (EPSG:4326, pixel-is-point, whole-degree edges); any other
/// grid an unreferenced one of its cell size (1 when unknown).
pub fn grid(s: Samples) -> HeightGrid {
    let georef = match s.place {
        Place::Srtm { lat, lon } => {
            let step = 1.0 / (s.width as f64 - 1.0);
            GeoRef {
                crs: Crs::Epsg(4326),
                origin_x: f64::from(lon),
                origin_y: f64::from(lat) + 1.0,
                pixel_x: step,
                pixel_y: -step,
                pixel_is: PixelIs::Point,
                known: true,
            }
        }
        Place::Ascii { cell, .. } => GeoRef::unreferenced(cell),
        _ => GeoRef::unreferenced(1.0),
    };
    HeightGrid::new(s.width, s.height, s.heights, georef).unwrap()
}

/// `s` as a grid with its voids filled (the default harmonic fill).
pub fn filled(s: Samples) -> HeightGrid {
    let mut g = grid(s);
    fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
    g
}

/// The bundled real tile (`fixtures/S29W072.hgt.zip`), voids filled.
pub fn tile() -> HeightGrid {
    filled(cota_fixtures::bundled_tile())
}

/// The shared SRTM tile `srtm/NAME`, voids kept, or `None` (after
/// `skipped: …`) when the shared data is absent.
pub fn shared_srtm(name: &str) -> Option<HeightGrid> {
    let p = cota_fixtures::shared(&format!("srtm/{name}"))?;
    Some(grid(cota_fixtures::read(&p).unwrap()))
}
