//! **Derived test inputs**: projected GeoTIFFs made at test time from real
//! geographic DEMs (nothing downloaded or derived is committed).
//!
//! * [`nad83_utm16n_1m`]: 400 × 300 m at 1 m in NAD83 / UTM zone 16N
//!   (EPSG:26916), from the shared `geotiff/dem-hills.tiff` (USGS 3DEP
//!   1/3″, about 10 m, near 87.49° W, 39.42° N; its lon/lat are NAD83's,
//!   whatever ellipsoid its GeoKeys name).
//! * [`wgs84_utm19s_30m`]: 24 × 18 km at 30 m in WGS 84 / UTM zone 19S
//!   (EPSG:32719), from an SRTM 3″ tile (the bundled `S29W072.hgt.zip`,
//!   around 71.5° W, 28.5° S).
//!
//! Each target pixel centre is mapped to the source's longitude/latitude by
//! the inverse UTM projection on the target's own ellipsoid (GRS 1980,
//! WGS 84), with no datum shift (the source is on the same datum), by
//! proj4rs (the projection library `cota-io` uses, which matches PROJ to
//! 1e-8 m on UTM); the height there is the bilinear interpolation of the
//! source's four surrounding samples, a void when any of them is one or the
//! point lies outside. Reference: Snyder, *Map Projections — A Working
//! Manual* (USGS PP 1395, 1987) for UTM; PROJ's `+proj=utm` definitions.

use std::path::Path;

use proj4rs::Proj;

use crate::geotiff::{read_geotiff_f32, GeoTiff, GeoTiffCrs};
use crate::{FixtureError, Place, Samples};

/// A projected grid made from a real DEM, ready to be written as a GeoTIFF.
#[derive(Debug, Clone, PartialEq)]
pub struct Derived {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Heights in metres, row-major from the north-west; voids NaN.
    pub heights: Vec<f32>,
    /// Easting of the grid's west edge (pixel-is-area), metres.
    pub west: f64,
    /// Northing of the grid's north edge, metres.
    pub north: f64,
    /// Pixel size, metres.
    pub pixel_m: f64,
    /// The projected CRS's EPSG code.
    pub epsg: u16,
}

/// The nodata value the derived GeoTIFFs are written with.
pub const NODATA: f32 = -9999.0;

impl Derived {
    /// The GeoTIFF of this grid (see [`crate::geotiff::write_geotiff`]).
    pub fn geotiff(&self) -> GeoTiff<'_> {
        GeoTiff {
            width: self.width,
            height: self.height,
            heights: &self.heights,
            west: self.west,
            north: self.north,
            pixel: self.pixel_m,
            pixel_y: 0.0,
            crs: GeoTiffCrs::Projected(self.epsg),
            nodata: NODATA,
        }
    }

    /// Writes the GeoTIFF to `path`.
    ///
    /// # Errors
    /// The file's or the encoder's error.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        crate::geotiff::write_geotiff(path, &self.geotiff())
    }

    /// The easting and northing of the centre of the sample at (`col`, `row`).
    pub fn sample_xy(&self, col: usize, row: usize) -> [f64; 2] {
        [
            self.west + (col as f64 + 0.5) * self.pixel_m,
            self.north - (row as f64 + 0.5) * self.pixel_m,
        ]
    }
}

/// A geographic source grid: the first sample's centre and the steps
/// between samples, in degrees.
struct Source<'a> {
    heights: &'a [f32],
    width: usize,
    height: usize,
    lon0: f64,
    lat0: f64,
    dlon: f64,
    dlat: f64,
}

impl Source<'_> {
    /// The bilinear height at (`lon`, `lat`), NaN outside or next to a void.
    fn bilinear(&self, lon: f64, lat: f64) -> f32 {
        let fc = (lon - self.lon0) / self.dlon;
        let fr = (self.lat0 - lat) / self.dlat;
        let (last_c, last_r) = ((self.width - 1) as f64, (self.height - 1) as f64);
        if !(0.0..=last_c).contains(&fc) || !(0.0..=last_r).contains(&fr) {
            return f32::NAN;
        }
        let (c0, r0) = (fc.floor().min(last_c - 1.0), fr.floor().min(last_r - 1.0));
        let (tx, ty) = (fc - c0, fr - r0);
        let at = |c: f64, r: f64| f64::from(self.heights[r as usize * self.width + c as usize]);
        let top = at(c0, r0) * (1.0 - tx) + at(c0 + 1.0, r0) * tx;
        let bottom = at(c0, r0 + 1.0) * (1.0 - tx) + at(c0 + 1.0, r0 + 1.0) * tx;
        (top * (1.0 - ty) + bottom * ty) as f32
    }
}

/// The target grid: its UTM definition and extent.
struct Target<'a> {
    utm: &'a str,
    geographic: &'a str,
    epsg: u16,
    west: f64,
    north: f64,
    pixel_m: f64,
    width: usize,
    height: usize,
}

/// Resamples `src` onto `t` (module docs).
fn resample(src: &Source<'_>, t: &Target<'_>) -> Result<Derived, String> {
    let utm = Proj::from_proj_string(t.utm).map_err(|e| e.to_string())?;
    let geo = Proj::from_proj_string(t.geographic).map_err(|e| e.to_string())?;
    let mut d = Derived {
        width: t.width,
        height: t.height,
        heights: Vec::with_capacity(t.width * t.height),
        west: t.west,
        north: t.north,
        pixel_m: t.pixel_m,
        epsg: t.epsg,
    };
    for row in 0..t.height {
        for col in 0..t.width {
            let [x, y] = d.sample_xy(col, row);
            let mut p = (x, y, 0.0);
            proj4rs::transform::transform(&utm, &geo, &mut p).map_err(|e| e.to_string())?;
            d.heights
                .push(src.bilinear(p.0.to_degrees(), p.1.to_degrees()));
        }
    }
    Ok(d)
}

/// 400 × 300 samples at 1 m in NAD83 / UTM zone 16N (EPSG:26916), west edge
/// 457 300 m E, north edge 4 363 875 m N: the middle of the shared
/// `geotiff/dem-hills.tiff` (`path`), away from its void border (module docs).
///
/// # Errors
/// A [`FixtureError`] naming `path` when it cannot be read as that file's
/// kind of GeoTIFF.
pub fn nad83_utm16n_1m(path: &Path) -> Result<Derived, FixtureError> {
    let fail = |reason: String| FixtureError {
        path: path.to_path_buf(),
        reason,
    };
    let g = read_geotiff_f32(path).map_err(fail)?;
    let src = Source {
        heights: &g.heights,
        width: g.width,
        height: g.height,
        lon0: g.west + 0.5 * g.pixel_x,
        lat0: g.north - 0.5 * g.pixel_y,
        dlon: g.pixel_x,
        dlat: g.pixel_y,
    };
    let target = Target {
        utm: "+proj=utm +zone=16 +ellps=GRS80 +units=m +no_defs",
        geographic: "+proj=longlat +ellps=GRS80 +no_defs",
        epsg: 26916,
        west: 457_300.0,
        north: 4_363_875.0,
        pixel_m: 1.0,
        width: 400,
        height: 300,
    };
    resample(&src, &target).map_err(fail)
}

/// 800 × 600 samples at 30 m in WGS 84 / UTM zone 19S (EPSG:32719), west
/// edge 243 300 m E, north edge 6 853 860 m N, from the SRTM tile `tile`
/// (the bundled `S29W072.hgt.zip`, which the window lies in; voids kept).
///
/// # Errors
/// A [`FixtureError`] when `tile` has no SRTM position or is not S29W072.
pub fn wgs84_utm19s_30m(tile: &Samples) -> Result<Derived, FixtureError> {
    let fail = |reason: String| FixtureError {
        path: crate::fixture(crate::BUNDLED_TILE),
        reason,
    };
    let Place::Srtm { lat: -29, lon: -72 } = tile.place else {
        return Err(fail(format!(
            "expected the SRTM tile S29W072, found a grid placed at {:?}",
            tile.place
        )));
    };
    let step = 1.0 / (tile.width - 1) as f64;
    let src = Source {
        heights: &tile.heights,
        width: tile.width,
        height: tile.height,
        lon0: -72.0,
        lat0: -28.0,
        dlon: step,
        dlat: step,
    };
    let target = Target {
        utm: "+proj=utm +zone=19 +south +ellps=WGS84 +units=m +no_defs",
        geographic: "+proj=longlat +ellps=WGS84 +no_defs",
        epsg: 32719,
        west: 243_300.0,
        north: 6_853_860.0,
        pixel_m: 30.0,
        width: 800,
        height: 600,
    };
    resample(&src, &target).map_err(fail)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_is_exact_on_a_plane_and_void_next_to_a_void() {
        // h = 10·col + 100·row on a 3×3 grid of 1° steps from (0°, 2°).
        let h: Vec<f32> = (0..9)
            .map(|i| (10 * (i % 3) + 100 * (i / 3)) as f32)
            .collect();
        let src = Source {
            heights: &h,
            width: 3,
            height: 3,
            lon0: 0.0,
            lat0: 2.0,
            dlon: 1.0,
            dlat: 1.0,
        };
        assert_eq!(src.bilinear(0.5, 1.5), 55.0);
        assert_eq!(src.bilinear(2.0, 0.0), 220.0);
        assert!(src.bilinear(2.5, 1.0).is_nan());
        let mut voided = h.clone();
        voided[8] = f32::NAN; // the south-east sample
        let src = Source {
            heights: &voided,
            ..src
        };
        assert!(src.bilinear(1.5, 0.5).is_nan());
        assert_eq!(src.bilinear(0.5, 1.5), 55.0);
    }

    #[test]
    fn the_srtm_derived_grid_is_made_from_the_bundled_tile() {
        let d = wgs84_utm19s_30m(&crate::bundled_tile()).unwrap();
        assert_eq!((d.width, d.height, d.epsg), (800, 600, 32719));
        let valid: Vec<f32> = d.heights.iter().copied().filter(|h| !h.is_nan()).collect();
        assert!(valid.len() > 479_000, "{} valid", valid.len());
        let max = valid.iter().copied().fold(f32::MIN, f32::max);
        assert!((0.0..=1899.0).contains(&max), "{max}");
        let other = Samples {
            place: Place::Unknown,
            ..crate::bundled_tile()
        };
        assert!(wgs84_utm19s_30m(&other).is_err());
    }
}
