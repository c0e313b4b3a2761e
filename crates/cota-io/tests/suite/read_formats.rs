//! The readers of issue 22 on real heights: Terrarium WebP (the bundled tile,
//! lossless, against its PNG), z/x/y web tiles made from the shared Mapzen
//! GeoTIFF tile and mosaicked by their Web-Mercator bounds, a PMTiles archive
//! of those tiles, NumPy `.npz`/`.npy` and USGS ASCII DEMs written from
//! bundled grids in the set-up; and their bad-input cases (each a one-line
//! error naming the file).
// Test helpers outside #[test] functions unwrap and panic like the tests do.
#![allow(clippy::unwrap_used, clippy::panic)]

use crate::common;

use std::path::{Path, PathBuf};

use common::{assert_contains, fixture, shared_data, write_file};
use cota_core::{Crs, PixelIs};
use cota_fixtures::formats::{self, ArchiveTile};
use cota_io::read::pmtiles;
use cota_io::{
    read_dem, read_region, ArrayName, DataType, Dem, Format, PngEncoding, ReadErrorKind,
    ReadOptions, RegionOptions, TileRequest,
};

fn read(path: &Path, opts: &ReadOptions) -> Dem {
    read_dem(path, opts).unwrap_or_else(|e| panic!("{e}"))
}

/// The error of reading `path`, checked to be one line naming the file.
fn error_of(path: &Path, opts: &ReadOptions) -> (String, ReadErrorKind) {
    let err = match read_dem(path, opts) {
        Ok(dem) => panic!("{} read as {:?}", path.display(), dem.format),
        Err(e) => e,
    };
    let msg = err.to_string();
    eprintln!("{msg}");
    let name = path.file_name().unwrap().to_string_lossy();
    assert!(msg.contains(&*name), "{msg:?} does not name {name}");
    assert!(!msg.contains('\n'), "{msg:?} is not one line");
    (msg, err.kind)
}

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

#[test]
fn webp_and_png_terrarium_tiles_decode_to_the_same_heights() {
    let png = read(&fixture("terrarium.png"), &ReadOptions::DEFAULT);
    let webp = read(&fixture("terrarium.webp"), &ReadOptions::DEFAULT);
    // Both detected as Terrarium without being told (terrain-RGB is absurd on them).
    assert_eq!(png.format, Format::Png(PngEncoding::Terrarium));
    assert_eq!(webp.format, Format::WebP(PngEncoding::Terrarium));
    assert_eq!(webp.data_type, DataType::Rgb8);
    assert_eq!((webp.grid.width(), webp.grid.height()), (256, 256));
    // Lossless: bit-identical heights.
    assert_eq!(webp.grid.heights(), png.grid.heights());
    let (lo, hi) = webp.grid.valid_range().unwrap();
    assert!((lo - 852.117).abs() < 0.002 && (hi - 2475.066).abs() < 0.002);
}

#[test]
fn truncated_and_gray_webp_are_refused() {
    let dir = tmp();
    let bytes = std::fs::read(fixture("terrarium.webp")).unwrap();
    for cut in [13, 40, bytes.len() / 2, bytes.len() - 1] {
        let p = write_file(dir.path(), "cut.webp", &bytes[..cut]);
        let (msg, _) = error_of(&p, &ReadOptions::DEFAULT);
        assert_contains(&msg, &["expected a valid WebP image"]);
    }
    let gray = ReadOptions::DEFAULT.with_png_encoding(Some(PngEncoding::Gray16));
    let (msg, _) = error_of(&fixture("terrarium.webp"), &gray);
    assert_contains(&msg, &["gray16", "terrarium"]);
}

/// A 34-byte lossless WebP whose header claims 16 129 × 15 340 pixels (found
/// by `cargo fuzz run read_webp` without a sanitizer: it took 6 s and 2.7 GB
/// to decode before its heights were refused) is refused as a bomb at once,
/// and the bundled tile (512², 1,024 pixels per byte allowed) still reads.
#[test]
fn a_webp_bomb_is_refused_before_its_pixels_are_allocated() {
    let bomb: [u8; 34] = [
        0x52, 0x49, 0x46, 0x46, 0x1a, 0x00, 0x00, 0x00, 0x57, 0x45, 0x42, 0x50, 0x56, 0x50, 0x38,
        0x4c, 0x0e, 0x00, 0x07, 0x00, 0x2f, 0x00, 0xff, 0xfa, 0x0e, 0xcd, 0x55, 0x20, 0x22, 0x02,
        0x51, 0xc0, 0x88, 0x04,
    ];
    let dir = tmp();
    let p = write_file(dir.path(), "bomb.webp", &bomb);
    let t = std::time::Instant::now();
    let (msg, _) = error_of(&p, &ReadOptions::DEFAULT);
    assert_contains(&msg, &["bomb", "247418860 pixels", "34 bytes"]);
    assert!(t.elapsed().as_secs_f64() < 1.0, "{:?}", t.elapsed());
    read(&fixture("terrarium.webp"), &ReadOptions::DEFAULT);
}

/// The shared Mapzen GeoTIFF tile 14/10348/7801 (512², EPSG:3857) cut into
/// its four zoom-15 tiles, each a lossless Terrarium WebP.
fn zoom15_tiles() -> Option<(Dem, Vec<ArchiveTile>)> {
    let data = shared_data()?;
    let tif = read(
        &data.join("geotiff/mapzen-geotiff-14-10348-7801.tif"),
        &ReadOptions::DEFAULT,
    );
    let g = &tif.grid;
    let mut tiles = Vec::new();
    for (dy, dx) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
        let part: Vec<f32> = (0..256)
            .flat_map(|r| {
                let row = (dy * 256 + r) * 512 + dx * 256;
                g.heights()[row..row + 256].to_vec()
            })
            .collect();
        let bytes = formats::webp_lossless(&formats::terrarium_rgb(&part), 256, 256);
        tiles.push(ArchiveTile {
            z: 15,
            x: 2 * 10348 + dx as u32,
            y: 2 * 7801 + dy as u32,
            bytes,
        });
    }
    Some((tif, tiles))
}

/// Asserts that `dem` holds the GeoTIFF's heights (within Terrarium's
/// 1/256 m step) at the same places.
fn assert_same_tile(dem: &Dem, tif: &Dem) {
    let (g, t) = (&dem.grid, &tif.grid);
    assert_eq!((g.width(), g.height()), (512, 512));
    assert_eq!(g.georef().crs, Crs::Epsg(3857));
    assert_eq!(g.georef().pixel_is, PixelIs::Area);
    let (a, b) = (
        g.georef().sample_xy(0.0, 0.0),
        t.georef().sample_xy(0.0, 0.0),
    );
    let px = t.georef().pixel_x;
    assert!(
        (a.0 - b.0).abs() < 1e-6 * px && (a.1 - b.1).abs() < 1e-6 * px,
        "{a:?} vs {b:?}"
    );
    assert!((g.georef().pixel_x - px).abs() < 1e-9 * px);
    let worst = g
        .heights()
        .iter()
        .zip(t.heights())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert!(worst <= 1.0 / 512.0 + 1e-4, "largest difference {worst} m");
}

#[test]
fn xyz_tiles_mosaic_by_their_web_mercator_bounds() {
    let Some((tif, tiles)) = zoom15_tiles() else {
        return;
    };
    let dir = tmp();
    let paths: Vec<PathBuf> = tiles
        .iter()
        .map(|t| {
            let d = dir.path().join(format!("{}/{}", t.z, t.x));
            std::fs::create_dir_all(&d).unwrap();
            write_file(&d, &format!("{}.webp", t.y), &t.bytes)
        })
        .collect();
    let one = read(&paths[0], &ReadOptions::DEFAULT);
    assert_eq!(one.grid.georef().crs, Crs::Epsg(3857));
    let region = read_region(&paths, &RegionOptions::DEFAULT.with_fill(None)).unwrap();
    assert_eq!(region.hole_samples, 0);
    let seams = region.seams.unwrap();
    assert_eq!(
        seams.overlap_samples, 0,
        "web tiles abut, they do not overlap"
    );
    let dem = Dem {
        grid: region.grid,
        format: one.format,
        data_type: one.data_type,
        nodata: None,
        path: paths[0].clone(),
    };
    assert_same_tile(&dem, &tif);
}

/// The tile's box in degrees, shrunk by `inset` degrees.
fn tile14_bbox(inset: f64) -> [f64; 4] {
    let n = 2f64.powi(14);
    let lon = |x: f64| x / n * 360.0 - 180.0;
    let lat = |y: f64| {
        (std::f64::consts::PI * (1.0 - 2.0 * y / n))
            .sinh()
            .atan()
            .to_degrees()
    };
    [
        lon(10348.0) + inset,
        lat(7802.0) + inset,
        lon(10349.0) - inset,
        lat(7801.0) - inset,
    ]
}

#[test]
fn pmtiles_archive_reads_the_tiles_of_a_box() {
    let Some((tif, tiles)) = zoom15_tiles() else {
        return;
    };
    let dir = tmp();
    let (bytes, _) = formats::pmtiles(&tiles, 4, tile14_bbox(0.0));
    let p = write_file(dir.path(), "terrain.pmtiles", &bytes);

    let s = pmtiles::summary(&p).unwrap();
    assert_eq!(
        (s.min_zoom, s.max_zoom, s.tile_type.as_str()),
        (15, 15, "webp")
    );
    assert!((s.bounds_deg[0] - tile14_bbox(0.0)[0]).abs() < 1e-6);

    let all = TileRequest {
        zoom: 15,
        bbox_deg: tile14_bbox(1e-4),
    };
    let dem = read(&p, &ReadOptions::DEFAULT.with_tiles(Some(all)));
    assert_eq!(dem.format, Format::Pmtiles(PngEncoding::Terrarium));
    assert_same_tile(&dem, &tif);

    // A box inside the north-west zoom-15 tile reads that tile alone.
    let b = tile14_bbox(0.0);
    let nw = [
        b[0] + 1e-4,
        (b[1] + b[3]) / 2.0 + 1e-4,
        (b[0] + b[2]) / 2.0 - 1e-4,
        b[3] - 1e-4,
    ];
    let one = read(
        &p,
        &ReadOptions::DEFAULT.with_tiles(Some(TileRequest {
            zoom: 15,
            bbox_deg: nw,
        })),
    );
    assert_eq!((one.grid.width(), one.grid.height()), (256, 256));
    assert_eq!(one.grid.get(0, 0), dem.grid.get(0, 0));
}

#[test]
fn pmtiles_bad_requests_and_corrupt_directories() {
    let Some((_, tiles)) = zoom15_tiles() else {
        return;
    };
    let dir = tmp();
    let (bytes, root) = formats::pmtiles(&tiles, 4, tile14_bbox(0.0));
    let p = write_file(dir.path(), "terrain.pmtiles", &bytes);
    // No selection: the zooms and bounds are named.
    let (msg, _) = error_of(&p, &ReadOptions::DEFAULT);
    assert_contains(&msg, &["--input-zoom", "--bbox", "zooms 15..15"]);
    let wrong_zoom = TileRequest {
        zoom: 9,
        bbox_deg: tile14_bbox(1e-4),
    };
    let (msg, _) = error_of(&p, &ReadOptions::DEFAULT.with_tiles(Some(wrong_zoom)));
    assert_contains(&msg, &["zooms 15..15", "found 9"]);
    let huge = TileRequest {
        zoom: 15,
        bbox_deg: [-180.0, -85.0, 180.0, 85.0],
    };
    let (msg, _) = error_of(&p, &ReadOptions::DEFAULT.with_tiles(Some(huge)));
    assert_contains(&msg, &["at most 4096 tiles"]);
    let req = ReadOptions::DEFAULT.with_tiles(Some(TileRequest {
        zoom: 15,
        bbox_deg: tile14_bbox(1e-4),
    }));
    // A directory whose gzip stream is damaged.
    let mut bad = bytes.clone();
    for b in &mut bad[root.start + 10..root.end - 8] {
        *b ^= 0x5a;
    }
    let p = write_file(dir.path(), "corrupt.pmtiles", &bad);
    let (msg, _) = error_of(&p, &req);
    assert_contains(&msg, &["directory"]);
    // A root directory pointing past the end of the file.
    let mut bad = bytes.clone();
    bad[16..24].copy_from_slice(&(1u64 << 40).to_le_bytes());
    let p = write_file(dir.path(), "past_end.pmtiles", &bad);
    let (msg, _) = error_of(&p, &req);
    assert_contains(&msg, &["inside the file"]);
    // Truncated inside the tile data.
    let p = write_file(dir.path(), "short.pmtiles", &bytes[..bytes.len() - 100]);
    error_of(&p, &req);
    let p = write_file(dir.path(), "header.pmtiles", &bytes[..50]);
    let (msg, _) = error_of(&p, &req);
    assert_contains(&msg, &["127 bytes"]);
}

/// The bundled ESRI grid with voids, as (heights, width, height).
fn hugo() -> (Vec<f32>, usize, usize) {
    let s = cota_fixtures::bundled("hugo_site.asc");
    (s.heights, s.width, s.height)
}

#[test]
fn npz_written_from_a_real_grid() {
    let (h, w, ht) = hugo();
    let dir = tmp();
    let npz = formats::npz(&[
        ("elevation", formats::npy_f32(&h, w, ht)),
        ("cell_size_m", formats::npy_scalar(10.0)),
    ]);
    let p = write_file(dir.path(), "hugo.npz", &npz);
    let dem = read(&p, &ReadOptions::DEFAULT);
    assert_eq!(dem.format, Format::Npz);
    assert_eq!((dem.grid.width(), dem.grid.height()), (w, ht));
    assert_eq!(dem.grid.void_count(), 2028);
    assert_eq!(dem.grid.cell_size_m(), [10.0, 10.0]);
    let same = dem
        .grid
        .heights()
        .iter()
        .zip(&h)
        .all(|(a, b)| a == b || (a.is_nan() && b.is_nan()));
    assert!(same);

    // Two 2-D arrays with no conventional name: ambiguous, the names listed.
    let two = formats::npz(&[
        ("a", formats::npy_f32(&h, w, ht)),
        ("b", formats::npy_f32(&h, w, ht)),
    ]);
    let p = write_file(dir.path(), "two.npz", &two);
    let (msg, _) = error_of(&p, &ReadOptions::DEFAULT);
    assert_contains(&msg, &["a, b", "--array"]);
    let b = ReadOptions::DEFAULT.with_array(ArrayName::new("b"));
    assert_eq!(read(&p, &b).grid.width(), w);
    let (msg, _) = error_of(&p, &ReadOptions::DEFAULT.with_array(ArrayName::new("c")));
    assert_contains(&msg, &["\"c\"", "a, b"]);

    // A plain .npy with the cell size from the options.
    let p = write_file(dir.path(), "hugo.npy", &formats::npy_f32(&h, w, ht));
    let dem = read(&p, &ReadOptions::DEFAULT.with_cell_size_m(10.0));
    assert_eq!((dem.format, dem.data_type), (Format::Npy, DataType::F32));
    assert_eq!(dem.grid.cell_size_m(), [10.0, 10.0]);
}

#[test]
fn npz_companion_arrays_give_a_georeference() {
    let (h, w, ht) = hugo();
    let dir = tmp();
    let npz = formats::npz(&[
        ("elevation", formats::npy_f32(&h, w, ht)),
        ("dx", formats::npy_scalar(1.0 / 3600.0)),
        ("dy", formats::npy_scalar(1.0 / 3600.0)),
        ("xmin", formats::npy_scalar(-105.0)),
        ("ymax", formats::npy_scalar(40.0)),
    ]);
    let p = write_file(dir.path(), "geo.npz", &npz);
    let dem = read(&p, &ReadOptions::DEFAULT);
    let g = dem.grid.georef();
    assert!(g.known && g.crs.is_geographic(), "{:?}", g.crs);
    assert_eq!(g.sample_xy(0.0, 0.0), (-105.0, 40.0));
    let [dx, dy] = dem.grid.cell_size_m();
    assert!(
        (dy - 30.85).abs() < 0.1 && (dx - 23.7).abs() < 0.2,
        "{dx} {dy}"
    );
}

/// Companion scalars: `x0`/`y0` with signed steps (rows stored south to
/// north with a positive `dy` read north-up at the same place), UTM-sized
/// origins kept to the millimetre (read as f64, not f32), and incomplete or
/// zero steps refused naming what is missing.
#[test]
fn npz_scalars_signed_steps_precision_and_refusals() {
    let (h, w, ht) = hugo();
    let dir = tmp();
    let s = formats::npy_scalar;
    let same = |a: &[f32], b: &[f32]| {
        a.iter()
            .zip(b)
            .all(|(a, b)| a == b || (a.is_nan() && b.is_nan()))
    };
    let flipped_rows: Vec<f32> = h.chunks(w).rev().flatten().copied().collect();
    let up = formats::npz(&[
        ("elevation", formats::npy_f32(&flipped_rows, w, ht)),
        ("dx", s(30.0)),
        ("dy", s(30.0)),
        ("x0", s(500_000.125)),
        ("y0", s(4_400_000.375 - 30.0 * (ht as f64 - 1.0))),
    ]);
    let p = write_file(dir.path(), "up.npz", &up);
    let dem = read(&p, &ReadOptions::DEFAULT);
    let g = dem.grid.georef();
    assert!(g.known && g.pixel_y < 0.0, "{g:?}");
    assert_eq!(g.sample_xy(0.0, 0.0), (500_000.125, 4_400_000.375));
    assert!(same(dem.grid.heights(), &h), "rows not flipped north-up");
    let extents = formats::npz(&[
        ("elevation", formats::npy_f32(&h, w, ht)),
        ("dx", s(30.0)),
        ("dy", s(-30.0)),
        ("xmin", s(500_000.125)),
        ("ymax", s(4_400_000.375)),
    ]);
    let p = write_file(dir.path(), "extents.npz", &extents);
    let dem = read(&p, &ReadOptions::DEFAULT);
    assert_eq!(
        dem.grid.georef().sample_xy(0.0, 0.0),
        (500_000.125, 4_400_000.375)
    );
    assert!(same(dem.grid.heights(), &h));
    for (name, members, expect) in [
        (
            "onlydx.npz",
            vec![("dx", s(30.0)), ("xmin", s(0.0))],
            "\"dx\" and \"dy\"",
        ),
        ("zero.npz", vec![("dx", s(0.0)), ("dy", s(30.0))], "dx = 0"),
        (
            "noorigin.npz",
            vec![("dx", s(30.0)), ("dy", s(30.0)), ("ymax", s(1.0))],
            "only ymax",
        ),
    ] {
        let mut m = vec![("elevation", formats::npy_f32(&h, w, ht))];
        m.extend(members);
        let p = write_file(dir.path(), name, &formats::npz(&m));
        let (msg, _) = error_of(&p, &ReadOptions::DEFAULT);
        assert_contains(&msg, &[name, expect]);
    }
}

/// 1-D coordinate arrays give the georeference and the direction: the same
/// real grid stored north to south (y falling) and south to north (y rising,
/// rows flipped), or east to west, reads as the same north-up grid at the
/// same place; uneven coordinates are refused, naming the array.
#[test]
fn npz_coordinate_arrays_are_honoured_in_either_direction() {
    let (h, w, ht) = hugo();
    let dir = tmp();
    let step = 1.0 / 3600.0;
    let f64s = |v: &[f64]| -> Vec<u8> {
        let data: Vec<u8> = v.iter().flat_map(|c| c.to_le_bytes()).collect();
        formats::npy("<f8", false, &[v.len()], &data)
    };
    let xs: Vec<f64> = (0..w).map(|i| -105.0 + i as f64 * step).collect();
    let ys: Vec<f64> = (0..ht).map(|j| 40.0 - j as f64 * step).collect();
    let north = formats::npz(&[
        ("elevation", formats::npy_f32(&h, w, ht)),
        ("x", f64s(&xs)),
        ("y", f64s(&ys)),
    ]);
    let flipped_rows: Vec<f32> = h.chunks(w).rev().flatten().copied().collect();
    let ys_up: Vec<f64> = ys.iter().rev().copied().collect();
    let south = formats::npz(&[
        ("elevation", formats::npy_f32(&flipped_rows, w, ht)),
        ("lon", f64s(&xs)),
        ("lat", f64s(&ys_up)),
    ]);
    let flipped_cols: Vec<f32> = h
        .chunks(w)
        .flat_map(|r| r.iter().rev().copied().collect::<Vec<_>>())
        .collect();
    let xs_west: Vec<f64> = xs.iter().rev().copied().collect();
    let west = formats::npz(&[
        ("elevation", formats::npy_f32(&flipped_cols, w, ht)),
        ("x", f64s(&xs_west)),
        ("y", f64s(&ys)),
    ]);
    let same = |a: &[f32], b: &[f32]| {
        a.iter()
            .zip(b)
            .all(|(a, b)| a == b || (a.is_nan() && b.is_nan()))
    };
    for (name, bytes) in [
        ("north.npz", north),
        ("south.npz", south),
        ("west.npz", west),
    ] {
        let p = write_file(dir.path(), name, &bytes);
        let dem = read(&p, &ReadOptions::DEFAULT);
        let g = dem.grid.georef();
        assert!(g.known && g.crs.is_geographic(), "{name}: {:?}", g.crs);
        let (x, y) = g.sample_xy(0.0, 0.0);
        assert!(
            (x + 105.0).abs() < 1e-9 && (y - 40.0).abs() < 1e-9,
            "{name}: row 0 col 0 at {x}, {y}"
        );
        assert!(g.pixel_x > 0.0 && g.pixel_y < 0.0, "{name}: {g:?}");
        assert!(same(dem.grid.heights(), &h), "{name}: heights not north-up");
    }
    let mut uneven = ys.clone();
    uneven[3] += step / 2.0;
    let bad = formats::npz(&[
        ("elevation", formats::npy_f32(&h, w, ht)),
        ("x", f64s(&xs)),
        ("y", f64s(&uneven)),
    ]);
    let p = write_file(dir.path(), "uneven.npz", &bad);
    let (msg, _) = error_of(&p, &ReadOptions::DEFAULT);
    assert_contains(
        &msg,
        &[
            "uneven.npz",
            "evenly spaced coordinates in array \"y\"",
            "index 3",
        ],
    );
    // An absurd shape beside coordinate arrays: refused, not overflowed.
    let huge = formats::npz(&[
        (
            "elevation",
            formats::npy("<f4", false, &[1 << 40, 2], &[0; 8]),
        ),
        ("x", f64s(&[0.0, 1.0])),
        ("y", f64s(&[0.0, 1.0])),
    ]);
    let p = write_file(dir.path(), "huge.npz", &huge);
    let (msg, _) = error_of(&p, &ReadOptions::DEFAULT);
    assert_contains(&msg, &["huge.npz", "coordinate array \"y\""]);
}

#[test]
fn npy_bad_input() {
    let dir = tmp();
    let cases: [(&str, Vec<u8>, &[&str]); 5] = [
        (
            "complex.npy",
            formats::npy("<c8", false, &[2, 2], &[0; 32]),
            &["dtype", "c8"],
        ),
        (
            "cube.npy",
            formats::npy("<f4", false, &[2, 2, 2], &[0; 32]),
            &["2-D"],
        ),
        (
            "short.npy",
            formats::npy("<f4", false, &[3, 3], &[0; 20]),
            &["36 bytes", "found 20 bytes"],
        ),
        (
            "huge.npy",
            formats::npy("<f4", false, &[1 << 20, 1 << 20], &[0; 8]),
            &["too large"],
        ),
        (
            "trunc.npy",
            formats::npy("<f4", false, &[3, 3], &[0; 36])[..20].to_vec(),
            &[".npy header"],
        ),
    ];
    for (name, bytes, needles) in cases {
        let p = write_file(dir.path(), name, &bytes);
        let (msg, _) = error_of(&p, &ReadOptions::DEFAULT);
        assert_contains(&msg, needles);
    }
    // Fortran order is read (transposed), not refused.
    let data: Vec<u8> = [1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let p = write_file(
        dir.path(),
        "f.npy",
        &formats::npy("<f4", true, &[2, 3], &data),
    );
    assert_eq!(
        read(&p, &ReadOptions::DEFAULT).grid.heights(),
        &[1.0, 3.0, 5.0, 2.0, 4.0, 6.0]
    );
}

#[test]
fn usgs_dem_written_from_the_bundled_srtm_tile() {
    let s = cota_fixtures::bundled_tile();
    let dir = tmp();
    let bytes = formats::usgs_dem(&s.heights, s.width, -72.0, -29.0, 3.0, s.width);
    let p = write_file(dir.path(), "S29W072.dem", &bytes);
    let dem = read(&p, &ReadOptions::DEFAULT);
    assert_eq!(dem.format, Format::UsgsDem);
    assert_eq!((dem.grid.width(), dem.grid.height()), (1201, 1201));
    assert_eq!(dem.grid.georef().crs, Crs::WGS84);
    let (x, y) = dem.grid.georef().sample_xy(0.0, 0.0);
    assert!(
        (x + 72.0).abs() < 1e-9 && (y + 28.0).abs() < 1e-9,
        "{x} {y}"
    );
    let srtm = read(&fixture("S29W072.hgt.zip"), &ReadOptions::DEFAULT);
    assert_eq!(dem.grid.void_count(), srtm.grid.void_count());
    let same = dem
        .grid
        .heights()
        .iter()
        .zip(srtm.grid.heights())
        .all(|(a, b)| a == b || (a.is_nan() && b.is_nan()));
    assert!(same, "the .dem and the .hgt.zip differ");
}

#[test]
fn usgs_dem_with_a_wrong_profile_count() {
    let s = cota_fixtures::bundled_tile().crop(0, 0, 101, 101);
    let dir = tmp();
    let more = formats::usgs_dem(&s.heights, 101, -72.0, -29.0, 3.0, 102);
    let p = write_file(dir.path(), "more.dem", &more);
    let (msg, _) = error_of(&p, &ReadOptions::DEFAULT);
    assert_contains(&msg, &["102 profiles", "found 101"]);
    let ok = formats::usgs_dem(&s.heights, 101, -72.0, -29.0, 3.0, 101);
    let p = write_file(dir.path(), "cut.dem", &ok[..ok.len() - 1024 * 3]);
    let (msg, _) = error_of(&p, &ReadOptions::DEFAULT);
    assert_contains(&msg, &["profile"]);
    let absurd = formats::usgs_dem(&s.heights, 101, -72.0, -29.0, 3.0, 999_999);
    let p = write_file(dir.path(), "absurd.dem", &absurd);
    let (msg, _) = error_of(&p, &ReadOptions::DEFAULT);
    assert_contains(&msg, &["999999 profiles"]);
}

#[test]
fn usgs_dem_profiles_far_apart_are_refused_before_their_grid_is_allocated() {
    // Two 2-sample profiles, the second 2^26 rows above the first: 2^27
    // samples (512 MB) of voids around 4 elevations. Found by the fuzzer.
    let s = cota_fixtures::bundled_tile().crop(0, 0, 2, 2);
    let mut bytes = formats::usgs_dem(&s.heights, 2, -72.0, -29.0, 3.0, 2);
    let y = -29.0 * 3600.0 + 3.0 * f64::from(1u32 << 26);
    let field = format!("{:>24}", format!("{y:.15E}").replace('E', "D"));
    // The second B record starts at 2048; its y follows 4 six-wide integers
    // and its x.
    bytes[2048 + 48..2048 + 72].copy_from_slice(field.as_bytes());
    let dir = tmp();
    let p = write_file(dir.path(), "apart.dem", &bytes);
    let opts = ReadOptions::DEFAULT.with_max_samples(Some(1 << 30));
    let (msg, _) = error_of(&p, &opts);
    assert_contains(
        &msg,
        &["apart.dem", "4 elevations spread over 134217732 samples"],
    );
}
