//! Gzipped DEMs (`N00E010.hgt.gz` as served by the AWS/Mapzen "skadi" tiles,
//! or any gzipped format) are read through one level of gzip.
#![allow(clippy::unwrap_used, clippy::panic, reason = "tests")]

use crate::common;

use std::io::Write;

use common::{fixture, hgt_bytes, write_file};
use cota_io::{read_dem, Format, PngEncoding, ReadOptions};

fn gz(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

#[test]
fn gzipped_hgt_and_png_read_like_the_originals() {
    let dir = tempfile::tempdir().unwrap();
    let samples: Vec<i16> = (0..9).map(|i| i * 10 - 3).collect();
    let p = write_file(dir.path(), "S29W072.hgt.gz", &gz(&hgt_bytes(&samples)));
    let dem = read_dem(&p, &ReadOptions::DEFAULT).unwrap();
    assert_eq!(dem.format, Format::SrtmHgt);
    assert_eq!((dem.grid.width(), dem.grid.height()), (3, 3));
    assert_eq!(dem.grid.valid_range(), Some((-3.0, 77.0)));
    assert_eq!(dem.grid.georef().sample_xy(0.0, 2.0), (-72.0, -29.0));
    assert_eq!(dem.path, p);

    let png = std::fs::read(fixture("terrarium.png")).unwrap();
    let p = write_file(dir.path(), "tile.png.gz", &gz(&png));
    let dem = read_dem(&p, &ReadOptions::DEFAULT).unwrap();
    assert_eq!(dem.format, Format::Png(PngEncoding::Terrarium));
}

#[test]
fn broken_or_nested_gzip_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let full = gz(&hgt_bytes(&[1, 2, 3, 4]));
    let p = write_file(dir.path(), "cut.hgt.gz", &full[..full.len() / 2]);
    let e = read_dem(&p, &ReadOptions::DEFAULT).unwrap_err().to_string();
    assert!(
        e.contains("cut.hgt.gz") && e.contains("expected a complete gzip stream"),
        "{e}"
    );
    let p = write_file(dir.path(), "twice.hgt.gz.gz", &gz(&full));
    let e = read_dem(&p, &ReadOptions::DEFAULT).unwrap_err().to_string();
    assert!(e.contains("gzip stream inside a gzip stream"), "{e}");
}
