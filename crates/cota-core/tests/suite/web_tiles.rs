//! Web-tile sizes (an odd span `W − 1`, such as 256 or 512 samples) meshed
//! on their clamp-extended grid and clipped back (`grid::extend`,
//! `mesh::clip`): flat grids mesh to a handful of triangles, real windows to
//! far fewer than with a unit-resolution border, and the one checker proves
//! every mesh (coverage of the real rectangle, no T-junction, the bound at
//! every real sample).

#![allow(clippy::unwrap_used, clippy::panic, reason = "tests fail loudly")]

use crate::common;

use cota_core::{
    check_mesh, Bitree, ExtractOptions, GeoRef, HeightGrid, MaxVerticalError, MeshPlan, Meshed,
    Mesher,
};

fn mesh(grid: &HeightGrid, e: f64, extend: bool) -> Meshed {
    let c = MaxVerticalError::new(e).unwrap();
    let m = Mesher::new(grid)
        .mesh(&MeshPlan::new(&c).with_extend_odd_spans(extend))
        .unwrap();
    check_mesh(grid, &m.mesh, &m.check)
        .unwrap_or_else(|err| panic!("{}x{} at {e} m: {err}", grid.width(), grid.height()));
    m
}

fn flat(w: usize, h: usize, z: f32) -> HeightGrid {
    HeightGrid::new(w, h, vec![z; w * h], GeoRef::unreferenced(30.0)).unwrap()
}

#[test]
fn flat_web_tiles_need_a_handful_of_triangles() {
    for (w, h) in [(512, 512), (256, 256), (512, 300), (300, 512), (1024, 1024)] {
        let g = flat(w, h, 1234.5);
        for e in [0.0, 0.01, 1.0, 10.0, 1000.0] {
            let n = mesh(&g, e, true).mesh.triangle_count();
            assert!(n <= 8, "{w}x{h} flat at {e} m: {n} triangles");
        }
        // The unit-resolution border of the grid's own hierarchy.
        let (old, new) = (mesh(&g, 1.0, false), mesh(&g, 1.0, true));
        let (old, new) = (old.mesh.triangle_count(), new.mesh.triangle_count());
        eprintln!("flat {w}x{h}: {old} -> {new} triangles");
        assert!(old > 500);
    }
}

#[test]
fn tilted_plane_stays_lean() {
    let (w, h) = (512, 512);
    let heights = (0..w * h)
        .map(|i| 100.0 + 0.25 * (i % w) as f32 - 0.5 * (i / w) as f32)
        .collect();
    let g = HeightGrid::new(w, h, heights, GeoRef::unreferenced(30.0)).unwrap();
    // The repeated column bends the plane by one step: 0.25 m.
    let n = mesh(&g, 0.5, true).mesh.triangle_count();
    assert!(n <= 8, "{n}");
}

#[test]
fn real_web_tile_windows_are_leaner_and_checked() {
    let tile = common::tile();
    for (col, row, w, h) in [
        (600, 600, 512, 512),
        (100, 100, 256, 256),
        (600, 300, 512, 300),
    ] {
        let g = HeightGrid::new(
            w,
            h,
            cota_fixtures::crop(tile.heights(), tile.width(), col, row, w, h),
            GeoRef::unreferenced(90.0),
        )
        .unwrap();
        for e in [1.0, 5.0, 20.0] {
            let new = mesh(&g, e, true).mesh.triangle_count();
            let old = mesh(&g, e, false).mesh.triangle_count();
            eprintln!("{w}x{h} at ({col}, {row}), {e} m: {old} -> {new} triangles");
            assert!(new < old, "{w}x{h} at {e} m: {new} vs {old}");
        }
    }
}

#[test]
fn odd_spans_of_any_shape_pass_the_checker() {
    for (w, h, seed) in [
        (40, 33, 1),
        (64, 50, 2),
        (100, 77, 3),
        (2, 9, 4),
        (130, 3, 5),
    ] {
        let g = HeightGrid::new(
            w,
            h,
            cota_fixtures::rough_terrain(w, h, seed),
            GeoRef::unreferenced(10.0),
        )
        .unwrap();
        for e in [0.0, 0.5, 3.0, 50.0] {
            mesh(&g, e, true);
        }
    }
}

#[test]
fn two_to_the_k_plus_one_grids_unchanged() {
    let tile = common::tile();
    let g = HeightGrid::new(
        513,
        257,
        cota_fixtures::crop(tile.heights(), tile.width(), 300, 200, 513, 257),
        GeoRef::unreferenced(90.0),
    )
    .unwrap();
    let tree = Bitree::build(&g).unwrap();
    for e in [0.5, 5.0] {
        let want = tree.extract(&ExtractOptions::max_error_m(e)).unwrap().mesh;
        assert_eq!(mesh(&g, e, true).mesh, want);
    }
}

#[test]
fn checker_rejects_what_clipping_must_not_do() {
    use cota_core::mesh::check::Violation;
    let tile = common::tile();
    let (w, h) = (256, 256);
    let g = HeightGrid::new(
        w,
        h,
        cota_fixtures::crop(tile.heights(), tile.width(), 600, 600, w, h),
        GeoRef::unreferenced(90.0),
    )
    .unwrap();
    let m = mesh(&g, 10.0, true);
    assert_eq!(m.extended_to, Some([257, 257]));
    assert!(m.check.clipped_border);
    // Without the option, the border's interpolated heights are wrong heights.
    let strict = m.check.with_clipped_border(false);
    let err = check_mesh(&g, &m.mesh, &strict).unwrap_err();
    assert!(err
        .violations
        .iter()
        .any(|v| matches!(v, Violation::WrongHeight { .. })));
    // A border vertex moved past the bound breaks check 5.
    let mut bad = m.mesh.clone();
    let k = bad
        .vertices
        .iter()
        .position(|v| v.col as usize == w - 1 && v.row > 0 && (v.row as usize) < h - 1)
        .unwrap();
    bad.vertices[k].z_m += 25.0;
    let err = check_mesh(&g, &bad, &m.check).unwrap_err();
    assert!(err
        .violations
        .iter()
        .any(|v| matches!(v, Violation::ErrorBound { .. })));
    // A piece of a cut triangle left out leaves a hole.
    let mut holed = m.mesh.clone();
    holed.triangles.pop();
    assert!(check_mesh(&g, &holed, &m.check).is_err());
}
