//! The imagery reader and the textured GLB, on the DEM + Landsat pair of
//! `fixtures/` (copies of `../shared/data/texture/`).
#![allow(clippy::unwrap_used, reason = "tests")]

use crate::common;

use cota_core::texture::{drape, DrapeOptions, RgbImage, TextureQuadtree};
use cota_core::{Bitree, ExtractOptions, HeightGrid};
use cota_io::export::{encode_png, textured_mesh_bytes, write_glb_textured, ExportOptions};
use cota_io::image::{place_on, read_image, Bands, ImageErrorKind, ImageOptions};
use cota_io::{read_dem, ReadOptions};

fn dem() -> HeightGrid {
    read_dem(
        &common::fixture("olinda_dem_utm25s.tif"),
        &ReadOptions::DEFAULT,
    )
    .unwrap()
    .grid
}

fn true_colour() -> ImageOptions {
    ImageOptions::DEFAULT.with_bands(Some(Bands::parse("3,2,1").unwrap()))
}

#[test]
fn landsat_bands_are_read_and_placed() {
    let img = read_image(&common::fixture("L7_ETMs.tif"), &true_colour()).unwrap();
    assert_eq!(
        (
            img.format,
            img.band_count,
            img.rgb.width(),
            img.rgb.height()
        ),
        ("GeoTIFF", 6, 349, 352)
    );
    assert_eq!(img.crs.to_string(), "EPSG:31985");
    let at = img.placement.unwrap();
    assert!((at.origin_x - 288_776.25).abs() < 1e-3 && (at.pixel_x - 28.5).abs() < 1e-6);
    // Each channel is the band the DEM reader reads.
    for (k, band) in [3u16, 2, 1].into_iter().enumerate() {
        let b = read_dem(
            &common::fixture("L7_ETMs.tif"),
            &ReadOptions::DEFAULT.with_band(Some(band)),
        )
        .unwrap();
        assert!(img
            .rgb
            .pixels()
            .iter()
            .zip(b.grid.heights())
            .all(|(p, h)| f32::from(p[k]) == *h));
    }
    let grid = dem();
    let placed = place_on(&img, &grid, false).unwrap();
    assert!(placed.rule.contains("same projection"), "{}", placed.rule);
    let t = drape(&img.rgb, &placed.placement, &grid, &DrapeOptions::DEFAULT).unwrap();
    // 110 cells of 89.994 m over 28.5 m pixels: 347.35 -> 347 texels.
    assert_eq!((t.width(), t.height()), (347, 347));
}

#[test]
fn jpeg_and_png_with_world_files_land_where_the_geotiff_does() {
    let grid = dem();
    let tif = read_image(&common::fixture("L7_ETMs.tif"), &true_colour()).unwrap();
    let jpg = read_image(&common::fixture("L7_ETMs_321.jpg"), &ImageOptions::DEFAULT).unwrap();
    assert_eq!(
        (jpg.format, jpg.rgb.width(), jpg.rgb.height()),
        ("JPEG", 349, 352)
    );
    assert!(jpg.placement_source.ends_with("L7_ETMs_321.jgw"));
    let (a, b) = (tif.placement.unwrap(), jpg.placement.unwrap());
    assert!((a.origin_x - b.origin_x).abs() < 1e-6 && (a.origin_y - b.origin_y).abs() < 1e-6);
    // JPEG is lossy: the colours are close, not equal.
    let mean_diff: f64 = tif
        .rgb
        .as_bytes()
        .iter()
        .zip(jpg.rgb.as_bytes())
        .map(|(x, y)| (f64::from(*x) - f64::from(*y)).abs())
        .sum::<f64>()
        / tif.rgb.as_bytes().len() as f64;
    assert!(mean_diff < 6.0, "{mean_diff}");
    // The image has no CRS of its own: taken as the DEM's.
    assert!(place_on(&jpg, &grid, false)
        .unwrap()
        .rule
        .contains("no CRS"));
    // A PNG of the GeoTIFF's pixels with a .pgw: the same texture exactly.
    let dir = tempfile::tempdir().unwrap();
    let png = common::write_file(dir.path(), "l7.png", &encode_png(&tif.rgb).unwrap());
    let jgw = std::fs::read(common::fixture("L7_ETMs_321.jgw")).unwrap();
    common::write_file(dir.path(), "l7.pgw", &jgw);
    let png = read_image(&png, &ImageOptions::DEFAULT).unwrap();
    assert_eq!(png.rgb, tif.rgb);
    let draped = |i: &cota_io::image::Image| {
        let p = place_on(i, &grid, false).unwrap().placement;
        drape(&i.rgb, &p, &grid, &DrapeOptions::DEFAULT).unwrap()
    };
    assert_eq!(draped(&png), draped(&tif));
    // Without a world file the image spans the DEM's footprint.
    let bare = common::write_file(dir.path(), "bare.png", &encode_png(&tif.rgb).unwrap());
    let bare = read_image(&bare, &ImageOptions::DEFAULT).unwrap();
    assert!(place_on(&bare, &grid, false)
        .unwrap()
        .rule
        .contains("stretched"));
}

#[test]
fn bad_inputs_are_clear_errors() {
    // A one-band image where three bands are asked for.
    let e = read_image(&common::fixture("olinda_dem_utm25s.tif"), &true_colour()).unwrap_err();
    assert!(
        matches!(e.kind, ImageErrorKind::MissingBand { found: 1, .. }),
        "{e}"
    );
    assert!(
        e.to_string().contains(
            "olinda_dem_utm25s.tif: expected an image with bands 3,2,1 (--bands), found 1 band"
        ),
        "{e}"
    );
    // Band 7 of six.
    let seven = ImageOptions::DEFAULT.with_bands(Some(Bands::parse("7,2,1").unwrap()));
    assert!(read_image(&common::fixture("L7_ETMs.tif"), &seven).is_err());
    assert!(
        Bands::parse("3,2").is_err() && Bands::parse("0").is_err() && Bands::parse("a").is_err()
    );
    // A mismatched image and DEM: Landsat in UTM 25S on an SRTM tile in EPSG:4326.
    let srtm = read_dem(&common::fixture("S29W072.hgt.zip"), &ReadOptions::DEFAULT)
        .unwrap()
        .grid;
    let img = read_image(&common::fixture("L7_ETMs.tif"), &true_colour()).unwrap();
    let e = place_on(&img, &srtm, false).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("EPSG:4326")
            && msg.contains("EPSG:31985")
            && msg.contains("does not reproject"),
        "{msg}"
    );
    // Same CRS assumed, but the image lies elsewhere: not covered.
    let at = place_on(&img, &srtm, true).unwrap().placement;
    assert!(drape(&img.rgb, &at, &srtm, &DrapeOptions::DEFAULT).is_err());
    // Not an image; a truncated PNG; a broken world file.
    let dir = tempfile::tempdir().unwrap();
    let txt = common::write_file(dir.path(), "x.png", b"hello");
    assert!(matches!(
        read_image(&txt, &ImageOptions::DEFAULT).unwrap_err().kind,
        ImageErrorKind::UnknownFormat { .. }
    ));
    let png = encode_png(&RgbImage::new(8, 8, vec![[1, 2, 3]; 64]).unwrap()).unwrap();
    let cut = common::write_file(dir.path(), "cut.png", &png[..png.len() / 2]);
    assert!(matches!(
        read_image(&cut, &ImageOptions::DEFAULT).unwrap_err().kind,
        ImageErrorKind::Decode { .. }
    ));
    let ok = common::write_file(dir.path(), "w.png", &png);
    common::write_file(dir.path(), "w.pgw", b"1 0.5 0 -1 10 20");
    let e = read_image(&ok, &ImageOptions::DEFAULT).unwrap_err();
    assert!(e.to_string().contains("north-up"), "{e}");
}

/// The parts of a GLB: its JSON and BIN chunk.
fn glb_parts(bytes: &[u8]) -> (serde_json::Value, Vec<u8>) {
    let u32_at = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap()) as usize;
    assert_eq!(&bytes[0..4], b"glTF");
    assert_eq!(u32_at(8), bytes.len());
    let jl = u32_at(12);
    let json = serde_json::from_slice(&bytes[20..20 + jl]).unwrap();
    let bl = u32_at(20 + jl);
    (json, bytes[28 + jl..28 + jl + bl].to_vec())
}

fn f32s(bin: &[u8], json: &serde_json::Value, accessor: usize, n: usize) -> Vec<f32> {
    let view =
        &json["bufferViews"][json["accessors"][accessor]["bufferView"].as_u64().unwrap() as usize];
    let at = view["byteOffset"].as_u64().unwrap_or(0) as usize;
    bin[at..at + 4 * n]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

#[test]
fn textured_glb_maps_each_vertex_to_the_texel_of_its_ground_position() {
    let grid = dem();
    let img = read_image(&common::fixture("L7_ETMs.tif"), &true_colour()).unwrap();
    let at = place_on(&img, &grid, false).unwrap().placement;
    let texture = drape(&img.rgb, &at, &grid, &DrapeOptions::DEFAULT).unwrap();
    let png = encode_png(&texture).unwrap();
    let mesh = Bitree::build(&grid)
        .unwrap()
        .extract(&ExtractOptions::max_error_m(2.0))
        .unwrap()
        .mesh;
    let mut bytes = Vec::new();
    let written =
        write_glb_textured(&mut bytes, &mesh, &grid, &png, &ExportOptions::DEFAULT).unwrap();
    assert_eq!(written, bytes.len() as u64);
    let (json, bin) = glb_parts(&bytes);
    // The byte model: BIN = C(M) + C(T), each padded to 4.
    let c_m = textured_mesh_bytes(mesh.vertex_count(), mesh.triangle_count());
    assert_eq!(bin.len() as u64, c_m + (png.len() as u64).div_ceil(4) * 4);
    assert_eq!(json["extensionsUsed"][0], "KHR_materials_unlit");
    assert!(json["materials"][0]["extensions"]["KHR_materials_unlit"].is_object());
    assert_eq!(json["images"][0]["mimeType"], "image/png");
    assert_eq!(
        json["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"],
        1
    );
    // The embedded PNG decodes to the texture raster.
    let view = &json["bufferViews"][3];
    let (off, len) = (
        view["byteOffset"].as_u64().unwrap() as usize,
        view["byteLength"].as_u64().unwrap() as usize,
    );
    let dir = tempfile::tempdir().unwrap();
    let back = common::write_file(dir.path(), "t.png", &bin[off..off + len]);
    assert_eq!(
        read_image(&back, &ImageOptions::DEFAULT).unwrap().rgb,
        texture
    );
    // Each vertex: its position gives its sample, hence its ground point;
    // its UV falls in the texel whose footprint holds that ground point.
    let n = mesh.vertex_count();
    let (pos, uv) = (f32s(&bin, &json, 0, 3 * n), f32s(&bin, &json, 1, 2 * n));
    let [dx, dy] = grid.cell_size_m();
    let g = grid.georef();
    let (x0, y0) = g.sample_xy(0.0, 0.0);
    let (x1, y1) = g.sample_xy(grid.width() as f64 - 1.0, grid.height() as f64 - 1.0);
    let (tw, th) = (texture.width(), texture.height());
    for k in 0..n {
        let col = f64::from(pos[3 * k]) / dx;
        let row = (grid.height() - 1) as f64 - f64::from(pos[3 * k + 1]) / dy;
        assert!((col - col.round()).abs() < 1e-3 && (row - row.round()).abs() < 1e-3);
        let (gx, gy) = g.sample_xy(col.round(), row.round());
        let i = ((f64::from(uv[2 * k]) * tw as f64).floor() as usize).min(tw - 1);
        let j = ((f64::from(uv[2 * k + 1]) * th as f64).floor() as usize).min(th - 1);
        let tx = |i: usize| x0 + i as f64 / tw as f64 * (x1 - x0);
        let ty = |j: usize| y0 + j as f64 / th as f64 * (y1 - y0);
        assert!(
            tx(i) - 1e-6 <= gx && gx <= tx(i + 1) + 1e-6,
            "vertex {k}: x {gx} not in texel {i}"
        );
        assert!(
            ty(j) + 1e-6 >= gy && gy >= ty(j + 1) - 1e-6,
            "vertex {k}: y {gy} not in texel row {j}"
        );
    }
}

#[test]
fn the_texture_quadtree_tiles_the_draped_landsat_image_exactly() {
    let grid = dem();
    let img = read_image(&common::fixture("L7_ETMs.tif"), &true_colour()).unwrap();
    let at = place_on(&img, &grid, false).unwrap().placement;
    let texture = drape(&img.rgb, &at, &grid, &DrapeOptions::DEFAULT).unwrap();
    let tree = TextureQuadtree::build(&texture);
    let (w, h) = (texture.width(), texture.height());
    let mut last = usize::MAX;
    for tol in [0.0, 4.0, 16.0, 64.0] {
        let x = tree.extract(tol);
        // Each texel in exactly one leaf.
        let mut count = vec![0u8; w * h];
        for l in &x.leaves {
            for y in l.y..l.y + l.height {
                for xx in l.x..l.x + l.width {
                    count[y as usize * w + xx as usize] += 1;
                }
            }
        }
        assert!(count.iter().all(|&c| c == 1), "gaps or overlaps at {tol}");
        // D(T) is the squared RGB difference of the rendered leaves.
        let r = x.render();
        let brute: u64 = texture
            .as_bytes()
            .iter()
            .zip(r.as_bytes())
            .map(|(a, b)| (i64::from(*a) - i64::from(*b)).pow(2) as u64)
            .sum();
        assert_eq!(x.distortion, brute, "at {tol}");
        if tol == 0.0 {
            assert_eq!((x.distortion, &r), (0, &texture));
        }
        assert!(x.leaves.len() < last);
        last = x.leaves.len();
    }
}
