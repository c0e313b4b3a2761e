//! SRTM `.hgt` / `.hgt.zip` reader: the bundled fixture, every shared tile
//! against DATA.md, georeference, shared tile edges, and small synthetic tiles
//! (any n×n, names with and without a position, ZIP member selection).
// Test helpers outside #[test] functions unwrap and panic like the tests do.
#![allow(clippy::unwrap_used, clippy::panic)]

use crate::common;

use std::path::Path;

use common::{fixture, hgt_bytes, shared_data, write_file, zip_bytes};
use cota_core::{Crs, PixelIs};
use cota_io::{read_dem, DataType, Dem, Format, ReadOptions};

fn read(path: &Path) -> Dem {
    read_dem(path, &ReadOptions::DEFAULT).unwrap_or_else(|e| panic!("{e}"))
}

/// Checks dimensions, valid range and void count.
fn check_stats(dem: &Dem, n: usize, range: (f32, f32), voids: usize) {
    let name = dem.path.display();
    assert_eq!((dem.grid.width(), dem.grid.height()), (n, n), "{name}");
    assert_eq!(dem.grid.valid_range(), Some(range), "{name}");
    assert_eq!(dem.grid.void_count(), voids, "{name}");
    assert_eq!(dem.data_type, DataType::I16);
    assert_eq!(dem.nodata, Some(-32768.0));
}

/// Checks the georeference of a 1201² tile with south-west corner (lat, lon).
fn check_georef(dem: &Dem, lat: f64, lon: f64) {
    let g = dem.grid.georef();
    assert_eq!(g.crs, Crs::Epsg(4326));
    assert_eq!(g.pixel_is, PixelIs::Point);
    assert!(g.known);
    assert_eq!((g.origin_x, g.origin_y), (lon, lat + 1.0));
    assert_eq!((g.pixel_x, g.pixel_y), (1.0 / 1200.0, -1.0 / 1200.0));
    let (x, y) = g.sample_xy(1200.0, 1200.0);
    assert!((x - (lon + 1.0)).abs() < 1e-9 && (y - lat).abs() < 1e-9);
}

#[test]
fn bundled_fixture_s29w072() {
    let dem = read(&fixture("S29W072.hgt.zip"));
    assert_eq!(dem.format, Format::SrtmHgtZip);
    check_stats(&dem, 1201, (-5.0, 1899.0), 21);
    check_georef(&dem, -29.0, -72.0);
    let [dx, dy] = dem.grid.cell_size_m();
    // 3 arc-seconds at 28.5° S: 92.8·cos(28.5°) ≈ 81.6 m east-west, ~92.3 m north-south.
    assert!((dx - 81.6).abs() < 0.5, "{dx}");
    assert!((dy - 92.3).abs() < 0.5, "{dy}");
}

/// A tile's expected statistics and position.
type Tile = (&'static str, (f32, f32), usize, f64, f64);

#[test]
fn shared_tiles_match_data_md() {
    let Some(data) = shared_data() else { return };
    // (file, valid range, voids, south-west latitude, longitude) from DATA.md.
    let tiles: [Tile; 7] = [
        ("N00E010.hgt", (1.0, 1005.0), 0, 0.0, 10.0),
        ("N00E011.hgt.zip", (105.0, 1023.0), 0, 0.0, 11.0),
        ("N41E001.hgt.zip", (-20.0, 1204.0), 134, 41.0, 1.0),
        ("N42E001.hgt.zip", (349.0, 3100.0), 7652, 42.0, 1.0),
        ("N49E011.hgt.zip", (234.0, 920.0), 20, 49.0, 11.0),
        ("N50E011.hgt.zip", (129.0, 1044.0), 8, 50.0, 11.0),
        ("S29W072.hgt.zip", (-5.0, 1899.0), 21, -29.0, -72.0),
    ];
    for (name, range, voids, lat, lon) in tiles {
        let dem = read(&data.join("srtm").join(name));
        let zipped = name.ends_with(".zip");
        let format = if zipped {
            Format::SrtmHgtZip
        } else {
            Format::SrtmHgt
        };
        assert_eq!(dem.format, format, "{name}");
        check_stats(&dem, 1201, range, voids);
        check_georef(&dem, lat, lon);
    }
}

#[test]
fn cell_size_at_the_equator() {
    let Some(data) = shared_data() else { return };
    let dem = read(&data.join("srtm/N00E010.hgt"));
    let [dx, dy] = dem.grid.cell_size_m();
    assert!((dx - 92.76).abs() < 0.1, "{dx}");
    assert!((dy - 92.13).abs() < 0.1, "{dy}");
}

/// Bit patterns, so that two voids compare equal.
fn bits(values: impl Iterator<Item = f32>) -> Vec<u32> {
    values.map(f32::to_bits).collect()
}

fn column(dem: &Dem, col: usize) -> Vec<u32> {
    bits((0..dem.grid.height()).map(|r| dem.grid.get(col, r)))
}

fn row(dem: &Dem, r: usize) -> Vec<u32> {
    bits((0..dem.grid.width()).map(|c| dem.grid.get(c, r)))
}

#[test]
fn adjacent_tiles_share_their_edges() {
    let Some(data) = shared_data() else { return };
    let srtm = data.join("srtm");
    let west = read(&srtm.join("N00E010.hgt"));
    let east = read(&srtm.join("N00E011.hgt.zip"));
    assert_eq!(column(&west, 1200), column(&east, 0));
    for (south, north) in [("N41E001", "N42E001"), ("N49E011", "N50E011")] {
        let s = read(&srtm.join(format!("{south}.hgt.zip")));
        let n = read(&srtm.join(format!("{north}.hgt.zip")));
        assert_eq!(
            row(&s, 0),
            row(&n, 1200),
            "{south} north row vs {north} south row"
        );
        // And the georeferences agree on where that row is.
        assert_eq!(
            s.grid.georef().sample_xy(0.0, 0.0),
            n.grid.georef().sample_xy(0.0, 1200.0)
        );
    }
}

#[test]
fn tiny_tiles_of_any_size() {
    let dir = tempfile::tempdir().unwrap();
    // 2×2 and 3×3; voids, negative heights, lowercase names, long names.
    let p = write_file(dir.path(), "n10e020.hgt", &hgt_bytes(&[1, -32768, -5, 300]));
    let dem = read(&p);
    assert_eq!(dem.format, Format::SrtmHgt);
    assert_eq!(dem.grid.width(), 2);
    assert!(dem.grid.get(1, 0).is_nan());
    assert_eq!((dem.grid.get(0, 1), dem.grid.get(1, 1)), (-5.0, 300.0));
    let g = dem.grid.georef();
    assert_eq!((g.origin_x, g.origin_y, g.pixel_x), (20.0, 11.0, 1.0));

    let p = write_file(dir.path(), "S01W180.SRTMGL1.HGT", &hgt_bytes(&[7; 9]));
    let g = read(&p).grid.georef().clone();
    assert_eq!(
        (g.origin_x, g.origin_y, g.pixel_x, g.pixel_y),
        (-180.0, 0.0, 0.5, -0.5)
    );
}

#[test]
fn zipped_names_and_members() {
    let dir = tempfile::tempdir().unwrap();
    let tile = hgt_bytes(&[1, 2, 3, 4, 5, 6, 7, 8, 9]);
    // Position from the archive's name, whatever the member is called.
    let z = zip_bytes(&[("readme.txt", b"hello"), ("data/tile.hgt", &tile)]);
    let dem = read(&write_file(dir.path(), "N00E010.SRTMGL1.hgt.zip", &z));
    assert_eq!(dem.format, Format::SrtmHgtZip);
    assert_eq!(
        dem.grid.heights(),
        &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]
    );
    assert_eq!(dem.grid.georef().origin_x, 10.0);
    // Position from the member when the archive's name has none.
    let z = zip_bytes(&[("S29W072.HGT", &tile)]);
    let g = read(&write_file(dir.path(), "download.zip", &z))
        .grid
        .georef()
        .clone();
    assert_eq!((g.origin_x, g.origin_y), (-72.0, -28.0));
    assert!(g.known);
}

#[test]
fn tiles_without_a_position_are_unreferenced() {
    let dir = tempfile::tempdir().unwrap();
    let dem = read(&write_file(dir.path(), "tile.hgt", &hgt_bytes(&[0; 16])));
    let g = dem.grid.georef();
    assert!(!g.known);
    assert_eq!(g.crs, Crs::Unknown);
    // One degree over n−1 = 3 steps on the mean sphere.
    assert!((g.pixel_x - 111_195.0 / 3.0).abs() < 1e-6, "{}", g.pixel_x);
    // An impossible latitude is no position either.
    let dem = read(&write_file(dir.path(), "N95E010.hgt", &hgt_bytes(&[0; 4])));
    assert!(!dem.grid.georef().known);
}

#[test]
fn standard_size_is_recognised_without_the_extension() {
    let Some(data) = shared_data() else { return };
    let bytes = std::fs::read(data.join("srtm/N00E010.hgt")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let dem = read(&write_file(dir.path(), "N00E010.raw", &bytes));
    assert_eq!(dem.format, Format::SrtmHgt);
    assert_eq!(dem.grid.georef().origin_x, 10.0);
}
