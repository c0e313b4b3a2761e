//! `cota tiles` end to end: the bundled sample into a pyramid, the report,
//! a resumed run; projected inputs, a grid given its CRS by `--src-crs`, and
//! inputs of two resolutions, each checked as drawn against its own samples.
#![allow(clippy::unwrap_used, clippy::panic)]

use crate::common;

use std::collections::BTreeSet;

use common::{cota, shared, stderr, stdout};

#[test]
fn sample_pyramid_report_and_resume() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tiles");
    let o = out.to_str().unwrap();
    let r = cota(&[
        "tiles",
        "--max-zoom",
        "7",
        "--normals",
        "--metadata",
        "--check",
        "--json",
        "-o",
        o,
    ]);
    assert!(r.status.success(), "{}", stderr(&r));
    let v: serde_json::Value = serde_json::from_str(&stdout(&r)).unwrap();
    let tiles = v["tiles"].as_u64().unwrap();
    assert!(tiles > 5 && v["written"].as_u64() == Some(tiles), "{v}");
    for z in v["zooms"].as_array().unwrap() {
        assert!(
            z["measured_error_m"].as_f64().unwrap() <= z["max_error_m"].as_f64().unwrap(),
            "{z}"
        );
    }
    assert!(v["check"].as_str().unwrap().starts_with("passed"), "{v}");
    assert!(out.join("layer.json").is_file() && out.join("0/0/0.terrain").is_file());
    let again = cota(&[
        "tiles",
        "--max-zoom",
        "7",
        "--normals",
        "--metadata",
        "-o",
        o,
    ]);
    assert!(again.status.success(), "{}", stderr(&again));
    assert!(
        stdout(&again).contains(&format!("0 written, {tiles} skipped")),
        "{}",
        stdout(&again)
    );
    let changed = cota(&["tiles", "--max-zoom", "7", "-o", o]);
    assert!(!changed.status.success());
    assert!(stderr(&changed).contains("--force"), "{}", stderr(&changed));
}

/// A UTM GeoTIFF (90 m, UTM 25S) is tiled without any option beyond the
/// input, every tile checked as drawn against the file's own samples
/// through its projection, and `layer.json`'s bounds hold its footprint.
#[test]
fn projected_input_is_tiled_and_checked_through_its_crs() {
    let Some(f) = common::shared("texture/olinda_dem_utm25s.tif") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t");
    let r = cota(&[
        "tiles",
        f.to_str().unwrap(),
        "--check",
        "--json",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", stderr(&r));
    let v: serde_json::Value = serde_json::from_str(&stdout(&r)).unwrap();
    for z in v["zooms"].as_array().unwrap() {
        let (got, bound) = (
            z["drawn_error_m"].as_f64().unwrap(),
            z["max_error_m"].as_f64().unwrap(),
        );
        assert!(got <= bound, "{z}");
    }
    let layer: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("layer.json")).unwrap()).unwrap();
    let b: Vec<f64> = layer["bounds"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    // Olinda, Brazil: about 34.9° W, 8.0° S (UTM 25S, 111 samples of 90 m).
    assert!(
        b[0] > -35.1 && b[2] < -34.7 && b[1] > -8.2 && b[3] < -7.8,
        "{b:?}"
    );
    assert!(b[2] - b[0] > 0.08 && b[3] - b[1] > 0.08, "{b:?}");
}

/// A grid without a CRS of its own is refused unless `--src-crs` gives it
/// one, and then tiled through it.
#[test]
fn a_grid_without_crs_needs_src_crs() {
    let dir = tempfile::tempdir().unwrap();
    let asc = dir.path().join("utm.asc");
    // A real SRTM clip (Boulder) laid on a UTM 13N grid of 90 m: heights
    // only; the position is what --src-crs says.
    let src = common::shared("asc/boulder_srtmgl3_240x144.asc");
    let Some(src) = src else {
        return;
    };
    let text = std::fs::read_to_string(src).unwrap();
    let body: String = text.lines().skip(6).map(|l| format!("{l}\n")).collect();
    let head =
        "ncols 240\nnrows 144\nxllcorner 470000\nyllcorner 4440000\ncellsize 90\nNODATA_value 0\n";
    std::fs::write(&asc, format!("{head}{body}")).unwrap();
    let out = dir.path().join("t");
    let a = asc.to_str().unwrap();
    let r = cota(&["tiles", a, "-o", out.to_str().unwrap()]);
    assert!(!r.status.success());
    assert!(stderr(&r).contains("--src-crs"), "{}", stderr(&r));
    let r = cota(&[
        "tiles",
        a,
        "--src-crs",
        "EPSG:32613",
        "--check",
        "--max-zoom",
        "11",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", stderr(&r));
    assert!(stdout(&r).contains("check       passed"), "{}", stdout(&r));
}

/// Two adjacent DEMs of different resolutions (SRTM 3" and the next tile at
/// 6") make one pyramid with no crack, checked against both files' own
/// samples.
#[test]
fn mixed_resolutions_mosaic_through_the_lattice() {
    let (Some(w), Some(e)) = (
        common::shared("srtm/N00E010.hgt"),
        common::shared("srtm/N00E011.hgt.zip"),
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let coarse = dir.path().join("N00E011_6s.asc");
    write_every_other(&e, &coarse);
    let out = dir.path().join("t");
    let r = cota(&[
        "tiles",
        w.to_str().unwrap(),
        coarse.to_str().unwrap(),
        "--max-zoom",
        "10",
        "--check",
        "--json",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", stderr(&r));
    let v: serde_json::Value = serde_json::from_str(&stdout(&r)).unwrap();
    assert!(v["check"].as_str().unwrap().starts_with("passed"), "{v}");
    // Both files' footprints are covered: tiles east and west of 11°E.
    let layer = std::fs::read_to_string(out.join("layer.json")).unwrap();
    let layer: serde_json::Value = serde_json::from_str(&layer).unwrap();
    let b: Vec<f64> = layer["bounds"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert!(b[0] < 10.01 && b[2] > 11.99, "{b:?}");
}

/// Every other sample of an SRTM 3" tile as an ESRI ASCII grid at 6".
fn write_every_other(hgt_zip: &std::path::Path, out: &std::path::Path) {
    let s = cota_fixtures::read(hgt_zip).unwrap();
    let (n, h) = (s.width, &s.heights);
    let m = n.div_ceil(2);
    let mut text = format!(
        "ncols {m}\nnrows {m}\nxllcenter 11.0\nyllcenter 0.0\ncellsize {}\nNODATA_value -32768\n",
        1.0 / 600.0
    );
    for r in (0..n).step_by(2) {
        let row: Vec<String> = (0..n)
            .step_by(2)
            .map(|c| {
                let v = h[r * n + c];
                if v.is_nan() {
                    "-32768".to_string()
                } else {
                    format!("{v}")
                }
            })
            .collect();
        text.push_str(&row.join(" "));
        text.push('\n');
    }
    std::fs::write(out, text).unwrap();
}

/// Two 1° tiles the way Copernicus GLO-30 cuts them at 50° N: float32
/// GeoTIFFs whose width shrinks with latitude (the northern one 1.5 times
/// coarser east-west), made from two adjacent real SRTM tiles; with and
/// without a shared edge row. They tile with no crack and no seam of NaN,
/// every tile checked as drawn against both files' own samples, and the
/// tiles over the seam exist; `cota mesh` joins them too.
#[test]
fn copernicus_style_tiles_mosaic_without_gaps() {
    let (Some(s), Some(n)) = (
        common::shared("srtm/N49E011.hgt.zip"),
        common::shared("srtm/N50E011.hgt.zip"),
    ) else {
        return;
    };
    let (s, n) = (
        cota_fixtures::read(&s).unwrap(),
        cota_fixtures::read(&n).unwrap(),
    );
    for shared_edge in [false, true] {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("south.tif");
        let b = dir.path().join("north.tif");
        copernicus_like(&s, 49.0, 1200, shared_edge, &a);
        copernicus_like(&n, 50.0, 800, shared_edge, &b);
        let out = dir.path().join("t");
        let r = cota(&[
            "tiles",
            a.to_str().unwrap(),
            b.to_str().unwrap(),
            "--max-zoom",
            "10",
            "--check",
            "--json",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(
            r.status.success(),
            "shared edge {shared_edge}: {}",
            stderr(&r)
        );
        let v: serde_json::Value = serde_json::from_str(&stdout(&r)).unwrap();
        assert!(v["check"].as_str().unwrap().starts_with("passed"), "{v}");
        // The zoom-10 tile across 50° N at 11.5° E (x 1089, row 796 of 1024).
        assert!(out.join("10/1089/796.terrain").is_file());
        let glb = dir.path().join("m.glb");
        let m = cota(&[
            "mesh",
            a.to_str().unwrap(),
            b.to_str().unwrap(),
            "--max-error",
            "10",
            "--check",
            "-o",
            glb.to_str().unwrap(),
        ]);
        assert!(m.status.success(), "{}", stderr(&m));
        assert!(stdout(&m).contains("check       passed"), "{}", stdout(&m));
    }
}

/// A 1° float32 GeoTIFF (EPSG:4326, pixel-is-area) whose south edge is at
/// `south` degrees, `width` columns (the east-west spacing 1°/width), 3"
/// north-south, from the SRTM tile `t` by bilinear interpolation; with
/// `shared_edge` it holds 1201 rows whose outer rows lie on the tile's
/// edges (what the next tile repeats), else 1200 rows between them.
fn copernicus_like(
    t: &cota_fixtures::Samples,
    south: f64,
    width: usize,
    shared_edge: bool,
    path: &std::path::Path,
) {
    let n = t.width;
    let rows = if shared_edge { 1201 } else { 1200 };
    let (dx, dy) = (1.0 / width as f64, 1.0 / 1200.0);
    // Pixel centres: column i at 11 + (i + 0.5)·dx; row j at the north edge
    // minus (j + 0.5)·dy, or minus j·dy with a shared edge.
    let off = if shared_edge { 0.0 } else { 0.5 };
    let bil = |x: f64, y: f64| {
        let (c, r) = (
            (x * (n - 1) as f64).clamp(0.0, (n - 1) as f64),
            (y * (n - 1) as f64).clamp(0.0, (n - 1) as f64),
        );
        let (i, j) = ((c as usize).min(n - 2), (r as usize).min(n - 2));
        let (fx, fy) = (c - i as f64, r - j as f64);
        let z = |a: usize, b: usize| f64::from(t.heights[b * n + a]);
        let top = z(i, j) + (z(i + 1, j) - z(i, j)) * fx;
        let bottom = z(i, j + 1) + (z(i + 1, j + 1) - z(i, j + 1)) * fx;
        (top + (bottom - top) * fy) as f32
    };
    let heights: Vec<f32> = (0..rows)
        .flat_map(|j| (0..width).map(move |i| ((i as f64 + 0.5) * dx, (j as f64 + off) * dy)))
        .map(|(x, y)| bil(x, y))
        .collect();
    let g = cota_fixtures::geotiff::GeoTiff {
        width,
        height: rows,
        heights: &heights,
        west: 11.0,
        north: south + 1.0 + if shared_edge { dy / 2.0 } else { 0.0 },
        pixel: dx,
        pixel_y: dy,
        crs: cota_fixtures::geotiff::GeoTiffCrs::Geographic(4326),
        nodata: -9999.0,
    };
    cota_fixtures::geotiff::write_geotiff(path, &g).unwrap();
}

/// A small ESRI ASCII grid (gentle relief) at `xll`, `yll`, `cell` units a
/// pixel, 40 × 40 samples.
fn small_asc(path: &std::path::Path, xll: f64, yll: f64, cell: f64) {
    let mut s = format!(
        "ncols 40\nnrows 40\nxllcorner {xll}\nyllcorner {yll}\ncellsize {cell}\nNODATA_value -9999\n"
    );
    for r in 0..40 {
        let row: Vec<String> = (0..40)
            .map(|c| format!("{:.1}", 100.0 + 10.0 * (r as f64 * 0.1).sin() + c as f64))
            .collect();
        s += &row.join(" ");
        s.push('\n');
    }
    std::fs::write(path, s).unwrap();
}

#[test]
fn poles_and_beyond_the_world_are_refused_before_any_tile() {
    let dir = tempfile::tempdir().unwrap();
    // (file, CRS, x, y, cell, what the message must say)
    let cases = [
        (
            "polar.asc",
            "EPSG:3413",
            -20000.0,
            -20000.0,
            1000.0,
            "north pole",
        ),
        (
            "beyond.asc",
            "EPSG:4326",
            10.0,
            89.8,
            0.01,
            "latitudes -90..90",
        ),
    ];
    for (name, crs, x, y, cell, says) in cases {
        let f = dir.path().join(name);
        small_asc(&f, x, y, cell);
        let out = dir.path().join(format!("out-{name}"));
        let r = cota(&[
            "tiles",
            f.to_str().unwrap(),
            "--src-crs",
            crs,
            "--max-zoom",
            "8",
            "-o",
            out.to_str().unwrap(),
        ]);
        let e = stderr(&r);
        assert!(
            !r.status.success() && e.contains(says) && e.contains(name),
            "{name}: {e}"
        );
        assert!(
            !out.join("layer.json").exists(),
            "{name}: a pyramid was written"
        );
    }
}

/// Every `(z, x, y)` that `layer.json`'s `available` lists, and every tile
/// file under `out`.
fn listed_and_written(out: &std::path::Path) -> (BTreeSet<[u32; 3]>, BTreeSet<[u32; 3]>) {
    let layer: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("layer.json")).unwrap()).unwrap();
    let mut listed = BTreeSet::new();
    for (z, rects) in layer["available"].as_array().unwrap().iter().enumerate() {
        for r in rects.as_array().unwrap() {
            let v = |k: &str| r[k].as_u64().unwrap() as u32;
            for x in v("startX")..=v("endX") {
                for y in v("startY")..=v("endY") {
                    listed.insert([z as u32, x, y]);
                }
            }
        }
    }
    let mut written = BTreeSet::new();
    for z in std::fs::read_dir(out).unwrap().flatten() {
        let Ok(zi) = z.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        for x in std::fs::read_dir(z.path()).unwrap().flatten() {
            let xi: u32 = x.file_name().to_string_lossy().parse().unwrap();
            for y in std::fs::read_dir(x.path()).unwrap().flatten() {
                let name = y.file_name().to_string_lossy().into_owned();
                let yi: u32 = name.strip_suffix(".terrain").unwrap().parse().unwrap();
                written.insert([zi, xi, yi]);
            }
        }
    }
    (listed, written)
}

/// The tile `z/x/y` under `out`, decoded.
fn decoded(out: &std::path::Path, [z, x, y]: [u32; 3]) -> cota_tiles::DecodedTile {
    let bytes = std::fs::read(out.join(format!("{z}/{x}/{y}.terrain"))).unwrap();
    cota_tiles::decode(&bytes).unwrap()
}

/// `cota tiles` of `files` to `out` at zooms up to 9, checked; its report.
fn tiles_checked(
    files: &[&std::path::Path],
    out: &std::path::Path,
    more: &[&str],
) -> serde_json::Value {
    let mut args = vec!["tiles"];
    args.extend(files.iter().map(|f| f.to_str().unwrap()));
    args.extend(more);
    args.extend([
        "--max-zoom",
        "9",
        "--check",
        "--json",
        "-o",
        out.to_str().unwrap(),
    ]);
    let r = cota(&args);
    assert!(r.status.success(), "{}", stderr(&r));
    let v: serde_json::Value = serde_json::from_str(&stdout(&r)).unwrap();
    assert!(v["check"].as_str().unwrap().starts_with("passed"), "{v}");
    v
}

#[test]
fn a_footprint_across_the_antimeridian_is_tiled_on_both_sides_without_a_seam() {
    let (Some(w), Some(e)) = (shared("srtm/N00E010.hgt"), shared("srtm/N00E011.hgt.zip")) else {
        return;
    };
    // The two real adjacent tiles renamed (an .hgt is placed by its name):
    // the same terrain, their shared column now at ±180°.
    let dir = tempfile::tempdir().unwrap();
    let (east, west) = (
        dir.path().join("N00E179.hgt"),
        dir.path().join("N00W180.hgt.zip"),
    );
    std::fs::copy(w, &east).unwrap();
    std::fs::copy(e, &west).unwrap();
    let out = dir.path().join("across");
    tiles_checked(&[&east, &west], &out, &[]);
    let layer: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("layer.json")).unwrap()).unwrap();
    let b: Vec<f64> = layer["bounds"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!(
        (b[0] - 179.0).abs() < 1e-6 && (b[2] + 179.0).abs() < 1e-6,
        "{b:?}"
    );
    let (listed, written) = listed_and_written(&out);
    assert_eq!(listed, written);
    let (mut seams, mut on_land) = (0, 0);
    for z in 0..=9u32 {
        let last = (2u32 << z) - 1;
        // Both sides, `available` split in two ranges where it wraps.
        assert_eq!(
            layer["available"][z as usize].as_array().unwrap().len(),
            2,
            "zoom {z}"
        );
        let ys: Vec<u32> = written
            .iter()
            .filter(|t| t[0] == z && t[1] == last)
            .map(|t| t[2])
            .collect();
        assert!(
            !ys.is_empty() && written.iter().any(|t| t[0] == z && t[1] == 0),
            "zoom {z}"
        );
        for y in ys {
            let (a, b) = (decoded(&out, [z, last, y]), decoded(&out, [z, 0, y]));
            let c = cota_tiles::compare_border(&a, &b, cota_tiles::Neighbour::East);
            assert_eq!(c.mismatches(), 0, "{z}/{last}/{y} and {z}/0/{y}: {c:?}");
            seams += 1;
            on_land += (0..a.u.len())
                .filter(|&i| a.u[i] == 32767 && a.height_m(i) > 1.0)
                .count();
        }
    }
    assert!(
        seams >= 10 && on_land > 20,
        "{seams} seams, {on_land} border vertices on land"
    );
    // The same pair is one grid for `cota info` (its footprint across
    // 180°, west > east) and `cota mesh` (2401 x 1201 samples, checked).
    let (e, w) = (east.to_str().unwrap(), west.to_str().unwrap());
    let r = cota(&["info", "--json", e, w]);
    assert!(r.status.success(), "{}", stderr(&r));
    let v: serde_json::Value = serde_json::from_str(&stdout(&r)).unwrap();
    let fp: Vec<f64> = v["footprint_deg"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(
        (v["width"].as_u64(), v["hole_samples"].as_u64()),
        (Some(2401), Some(0)),
        "{v}"
    );
    assert!(
        (fp[0] - 179.0).abs() < 1e-9 && (fp[2] + 179.0).abs() < 1e-9,
        "{fp:?}"
    );
    let mesh = dir.path().join("pair.ply");
    let args = ["mesh", e, w, "--max-error", "50", "--check", "--json", "-o"];
    let r = cota(&[&args[..], &[mesh.to_str().unwrap()]].concat());
    assert!(r.status.success(), "{}", stderr(&r));
    let v: serde_json::Value = serde_json::from_str(&stdout(&r)).unwrap();
    assert_eq!(
        (v["width"].as_u64(), v["checked"].as_bool()),
        (Some(2401), Some(true)),
        "{v}"
    );
    assert_eq!(v["seams"]["max_abs_diff_m"].as_f64(), Some(0.0), "{v}");
    // Touching 180° without crossing it: one side only, as before.
    let out = dir.path().join("touching");
    tiles_checked(&[&east], &out, &[]);
    let (listed, written) = listed_and_written(&out);
    assert_eq!(listed, written);
    assert!(
        !written.iter().any(|t| t[0] > 0 && t[1] == 0),
        "{written:?}"
    );
}

#[test]
fn geographic_and_projected_grids_across_the_antimeridian_are_tiled() {
    let dir = tempfile::tempdir().unwrap();
    // (file, CRS, x, y, cell): 179.8° to 180.19°, and UTM zone 60 south
    // (Fiji) past 180°.
    let cases = [
        ("lonlat.asc", "EPSG:4326", 179.8, -17.0, 0.01),
        ("utm60.asc", "EPSG:32760", 800000.0, 8100000.0, 1000.0),
    ];
    for (name, crs, x, y, cell) in cases {
        let f = dir.path().join(name);
        small_asc(&f, x, y, cell);
        let out = dir.path().join(format!("out-{name}"));
        tiles_checked(&[&f], &out, &["--src-crs", crs]);
        let (listed, written) = listed_and_written(&out);
        assert_eq!(listed, written, "{name}");
        let last = (2u32 << 9) - 1;
        let at = |x: u32| written.iter().any(|t| t[0] == 9 && t[1] == x);
        assert!(at(last) && at(0), "{name}: {written:?}");
    }
}

#[test]
fn mbtiles_archive_output_checked_and_refused_for_shards() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.mbtiles");
    let o = out.to_str().unwrap();
    let r = cota(&[
        "tiles",
        "--max-zoom",
        "8",
        "--check",
        "--gzip",
        "--json",
        "-o",
        o,
    ]);
    assert!(r.status.success(), "{}", stderr(&r));
    let v: serde_json::Value = serde_json::from_str(&stdout(&r)).unwrap();
    assert!(v["check"].as_str().unwrap().starts_with("passed"), "{v}");
    let tiles = v["tiles"].as_u64().unwrap();
    let a = cota_tiles::MbtilesReader::open(&out).unwrap();
    assert_eq!(a.tile_ids().unwrap().len() as u64, tiles);
    assert!(a.layer_json().unwrap().contains("quantized-mesh-1.0"));
    let again = cota(&["tiles", "--max-zoom", "8", "--gzip", "--json", "-o", o]);
    let v: serde_json::Value = serde_json::from_str(&stdout(&again)).unwrap();
    assert_eq!(v["skipped"].as_u64(), Some(tiles), "{v}");
    let plan = cota(&["tiles", "--plan", "--shards", "2", "-o", o]);
    assert!(
        !plan.status.success() && stderr(&plan).contains("t.mbtiles"),
        "{}",
        stderr(&plan)
    );
}

/// `--format 3dtiles -o OUT.3tz`: one 3D Tiles Archive holding exactly the
/// directory pyramid's files (read back through its index), no staging or
/// partial file left; a quantized-mesh run into a .3tz name is refused.
#[test]
fn three_d_tiles_archive_holds_the_directory_pyramid() {
    let dir = tempfile::tempdir().unwrap();
    let (plain, packed) = (dir.path().join("t3d"), dir.path().join("t.3tz"));
    let args = [
        "tiles",
        "--format",
        "3dtiles",
        "--meshopt",
        "--max-zoom",
        "7",
    ];
    for out in [&plain, &packed] {
        let r = cota(&[&args[..], &["-o", out.to_str().unwrap()]].concat());
        assert!(r.status.success(), "{}", stderr(&r));
    }
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}: staging or partial files left");
    let reader = cota_tiles::Tz3Reader::open(&packed).unwrap();
    let mut files = Vec::new();
    let mut stack = vec![plain.clone()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            if p.file_name().unwrap().to_string_lossy().starts_with('.') {
                continue;
            }
            if p.is_dir() {
                stack.push(p);
            } else {
                files.push(p);
            }
        }
    }
    assert!(files.len() > 20, "{} files", files.len());
    assert_eq!(reader.len(), files.len());
    for f in &files {
        let rel = f
            .strip_prefix(&plain)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        let got = reader.get(&rel).unwrap();
        assert_eq!(
            got.as_deref(),
            Some(&std::fs::read(f).unwrap()[..]),
            "{rel}"
        );
    }
    assert_eq!(reader.get("0/no.glb").unwrap(), None);
    let r = cota(&[
        "tiles",
        "--max-zoom",
        "7",
        "-o",
        dir.path().join("q.3tz").to_str().unwrap(),
    ]);
    assert!(
        !r.status.success() && stderr(&r).contains("--format 3dtiles"),
        "{}",
        stderr(&r)
    );
}

/// `--format 3dtiles` (issue 30): tileset.json, subtrees and GLBs, checked as
/// drawn; what it cannot write is refused in words.
#[test]
fn three_d_tiles_pyramid_and_its_refusals() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t3d");
    let o = out.to_str().unwrap();
    let args = [
        "tiles",
        "--format",
        "3dtiles",
        "--max-zoom",
        "7",
        "--check",
        "--json",
    ];
    let r = cota(&[&args[..], &["-o", o]].concat());
    assert!(r.status.success(), "{}", stderr(&r));
    let v: serde_json::Value = serde_json::from_str(&stdout(&r)).unwrap();
    assert!(v["check"].as_str().unwrap().starts_with("passed"), "{v}");
    assert!(out.join("tileset.json").is_file());
    assert!(out.join("0/0/0/0.glb").is_file() && out.join("1/0/0/0.glb").is_file());
    assert!(out.join("0/subtrees/0/0/0.subtree").is_file());
    assert!(!out.join("layer.json").exists());
    // The fill tiles (every refined tile's four children) come on top of
    // the pyramid's tiles: the west root's other three quadrants at least.
    let fill = v["fill"].as_u64().unwrap();
    assert!(fill >= 3, "{v}");
    assert_eq!(
        v["written"].as_u64(),
        Some(v["tiles"].as_u64().unwrap() + fill)
    );
    // The same directory as quantized-mesh: other settings, refused.
    let r = cota(&["tiles", "--max-zoom", "7", "-o", o]);
    assert!(!r.status.success());
    assert!(stderr(&r).contains("other settings"), "{}", stderr(&r));
    let r = cota(&["tiles", "--format", "3dtiles", "--gzip", "-o", o]);
    assert!(
        !r.status.success() && stderr(&r).contains("--gzip"),
        "{}",
        stderr(&r)
    );
    // --meshopt: the same pyramid with compressed GLBs, checked; a
    // quantized-mesh run with it, refused.
    let packed = dir.path().join("t3dm");
    let r = cota(&[&args[..], &["--meshopt", "-o", packed.to_str().unwrap()]].concat());
    assert!(r.status.success(), "{}", stderr(&r));
    let glb = std::fs::read(packed.join("0/0/0/0.glb")).unwrap();
    assert!(String::from_utf8_lossy(&glb).contains("EXT_meshopt_compression"));
    let r = cota(&["tiles", "--meshopt", "-o", packed.to_str().unwrap()]);
    assert!(
        !r.status.success() && stderr(&r).contains("--format 3dtiles"),
        "{}",
        stderr(&r)
    );
    // Skirts by default (a second primitive); --no-skirts is another
    // setting for an output made with them, and 3D Tiles only.
    assert!(String::from_utf8_lossy(&glb).contains(r#""mode":4},{"attributes""#));
    let r = cota(
        &[
            &args[..],
            &["--meshopt", "--no-skirts", "-o", packed.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(
        !r.status.success() && stderr(&r).contains("other settings"),
        "{}",
        stderr(&r)
    );
    let r = cota(&["tiles", "--no-skirts", "-o", packed.to_str().unwrap()]);
    assert!(
        !r.status.success() && stderr(&r).contains("--format 3dtiles"),
        "{}",
        stderr(&r)
    );
    let mb = dir.path().join("t.mbtiles");
    let r = cota(&["tiles", "--format", "3dtiles", "-o", mb.to_str().unwrap()]);
    assert!(
        !r.status.success() && stderr(&r).contains("3dtiles"),
        "{}",
        stderr(&r)
    );
    let r = cota(
        &[
            &args[..],
            &[
                "--min-zoom",
                "2",
                "-o",
                dir.path().join("z2").to_str().unwrap(),
            ],
        ]
        .concat(),
    );
    assert!(
        !r.status.success() && stderr(&r).contains("--min-zoom 0"),
        "{}",
        stderr(&r)
    );
}
