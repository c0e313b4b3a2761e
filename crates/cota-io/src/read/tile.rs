//! Web map tiles addressed by z/x/y: their Web-Mercator bounds (EPSG:3857),
//! so that adjacent tiles mosaic as other georeferenced inputs do.
//!
//! # Facts this module relies on (the XYZ / "slippy map" tile scheme)
//! * At zoom z the world (±20 037 508.34 m in x and y, i.e. ±180° of longitude
//!   and ±85.0511° of latitude) is cut into 2^z × 2^z tiles; x counts east
//!   from −180°, y counts **south** from the northern edge (not TMS's north).
//! * A tile of W×H pixels covers its square exactly: pixel-is-area, origin at
//!   the tile's north-west corner, pixel size (extent / 2^z) / W by / H.
//! * A file is taken for a tile when its last three path components are
//!   `z/x/y.ext` (decimal, x and y below 2^z, z at most [`MAX_ZOOM`]), as tile
//!   servers and `pmtiles extract`-style dumps lay them out.

use std::f64::consts::PI;
use std::path::Path;

use cota_core::{Crs, GeoRef, PixelIs};

/// Half the width of the Web-Mercator world, metres (π · 6 378 137).
pub(crate) const HALF_WORLD_M: f64 = PI * 6_378_137.0;

/// The deepest zoom accepted (tile numbers fit in u32 below it).
pub(crate) const MAX_ZOOM: u8 = 30;

/// A tile's address.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct TileId {
    pub z: u8,
    pub x: u32,
    pub y: u32,
}

impl TileId {
    /// The address when valid at its zoom.
    pub(crate) fn new(z: u8, x: u32, y: u32) -> Option<Self> {
        let n = 1u64 << z.min(MAX_ZOOM);
        (z <= MAX_ZOOM && u64::from(x) < n && u64::from(y) < n).then_some(TileId { z, x, y })
    }

    /// The georeference of this tile as a `width` × `height` image.
    pub(crate) fn georef(self, width: usize, height: usize) -> GeoRef {
        let size = 2.0 * HALF_WORLD_M / (1u64 << self.z) as f64;
        GeoRef {
            crs: Crs::Epsg(3857),
            origin_x: -HALF_WORLD_M + f64::from(self.x) * size,
            origin_y: HALF_WORLD_M - f64::from(self.y) * size,
            pixel_x: size / width as f64,
            pixel_y: -size / height as f64,
            pixel_is: PixelIs::Area,
            known: true,
        }
    }
}

/// The tile a path names as `…/z/x/y.ext`, if any.
pub(crate) fn tile_of_path(path: &Path) -> Option<TileId> {
    let y = path.file_stem()?.to_str()?;
    let parent = path.parent()?;
    let x = parent.file_name()?.to_str()?;
    let z = parent.parent()?.file_name()?.to_str()?;
    let digits = |s: &str| !s.is_empty() && s.len() <= 10 && s.bytes().all(|b| b.is_ascii_digit());
    if !(digits(z) && digits(x) && digits(y)) {
        return None;
    }
    TileId::new(z.parse().ok()?, x.parse().ok()?, y.parse().ok()?)
}

/// The Web-Mercator georeference of a `width` × `height` image at `path`
/// when the path names a tile.
pub(crate) fn georef_for(path: &Path, width: usize, height: usize) -> Option<GeoRef> {
    tile_of_path(path).map(|t| t.georef(width, height))
}

/// Fractional tile coordinates of a longitude/latitude (degrees) at zoom `z`;
/// latitudes are clamped to the Web-Mercator limit.
pub(crate) fn tile_xy(z: u8, lon_deg: f64, lat_deg: f64) -> (f64, f64) {
    let n = (1u64 << z) as f64;
    let lat = lat_deg.clamp(-85.051_128_78, 85.051_128_78).to_radians();
    let x = (lon_deg + 180.0) / 360.0 * n;
    let y = (1.0 - (lat.tan() + 1.0 / lat.cos()).ln() / PI) / 2.0 * n;
    (x, y)
}

/// The inclusive tile ranges `(x0, x1, y0, y1)` at zoom `z` that cover the
/// box `[west, south, east, north]` (degrees, west < east).
pub(crate) fn tiles_covering(z: u8, bbox: [f64; 4]) -> (u32, u32, u32, u32) {
    let [w, s, e, n] = bbox;
    let last = ((1u64 << z) - 1) as f64;
    let clamp = |v: f64| v.floor().clamp(0.0, last) as u32;
    let (x0, y0) = tile_xy(z, w, n);
    let (x1, y1) = tile_xy(z, e, s);
    // A box edge exactly on a tile edge does not take the next tile.
    let below = |v: f64| {
        if v.fract() == 0.0 && v > 0.0 {
            v - 1.0
        } else {
            v
        }
    };
    (clamp(x0), clamp(below(x1)), clamp(y0), clamp(below(y1)))
}

/// Longitude/latitude (degrees) of a tile's north-west corner.
#[cfg(test)]
pub(crate) fn tile_corner_deg(z: u8, x: f64, y: f64) -> (f64, f64) {
    let n = (1u64 << z) as f64;
    let lon = x / n * 360.0 - 180.0;
    let lat = (PI * (1.0 - 2.0 * y / n)).sinh().atan().to_degrees();
    (lon, lat)
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn paths_name_tiles() {
        let t = tile_of_path(Path::new("tiles/14/10348/7801.webp"));
        assert_eq!(t, TileId::new(14, 10348, 7801));
        assert_eq!(tile_of_path(Path::new("a/b/7801.webp")), None);
        assert_eq!(tile_of_path(Path::new("1/2/0.png")), None, "x beyond 2^z");
        assert_eq!(tile_of_path(Path::new("terrarium.png")), None);
    }

    #[test]
    fn tile_bounds() {
        let t = TileId::new(1, 1, 0).unwrap();
        let g = t.georef(256, 256);
        assert_eq!((g.origin_x, g.origin_y), (0.0, HALF_WORLD_M));
        assert!((g.pixel_x * 256.0 - HALF_WORLD_M).abs() < 1e-6);
        let (x, y) = tile_xy(14, -122.4, 37.8);
        let (lon, lat) = tile_corner_deg(14, x, y);
        assert!((lon + 122.4).abs() < 1e-9 && (lat - 37.8).abs() < 1e-9);
        assert_eq!(tiles_covering(1, [-10.0, -10.0, 10.0, 10.0]), (0, 1, 0, 1));
        assert_eq!(tiles_covering(1, [1.0, 1.0, 2.0, 2.0]), (1, 1, 0, 0));
    }
}
