//! Where a grid lies in WGS 84 longitude/latitude ([`footprint`]), and the
//! check that its CRS's map can be inverted there ([`check_round_trip`],
//! [`transform_for_grid`]).
//!
//! Reference: GDAL's `OCTTransformBounds` (the boundary densified, each point
//! transformed, the extremes taken; <https://gdal.org/en/stable/api/ogr_srs_api.html>),
//! applied here to the rectangle through the outer samples' centres.
//!
//! 1. The rectangle's four sides are each cut into `per_side` steps; every
//!    point is mapped to WGS 84 (a point with no image is an error).
//! 2. Longitudes are unwrapped along the boundary (each within 180° of the
//!    one before), so a grid across the antimeridian gives `west > east`
//!    once folded back into [-180°, 180°).
//! 3. A boundary that winds once around a pole (its unwrapped longitude
//!    ends 360° from where it started) encloses that pole: the footprint is
//!    then every longitude, up to the pole.

use cota_core::{GeoRef, GeoTransform};

use super::error::CrsError;
use super::resolve::{describe, transform_and_tolerance};

/// Points per side of the boundary in [`footprint`] (and `cota info`).
pub const FOOTPRINT_STEPS_PER_SIDE: usize = 32;

/// The corners of the rectangle through the outer samples' centres, in CRS
/// coordinates: north-west, north-east, south-east, south-west (for a
/// north-up grid).
pub fn sample_corners(georef: &GeoRef, width: usize, height: usize) -> [[f64; 2]; 4] {
    let (c1, r1) = (
        width.saturating_sub(1) as f64,
        height.saturating_sub(1) as f64,
    );
    [(0.0, 0.0), (c1, 0.0), (c1, r1), (0.0, r1)].map(|(c, r)| {
        let (x, y) = georef.sample_xy(c, r);
        [x, y]
    })
}

/// Checks that every point of `points` (CRS coordinates) maps to WGS 84
/// longitude/latitude and back to within `tolerance` (CRS units) of itself;
/// `label` names the CRS in errors. [`transform_for_grid`] uses
/// [`ROUND_TRIP_TOLERANCE_M`](super::resolve::ROUND_TRIP_TOLERANCE_M), or
/// [`HELMERT_ROUND_TRIP_TOLERANCE_M`](super::resolve::HELMERT_ROUND_TRIP_TOLERANCE_M)
/// for a datum shift.
///
/// # Errors
/// [`CrsError::OutsideDomain`] for a point either direction cannot map,
/// [`CrsError::RoundTrip`] for one that comes back elsewhere.
pub fn check_round_trip(
    t: &dyn GeoTransform,
    label: &str,
    points: &[[f64; 2]],
    tolerance: f64,
) -> Result<(), CrsError> {
    for &[x, y] in points {
        let outside = |direction: &str, reason: &str| CrsError::OutsideDomain {
            crs: label.to_string(),
            x,
            y,
            direction: direction.to_string(),
            reason: reason.to_string(),
        };
        let [lon, lat] = t.to_lonlat(x, y).ok_or_else(|| {
            outside(
                "to WGS 84 longitude/latitude",
                "outside the projection's domain",
            )
        })?;
        let [bx, by] = t.from_lonlat(lon, lat).ok_or_else(|| {
            outside(
                "back from WGS 84",
                &format!("no inverse at longitude {lon}, latitude {lat}"),
            )
        })?;
        let distance = (bx - x).hypot(by - y);
        // NaN (a non-finite result) fails too.
        if distance.is_nan() || distance > tolerance {
            return Err(CrsError::RoundTrip {
                crs: label.to_string(),
                x,
                y,
                back_x: bx,
                back_y: by,
                distance,
                tolerance,
            });
        }
    }
    Ok(())
}

/// [`transform_for`](super::resolve::transform_for) the grid's CRS, checked with [`check_round_trip`] on
/// the corners of its samples' rectangle: what a tiler reprojecting the grid
/// needs.
///
/// # Errors
/// As [`transform_for`](super::resolve::transform_for) and [`check_round_trip`].
pub fn transform_for_grid(
    georef: &GeoRef,
    width: usize,
    height: usize,
) -> Result<Box<dyn GeoTransform>, CrsError> {
    let (t, tolerance) = transform_and_tolerance(&georef.crs)?;
    let corners = sample_corners(georef, width, height);
    check_round_trip(t.as_ref(), &describe(&georef.crs), &corners, tolerance)?;
    Ok(t)
}

/// The WGS 84 bounds `[west, south, east, north]` (degrees) of the
/// rectangle through the grid's outer samples' centres, its boundary
/// densified to `steps_per_side` steps a side (module docs). `west > east`
/// when the footprint crosses the antimeridian.
///
/// # Errors
/// [`CrsError::OutsideDomain`] for a boundary point the map cannot take.
pub fn footprint(
    georef: &GeoRef,
    width: usize,
    height: usize,
    t: &dyn GeoTransform,
    steps_per_side: usize,
) -> Result<[f64; 4], CrsError> {
    let n = steps_per_side.max(1);
    let corners = sample_corners(georef, width, height);
    let mut lonlat = Vec::with_capacity(4 * n);
    for side in 0..4 {
        let ([x0, y0], [x1, y1]) = (corners[side], corners[(side + 1) % 4]);
        for i in 0..n {
            let f = i as f64 / n as f64;
            let (x, y) = (x0 + f * (x1 - x0), y0 + f * (y1 - y0));
            let p = t.to_lonlat(x, y).ok_or_else(|| CrsError::OutsideDomain {
                crs: describe(&georef.crs),
                x,
                y,
                direction: "to WGS 84 longitude/latitude".to_string(),
                reason: "outside the projection's domain".to_string(),
            })?;
            lonlat.push(p);
        }
    }
    Ok(bounds(&lonlat))
}

/// The bounds of a closed ring of longitude/latitude points (module docs,
/// steps 2 and 3).
fn bounds(ring: &[[f64; 2]]) -> [f64; 4] {
    let Some(&[lon0, _]) = ring.first() else {
        return [0.0; 4];
    };
    let (mut prev, mut west, mut east) = (lon0, lon0, lon0);
    let (mut south, mut north) = (f64::INFINITY, f64::NEG_INFINITY);
    for &[lon, lat] in ring.iter().chain(ring.first()) {
        let unwrapped = prev + (lon - prev + 180.0).rem_euclid(360.0) - 180.0;
        prev = unwrapped;
        west = west.min(unwrapped);
        east = east.max(unwrapped);
        south = south.min(lat);
        north = north.max(lat);
    }
    if (prev - lon0).abs() > 180.0 {
        // Once around a pole: the side of the mean latitude.
        let mean = ring.iter().map(|p| p[1]).sum::<f64>() / ring.len() as f64;
        return if mean >= 0.0 {
            [-180.0, south, 180.0, 90.0]
        } else {
            [-180.0, -90.0, 180.0, north]
        };
    }
    if east - west >= 360.0 {
        return [-180.0, south, 180.0, north];
    }
    let shift = 360.0 * ((west + 180.0) / 360.0).floor();
    let (w, e) = (west - shift, east - shift);
    [w, south, if e > 180.0 { e - 360.0 } else { e }, north]
}

#[cfg(test)]
mod tests {
    use super::*;
    use cota_core::{Crs, LonLat, PixelIs};

    fn georef(crs: Crs, origin: (f64, f64), pixel: f64) -> GeoRef {
        GeoRef {
            crs,
            origin_x: origin.0,
            origin_y: origin.1,
            pixel_x: pixel,
            pixel_y: -pixel,
            pixel_is: PixelIs::Point,
            known: true,
        }
    }

    #[test]
    fn geographic_footprint_is_the_sample_rectangle() {
        let g = georef(Crs::WGS84, (10.0, 50.0), 0.5);
        assert_eq!(sample_corners(&g, 3, 5)[2], [11.0, 48.0]);
        let f = footprint(&g, 3, 5, &LonLat, 32).unwrap();
        assert_eq!(f, [10.0, 48.0, 11.0, 50.0]);
    }

    #[test]
    fn antimeridian_and_poles() {
        assert_eq!(
            bounds(&[[179.0, 0.0], [-179.0, 0.0], [-179.0, 1.0], [179.0, 1.0]]),
            [179.0, 0.0, -179.0, 1.0]
        );
        let ring: Vec<[f64; 2]> = (0..36).map(|i| [-180.0 + 10.0 * i as f64, 70.0]).collect();
        assert_eq!(bounds(&ring), [-180.0, 70.0, 180.0, 90.0]);
        let south: Vec<[f64; 2]> = ring.iter().map(|p| [p[0], -p[1]]).collect();
        assert_eq!(bounds(&south), [-180.0, -90.0, 180.0, -70.0]);
    }

    #[test]
    fn utm_round_trip_and_footprint() {
        // 10 km of UTM 33N around its central meridian at the equator.
        let g = georef(Crs::Epsg(32633), (495_000.0, 5_000.0), 100.0);
        let t = transform_for_grid(&g, 101, 101).unwrap();
        let [w, s, e, n] = footprint(&g, 101, 101, t.as_ref(), 32).unwrap();
        assert!(
            (w - 14.955).abs() < 1e-3 && (e - 15.045).abs() < 1e-3,
            "{w} {e}"
        );
        assert!(
            (s + 0.0452).abs() < 1e-3 && (n - 0.0452).abs() < 1e-3,
            "{s} {n}"
        );
    }

    #[test]
    fn helmert_round_trip_is_within_a_centimetre() {
        // British National Grid around Snowdon: OSGB36 -> WGS 84 by Helmert.
        let g = georef(Crs::Epsg(27700), (260_000.0, 360_000.0), 5.0);
        let t = transform_for_grid(&g, 400, 300).unwrap();
        let e =
            check_round_trip(t.as_ref(), "BNG", &sample_corners(&g, 400, 300), 1e-6).unwrap_err();
        assert!(
            matches!(e, CrsError::RoundTrip { distance, .. } if distance < 0.01),
            "{e}"
        );
    }

    #[test]
    fn unknown_crs_and_bad_points_are_refused() {
        let g = georef(Crs::Unknown, (0.0, 0.0), 1.0);
        assert_eq!(transform_for_grid(&g, 2, 2).unwrap_err(), CrsError::Unknown);
        // Web Mercator past the pole's latitude has no image.
        let g = georef(Crs::Epsg(3857), (0.0, 1e9), 1.0);
        let e = transform_for_grid(&g, 2, 2).unwrap_err();
        assert!(
            matches!(
                e,
                CrsError::OutsideDomain { .. } | CrsError::RoundTrip { .. }
            ),
            "{e}"
        );
    }
}
