//! 3D Tiles terrain pyramids on a real DEM (issue 30): every GLB decodes with
//! the independent decoder into the quantized-mesh tile's triangles, drawn
//! within its zoom's bound (plus float32's rounding) at every source sample;
//! the subtrees mark exactly the tiles written; a resumed run skips them and
//! rebuilds the same subtrees and tileset.
#![allow(clippy::unwrap_used, clippy::panic)]

#[path = "tiles3d_meshopt.rs"]
mod meshopt;

use std::collections::HashSet;

use cota_core::tiles::{Lattice, LatticeOptions, Prepared, TileId, TilerOptions};
use cota_core::{fill_voids, FillOptions, LonLat};
use cota_io::{read_dem, ReadOptions};
use cota_tiles::drawn::{check_samples, Against, DrawnTile, SourceGrid};
use cota_tiles::ellipsoid::geodetic;
use cota_tiles::glb_decode::{decode_glb, same_triangles, DecodedGlb};
use cota_tiles::glb_tile::{float32_budget_m, u16_budget_m, SKIRT_LEVELS};
use cota_tiles::pyramid3d::skirt_depth;
use cota_tiles::tileset3d::glb_rel_path;
use cota_tiles::{
    decode, make_glb_tile, make_tile, write_tiles3d, PyramidError, PyramidOptions, TileExtensions,
    TileFormat,
};

fn opts() -> PyramidOptions {
    PyramidOptions::DEFAULT
        .with_format(TileFormat::Tiles3d)
        .with_extensions(TileExtensions::with(true, false, false))
}

fn meshopt_opts() -> PyramidOptions {
    opts().with_meshopt(true)
}

/// The subtree file's JSON and availability bits.
fn subtree(bytes: &[u8]) -> (serde_json::Value, Vec<u8>) {
    assert_eq!(&bytes[..4], b"subt");
    let n = u64::from_le_bytes(bytes[8..16].try_into().unwrap()) as usize;
    let doc: serde_json::Value = serde_json::from_slice(&bytes[24..24 + n]).unwrap();
    (doc, bytes[24 + n..].to_vec())
}

#[test]
fn fixture_pyramid_as_glb_within_bounds_and_resumable() {
    pyramid_within_bounds_and_resumable(opts());
}

/// The same with `KHR_mesh_quantization` and `EXT_meshopt_compression`:
/// the dequantised positions within the bound plus the u16 budget.
#[test]
fn fixture_pyramid_as_meshopt_glb_within_bounds_and_resumable() {
    pyramid_within_bounds_and_resumable(meshopt_opts());
}

fn pyramid_within_bounds_and_resumable(opts: PyramidOptions) {
    let mut g = read_dem(
        &cota_fixtures::fixture("S29W072.hgt.zip"),
        &ReadOptions::DEFAULT,
    )
    .unwrap()
    .grid;
    fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
    let lat = Lattice::resample(&g, &LatticeOptions::DEFAULT.with_max_zoom(Some(10))).unwrap();
    let prep = Prepared::new(&lat, &g, &TilerOptions::DEFAULT).unwrap();
    let rect = [-72.0, -29.0, -71.0, -28.0];
    let grid = SourceGrid {
        grid: &g,
        transform: &LonLat,
    };
    let against = Against::new(vec![grid], vec![rect], 0.5);
    let out = tempfile::tempdir().unwrap();
    let report = write_tiles3d(&prep, out.path(), &opts, Some(&against), &|_| {}).unwrap();
    let fills: Vec<TileId> = prep.fills().collect();
    let written = prep.tile_count() + fills.len() as u64;
    assert_eq!(report.written(), written);
    assert_eq!(report.fill(), fills.len() as u64);
    fills_complete_the_tree(&prep, out.path(), &fills, &against);
    let mut worst = 0.0f64;
    for t in prep.tiles() {
        let bytes = std::fs::read(out.path().join(glb_rel_path(t))).unwrap();
        let glb = decode_glb(&bytes).unwrap();
        // The same tile as quantized-mesh, decoded: same triangles, same vertices.
        let qm = make_tile(&prep, t, &PyramidOptions::DEFAULT.with_check(false), None).unwrap();
        let d = decode(&qm.bytes).unwrap();
        assert!(same_triangles(&glb.triangles, &d.triangles), "{t}");
        if opts.meshopt {
            assert!(glb.quantized_scale.is_some(), "{t}");
        } else {
            assert_eq!(glb.triangles, d.triangles, "{t}");
        }
        assert!(glb
            .normals
            .as_ref()
            .is_some_and(|n| n.len() == glb.positions.len()));
        let z = prep.zoom(t.z).unwrap();
        let r = d.header.sphere_radius_m + 1e3;
        let rect = prep.lattice().scheme().tile_rect_deg(t);
        let drawn = DrawnTile::new(&d, rect).with_positions(&glb.positions);
        let got = check_samples(&drawn, &against.samples).max_error_m;
        let budget = glb
            .quantized_scale
            .map_or(float32_budget_m(r), u16_budget_m);
        let bound = prep.source_bound_m(t.z) + budget;
        assert!(
            got <= bound + 1e-6,
            "{t}: {got} m as drawn, bound {bound} m"
        );
        worst = worst.max(got / z.max_error_m);
        skirt_hangs_outwards(&glb, &prep, t, budget);
    }
    eprintln!("worst error as drawn / e_z over the GLB tiles: {worst:.3}");
    // The subtrees mark exactly the tiles written: count them.
    let tileset: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.path().join("tileset.json")).unwrap()).unwrap();
    assert_eq!(tileset["root"]["children"].as_array().unwrap().len(), 2);
    let levels = tileset["root"]["children"][0]["implicitTiling"]["subtreeLevels"]
        .as_u64()
        .unwrap();
    assert_eq!(levels, 6, "zooms 0-10 in two layers of subtrees");
    let mut marked = 0;
    for root in 0..2 {
        let dir = out.path().join(format!("{root}/subtrees"));
        for e in crate::tiles::walk(&dir) {
            let (doc, _) = subtree(&std::fs::read(&e).unwrap());
            marked += doc["tileAvailability"]["availableCount"].as_u64().unwrap();
            assert_eq!(
                doc["propertyTables"][0]["count"],
                doc["tileAvailability"]["availableCount"]
            );
        }
    }
    assert_eq!(marked, written);
    // Resumed: one tile removed is made again, the rest skipped; same tileset.
    let victim = out.path().join(glb_rel_path(prep.tiles().last().unwrap()));
    std::fs::remove_file(&victim).unwrap();
    let before = std::fs::read(out.path().join("0/subtrees/0/0/0.subtree")).unwrap();
    let again = write_tiles3d(&prep, out.path(), &opts, None, &|_| {}).unwrap();
    assert_eq!((again.written(), again.skipped()), (1, written - 1));
    assert_eq!(again.fill(), fills.len() as u64);
    assert_eq!(
        std::fs::read(out.path().join("0/subtrees/0/0/0.subtree")).unwrap(),
        before
    );
    // Other settings are refused, as for quantized-mesh: no normals, or
    // the other geometry.
    let qm = PyramidOptions::DEFAULT;
    for other in [
        qm.with_format(TileFormat::Tiles3d),
        opts.with_meshopt(!opts.meshopt),
        opts.with_skirts(false),
    ] {
        let err = write_tiles3d(&prep, out.path(), &other, None, &|_| {}).unwrap_err();
        assert!(matches!(err, PyramidError::Changed { .. }), "{err}");
    }
}

/// The GLB's second primitive: every edge vertex (bit for bit the surface's)
/// and the same lowered along the ellipsoid normal by the zoom's skirt
/// depth (within the positions' budget), two triangles per edge segment,
/// each facing away from the tile's centre.
fn skirt_hangs_outwards(glb: &DecodedGlb, prep: &Prepared<'_>, t: TileId, budget: f64) {
    let (pos, tris) = glb.skirt.as_ref().expect("a skirt");
    let depth = skirt_depth(prep, t.z);
    let e = prep.zoom(t.z).unwrap().max_error_m;
    assert!(
        depth >= e * (1.0 + 2f64.powi(i32::from(SKIRT_LEVELS.min(t.z)))),
        "{t}"
    );
    let mut at = 0;
    let mut segments = 0;
    for list in &glb.edges {
        let n = list.len();
        for (k, &i) in list.iter().enumerate() {
            assert_eq!(pos[at + k], glb.positions[i as usize], "{t}: skirt top");
            let [lon, lat, h] = geodetic(pos[at + k]);
            let [lon2, lat2, h2] = geodetic(pos[at + n + k]);
            assert!(
                (h - h2 - depth).abs() <= 2.0 * budget + 1e-6,
                "{t}: {} m deep, want {depth}",
                h - h2
            );
            let east = (lon - lon2).abs() * lat.to_radians().cos();
            let moved = east.max((lat - lat2).abs()) * 111_000.0;
            assert!(
                lat.abs() > 89.0 || moved <= 2.0 * budget + 1e-3,
                "{t}: the skirt leans {moved} m"
            );
        }
        at += 2 * n;
        segments += n - 1;
    }
    assert_eq!(pos.len(), at, "{t}");
    assert_eq!(tris.len(), 2 * segments, "{t}");
    if t.z >= 2 {
        let c = glb.meta.unwrap().sphere;
        for tri in tris {
            let [a, b, d] = tri.map(|i| pos[i as usize]);
            let (u, v) = (sub(b, a), sub(d, a));
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let out = sub(a, [c[0], c[1], c[2]]);
            assert!(
                n[0] * out[0] + n[1] * out[1] + n[2] * out[2] > 0.0,
                "{t}: a skirt triangle faces inwards"
            );
        }
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Every written tile with a child has all four (REPLACE refinement draws
/// no hole); the fill tiles are GLBs on the ellipsoid (within their zoom's
/// bound of 0 m as drawn, away from the data), a few triangles each, with
/// no children, and quantized-mesh does not make them.
fn fills_complete_the_tree(
    prep: &Prepared<'_>,
    out: &std::path::Path,
    fills: &[TileId],
    against: &Against<'_>,
) {
    assert!(!fills.is_empty());
    let written: HashSet<TileId> = prep.tiles().chain(fills.iter().copied()).collect();
    let kids = |t: TileId| {
        [(0, 0), (1, 0), (0, 1), (1, 1)].map(|(dx, dy)| TileId {
            z: t.z + 1,
            x: 2 * t.x + dx,
            y: 2 * t.y + dy,
        })
    };
    for &t in &written {
        let n = kids(t).iter().filter(|c| written.contains(c)).count();
        assert!(n == 0 || n == 4, "{t}: {n} of 4 children written");
    }
    let mut far_fills = 0;
    for &f in fills {
        assert!(kids(f).iter().all(|c| !written.contains(c)), "{f}");
        assert!(make_tile(prep, f, &PyramidOptions::DEFAULT, None).is_err());
        let glb = decode_glb(&std::fs::read(out.join(glb_rel_path(f))).unwrap()).unwrap();
        assert_eq!(glb.edges.iter().filter(|e| e.len() >= 2).count(), 4, "{f}");
        let rect = prep.lattice().scheme().tile_rect_deg(f);
        // Wholly a finest tile (the ramp) or more from the data: the
        // ellipsoid, a few triangles.
        let s = prep.lattice().scheme();
        let d = 180.0 / f64::from(1u32 << s.max_zoom) + s.cell_deg();
        let far = rect[2] < -72.0 - d
            || rect[0] > -71.0 + d
            || rect[3] < -29.0 - d
            || rect[1] > -28.0 + d;
        if far {
            far_fills += 1;
            let meta = glb.meta.unwrap();
            assert_eq!((meta.min_height_m, meta.max_height_m), (0.0, 0.0), "{f}");
            assert!(
                glb.triangles.len() <= 300,
                "{f}: {} triangles",
                glb.triangles.len()
            );
        }
        // Made again with the check: as drawn within e_z (plus float32's
        // rounding) of the source's samples and of the ellipsoid.
        let (made, _) = make_glb_tile(prep, f, &opts().with_check(true), Some(against)).unwrap();
        let (bare, _) = make_glb_tile(prep, f, &opts().with_skirts(false), None).unwrap();
        assert!(decode_glb(&bare.bytes).unwrap().skirt.is_none(), "{f}");
        let bound = prep.zoom(f.z).unwrap().max_error_m + float32_budget_m(1e7);
        assert!(made.drawn_error_m <= bound, "{f}: {} m", made.drawn_error_m);
    }
    assert!(far_fills > 0, "no fill tile a finest tile from the data");
}

#[test]
fn a_pyramid_not_from_zoom_0_is_refused() {
    let mut g = read_dem(
        &cota_fixtures::fixture("S29W072.hgt.zip"),
        &ReadOptions::DEFAULT,
    )
    .unwrap()
    .grid;
    fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
    let lat = Lattice::resample(&g, &LatticeOptions::DEFAULT.with_max_zoom(Some(6))).unwrap();
    let prep = Prepared::new(&lat, &g, &TilerOptions::DEFAULT.with_min_zoom(3)).unwrap();
    let out = tempfile::tempdir().unwrap();
    let err = write_tiles3d(&prep, out.path(), &opts(), None, &|_| {}).unwrap_err();
    assert!(err.to_string().contains("--min-zoom 0"), "{err}");
}
