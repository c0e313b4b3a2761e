//! `--src-crs` and the CRS lines of `cota info`: the footprint of projected
//! and geographic inputs in WGS 84, a CRS given to an input that has none,
//! and the refusals (an unknown EPSG code, a flag that contradicts the
//! file's own CRS, no CRS where a map to longitude/latitude is needed).
#![allow(clippy::unwrap_used, clippy::panic)]

use crate::common;

use common::{cota, fixture, stderr, stdout};
use serde_json::Value;

fn s(p: &std::path::Path) -> &str {
    p.to_str().unwrap()
}

fn json(args: &[&str]) -> Value {
    let o = cota(args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

fn close(got: &Value, want: [f64; 4], tol: f64) {
    let got: Vec<f64> = got
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    for (g, w) in got.iter().zip(want) {
        assert!((g - w).abs() <= tol, "{got:?} against {want:?}");
    }
}

/// The Olinda DEM (user-defined UTM 25S in its GeoKeys): its footprint as
/// PROJ 9.5.1 maps its corners (`cota_io`'s tests/crs.rs), in text and JSON.
#[test]
fn info_prints_the_footprint_of_a_projected_input() {
    let f = fixture("olinda_dem_utm25s.tif");
    let o = cota(&["info", s(&f)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(
        text.contains("  crs         UTM Zone 25, Southern Hemisphere; ")
            && text.contains(
                "(+proj=utm +zone=25 +south +ellps=GRS80 +towgs84=0,0,0 +units=m +no_defs)"
            ),
        "{text}"
    );
    assert!(
        text.contains(
            "  footprint   -34.916177,-8.040134,-34.825987,-7.950231 (W,S,E,N degrees, WGS 84)"
        ),
        "{text}"
    );
    let r = json(&["info", "--json", s(&f)]);
    let want = [
        -34.916_177_105_979_656,
        -8.040_134_466_083_028,
        -34.825_986_991_407_46,
        -7.950_230_784_066_048,
    ];
    close(&r["footprint_deg"], want, 1e-8);
    close(&r["files"][0]["footprint_deg"], want, 1e-8);
    assert_eq!(
        r["crs_definition"],
        "+proj=utm +zone=25 +south +ellps=GRS80 +towgs84=0,0,0 +units=m +no_defs"
    );
    assert!(r["footprint_note"].is_null());
}

#[test]
fn info_prints_the_footprint_of_a_geographic_input() {
    let f = fixture("S29W072.hgt.zip");
    let o = cota(&["info", s(&f)]);
    let text = stdout(&o);
    assert!(text.contains("  crs         EPSG:4326 (WGS 84)"), "{text}");
    assert!(
        text.contains(
            "  footprint   -72.000000,-29.000000,-71.000000,-28.000000 (W,S,E,N degrees, WGS 84)"
        ),
        "{text}"
    );
    let r = json(&["info", "--json", s(&f)]);
    assert_eq!(r["crs"], "EPSG:4326");
    assert_eq!(r["crs_name"], "EPSG:4326 (WGS 84)");
    close(&r["footprint_deg"], [-72.0, -29.0, -71.0, -28.0], 1e-12);
}

/// An ESRI grid in UTM coordinates without a .prj: no footprint (and why)
/// without --src-crs; with it, the grid is placed; EPSG:N in any case and
/// a PROJ string give the same.
#[test]
fn src_crs_gives_a_crs_to_an_input_without_one() {
    let dir = tempfile::tempdir().unwrap();
    let asc = dir.path().join("utm.asc");
    std::fs::write(
        &asc,
        "ncols 3\nnrows 2\nxllcorner 499955\nyllcorner 3999970\ncellsize 30\n1 2 3\n4 5 6\n",
    )
    .unwrap();
    let r = json(&["info", "--json", s(&asc)]);
    assert_eq!(r["crs"], "unknown");
    assert!(r["footprint_deg"].is_null());
    let note = r["footprint_note"].as_str().unwrap();
    assert!(note.contains("pass --src-crs EPSG:N"), "{note}");
    let o = cota(&["info", s(&asc)]);
    assert!(
        stdout(&o).contains("  footprint   none: expected a known CRS"),
        "{}",
        stdout(&o)
    );
    // UTM 33N around (500 000 m, 4 000 000 m): PROJ 9.5.1 (pyproj) maps
    // the sample rectangle's corners to these bounds.
    let want = [
        14.999_666_527_766_038,
        36.144_582_862_461_206,
        15.000_333_472_233_926,
        36.144_853_334_242_775,
    ];
    for flag in ["epsg:32633", "+proj=utm +zone=33 +datum=WGS84 +units=m"] {
        let r = json(&["info", "--json", "--src-crs", flag, s(&asc)]);
        close(&r["footprint_deg"], want, 1e-8);
    }
    let r = json(&["info", "--json", "--src-crs", "EPSG:32633", s(&asc)]);
    assert_eq!(r["crs"], "EPSG:32633");
    assert_eq!(
        r["files"][0]["crs_name"],
        "EPSG:32633 (WGS 84 / UTM zone 33N)"
    );
}

/// An ESRI grid whose numbers only look like degrees takes the flag's CRS
/// instead of the guess.
#[test]
fn src_crs_replaces_the_guessed_wgs84_of_an_ascii_grid() {
    let dir = tempfile::tempdir().unwrap();
    let asc = dir.path().join("deg.asc");
    std::fs::write(
        &asc,
        "ncols 2\nnrows 2\nxllcorner -105.5\nyllcorner 40.0\ncellsize 0.001\n1 2\n3 4\n",
    )
    .unwrap();
    let r = json(&["info", "--json", s(&asc)]);
    assert!(
        r["crs"].as_str().unwrap().starts_with("WGS 84 (assumed"),
        "{}",
        r["crs"]
    );
    let r = json(&["info", "--json", "--src-crs", "EPSG:4269", s(&asc)]);
    assert_eq!(r["crs"], "EPSG:4269");
    close(
        &r["footprint_deg"],
        [-105.4995, 40.0005, -105.4985, 40.0015],
        1e-9,
    );
}

/// The file's own CRS against the flag: the same CRS (also when written
/// another way) is fine; another one is refused with both named and what
/// to do.
#[test]
fn src_crs_that_contradicts_the_file_is_refused() {
    let olinda = fixture("olinda_dem_utm25s.tif");
    // SIRGAS 2000 / UTM 25S: the same map as the file's GRS 1980 UTM 25S.
    let r = json(&["info", "--json", "--src-crs", "EPSG:31985", s(&olinda)]);
    assert_eq!(r["crs"], "EPSG:31985");
    for (flag, why) in [
        ("EPSG:32724", "m apart under the two"),
        ("EPSG:4326", "m apart under the two"),
    ] {
        let o = cota(&["info", "--src-crs", flag, s(&olinda)]);
        assert_eq!(o.status.code(), Some(1), "{flag}");
        let e = stderr(&o);
        assert!(
            e.contains("olinda_dem_utm25s.tif: the file declares its CRS as UTM Zone 25, Southern Hemisphere")
                && e.contains(&format!("contradicts --src-crs {flag}"))
                && e.contains(why)
                && e.contains("drop --src-crs"),
            "{flag}: {e}"
        );
    }
    let srtm = fixture("S29W072.hgt.zip");
    let o = cota(&[
        "mesh",
        "--src-crs",
        "EPSG:32719",
        s(&srtm),
        "--max-error",
        "50",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("S29W072.hgt.zip: the file declares its CRS as EPSG:4326 (WGS 84), which contradicts --src-crs EPSG:32719 (WGS 84 / UTM zone 19S) (different EPSG codes)"),
        "{e}"
    );
    // The same EPSG code is fine.
    assert!(cota(&["info", "--src-crs", "EPSG:4326", s(&srtm)])
        .status
        .success());
}

#[test]
fn unknown_epsg_codes_and_bad_proj_strings_are_refused() {
    let f = fixture("hugo_site.asc");
    for (flag, want) in [
        ("EPSG:99999", "found EPSG:99999"),
        ("EPSG:abc", "expected EPSG:N"),
        ("utm33", "expected EPSG:N"),
        (
            "+proj=nosuch",
            "expected a PROJ definition proj4rs can read",
        ),
    ] {
        let o = cota(&["info", "--src-crs", flag, s(&f)]);
        assert!(!o.status.success(), "{flag}");
        let e = stderr(&o);
        assert!(e.contains("--src-crs") && e.contains(want), "{flag}: {e}");
    }
}
