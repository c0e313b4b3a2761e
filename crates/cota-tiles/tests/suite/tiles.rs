//! Quantized-mesh pyramids on real DEMs: every tile decodes, holds its edge
//! lists, meets its bound after quantization (checked again here, on the
//! files as written), and shares its borders with its same-zoom neighbours
//! exactly (issue 17).
#![allow(clippy::unwrap_used, clippy::panic)]

use std::collections::HashMap;
use std::path::Path;

use cota_core::mesh::check::check_placed_mesh;
use cota_core::tiles::{ErrorSchedule, Lattice, LatticeOptions, Prepared, TileId, TilerOptions};
use cota_core::{fill_voids, mosaic, FillOptions, HeightGrid, Mesh, MeshVertex, MosaicOptions};
use cota_io::{read_dem, ReadOptions};
use cota_tiles::{
    compare_border, decode, edge_lists_match, encode, make_tile, tile_path, write_pyramid,
    DecodedTile, Extensions, Neighbour, PyramidError, PyramidOptions, TileExtensions, TileFrame,
    JOURNAL_DIR,
};

fn load(paths: &[std::path::PathBuf]) -> HeightGrid {
    let grids = paths
        .iter()
        .map(|p| read_dem(p, &ReadOptions::DEFAULT).unwrap().grid)
        .collect();
    let mut g = mosaic(grids, &MosaicOptions::DEFAULT).unwrap().grid;
    fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
    g
}

/// Decodes every tile of the pyramid, re-checks it and returns them.
fn decode_all(prep: &Prepared<'_>, out: &Path) -> HashMap<TileId, DecodedTile> {
    let mut tiles = HashMap::new();
    for t in prep.tiles() {
        let bytes = std::fs::read(tile_path(out, t)).unwrap();
        let d = decode(&bytes).unwrap();
        assert!(edge_lists_match(&d), "{t}: edge lists");
        let bound = prep.zoom(t.z).unwrap().max_error_m;
        let cells = prep.lattice().scheme().cells_at(t.z);
        check_placed_mesh(&prep.region(t), &d.to_placed(cells), Some(bound))
            .unwrap_or_else(|e| panic!("{t}: {e}"));
        tiles.insert(t, d);
    }
    tiles
}

/// Compares every pair of same-zoom neighbours; returns (borders, positions).
fn assert_no_seams(tiles: &HashMap<TileId, DecodedTile>) -> (usize, usize) {
    let (mut borders, mut positions) = (0, 0);
    for (t, a) in tiles {
        for (dx, dy, side) in [(1, 0, Neighbour::East), (0, 1, Neighbour::North)] {
            let n = TileId {
                z: t.z,
                x: t.x + dx,
                y: t.y + dy,
            };
            if let Some(b) = tiles.get(&n) {
                let c = compare_border(a, b, side);
                assert_eq!(c.mismatches(), 0, "{t} and {n}: {c:?}");
                borders += 1;
                positions += c.positions;
            }
        }
    }
    (borders, positions)
}

#[test]
fn fixture_pyramid_decodes_within_bounds_without_seams() {
    let g = load(&[cota_fixtures::fixture("S29W072.hgt.zip")]);
    let lat = Lattice::resample(&g, &LatticeOptions::DEFAULT).unwrap();
    assert_eq!(lat.scheme().max_zoom, 12);
    let prep = Prepared::new(&lat, &g, &TilerOptions::DEFAULT).unwrap();
    let out = tempfile::tempdir().unwrap();
    let ext = TileExtensions::with(true, true, true);
    let opts = PyramidOptions::DEFAULT.with_extensions(ext).with_gzip(true);
    let report = write_pyramid(&prep, out.path(), &opts, None, &|_| {}).unwrap();
    assert_eq!(report.written(), prep.tile_count());
    for z in &report.zooms {
        assert!(z.measured_error_m <= z.max_error_m, "{z:?}");
    }
    let tiles = decode_all(&prep, out.path());
    let (borders, positions) = assert_no_seams(&tiles);
    assert!(
        borders > 1000 && positions > 10_000,
        "{borders} {positions}"
    );
    // Extensions are there, and the roots exist.
    let root = &tiles[&TileId { z: 0, x: 0, y: 0 }];
    assert!(root.normals.is_some() && root.water_mask.is_some() && root.metadata.is_some());
    assert!(tiles.contains_key(&TileId { z: 0, x: 1, y: 0 }));
    let layer: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("layer.json")).unwrap())
            .unwrap();
    assert_eq!(layer["available"].as_array().unwrap().len(), 13);
    assert_eq!(
        layer["extensions"],
        serde_json::json!(["octvertexnormals", "watermask", "metadata"])
    );
}

#[test]
fn two_tile_mosaic_small_bounds_and_seams() {
    let Some(data) = cota_fixtures::shared_data() else {
        return;
    };
    let g = load(&[
        data.join("srtm/N00E010.hgt"),
        data.join("srtm/N00E011.hgt.zip"),
    ]);
    // Zooms 8 to 11 (the lattice one zoom short of the data's 12: a quarter
    // of the samples, every tile border and the files' seam still there).
    let lat = Lattice::resample(&g, &LatticeOptions::DEFAULT.with_max_zoom(Some(11))).unwrap();
    let opts = TilerOptions::DEFAULT
        .with_min_zoom(8)
        .with_error(ErrorSchedule::AtMaxZoom { max_error_m: 2.0 });
    let prep = Prepared::new(&lat, &g, &opts).unwrap();
    let out = tempfile::tempdir().unwrap();
    write_pyramid(&prep, out.path(), &PyramidOptions::DEFAULT, None, &|_| {}).unwrap();
    let tiles = decode_all(&prep, out.path());
    let (borders, _) = assert_no_seams(&tiles);
    assert!(borders > 700, "{borders}");
}

#[test]
fn unchecked_tiles_are_the_checked_tiles() {
    let g = load(&[cota_fixtures::fixture("S29W072.hgt.zip")]);
    let lat = Lattice::resample(&g, &LatticeOptions::DEFAULT.with_max_zoom(Some(7))).unwrap();
    let prep = Prepared::new(&lat, &g, &TilerOptions::DEFAULT).unwrap();
    let opts = PyramidOptions::DEFAULT.with_gzip(true);
    for t in prep.tiles() {
        let checked = make_tile(&prep, t, &opts, None).unwrap();
        let fast = make_tile(&prep, t, &opts.with_check(false), None).unwrap();
        assert_eq!(checked.bytes, fast.bytes, "{t}");
        assert_eq!(
            (checked.triangles, checked.vertices),
            (fast.triangles, fast.vertices),
            "{t}"
        );
        assert!(checked.measured_error_m <= checked.max_error_m && fast.measured_error_m.is_nan());
    }
}

#[test]
fn resume_skips_force_redoes_and_changed_settings_are_refused() {
    let g = load(&[cota_fixtures::fixture("S29W072.hgt.zip")]);
    let lat = Lattice::resample(&g, &LatticeOptions::DEFAULT.with_max_zoom(Some(8))).unwrap();
    let prep = Prepared::new(&lat, &g, &TilerOptions::DEFAULT).unwrap();
    let out = tempfile::tempdir().unwrap();
    let first = write_pyramid(&prep, out.path(), &PyramidOptions::DEFAULT, None, &|_| {}).unwrap();
    let victim = tile_path(out.path(), prep.tiles().last().unwrap());
    std::fs::remove_file(&victim).unwrap();
    let again = write_pyramid(&prep, out.path(), &PyramidOptions::DEFAULT, None, &|_| {}).unwrap();
    assert_eq!((again.written(), again.skipped()), (1, first.written() - 1));
    assert!(victim.is_file());
    let forced = PyramidOptions::DEFAULT.with_force(true);
    assert_eq!(
        write_pyramid(&prep, out.path(), &forced, None, &|_| {})
            .unwrap()
            .written(),
        first.written()
    );
    let gz = PyramidOptions::DEFAULT.with_gzip(true);
    let err = write_pyramid(&prep, out.path(), &gz, None, &|_| {}).unwrap_err();
    assert!(matches!(err, PyramidError::Changed { .. }), "{err}");
    assert!(err.to_string().contains("--force"));
    // No temporary file is left behind.
    let stray = walk(out.path())
        .into_iter()
        .filter(|p| p.ends_with(".tmp"))
        .count();
    assert_eq!(stray, 0);
}

#[test]
fn an_interrupted_directory_run_redoes_the_tiles_its_journal_left_unfinished() {
    let g = load(&[cota_fixtures::fixture("S29W072.hgt.zip")]);
    let lat = Lattice::resample(&g, &LatticeOptions::DEFAULT.with_max_zoom(Some(8))).unwrap();
    let prep = Prepared::new(&lat, &g, &TilerOptions::DEFAULT).unwrap();
    let out = tempfile::tempdir().unwrap();
    let first = write_pyramid(&prep, out.path(), &PyramidOptions::DEFAULT, None, &|_| {}).unwrap();
    let journals = out.path().join(JOURNAL_DIR);
    assert!(!journals.exists(), "a run that ended leaves no journal");
    let tiles: Vec<TileId> = prep.tiles().collect();
    let (cut, whole) = (tiles[tiles.len() - 1], tiles[tiles.len() - 2]);
    let good = std::fs::read(tile_path(out.path(), cut)).unwrap();
    let whole_before = std::fs::metadata(tile_path(out.path(), whole))
        .unwrap()
        .modified()
        .unwrap();
    // As a killed run leaves it: `cut` begun and half written, `whole` ended;
    // and another shard's journal with a tile outside this run's set.
    std::fs::write(tile_path(out.path(), cut), &good[..good.len() / 2]).unwrap();
    std::fs::create_dir_all(&journals).unwrap();
    let line = |k: char, t: TileId| format!("{k} {} {} {}\n", t.z, t.x, t.y);
    let killed = [
        line('b', whole),
        line('b', cut),
        line('e', whole),
        "b 9 1".into(),
    ]
    .concat();
    std::fs::write(journals.join("1-1.log"), killed).unwrap();
    std::fs::write(journals.join("2-2.log"), "b 20 0 0\n").unwrap();
    let again = write_pyramid(&prep, out.path(), &PyramidOptions::DEFAULT, None, &|_| {}).unwrap();
    assert_eq!((again.written(), again.skipped()), (1, first.written() - 1));
    assert_eq!(
        std::fs::read(tile_path(out.path(), cut)).unwrap(),
        good,
        "made again whole"
    );
    let whole_after = std::fs::metadata(tile_path(out.path(), whole))
        .unwrap()
        .modified()
        .unwrap();
    assert_eq!(whole_before, whole_after, "an ended tile is kept");
    assert!(
        !journals.join("1-1.log").exists(),
        "the journal it made good is removed"
    );
    assert!(
        journals.join("2-2.log").exists(),
        "another set's journal is kept"
    );
}

/// Every file under `dir`, as displayed paths.
pub(crate) fn walk(dir: &Path) -> Vec<String> {
    let mut v = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            v.extend(walk(&p));
        } else {
            v.push(p.display().to_string());
        }
    }
    v
}

#[test]
fn unwritable_output_names_the_path() {
    let g = load(&[cota_fixtures::fixture("S29W072.hgt.zip")]);
    let lat = Lattice::resample(&g, &LatticeOptions::DEFAULT.with_max_zoom(Some(6))).unwrap();
    let prep = Prepared::new(&lat, &g, &TilerOptions::DEFAULT).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("not-a-dir");
    std::fs::write(&file, b"x").unwrap();
    let err = write_pyramid(&prep, &file, &PyramidOptions::DEFAULT, None, &|_| {}).unwrap_err();
    assert!(err.to_string().contains("not-a-dir"), "{err}");
}

/// A full-resolution mesh of an `n × n` cell frame.
fn full_mesh(n: u32) -> Mesh {
    let vertices = (0..=n)
        .flat_map(|r| {
            (0..=n).map(move |c| MeshVertex {
                col: c,
                row: r,
                z_m: (c + r) as f32,
            })
        })
        .collect();
    let id = |c: u32, r: u32| r * (n + 1) + c;
    let triangles = (0..n)
        .flat_map(|r| {
            (0..n).flat_map(move |c| {
                [
                    [id(c, r), id(c, r + 1), id(c + 1, r)],
                    [id(c + 1, r), id(c, r + 1), id(c + 1, r + 1)],
                ]
            })
        })
        .collect();
    Mesh {
        vertices,
        triangles,
    }
}

#[test]
fn indices_are_16_bit_up_to_65536_vertices_and_32_bit_above() {
    for (n, wide) in [(255u32, false), (256, true)] {
        // (n + 1)² vertices: 65 536 and 66 049.
        let mesh = full_mesh(n);
        let frame = TileFrame {
            cells: [u64::from(n); 2],
            rect_deg: [10.0, 0.0, 10.1, 0.1],
        };
        let bytes = encode(&mesh, &frame, &Extensions::default()).unwrap();
        let d = decode(&bytes).unwrap();
        assert_eq!(d.wide_indices, wide, "n = {n}");
        assert_eq!(d.u.len(), mesh.vertices.len());
        assert_eq!(d.triangles.len(), mesh.triangles.len());
        // First-use order: the first triangle's vertices are 0, 1, 2.
        assert_eq!(d.triangles[0], [0, 1, 2]);
        assert!(edge_lists_match(&d));
        let region_grid = HeightGrid::new(
            n as usize + 1,
            n as usize + 1,
            mesh.vertices.iter().map(|v| v.z_m).collect(),
            cota_core::GeoRef::unreferenced(1.0),
        )
        .unwrap();
        let region = cota_core::mesh::check::Region {
            grid: &region_grid,
            origin: [0, 0],
            size: [u64::from(n) + 1; 2],
            background_m: 0.0,
        };
        // Heights over a 2n m range move by half a step, vertices by
        // n / 65534 cells on each axis over a slope of 1 m per cell on each:
        // the margin of `cota_core::tiles::plan`, 2n/65534 + 2·2·n/65534.
        let bound = 6.0 * f64::from(n) / 65534.0 + 1e-9;
        let rep = check_placed_mesh(&region, &d.to_placed(u64::from(n)), Some(bound)).unwrap();
        assert!(rep.metrics.max_error_m > 0.0);
    }
}

#[test]
fn truncated_and_corrupt_tiles_give_errors() {
    let mesh = full_mesh(4);
    let frame = TileFrame {
        cells: [4, 4],
        rect_deg: [0.0, 0.0, 1.0, 1.0],
    };
    let bytes = encode(&mesh, &frame, &Extensions::default()).unwrap();
    for cut in [0, 10, 88, 95, bytes.len() - 1] {
        assert!(decode(&bytes[..cut]).is_err(), "cut at {cut}");
    }
    let mut bad = bytes.clone();
    bad[88..92].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(decode(&bad).is_err());
    assert!(decode(&[0x1f, 0x8b, 0, 1, 2]).is_err());
}

#[test]
fn header_spheres_hold_the_vertices() {
    let g = load(&[cota_fixtures::fixture("S29W072.hgt.zip")]);
    let lat = Lattice::resample(&g, &LatticeOptions::DEFAULT.with_max_zoom(Some(9))).unwrap();
    let prep = Prepared::new(&lat, &g, &TilerOptions::DEFAULT).unwrap();
    for t in prep.tiles() {
        let tile = prep.cut(t, false, false).unwrap();
        let bytes = cota_tiles::encode_tile(&tile, &TileExtensions::NONE).unwrap();
        let d = decode(&bytes).unwrap();
        let [w, s, e, n] = tile.rect_deg;
        let h = d.header;
        for i in 0..d.u.len() {
            let lon = w + f64::from(d.u[i]) / 32767.0 * (e - w);
            let lat = s + f64::from(d.v[i]) / 32767.0 * (n - s);
            let p = cota_tiles::ellipsoid::ecef(lon, lat, d.height_m(i));
            let r = (0..3)
                .map(|k| (p[k] - h.sphere_center[k]).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(r <= h.sphere_radius_m * (1.0 + 1e-9) + 1e-6, "{t}");
        }
        assert!(h.min_height_m <= h.max_height_m);
        // Root tiles have no horizon occlusion point (NaN: never occluded).
        assert_eq!(t.z == 0, h.horizon_occlusion_point[0].is_nan(), "{t}");
    }
}
