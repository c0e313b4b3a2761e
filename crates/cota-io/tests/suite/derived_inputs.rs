//! The derived test inputs of `cota_fixtures::derived` (projected GeoTIFFs
//! resampled at test time from real DEMs) read back by cota-io: their CRS,
//! georeference and heights as written, their corners in longitude/latitude
//! as PROJ 9.5.1 (pyproj) puts them, and their heights where cota's own
//! transform says they lie in the source DEM.
#![allow(clippy::unwrap_used, clippy::panic)]

use cota_core::{Crs, GeoRef, GeoTransform, HeightGrid};
use cota_fixtures::derived::{nad83_utm16n_1m, wgs84_utm19s_30m, Derived};
use cota_io::crs::{sample_corners, transform_for_grid};
use cota_io::{read_dem, ReadOptions};

/// Writes `d`, reads it back and checks it is what was written.
fn written_and_read(d: &Derived, name: &str) -> HeightGrid {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    d.write(&path).unwrap();
    let dem = read_dem(&path, &ReadOptions::DEFAULT).unwrap();
    let g = dem.grid;
    assert_eq!((g.width(), g.height()), (d.width, d.height));
    let r = g.georef();
    assert_eq!(r.crs, Crs::Epsg(u32::from(d.epsg)));
    assert_eq!((r.pixel_x, r.pixel_y), (d.pixel_m, -d.pixel_m));
    let (x, y) = r.sample_xy(0.0, 0.0);
    assert_eq!([x, y], d.sample_xy(0, 0));
    for (got, want) in g.heights().iter().zip(&d.heights) {
        assert!(
            got == want || (got.is_nan() && want.is_nan()),
            "{got} {want}"
        );
    }
    g
}

/// The corners of `g`'s samples through its CRS, against PROJ's.
fn corners_match(g: &HeightGrid, proj: [[f64; 2]; 4]) -> Box<dyn GeoTransform> {
    let t = transform_for_grid(g.georef(), g.width(), g.height()).unwrap();
    for ([x, y], [lon, lat]) in sample_corners(g.georef(), g.width(), g.height())
        .into_iter()
        .zip(proj)
    {
        let [plon, plat] = t.to_lonlat(x, y).unwrap();
        assert!(
            (plon - lon).abs() < 1e-8 && (plat - lat).abs() < 1e-8,
            "({x}, {y}): {plon} {plat} against {lon} {lat}"
        );
    }
    t
}

/// The bilinear height of geographic `src` at (`lon`, `lat`).
fn bilinear(src: &HeightGrid, lon: f64, lat: f64) -> f64 {
    let r: &GeoRef = src.georef();
    let (x0, y0) = r.sample_xy(0.0, 0.0);
    let (fc, fr) = ((lon - x0) / r.pixel_x, (lat - y0) / r.pixel_y);
    let (c, rr) = (fc.floor(), fr.floor());
    let (tx, ty) = (fc - c, fr - rr);
    let h = |dc: f64, dr: f64| f64::from(src.get((c + dc) as usize, (rr + dr) as usize));
    (h(0.0, 0.0) * (1.0 - tx) + h(1.0, 0.0) * tx) * (1.0 - ty)
        + (h(0.0, 1.0) * (1.0 - tx) + h(1.0, 1.0) * tx) * ty
}

/// Every `step`-th sample of `g`: its height equals the source's at the
/// longitude/latitude cota's transform gives (the fixture resampled with
/// its own reader and projection), within `tol_m`.
fn heights_agree(g: &HeightGrid, t: &dyn GeoTransform, src: &HeightGrid, step: usize, tol_m: f64) {
    let mut worst = 0.0f64;
    for row in (0..g.height()).step_by(step) {
        for col in (0..g.width()).step_by(step) {
            let h = f64::from(g.get(col, row));
            if h.is_nan() {
                continue;
            }
            let (x, y) = g.georef().sample_xy(col as f64, row as f64);
            let [lon, lat] = t.to_lonlat(x, y).unwrap();
            worst = worst.max((bilinear(src, lon, lat) - h).abs());
        }
    }
    assert!(worst <= tol_m, "largest difference {worst} m");
}

#[test]
fn nad83_utm16n_1m_from_dem_hills() {
    let Some(path) = cota_fixtures::shared("geotiff/dem-hills.tiff") else {
        return;
    };
    let d = nad83_utm16n_1m(&path).unwrap();
    let g = written_and_read(&d, "hills_26916.tif");
    assert_eq!(g.void_count(), 0);
    let (lo, hi) = g.valid_range().unwrap();
    assert!(138.0 <= lo && hi <= 168.1 && hi - lo > 5.0, "{lo}..{hi}");
    // NAD83 is taken as WGS 84: PROJ's UTM inverse on GRS 1980.
    let t = corners_match(
        &g,
        [
            [-87.496_081_296_159_82, 39.423_342_886_279_41],
            [-87.491_445_888_681_03, 39.423_362_561_849_73],
            [-87.491_426_968_470_82, 39.420_668_461_115_9],
            [-87.496_062_197_508_48, 39.420_648_787_419_275],
        ],
    );
    let src = read_dem(&path, &ReadOptions::DEFAULT).unwrap().grid;
    heights_agree(&g, t.as_ref(), &src, 7, 1e-3);
}

#[test]
fn wgs84_utm19s_30m_from_srtm() {
    let d = wgs84_utm19s_30m(&cota_fixtures::bundled_tile()).unwrap();
    let g = written_and_read(&d, "s29w072_32719.tif");
    let t = corners_match(
        &g,
        [
            [-71.620_289_696_451_22, -28.416_671_330_695_422],
            [-71.375_780_790_886_94, -28.421_159_494_504_902],
            [-71.379_415_891_308_03, -28.583_227_905_924_716],
            [-71.624_297_914_294_6, -28.578_709_511_302_907],
        ],
    );
    let path = cota_fixtures::fixture(cota_fixtures::BUNDLED_TILE);
    let src = read_dem(&path, &ReadOptions::DEFAULT).unwrap().grid;
    heights_agree(&g, t.as_ref(), &src, 13, 1e-3);
}
