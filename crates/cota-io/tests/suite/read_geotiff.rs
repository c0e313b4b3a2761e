//! GeoTIFF reader: the real GeoTIFFs of the shared data directory (as listed in
//! its DATA.md), synthetic TIFFs covering each layout, sample type, compression
//! and predictor, and bad input that must fail with a clear error, never a panic.
//!
//! The shared data is found through `COTA_SHARED_DATA`, else at
//! `<workspace root>/../shared/data`; tests needing it print "skipped: …" and
//! pass when it is absent.

// Test helpers (here and in `common`) fail by panicking or unwrapping, also
// outside `#[test]` functions, where clippy's allow-in-tests does not reach.
#![allow(clippy::panic, clippy::unwrap_used)]

use crate::common;

use std::io::Cursor;
use std::path::{Path, PathBuf};

use cota_core::{Crs, PixelIs};
use cota_io::{read_dem, read_dem_bytes, DataType, Dem, Format, ReadError, ReadOptions};
use tiff::encoder::{colortype, Compression, DeflateLevel, TiffEncoder};
use tiff::tags::{Predictor, Tag};

// ---------------------------------------------------------------- helpers

/// A file of the shared data, or `None` after printing why the test is skipped.
fn shared(rel: &str) -> Option<PathBuf> {
    let p = common::shared_data()?.join(rel);
    if p.is_file() {
        Some(p)
    } else {
        println!("skipped: {} not found", p.display());
        None
    }
}

fn read(path: &Path) -> Dem {
    read_dem(path, &ReadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn read_bytes(bytes: &[u8], name: &str) -> Result<Dem, ReadError> {
    // The whole sample range and any height: these tests are about format
    // checks, not the memory budget or the height limit.
    let opts = ReadOptions::default()
        .with_max_samples(Some(cota_core::grid::MAX_SAMPLES))
        .with_max_abs_height_m(f64::INFINITY);
    read_dem_bytes(bytes, Path::new(name), &opts)
}

fn err_bytes(bytes: &[u8], name: &str) -> String {
    match read_bytes(bytes, name) {
        Ok(d) => panic!("{name}: expected an error, read {:?}", d.grid.valid_range()),
        Err(e) => e.to_string(),
    }
}

/// What DATA.md says about a file.
struct Expect {
    rel: &'static str,
    size: (usize, usize),
    data_type: DataType,
    range: (f32, f32),
    voids: usize,
    nodata: Option<f64>,
}

fn check(e: &Expect) -> Option<Dem> {
    let path = shared(e.rel)?;
    let dem = read(&path);
    let g = &dem.grid;
    assert_eq!(dem.format, Format::GeoTiff, "{}", e.rel);
    assert_eq!((g.width(), g.height()), e.size, "{}", e.rel);
    assert_eq!(dem.data_type, e.data_type, "{}", e.rel);
    let (lo, hi) = g.valid_range().expect("some valid samples");
    assert!(
        (lo - e.range.0).abs() <= 1e-3 && (hi - e.range.1).abs() <= 1e-3,
        "{}: range {lo}..{hi}, DATA.md {:?}",
        e.rel,
        e.range
    );
    assert_eq!(g.void_count(), e.voids, "{}", e.rel);
    assert_eq!(dem.nodata, e.nodata, "{}", e.rel);
    assert!(g.georef().known, "{}", e.rel);
    Some(dem)
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

// ---------------------------------------------------------------- real files

#[test]
fn mt_fuji_int16_tiled_srtm() {
    let Some(dem) = check(&Expect {
        rel: "geotiff/mt_fuji_90m.tif",
        size: (1201, 1201),
        data_type: DataType::I16,
        range: (-16.0, 3742.0),
        voids: 2437,
        nodata: Some(-32768.0),
    }) else {
        return;
    };
    let g = dem.grid.georef();
    assert_eq!(g.crs, Crs::Epsg(4326));
    assert_eq!(g.pixel_is, PixelIs::Area);
    assert!(close(g.pixel_x, 1.0 / 1200.0, 1e-12), "{}", g.pixel_x);
    assert!(close(g.pixel_y, -1.0 / 1200.0, 1e-12), "{}", g.pixel_y);
    // The first sample's centre is at 138 E, 36 N (the SRTM tile corner).
    let (x, y) = g.sample_xy(0.0, 0.0);
    assert!(close(x, 138.0, 1e-9) && close(y, 36.0, 1e-9), "{x} {y}");
    // 3 arc-seconds at about 35.5 N: ~75 m east-west, ~92 m north-south.
    let [dx, dy] = dem.grid.cell_size_m();
    assert!((73.0..78.0).contains(&dx), "{dx}");
    assert!((91.0..93.5).contains(&dy), "{dy}");
}

#[test]
fn mapzen_float32_deflate_float_predictor_pixel_is_point() {
    let Some(dem) = check(&Expect {
        rel: "geotiff/mapzen-geotiff-14-10348-7801.tif",
        size: (512, 512),
        data_type: DataType::F32,
        range: (599.605_47, 645.596_44),
        voids: 0,
        nodata: Some(f64::from(f32::MIN)),
    }) else {
        return;
    };
    let g = dem.grid.georef();
    assert_eq!(g.crs, Crs::Epsg(3857));
    assert_eq!(g.pixel_is, PixelIs::Point);
    assert!(close(g.pixel_x, 4.777_314_267_825, 1e-9));
    assert!(close(g.pixel_y, -4.777_314_267_822, 1e-9));
    // Pixel-is-point: the tie point is the first sample itself.
    assert_eq!(
        g.sample_xy(0.0, 0.0),
        (5_273_545.844_108_013, 956_377.709_246_991_3)
    );
    // Web Mercator metres at about 8.6 N: scale cos(lat).
    let [dx, _] = dem.grid.cell_size_m();
    assert!((4.6..4.75).contains(&dx), "{dx}");
}

#[test]
fn sanfrancisco_float32_lzw_tiled() {
    let Some(dem) = check(&Expect {
        rel: "geotiff/sanfrancisco_rio_rgbify.tif",
        size: (512, 512),
        data_type: DataType::F32,
        range: (0.436_010_42, 114.920_9),
        voids: 0,
        nodata: None,
    }) else {
        return;
    };
    let g = dem.grid.georef();
    assert_eq!(g.crs, Crs::Epsg(3857));
    assert_eq!(g.pixel_is, PixelIs::Area);
    assert!(close(g.origin_x, -13_630_156.552_455_971, 1e-6));
    assert!(close(g.pixel_y, -6.059_025_744_365_499, 1e-12));
}

#[test]
fn luxembourg_int16_lzw_strips_with_voids() {
    let Some(dem) = check(&Expect {
        rel: "geotiff/luxembourg_elev_terra.tif",
        size: (95, 90),
        data_type: DataType::I16,
        range: (141.0, 547.0),
        voids: 3942,
        nodata: Some(-32768.0),
    }) else {
        return;
    };
    let g = dem.grid.georef();
    assert_eq!(g.crs, Crs::Epsg(4326));
    assert!(close(g.origin_x, 5.741_666_666_666_666, 1e-12));
    assert!(close(g.origin_y, 50.191_666_666_666_66, 1e-12));
    assert!(close(g.pixel_x, 1.0 / 120.0, 1e-12));
}

#[test]
fn dem_hills_float32_strips_user_defined_geographic() {
    let Some(dem) = check(&Expect {
        rel: "geotiff/dem-hills.tiff",
        size: (333, 218),
        data_type: DataType::F32,
        range: (138.288_88, 168.003_7),
        voids: 949,
        nodata: Some(-999_999.0),
    }) else {
        return;
    };
    let g = dem.grid.georef();
    // DATA.md says "unknown" (GDAL finds no EPSG code); the GeoKeys say a
    // user-defined geographic CRS, described by its citation.
    match &g.crs {
        Crs::Geographic(s) => assert!(s.contains("Delambre"), "{s}"),
        other => panic!("expected a user-defined geographic CRS, got {other:?}"),
    }
    assert!(close(g.origin_x, -87.509_259_26, 1e-9));
    // 1/3 arc-second: about 10 m.
    let [dx, dy] = dem.grid.cell_size_m();
    assert!(
        (7.0..8.5).contains(&dx) && (10.0..10.6).contains(&dy),
        "{dx} {dy}"
    );
}

#[test]
fn olinda_float32_user_defined_utm_25s() {
    let Some(dem) = check(&Expect {
        rel: "texture/olinda_dem_utm25s.tif",
        size: (111, 111),
        data_type: DataType::F32,
        range: (-1.0, 88.0),
        voids: 0,
        nodata: None,
    }) else {
        return;
    };
    let g = dem.grid.georef();
    // The user-defined projection's keys (ProjectionGeoKey 16125 = UTM zone
    // 25S, the GRS 1980 axes, a zero TOWGS84) give its PROJ definition; the
    // citation follows as its title.
    let name = "UTM Zone 25, Southern Hemisphere; GCS Name = GRS 1980(IUGG, 1980); \
                Datum = unknown; Ellipsoid = GRS80; Primem = Greenwich";
    let def = "+proj=utm +zone=25 +south +ellps=GRS80 +towgs84=0,0,0 +units=m +no_defs";
    assert_eq!(g.crs, Crs::Proj(format!("{def} +title=\"{name}\"")));
    assert_eq!(cota_io::crs::describe(&g.crs), format!("{name} ({def})"));
    assert!(close(g.origin_x, 288_776.250_000_803_15, 1e-6));
    assert!(close(g.pixel_x, 89.994_067_349_451_16, 1e-9));
    assert_eq!(dem.grid.cell_size_m(), [g.pixel_x, -g.pixel_y]);
}

#[test]
fn landsat_six_bands_needs_a_band() {
    let Some(path) = shared("texture/L7_ETMs.tif") else {
        return;
    };
    let err = read_dem(&path, &ReadOptions::default())
        .expect_err("multi-band without --band")
        .to_string();
    assert!(err.contains("L7_ETMs.tif"), "{err}");
    assert!(
        err.contains("expected a single-band DEM, found 6 bands; choose one with --band"),
        "{err}"
    );
    let err = read_dem(&path, &ReadOptions::default().with_band(Some(7)))
        .expect_err("band 7 of 6")
        .to_string();
    assert!(
        err.contains("expected a band in 1..=6, found band 7"),
        "{err}"
    );
    assert!(read_dem(&path, &ReadOptions::default().with_band(Some(0))).is_err());

    let mut ranges = Vec::new();
    for band in 1..=6 {
        let dem = read_dem(&path, &ReadOptions::default().with_band(Some(band)))
            .unwrap_or_else(|e| panic!("band {band}: {e}"));
        let g = &dem.grid;
        assert_eq!((g.width(), g.height()), (349, 352));
        assert_eq!(dem.data_type, DataType::U8);
        assert_eq!(g.void_count(), 0);
        assert_eq!(g.georef().crs, Crs::Epsg(31985));
        assert!(close(g.georef().pixel_x, 28.5, 1e-6));
        ranges.push(g.valid_range().expect("valid"));
    }
    // DATA.md's range is band 1's; the other bands differ.
    assert_eq!(ranges[0], (47.0, 255.0));
    assert!(ranges.windows(2).any(|w| w[0] != w[1]), "{ranges:?}");
    println!("L7_ETMs band ranges: {ranges:?}");
}

/// Reads every shared GeoTIFF once and prints the time taken (informative).
#[test]
fn read_times() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    for rel in [
        "geotiff/dem-hills.tiff",
        "geotiff/luxembourg_elev_terra.tif",
        "geotiff/mapzen-geotiff-14-10348-7801.tif",
        "geotiff/mt_fuji_90m.tif",
        "geotiff/sanfrancisco_rio_rgbify.tif",
        "texture/olinda_dem_utm25s.tif",
    ] {
        let p = dir.join(rel);
        if !p.is_file() {
            continue;
        }
        let t = std::time::Instant::now();
        let dem = read(&p);
        println!("{rel}: {} samples in {:?}", dem.grid.len(), t.elapsed());
    }
}

// ---------------------------------------------------------------- bad input

#[test]
fn truncated_tiff_is_an_error_naming_the_file() {
    let Some(path) = shared("geotiff/mt_fuji_90m.tif") else {
        return;
    };
    let bytes = std::fs::read(&path).expect("read");
    let dir = tempfile::tempdir().expect("tempdir");
    for keep in [bytes.len() / 2, bytes.len() - 1, 600, 100, 9] {
        let p = dir.path().join(format!("fuji_cut_{keep}.tif"));
        std::fs::write(&p, &bytes[..keep]).expect("write");
        let err = read_dem(&p, &ReadOptions::default())
            .expect_err("truncated")
            .to_string();
        assert!(err.contains(&format!("fuji_cut_{keep}.tif")), "{err}");
        assert!(err.contains("expected") && err.contains("found"), "{err}");
    }
    // This file's directory is at its end: a cut loses it.
    let p = dir.path().join("fuji_half.tif");
    std::fs::write(&p, &bytes[..bytes.len() / 2]).expect("write");
    let err = read_dem(&p, &ReadOptions::default())
        .expect_err("cut")
        .to_string();
    assert!(
        err.ends_with("fuji_half.tif: expected the first image directory at byte 3277354, found a file of 1638949 bytes (truncated?)"),
        "{err}"
    );
    // Cut inside the image data (this file's directory precedes it): the
    // message says which tile is missing.
    let Some(path) = shared("geotiff/mapzen-geotiff-14-10348-7801.tif") else {
        return;
    };
    let bytes = std::fs::read(&path).expect("read");
    let p = dir.path().join("mapzen_half.tif");
    std::fs::write(&p, &bytes[..bytes.len() / 2]).expect("write");
    let err = read_dem(&p, &ReadOptions::default())
        .expect_err("cut")
        .to_string();
    assert!(
        err.contains("mapzen_half.tif: expected tile 2 of 4 at bytes 127624..258397 of the file, found a file of 255464 bytes (truncated?)"),
        "{err}"
    );
}

#[test]
fn corrupt_compressed_data_is_an_error() {
    for rel in [
        "geotiff/mapzen-geotiff-14-10348-7801.tif", // Deflate
        "geotiff/luxembourg_elev_terra.tif",        // LZW
    ] {
        let Some(path) = shared(rel) else {
            return;
        };
        let mut bytes = std::fs::read(&path).expect("read");
        // Overwrite the middle of the image data with a pattern.
        let n = bytes.len();
        for (i, b) in bytes[n / 4..n * 3 / 4].iter_mut().enumerate() {
            *b = (i as u8).wrapping_mul(37) ^ 0x5a;
        }
        let err = err_bytes(&bytes, "corrupt.tif");
        assert!(err.contains("corrupt.tif: expected"), "{err}");
        assert!(err.contains("decoding"), "{err}");
    }
}

#[test]
fn random_bytes_named_tif() {
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    let bytes: Vec<u8> = (0..4096).map(|_| xorshift(&mut state) as u8).collect();
    let err = err_bytes(&bytes, "noise.tif");
    assert!(err.starts_with("noise.tif: expected"), "{err}");
    assert!(err.contains("found"), "{err}");
    assert_eq!(
        err_bytes(b"II*\0\x08\0\0", "short.tif"),
        "short.tif: expected a TIFF header of 8 bytes, found 7 bytes"
    );
    // Random bytes behind a TIFF signature reach the GeoTIFF reader.
    for head in [&b"II*\0"[..], &b"MM\0*"[..]] {
        let mut b = head.to_vec();
        b.extend_from_slice(&bytes);
        let err = err_bytes(&b, "noise.tif");
        assert!(err.starts_with("noise.tif: "), "{err}");
        assert!(
            err.contains("expected") || err.contains("unsupported"),
            "{err}"
        );
    }
}

#[test]
fn absurd_dimensions_fail_before_allocating() {
    let tiff = Builder::le()
        .long(256, &[100_000])
        .long(257, &[100_000])
        .short(258, &[16])
        .short(262, &[1])
        .long(278, &[100_000])
        .strips(vec![vec![0; 16]]);
    let err = err_bytes(&tiff, "huge.tif");
    assert!(
        err.starts_with(
            "huge.tif: too large: a header of 100000x100000 (10000000000 samples), over the limit of"
        ),
        "{err}"
    );
    // Under the sample limit but far more data than the file holds.
    let tiff = Builder::le()
        .long(256, &[60_000])
        .long(257, &[30_000])
        .short(258, &[16])
        .short(262, &[1])
        .long(278, &[30_000])
        .strips(vec![vec![0; 16]]);
    let err = err_bytes(&tiff, "big.tif");
    assert!(
        err.contains("expected 3600000000 bytes of samples in strip 1 of 1, found 16 bytes"),
        "{err}"
    );
    // Deflate cannot expand 16 bytes to 3.6 GB either.
    let tiff = Builder::le()
        .long(256, &[60_000])
        .long(257, &[30_000])
        .short(258, &[16])
        .short(259, &[8])
        .short(262, &[1])
        .long(278, &[30_000])
        .strips(vec![vec![0; 16]]);
    let err = err_bytes(&tiff, "big.tif");
    assert!(
        err.contains("16 bytes of Deflate data, which cannot expand that far"),
        "{err}"
    );
    // Strip offsets pointing past the end of the file.
    let small = || {
        Builder::le()
            .long(256, &[4])
            .long(257, &[4])
            .short(258, &[8])
            .short(262, &[1])
    };
    assert!(read_bytes(&small().strips(vec![vec![1; 16]]), "ok.tif").is_ok());
    let far = small().long(273, &[1_000_000]).long(279, &[16]).build();
    let err = err_bytes(&far, "far.tif");
    assert!(
        err.contains(
            "expected strip 1 of 1 at bytes 1000000..1000016 of the file, found a file of"
        ),
        "{err}"
    );
}

#[test]
fn jpeg_and_other_compressions_are_unsupported() {
    for (code, name) in [
        (7u16, "JPEG"),
        (6, "old-style JPEG"),
        (34887, "LERC"),
        (50000, "ZSTD"),
    ] {
        let tiff = Builder::le()
            .long(256, &[4])
            .long(257, &[4])
            .short(258, &[8])
            .short(259, &[code])
            .short(262, &[1])
            .strips(vec![vec![0xff, 0xd8, 0xff, 0xd9]]);
        let err = err_bytes(&tiff, "photo.tif");
        assert_eq!(
            err,
            format!(
                "photo.tif: unsupported GeoTIFF compression: code {code} ({name}); supported: none (1), LZW (5), Deflate (8, 32946), PackBits (32773)"
            )
        );
    }
}

#[test]
fn unsupported_sample_types_are_named() {
    for (format, bits, what) in [(1u16, 1u16, "[1]"), (3, 16, "[16]"), (2, 64, "[64]")] {
        let tiff = Builder::le()
            .long(256, &[8])
            .long(257, &[1])
            .short(258, &[bits])
            .short(262, &[1])
            .short(339, &[format])
            .strips(vec![vec![0; 64]]);
        let err = err_bytes(&tiff, "odd.tif");
        assert!(
            err.starts_with("odd.tif: unsupported GeoTIFF sample type"),
            "{err}"
        );
        assert!(err.contains(what), "{err}");
    }
}

/// Mutated copies of real files: any outcome but a panic is fine. By default
/// 400 mutants of each of two small files; `COTA_FUZZ_ROUNDS=n` runs n mutants
/// of every shared GeoTIFF.
#[test]
fn mutated_real_files_never_panic() {
    let (rounds, files): (usize, &[&str]) = match std::env::var("COTA_FUZZ_ROUNDS") {
        Ok(n) => (
            n.parse().expect("COTA_FUZZ_ROUNDS is a number"),
            &[
                "geotiff/dem-hills.tiff",
                "geotiff/luxembourg_elev_terra.tif",
                "geotiff/mapzen-geotiff-14-10348-7801.tif",
                "geotiff/mt_fuji_90m.tif",
                "geotiff/sanfrancisco_rio_rgbify.tif",
                "texture/L7_ETMs.tif",
                "texture/olinda_dem_utm25s.tif",
            ],
        ),
        Err(_) => (
            400,
            &[
                "geotiff/luxembourg_elev_terra.tif",
                "texture/olinda_dem_utm25s.tif",
            ],
        ),
    };
    let opts = ReadOptions::default().with_band(Some(1));
    for rel in files {
        let Some(path) = shared(rel) else {
            return;
        };
        let original = std::fs::read(&path).expect("read");
        // The first directory, where sizes and offsets live, is mutated most.
        let ifd = if original.starts_with(b"II") {
            u32::from_le_bytes([original[4], original[5], original[6], original[7]])
        } else {
            u32::from_be_bytes([original[4], original[5], original[6], original[7]])
        } as usize;
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        for round in 0..rounds {
            let mut bytes = original.clone();
            let (from, to) = match round % 3 {
                0 => (0, bytes.len()),
                1 => (0, 1024.min(bytes.len())),
                _ => (ifd.min(bytes.len() - 1), (ifd + 1024).min(bytes.len())),
            };
            for _ in 0..1 + round % 8 {
                let at = from + (xorshift(&mut state) as usize) % (to - from);
                bytes[at] = xorshift(&mut state) as u8;
            }
            if round % 5 == 0 {
                let keep = (xorshift(&mut state) as usize) % bytes.len();
                bytes.truncate(keep.max(1));
            }
            let _ = read_dem_bytes(&bytes, Path::new("mutated.tif"), &opts);
        }
    }
}

// ---------------------------------------------------------------- synthetic files

/// Writes a single-band TIFF with the `tiff` encoder, plus extra ASCII tags.
fn encode<C>(
    w: u32,
    h: u32,
    data: &[C::Inner],
    comp: Compression,
    pred: Predictor,
    nodata: Option<&str>,
) -> Vec<u8>
where
    C: colortype::ColorType,
    [C::Inner]: tiff::encoder::TiffValue,
{
    let mut out = Cursor::new(Vec::new());
    {
        let mut enc = TiffEncoder::new(&mut out)
            .expect("encoder")
            .with_compression(comp)
            .with_predictor(pred);
        let mut img = enc.new_image::<C>(w, h).expect("image");
        img.rows_per_strip(2).expect("rows per strip");
        if let Some(nd) = nodata {
            img.encoder()
                .write_tag(Tag::GdalNodata, nd)
                .expect("nodata tag");
        }
        img.write_data(data).expect("data");
    }
    out.into_inner()
}

fn heights(bytes: &[u8]) -> (Vec<f32>, Dem) {
    let dem = read_bytes(bytes, "synthetic.tif").unwrap_or_else(|e| panic!("{e}"));
    (dem.grid.heights().to_vec(), dem)
}

fn same(a: &[f32], b: &[f32]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| x == y || (x.is_nan() && y.is_nan()))
}

#[test]
fn every_sample_type_compression_and_predictor() {
    let comps = [
        Compression::Uncompressed,
        Compression::Lzw,
        Compression::Deflate(DeflateLevel::Balanced),
        Compression::Packbits,
    ];
    let (w, h) = (7u32, 5u32);
    let idx = |i: usize| i as i64 * 37 % 200 - 100; // -100..99, with repeats
    for comp in comps {
        for pred in [Predictor::None, Predictor::Horizontal] {
            macro_rules! case {
                ($ct:ty, $t:ty, $dt:expr, $nd:expr, $voids:expr) => {
                    'case: {
                        let float = matches!($dt, DataType::F32 | DataType::F64);
                        if float && pred == Predictor::Horizontal {
                            // The encoder refuses it; the predictor-3 test covers floats.
                            break 'case;
                        }
                        let data: Vec<$t> = (0..(w * h) as usize)
                            .map(|i| (idx(i) + 100) as $t)
                            .collect();
                        let tiff = encode::<$ct>(w, h, &data, comp, pred, $nd);
                        let (got, dem) = heights(&tiff);
                        assert_eq!(dem.data_type, $dt);
                        assert_eq!(dem.grid.void_count(), $voids, "{:?}", $dt);
                        let want: Vec<f32> = data
                            .iter()
                            .map(|&v| {
                                if $voids > 0 && v as f64 == 100.0 {
                                    f32::NAN
                                } else {
                                    v as f32
                                }
                            })
                            .collect();
                        assert!(same(&got, &want), "{:?}: {got:?} vs {want:?}", $dt);
                        assert_eq!(dem.grid.georef().crs, Crs::Unknown);
                        assert!(!dem.grid.georef().known);
                    }
                };
            }
            let hundreds = (0..(w * h) as usize).filter(|&i| idx(i) == 0).count();
            case!(colortype::Gray8, u8, DataType::U8, Some("100"), hundreds);
            case!(colortype::GrayI8, i8, DataType::I8, None, 0);
            case!(
                colortype::Gray16,
                u16,
                DataType::U16,
                Some("100.2"),
                hundreds
            );
            case!(colortype::GrayI16, i16, DataType::I16, Some("-32768"), 0);
            case!(colortype::Gray32, u32, DataType::U32, Some("-100"), 0);
            case!(
                colortype::GrayI32,
                i32,
                DataType::I32,
                Some("100"),
                hundreds
            );
            case!(
                colortype::Gray32Float,
                f32,
                DataType::F32,
                Some("100"),
                hundreds
            );
            case!(colortype::Gray64Float, f64, DataType::F64, Some("nan"), 0);
        }
    }
}

#[test]
fn bigtiff_is_read() {
    let data: Vec<i16> = (0..12).map(|i| i * 100 - 300).collect();
    let mut out = Cursor::new(Vec::new());
    {
        let mut enc = TiffEncoder::new_big(&mut out)
            .expect("encoder")
            .with_compression(Compression::Lzw)
            .with_predictor(Predictor::Horizontal);
        let mut img = enc.new_image::<colortype::GrayI16>(4, 3).expect("image");
        img.encoder()
            .write_tag(Tag::GdalNodata, "-300")
            .expect("nodata");
        img.write_data(&data).expect("data");
    }
    let bytes = out.into_inner();
    assert!(bytes.starts_with(b"II+\0"));
    let (got, dem) = heights(&bytes);
    assert_eq!(dem.data_type, DataType::I16);
    assert!(got[0].is_nan());
    assert_eq!(
        &got[1..],
        &data[1..].iter().map(|&v| f32::from(v)).collect::<Vec<_>>()[..]
    );
}

#[test]
fn float_nan_samples_are_voids_and_nan_nodata_is_kept() {
    let data = [1.0f32, f32::NAN, 3.0, -9999.0];
    let tiff = encode::<colortype::Gray32Float>(
        2,
        2,
        &data,
        Compression::Uncompressed,
        Predictor::None,
        Some("nan"),
    );
    let (got, dem) = heights(&tiff);
    assert!(same(&got, &[1.0, f32::NAN, 3.0, -9999.0]));
    assert!(dem.nodata.is_some_and(f64::is_nan));
    let tiff = encode::<colortype::Gray32Float>(
        2,
        2,
        &data,
        Compression::Uncompressed,
        Predictor::None,
        Some("-9999"),
    );
    let (got, dem) = heights(&tiff);
    assert!(same(&got, &[1.0, f32::NAN, 3.0, f32::NAN]));
    assert_eq!(dem.nodata, Some(-9999.0));
}

#[test]
fn unparseable_nodata_is_an_error() {
    let tiff = encode::<colortype::Gray8>(
        2,
        2,
        &[1, 2, 3, 4],
        Compression::Uncompressed,
        Predictor::None,
        Some("n/a"),
    );
    let err = err_bytes(&tiff, "nd.tif");
    assert_eq!(
        err,
        "nd.tif: expected a number in the GDAL_NODATA tag 42113, found \"n/a\""
    );
}

/// Float-predictor (3) encoding of one row of f32 samples, per TIFF Technical
/// Note 3: bytes regrouped most significant first, then byte differences.
fn float_predict_row(row: &[f32]) -> Vec<u8> {
    let n = row.len();
    let mut planes = vec![0u8; n * 4];
    for (i, v) in row.iter().enumerate() {
        for (k, b) in v.to_be_bytes().iter().enumerate() {
            planes[k * n + i] = *b;
        }
    }
    for i in (1..planes.len()).rev() {
        planes[i] = planes[i].wrapping_sub(planes[i - 1]);
    }
    planes
}

#[test]
fn floating_point_predictor_big_endian_with_float_max_nodata() {
    let rows = [[1.5f32, -2.25, f32::MIN], [f32::NAN, 1.0e6, 0.125]];
    let strip: Vec<u8> = rows.iter().flat_map(|r| float_predict_row(r)).collect();
    for be in [true, false] {
        let b = if be { Builder::be() } else { Builder::le() };
        let tiff = b
            .long(256, &[3])
            .long(257, &[2])
            .short(258, &[32])
            .short(262, &[1])
            .short(317, &[3])
            .short(339, &[3])
            .ascii(42113, "-3.402823e+38")
            .strips(vec![strip.clone()]);
        let (got, dem) = heights(&tiff);
        assert!(
            same(&got, &[1.5, -2.25, f32::NAN, f32::NAN, 1.0e6, 0.125]),
            "big endian {be}: {got:?}"
        );
        assert_eq!(dem.nodata, Some(f64::from(f32::MIN)));
    }
}

#[test]
fn horizontal_predictor_on_floats_adds_bit_patterns() {
    let row = [1.5f32, -2.25, 1.0e6, 0.125];
    let mut strip = Vec::new();
    let mut prev = 0u32;
    for v in row {
        strip.extend_from_slice(&v.to_bits().wrapping_sub(prev).to_le_bytes());
        prev = v.to_bits();
    }
    let tiff = Builder::le()
        .long(256, &[4])
        .long(257, &[1])
        .short(258, &[32])
        .short(262, &[1])
        .short(317, &[2])
        .short(339, &[3])
        .strips(vec![strip]);
    let (got, _) = heights(&tiff);
    assert_eq!(got, row);
}

/// A zlib stream of `data` in one stored (uncompressed) deflate block.
fn zlib_stored(data: &[u8]) -> Vec<u8> {
    let len = data.len() as u16;
    let mut z = vec![0x78, 0x01, 0x01];
    z.extend_from_slice(&len.to_le_bytes());
    z.extend_from_slice(&(!len).to_le_bytes());
    z.extend_from_slice(data);
    let (mut a, mut b) = (1u32, 0u32);
    for &x in data {
        a = (a + u32::from(x)) % 65521;
        b = (b + a) % 65521;
    }
    z.extend_from_slice(&((b << 16) | a).to_be_bytes());
    z
}

#[test]
fn deflate_codes_8_and_32946() {
    let samples: Vec<u8> = [-5i16, 0, 7, 3000]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    for code in [8u16, 32946] {
        let tiff = Builder::le()
            .long(256, &[2])
            .long(257, &[2])
            .short(258, &[16])
            .short(259, &[code])
            .short(262, &[1])
            .short(339, &[2])
            .strips(vec![zlib_stored(&samples)]);
        let (got, _) = heights(&tiff);
        assert_eq!(got, [-5.0, 0.0, 7.0, 3000.0], "code {code}");
    }
}

/// 5×3 image in 4×2 tiles (2 across, 2 down, partial on both edges), two
/// bands; value = band·1000 + row·10 + col.
fn two_band_value(band: u16, x: usize, y: usize) -> u16 {
    band * 1000 + (y * 10 + x) as u16
}

#[test]
fn planar_tiled_partial_tiles_pick_the_band() {
    let (w, h, tw, th) = (5usize, 3usize, 4usize, 2usize);
    let mut tiles = Vec::new();
    for band in 1..=2u16 {
        for ty in 0..2 {
            for tx in 0..2 {
                let mut t = Vec::new();
                for y in 0..th {
                    for x in 0..tw {
                        let (gx, gy) = (tx * tw + x, ty * th + y);
                        let v = if gx < w && gy < h {
                            two_band_value(band, gx, gy)
                        } else {
                            9999
                        };
                        t.extend_from_slice(&v.to_le_bytes());
                    }
                }
                tiles.push(t);
            }
        }
    }
    let tiff = Builder::le()
        .long(256, &[w as u32])
        .long(257, &[h as u32])
        .short(258, &[16, 16])
        .short(262, &[1])
        .short(277, &[2])
        .short(284, &[2])
        .short(322, &[tw as u16])
        .short(323, &[th as u16])
        .tiles(tiles);
    assert!(err_bytes(&tiff, "planar.tif").contains("found 2 bands; choose one with --band"));
    for band in 1..=2u16 {
        let dem = read_dem_bytes(
            &tiff,
            Path::new("planar.tif"),
            &ReadOptions::default().with_band(Some(band)),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(dem.data_type, DataType::U16);
        for y in 0..h {
            for x in 0..w {
                assert_eq!(
                    dem.grid.get(x, y),
                    f32::from(two_band_value(band, x, y)),
                    "band {band} ({x},{y})"
                );
            }
        }
    }
}

#[test]
fn chunky_strips_pick_the_band() {
    let (w, h) = (5usize, 3usize);
    let mut strips = Vec::new();
    for rows in [0..2, 2..3] {
        let mut s = Vec::new();
        for y in rows {
            for x in 0..w {
                for band in 1..=3u16 {
                    s.extend_from_slice(&two_band_value(band, x, y).to_be_bytes());
                }
            }
        }
        strips.push(s);
    }
    let tiff = Builder::be()
        .long(256, &[w as u32])
        .long(257, &[h as u32])
        .short(258, &[16, 16, 16])
        .short(262, &[1])
        .short(277, &[3])
        .short(278, &[2])
        .short(338, &[0, 0])
        .strips(strips);
    for band in 1..=3u16 {
        let dem = read_dem_bytes(
            &tiff,
            Path::new("chunky.tif"),
            &ReadOptions::default().with_band(Some(band)),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        for y in 0..h {
            for x in 0..w {
                assert_eq!(dem.grid.get(x, y), f32::from(two_band_value(band, x, y)));
            }
        }
    }
}

#[test]
fn sparse_tiles_are_void_with_nodata_else_zero() {
    let tile: Vec<u8> = (1..=4u8).collect();
    for (nodata, fill) in [(Some("255"), f32::NAN), (None, 0.0)] {
        let mut b = Builder::le()
            .long(256, &[4])
            .long(257, &[2])
            .short(258, &[8])
            .short(262, &[1])
            .short(322, &[2])
            .short(323, &[2]);
        if let Some(nd) = nodata {
            b = b.ascii(42113, nd);
        }
        let tiff = b.tiles(vec![tile.clone(), Vec::new()]);
        let (got, _) = heights(&tiff);
        assert!(
            same(&got, &[1.0, 2.0, fill, fill, 3.0, 4.0, fill, fill]),
            "{got:?}"
        );
    }
}

/// GeoKeys for EPSG:4326, area or point.
fn geokeys_4326(raster_type: u16) -> Vec<u16> {
    vec![
        1,
        1,
        0,
        3,
        1024,
        0,
        1,
        2,
        1025,
        0,
        1,
        raster_type,
        2048,
        0,
        1,
        4326,
    ]
}

#[test]
fn south_up_grids_are_flipped_north_up() {
    for (raster_type, pixel_is, origin_y) in
        [(1u16, PixelIs::Area, 203.0), (2, PixelIs::Point, 202.0)]
    {
        let tiff = Builder::le()
            .long(256, &[2])
            .long(257, &[3])
            .short(258, &[8])
            .short(262, &[1])
            .double(33550, &[1.0, -1.0, 0.0])
            .double(33922, &[0.0, 0.0, 0.0, 100.0, 200.0, 0.0])
            .short(34735, &geokeys_4326(raster_type))
            .strips(vec![vec![1, 2, 3, 4, 5, 6]]);
        let (got, dem) = heights(&tiff);
        assert_eq!(got, [5.0, 6.0, 3.0, 4.0, 1.0, 2.0]);
        let g = dem.grid.georef();
        assert_eq!(g.pixel_is, pixel_is);
        assert_eq!(
            (g.origin_x, g.origin_y, g.pixel_x, g.pixel_y),
            (100.0, origin_y, 1.0, -1.0)
        );
        assert_eq!(g.crs, Crs::Epsg(4326));
    }
}

#[test]
fn model_transformation_and_feet() {
    let mut m = [0.0f64; 16];
    (m[0], m[3], m[5], m[7], m[15]) = (10.0, 500_000.0, -10.0, 4_000_000.0, 1.0);
    let keys = [
        1, 1, 0, 3, 1024, 0, 1, 1, 3072, 0, 1, 32611, 4099, 0, 1, 9002,
    ];
    let tiff = Builder::le()
        .long(256, &[2])
        .long(257, &[1])
        .short(258, &[16])
        .short(262, &[1])
        .double(34264, &m)
        .short(34735, &keys)
        .strips(vec![vec![100, 0, 200, 0]]);
    let (got, dem) = heights(&tiff);
    assert_eq!(got, [30.48, 60.96]);
    let g = dem.grid.georef();
    assert_eq!(
        (g.origin_x, g.origin_y, g.pixel_x, g.pixel_y),
        (500_000.0, 4_000_000.0, 10.0, -10.0)
    );
    assert_eq!(g.crs, Crs::Epsg(32611));
    // A rotated transform is refused.
    m[1] = 0.5;
    let tiff = Builder::le()
        .long(256, &[2])
        .long(257, &[1])
        .short(258, &[16])
        .short(262, &[1])
        .double(34264, &m)
        .strips(vec![vec![100, 0, 200, 0]]);
    let err = err_bytes(&tiff, "rotated.tif");
    assert!(
        err.starts_with("rotated.tif: unsupported GeoTIFF georeferencing: rotated or sheared"),
        "{err}"
    );
}

// ---------------------------------------------------------------- a tiny TIFF writer

fn xorshift(s: &mut u64) -> u64 {
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    *s
}

/// A tag value of the hand-built TIFFs.
enum Val {
    Short(Vec<u16>),
    Long(Vec<u32>),
    Double(Vec<f64>),
    Ascii(String),
}

/// Builds classic TIFFs byte by byte: header, chunk data, then one IFD with
/// out-of-line values after it. Enough to craft layouts and broken headers.
struct Builder {
    be: bool,
    tags: Vec<(u16, Val)>,
}

impl Builder {
    fn le() -> Self {
        Builder {
            be: false,
            tags: Vec::new(),
        }
    }

    fn be() -> Self {
        Builder {
            be: true,
            tags: Vec::new(),
        }
    }

    fn set(mut self, tag: u16, v: Val) -> Self {
        self.tags.retain(|(t, _)| *t != tag);
        self.tags.push((tag, v));
        self
    }

    fn short(self, tag: u16, v: &[u16]) -> Self {
        self.set(tag, Val::Short(v.to_vec()))
    }

    fn long(self, tag: u16, v: &[u32]) -> Self {
        self.set(tag, Val::Long(v.to_vec()))
    }

    fn double(self, tag: u16, v: &[f64]) -> Self {
        self.set(tag, Val::Double(v.to_vec()))
    }

    fn ascii(self, tag: u16, v: &str) -> Self {
        self.set(tag, Val::Ascii(v.to_string()))
    }

    fn strips(self, chunks: Vec<Vec<u8>>) -> Vec<u8> {
        self.chunks(273, 279, chunks)
    }

    fn tiles(self, chunks: Vec<Vec<u8>>) -> Vec<u8> {
        self.chunks(324, 325, chunks)
    }

    /// Lays out the chunks after the header (an empty chunk gets offset and
    /// byte count 0: sparse) and records their offsets and byte counts.
    fn chunks(self, offsets_tag: u16, counts_tag: u16, chunks: Vec<Vec<u8>>) -> Vec<u8> {
        let mut data = Vec::new();
        let (mut offsets, mut counts) = (Vec::new(), Vec::new());
        for c in &chunks {
            offsets.push(if c.is_empty() {
                0
            } else {
                8 + data.len() as u32
            });
            counts.push(c.len() as u32);
            data.extend_from_slice(c);
        }
        self.long(offsets_tag, &offsets)
            .long(counts_tag, &counts)
            .build_with(&data)
    }

    fn build(self) -> Vec<u8> {
        self.build_with(&[])
    }

    fn u16b(&self, v: u16) -> [u8; 2] {
        if self.be {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    }

    fn u32b(&self, v: u32) -> [u8; 4] {
        if self.be {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    }

    fn build_with(mut self, data: &[u8]) -> Vec<u8> {
        self.tags.sort_by_key(|(t, _)| *t);
        let mut out = Vec::new();
        out.extend_from_slice(if self.be { b"MM\0*" } else { b"II*\0" });
        let ifd = (8 + data.len() + 1) & !1;
        out.extend_from_slice(&self.u32b(ifd as u32));
        out.extend_from_slice(data);
        out.resize(ifd, 0);
        let n = self.tags.len();
        let mut extra_at = ifd + 2 + 12 * n + 4;
        let mut extra = Vec::new();
        out.extend_from_slice(&self.u16b(n as u16));
        for (tag, v) in &self.tags {
            let (ty, count, bytes): (u16, usize, Vec<u8>) = match v {
                Val::Short(x) => (3, x.len(), x.iter().flat_map(|&s| self.u16b(s)).collect()),
                Val::Long(x) => (4, x.len(), x.iter().flat_map(|&s| self.u32b(s)).collect()),
                Val::Double(x) => (
                    12,
                    x.len(),
                    x.iter()
                        .flat_map(|&d| {
                            if self.be {
                                d.to_be_bytes()
                            } else {
                                d.to_le_bytes()
                            }
                        })
                        .collect(),
                ),
                Val::Ascii(s) => {
                    let mut b = s.as_bytes().to_vec();
                    b.push(0);
                    (2, b.len(), b)
                }
            };
            out.extend_from_slice(&self.u16b(*tag));
            out.extend_from_slice(&self.u16b(ty));
            out.extend_from_slice(&self.u32b(count as u32));
            if bytes.len() <= 4 {
                let mut inline = bytes.clone();
                inline.resize(4, 0);
                out.extend_from_slice(&inline);
            } else {
                out.extend_from_slice(&self.u32b(extra_at as u32));
                extra.extend_from_slice(&bytes);
                if extra.len() % 2 == 1 {
                    extra.push(0);
                }
                extra_at = ifd + 2 + 12 * n + 4 + extra.len();
            }
        }
        out.extend_from_slice(&[0; 4]);
        out.extend_from_slice(&extra);
        out
    }
}

/// One empty strip (byte count 0) declaring 16384² samples: refused before
/// 1 GiB of voids is allocated (the fuzzer's case was 292 bytes and 4 GB).
#[test]
fn a_sparse_bomb_is_refused_before_its_samples_are_allocated() {
    let tiff = Builder::le()
        .long(256, &[16384])
        .long(257, &[16384])
        .short(258, &[32])
        .short(339, &[3])
        .short(262, &[1])
        .strips(vec![Vec::new()]);
    let msg = err_bytes(&tiff, "sparse-bomb.tif");
    assert!(
        msg.contains("sparse-bomb.tif")
            && msg.contains("268435456 samples in blocks with a byte count of 0"),
        "{msg}"
    );
    // A small sparse grid is read (as voids or zeros).
    let small = Builder::le()
        .long(256, &[64])
        .long(257, &[64])
        .short(258, &[8])
        .short(262, &[1])
        .strips(vec![Vec::new()]);
    let (got, _) = heights(&small);
    assert_eq!(got.len(), 64 * 64);
}
