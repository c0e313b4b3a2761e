//! PNG reader: the three shared PNGs cross-checked against DATA.md, the
//! bundled Terrarium fixture, and small encoded images for every layout and
//! encoding (defaults, alpha voids, gray scale/offset).
// Test helpers outside #[test] functions unwrap and panic like the tests do.
#![allow(clippy::unwrap_used, clippy::panic)]

use crate::common;

use std::path::Path;

use common::{fixture, png_bytes, shared_data, write_file};
use cota_io::{read_dem, DataType, Dem, Format, PngEncoding, ReadOptions};
use png::{BitDepth, ColorType};

/// Reads with `opts`, any height accepted: these tests are about the
/// encodings (synthetic pixels decode to heights far beyond a real DEM's).
fn read_with(path: &Path, opts: &ReadOptions) -> Dem {
    let opts = opts.with_max_abs_height_m(f64::INFINITY);
    read_dem(path, &opts).unwrap_or_else(|e| panic!("{e}"))
}

fn assert_range(dem: &Dem, lo: f32, hi: f32, tol: f32) {
    let (min, max) = dem.grid.valid_range().unwrap();
    assert!(
        (min - lo).abs() <= tol && (max - hi).abs() <= tol,
        "{}: {min}..{max}, expected {lo}..{hi}",
        dem.path.display()
    );
}

fn terrarium() -> ReadOptions {
    ReadOptions::DEFAULT.with_png_encoding(Some(PngEncoding::Terrarium))
}

#[test]
fn terrarium_fixture() {
    let dem = read_with(
        &fixture("terrarium.png"),
        &terrarium().with_cell_size_m(30.0),
    );
    assert_eq!(dem.format, Format::Png(PngEncoding::Terrarium));
    assert_eq!(dem.data_type, DataType::Rgb8);
    assert_eq!((dem.grid.width(), dem.grid.height()), (256, 256));
    assert_eq!(dem.grid.void_count(), 0);
    assert_range(&dem, 852.117, 2475.066, 0.002);
    let g = dem.grid.georef();
    assert!(!g.known);
    assert_eq!(dem.grid.cell_size_m(), [30.0, 30.0]);
}

#[test]
fn shared_pngs_match_data_md() {
    let Some(data) = shared_data() else { return };
    let png = data.join("png");

    // RGBA → terrain-RGB by default.
    let fuji = read_with(&png.join("fuji.png"), &ReadOptions::DEFAULT);
    assert_eq!(fuji.format, Format::Png(PngEncoding::TerrainRgb));
    assert_eq!((fuji.grid.width(), fuji.grid.height()), (512, 512));
    assert_eq!(fuji.grid.void_count(), 0);
    assert_range(&fuji, 13.7, 3751.0, 0.05);

    // 16-bit gray → gray16 by default: levels up to 43,798 are no heights
    // in metres, refused by default naming the flag; raw values when any
    // height is allowed, then scaled by 0.1 m.
    let err = cota_io::read_dem(&png.join("ps_height_1k.png"), &ReadOptions::DEFAULT)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    for want in [
        "ps_height_1k.png",
        "within ±12000 m",
        "--gray-scale-m",
        "--any-height",
    ] {
        assert!(err.contains(want), "{want:?} not in {err:?}");
    }
    let any = ReadOptions::DEFAULT.with_max_abs_height_m(f64::INFINITY);
    let raw = read_with(&png.join("ps_height_1k.png"), &any);
    assert_eq!(raw.format, Format::Png(PngEncoding::Gray16));
    assert_eq!(raw.data_type, DataType::U16);
    assert_eq!((raw.grid.width(), raw.grid.height()), (1025, 1025));
    assert_range(&raw, 0.0, 43798.0, 0.0);
    let opts = ReadOptions::DEFAULT.with_gray(0.1, 0.0);
    let ps = read_with(&png.join("ps_height_1k.png"), &opts);
    assert_range(&ps, 0.0, 4379.8, 0.01);
    assert_eq!(ps.grid.void_count(), 0);

    let t = read_with(&png.join("terrarium.png"), &terrarium());
    assert_range(&t, 852.117, 2475.066, 0.002);
}

#[test]
fn every_layout_and_encoding() {
    let dir = tempfile::tempdir().unwrap();
    let file =
        |name: &str, c, d, data: &[u8]| write_file(dir.path(), name, &png_bytes(2, 1, c, d, data));

    // Terrain-RGB 0 m and 1 m; terrarium of the same pixels.
    let p = file(
        "rgb.png",
        ColorType::Rgb,
        BitDepth::Eight,
        &[1, 134, 160, 1, 134, 170],
    );
    let dem = read_with(&p, &ReadOptions::DEFAULT);
    assert_eq!(dem.grid.heights(), &[0.0, 1.0]);
    let dem = read_with(&p, &terrarium());
    assert_eq!(
        dem.grid.heights()[0],
        256.0 + 134.0 + 160.0 / 256.0 - 32768.0
    );

    // RGBA: alpha 0 is a void, any other alpha is ignored.
    let p = file(
        "rgba.png",
        ColorType::Rgba,
        BitDepth::Eight,
        &[1, 134, 160, 0, 1, 134, 160, 7],
    );
    let dem = read_with(&p, &ReadOptions::DEFAULT);
    assert!(dem.grid.heights()[0].is_nan());
    assert_eq!(dem.grid.heights()[1], 0.0);

    // 8- and 16-bit gray with scale and offset.
    let opts = ReadOptions::DEFAULT.with_gray(0.5, -10.0);
    let p = file("g8.png", ColorType::Grayscale, BitDepth::Eight, &[0, 255]);
    let dem = read_with(&p, &opts);
    assert_eq!(
        (dem.grid.heights(), dem.data_type),
        (&[-10.0, 117.5][..], DataType::U8)
    );
    let p = file(
        "g16.png",
        ColorType::Grayscale,
        BitDepth::Sixteen,
        &[0x01, 0x00, 0xff, 0xff],
    );
    let dem = read_with(&p, &opts);
    assert_eq!(dem.grid.heights(), &[118.0, 32757.5]);

    // Gray with alpha.
    let p = file(
        "ga.png",
        ColorType::GrayscaleAlpha,
        BitDepth::Eight,
        &[9, 0, 9, 255],
    );
    let dem = read_with(&p, &ReadOptions::DEFAULT);
    assert!(dem.grid.heights()[0].is_nan());
    assert_eq!(dem.grid.heights()[1], 9.0);
    let p = file(
        "ga16.png",
        ColorType::GrayscaleAlpha,
        BitDepth::Sixteen,
        &[0, 9, 0, 0, 0, 9, 0, 1],
    );
    let dem = read_with(&p, &ReadOptions::DEFAULT);
    assert!(dem.grid.heights()[0].is_nan());
    assert_eq!(dem.grid.heights()[1], 9.0);
}

#[test]
fn images_beyond_the_png_crate_default_memory_limit() {
    // 6000² 16-bit gray = 72 MB of pixels, past the png crate's 64 MiB default.
    let (w, h) = (6000u32, 6000u32);
    let mut data = vec![0u8; (w * h * 2) as usize];
    data[1] = 7;
    let bytes = png_bytes(w, h, ColorType::Grayscale, BitDepth::Sixteen, &data);
    drop(data);
    let dir = tempfile::tempdir().unwrap();
    let dem = read_with(
        &write_file(dir.path(), "big.png", &bytes),
        &ReadOptions::DEFAULT,
    );
    assert_eq!(dem.grid.len(), 36_000_000);
    assert_eq!(dem.grid.valid_range(), Some((0.0, 7.0)));
}

/// Without `--encoding`, an RGB tile that is absurd in terrain-RGB but plausible
/// in Terrarium is read as Terrarium; a terrain-RGB tile stays terrain-RGB.
#[test]
fn default_encoding_picks_the_plausible_one() {
    let dem = read_with(&fixture("terrarium.png"), &ReadOptions::DEFAULT);
    assert_eq!(dem.format, Format::Png(PngEncoding::Terrarium));
    assert_range(&dem, 852.117, 2475.066, 0.01);
    if let Some(root) = shared_data() {
        let dem = read_with(&root.join("png/fuji.png"), &ReadOptions::DEFAULT);
        assert_eq!(dem.format, Format::Png(PngEncoding::TerrainRgb));
        assert_range(&dem, 13.7, 3751.0, 0.05);
    }
}
