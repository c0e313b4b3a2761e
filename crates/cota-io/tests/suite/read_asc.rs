//! ESRI ASCII grid reader: the bundled fixtures against DATA.md (these always
//! run), the shared copies when present, and header variants.
// Test helpers outside #[test] functions unwrap and panic like the tests do.
#![allow(clippy::unwrap_used, clippy::panic)]

use crate::common;

use std::path::Path;

use common::{fixture, shared_data, write_file};
use cota_core::{Crs, PixelIs};
use cota_io::{read_dem, DataType, Dem, Format, ReadOptions};

fn read(path: &Path) -> Dem {
    read_dem(path, &ReadOptions::DEFAULT).unwrap_or_else(|e| panic!("{e}"))
}

/// (file, width, height, valid range, voids, data type, nodata) from DATA.md.
type Expected = (
    &'static str,
    usize,
    usize,
    (f32, f32),
    usize,
    DataType,
    Option<f64>,
);

const FILES: [Expected; 3] = [
    (
        "bijou_gully_subset_5m_edit_dx_filled.asc",
        105,
        77,
        (1673.0679, 1729.865),
        0,
        DataType::F32,
        None,
    ),
    (
        "boulder_srtmgl3_240x144.asc",
        240,
        144,
        (1943.0, 3286.0),
        0,
        DataType::I32,
        Some(0.0),
    ),
    (
        "hugo_site.asc",
        76,
        55,
        (1660.0, 1711.0),
        2028,
        DataType::I32,
        Some(-9999.0),
    ),
];

fn check(dem: &Dem, e: &Expected) {
    let (name, w, h, (lo, hi), voids, dt, nodata) = *e;
    assert_eq!(dem.format, Format::EsriAscii, "{name}");
    assert_eq!((dem.grid.width(), dem.grid.height()), (w, h), "{name}");
    let (min, max) = dem.grid.valid_range().unwrap();
    assert!(
        (min - lo).abs() < 1e-3 && (max - hi).abs() < 1e-3,
        "{name}: {min}..{max}"
    );
    assert_eq!(dem.grid.void_count(), voids, "{name}");
    assert_eq!(dem.data_type, dt, "{name}");
    assert_eq!(dem.nodata, nodata, "{name}");
    // No .prj is read; read_dem assumes WGS 84 only where the georeference
    // looks like degrees (the Boulder SRTM clip), else the CRS stays unknown.
    let crs = &dem.grid.georef().crs;
    if name.starts_with("boulder") {
        assert!(crs.is_geographic(), "{name}: {crs}");
    } else {
        assert_eq!(*crs, Crs::Unknown, "{name}");
    }
}

#[test]
fn fixtures_match_data_md() {
    for e in &FILES {
        check(&read(&fixture(e.0)), e);
    }
}

#[test]
fn shared_copies_match_data_md() {
    let Some(data) = shared_data() else { return };
    for e in &FILES {
        check(&read(&data.join("asc").join(e.0)), e);
    }
}

#[test]
fn corner_georeference_of_boulder() {
    let dem = read(&fixture("boulder_srtmgl3_240x144.asc"));
    let g = dem.grid.georef();
    assert_eq!(g.pixel_is, PixelIs::Area);
    assert!(g.known);
    assert_eq!(g.origin_x, -105.550416666684);
    let top = 40.090416666671 + 144.0 * 0.000833333333;
    assert!((g.origin_y - top).abs() < 1e-12, "{}", g.origin_y);
    assert_eq!((g.pixel_x, g.pixel_y), (0.000833333333, -0.000833333333));
    // 3 arc-seconds at 40.15° N, once the degrees are recognised.
    let [dx, dy] = dem.grid.cell_size_m();
    assert!(
        (dx - 71.0).abs() < 0.5 && (dy - 92.5).abs() < 0.5,
        "{dx} x {dy}"
    );
    // The south-west sample sits half a cell inside the lower-left corner.
    let (x, y) = g.sample_xy(0.0, 143.0);
    assert!((x - (-105.550416666684 + 0.0004166666665)).abs() < 1e-9);
    assert!((y - (40.090416666671 + 0.0004166666665)).abs() < 1e-9);
}

#[test]
fn hugo_voids_are_where_the_file_has_minus_9999() {
    let dem = read(&fixture("hugo_site.asc"));
    assert!(dem.grid.get(0, 0).is_nan());
    assert_eq!(dem.grid.georef().pixel_x, 10.0);
}

#[test]
fn header_variants() {
    let dir = tempfile::tempdir().unwrap();
    // Keys in any case and order, values wrapped across lines, centres.
    let text = "NRows 2\nNCOLS 3\nXLLCENTER 100\nYLLCENTER 200\nCellSize 10\n\
                NoData_Value -1\n1 2\n3 4 -1\n6\n";
    let dem = read(&write_file(dir.path(), "c.asc", text.as_bytes()));
    assert_eq!(dem.grid.width(), 3);
    assert_eq!(dem.grid.void_count(), 1);
    assert!(dem.grid.get(1, 1).is_nan());
    let g = dem.grid.georef();
    assert_eq!(g.pixel_is, PixelIs::Point);
    assert_eq!(g.sample_xy(0.0, 1.0), (100.0, 200.0));
    assert_eq!(g.sample_xy(0.0, 0.0), (100.0, 210.0));
    // GDAL's dx/dy, decimals, CRLF line ends.
    let text = "ncols 2\r\nnrows 1\r\nxllcorner 0\r\nyllcorner 0\r\ndx 2\r\ndy 5\r\n1.25 -3e1\r\n";
    let dem = read(&write_file(dir.path(), "d.asc", text.as_bytes()));
    assert_eq!(dem.grid.heights(), &[1.25, -30.0]);
    assert_eq!(dem.data_type, DataType::F32);
    let g = dem.grid.georef();
    assert_eq!((g.pixel_x, g.pixel_y, g.origin_y), (2.0, -5.0, 5.0));
}
