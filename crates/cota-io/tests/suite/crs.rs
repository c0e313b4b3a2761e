//! cota's map projections against PROJ: the reference points of
//! `tests/data/crs_reference.json`, written by `tools/crs_reference.py`
//! (pyproj; see that script for which PROJ operation each CRS is checked
//! against). Forward (lon/lat -> x/y) within 1 mm, inverse (x/y -> lon/lat)
//! within 1e-8 degrees (about 1 mm).
#![allow(clippy::unwrap_used, clippy::panic)]

use cota_core::{Crs, GeoTransform};
use cota_io::crs::{
    check_round_trip, epsg, parse_crs, transform_and_tolerance, transform_for, CrsError,
};
use serde_json::Value;

/// Forward tolerance, metres.
const TOL_M: f64 = 1e-3;
/// Inverse tolerance, degrees.
const TOL_DEG: f64 = 1e-8;

fn reference() -> Value {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/crs_reference.json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn rows(v: &Value) -> Vec<[f64; 4]> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|r| {
            let r: Vec<f64> = r
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            [r[0], r[1], r[2], r[3]]
        })
        .collect()
}

/// The largest forward error (metres) and inverse error (degrees) of `t`
/// on one CRS's reference points.
fn errors(t: &dyn GeoTransform, c: &Value) -> (f64, f64) {
    let mut fwd = 0.0f64;
    for [lon, lat, x, y] in rows(&c["forward"]) {
        let [px, py] = t.from_lonlat(lon, lat).unwrap();
        fwd = fwd.max((px - x).abs()).max((py - y).abs());
    }
    let mut inv = 0.0f64;
    for [x, y, lon, lat] in rows(&c["inverse"]) {
        let [plon, plat] = t.to_lonlat(x, y).unwrap();
        inv = inv.max((plon - lon).abs()).max((plat - lat).abs());
    }
    (fwd, inv)
}

#[test]
fn transforms_match_proj() {
    let doc = reference();
    println!("reference: pyproj {} / PROJ {}", doc["pyproj"], doc["proj"]);
    println!(
        "{:>6}  {:>12}  {:>12}  name",
        "EPSG", "forward m", "inverse deg"
    );
    let mut failures = Vec::new();
    for c in doc["crs"].as_array().unwrap() {
        let code = c["code"].as_u64().unwrap() as u32;
        // The reference was made from the definition cota reads.
        if !epsg::is_web_mercator(code) {
            assert_eq!(
                epsg::definition(code),
                c["proj_cota"].as_str(),
                "EPSG:{code}: crs-definitions changed; rerun tools/crs_reference.py"
            );
        }
        let t = transform_for(&Crs::Epsg(code)).unwrap();
        let (fwd, inv) = errors(t.as_ref(), c);
        println!("{code:>6}  {fwd:>12.3e}  {inv:>12.3e}  {}", c["name"]);
        if fwd > TOL_M || inv > TOL_DEG {
            failures.push(format!(
                "EPSG:{code}: forward {fwd:.3e} m, inverse {inv:.3e} deg"
            ));
        }
        // The same definition given as a PROJ string maps the same.
        let def = Crs::Proj(c["proj_cota"].as_str().unwrap().to_string());
        let (fwd2, inv2) = errors(transform_for(&def).unwrap().as_ref(), c);
        assert!(
            fwd2 <= fwd.max(TOL_M) && inv2 <= inv.max(TOL_DEG),
            "EPSG:{code} as PROJ"
        );
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Every reference point maps to WGS 84 and back within the CRS's
/// round-trip tolerance (1e-5 m; 1 cm through a Helmert datum shift); the
/// largest round trips are printed.
#[test]
fn reference_points_round_trip() {
    let doc = reference();
    for c in doc["crs"].as_array().unwrap() {
        let code = c["code"].as_u64().unwrap() as u32;
        let (t, tol) = transform_and_tolerance(&Crs::Epsg(code)).unwrap();
        let points: Vec<[f64; 2]> = rows(&c["inverse"]).iter().map(|r| [r[0], r[1]]).collect();
        let worst = points
            .iter()
            .map(|&[x, y]| {
                let [lon, lat] = t.to_lonlat(x, y).unwrap();
                let [bx, by] = t.from_lonlat(lon, lat).unwrap();
                (bx - x).hypot(by - y)
            })
            .fold(0.0f64, f64::max);
        println!("EPSG:{code}: round trip {worst:.3e} (tolerance {tol:e})");
        check_round_trip(t.as_ref(), &format!("EPSG:{code}"), &points, tol)
            .unwrap_or_else(|e| panic!("{e}"));
    }
}

#[test]
fn web_mercator_codes_are_one_map() {
    let a = transform_for(&Crs::Epsg(3857)).unwrap();
    for code in [900_913, 3785, 102_100, 102_113] {
        let b = transform_for(&Crs::Epsg(code)).unwrap();
        assert_eq!(
            a.from_lonlat(12.5, 41.9),
            b.from_lonlat(12.5, 41.9),
            "{code}"
        );
    }
    // The Mercator y of 85.0511287798° is half the equator's length.
    let [_, y] = a.from_lonlat(0.0, 85.051_128_779_806_59).unwrap();
    assert!((y - 20_037_508.342_789_244).abs() < 1e-6, "{y}");
}

#[test]
fn bad_crs_text_and_codes() {
    assert_eq!(
        parse_crs("EPSG:99999").unwrap_err(),
        CrsError::UnknownEpsg { code: 99_999 }
    );
    let e = parse_crs("EPSG:99999").unwrap_err().to_string();
    assert!(
        e.contains("found EPSG:99999") && e.contains("+proj="),
        "{e}"
    );
    let e = parse_crs("utm33").unwrap_err().to_string();
    assert!(
        e.contains("expected EPSG:N") && e.contains("\"utm33\""),
        "{e}"
    );
    let e = transform_for(&Crs::Epsg(99_999)).unwrap_err();
    assert_eq!(e, CrsError::UnknownEpsg { code: 99_999 });
    let e = transform_for(&Crs::Unknown).unwrap_err().to_string();
    assert!(e.contains("--src-crs EPSG:N"), "{e}");
}

/// The shared Olinda DEM (a GeoTIFF with a user-defined UTM 25S on GRS
/// 1980): its corners in WGS 84 as PROJ 9.5.1 gives them for the same
/// definition (pyproj), and its footprint.
#[test]
fn olinda_user_defined_utm_maps_like_proj() {
    let Some(dir) = cota_fixtures::shared_data() else {
        return;
    };
    let path = dir.join("texture/olinda_dem_utm25s.tif");
    let dem = cota_io::read_dem(&path, &cota_io::ReadOptions::DEFAULT).unwrap();
    let g = dem.grid.georef();
    let (w, h) = (dem.grid.width(), dem.grid.height());
    let t = cota_io::crs::transform_for_grid(g, w, h).unwrap();
    assert!(!t.is_identity());
    let proj = [
        [-34.915_759_377_927_81, -7.950_230_784_066_048],
        [-34.825_986_991_407_46, -7.950_635_138_706_903],
        [-34.826_385_171_920_59, -8.040_134_466_083_028],
        [-34.916_177_105_979_656, -8.039_725_502_061_65],
    ];
    for ([x, y], [lon, lat]) in cota_io::crs::sample_corners(g, w, h).into_iter().zip(proj) {
        let [plon, plat] = t.to_lonlat(x, y).unwrap();
        assert!(
            (plon - lon).abs() < TOL_DEG && (plat - lat).abs() < TOL_DEG,
            "{plon} {plat}"
        );
    }
    let f = cota_io::crs::footprint(g, w, h, t.as_ref(), 32).unwrap();
    // West, south, east, north: corners of the (slightly rotated) rectangle.
    let want = [proj[3][0], proj[2][1], proj[1][0], proj[0][1]];
    for (got, want) in f.iter().zip(want) {
        assert!((got - want).abs() < TOL_DEG, "{f:?}");
    }
}

/// Informative: the time of one point each way (the parsed proj4rs objects
/// are reused; nothing is parsed per call).
#[test]
fn time_per_point() {
    for code in [32633, 27700, 2154, 3857] {
        let t = transform_for(&Crs::Epsg(code)).unwrap();
        let n = 200_000;
        let start = std::time::Instant::now();
        let mut sum = 0.0;
        for i in 0..n {
            let f = f64::from(i) / f64::from(n);
            let [x, y] = t.from_lonlat(-2.0 + 0.5 * f, 50.0 + f).unwrap();
            let [lon, lat] = t.to_lonlat(x, y).unwrap();
            sum += lon + lat;
        }
        let ns = start.elapsed().as_secs_f64() * 1e9 / f64::from(2 * n);
        println!("EPSG:{code}: {ns:.0} ns per point and direction ({sum:.0})");
    }
}
