//! The full-resolution mesh's strips (the mesh itself is crate-private):
//! moved from `tests/strip.rs` with their assertions.
#![allow(clippy::unwrap_used, reason = "tests")]

use super::*;
use crate::mesh::check::{check_mesh, CheckOptions};
use crate::{Bitree, ExtractOptions, GeoRef, HeightGrid};

/// The strip has exactly the mesh's triangles, same orientation, each once.
fn assert_same_triangles(mesh: &Mesh, strip: &Strip) {
    let valid = strip.validate(mesh);
    assert!(
        valid.is_ok(),
        "strip triangles differ from the mesh's: {valid:?}"
    );
    assert_eq!(strip.triangles, mesh.triangles.len());
    assert_eq!(strip.triangles + strip.degenerate + 2, strip.indices.len());
}

/// Every non-degenerate triangle of the strip, drawn with the strip's parity,
/// is counter-clockwise seen from above; degenerate windows repeat an index.
fn assert_winding(mesh: &Mesh, strip: &Strip) {
    for (k, w) in strip.indices.windows(3).enumerate() {
        if w[0] == w[1] || w[1] == w[2] || w[0] == w[2] {
            continue;
        }
        let t = if k % 2 == 0 {
            [w[0], w[1], w[2]]
        } else {
            [w[1], w[0], w[2]]
        };
        assert!(
            mesh.signed_area2(t) > 0,
            "window {k} {t:?} is not counter-clockwise"
        );
    }
}

/// The cells strip: its own mesh (same vertices, cells flipped) holds
/// exactly its triangles, faces up, and passes `check`.
fn assert_cells(grid: &HeightGrid, mesh: &Mesh, c: &MeshStrip<'_>, check: &CheckOptions) {
    assert_eq!(c.method, StripMethod::Cells);
    assert_eq!(c.mesh.vertices, mesh.vertices);
    assert_eq!(c.mesh.triangles.len(), mesh.triangles.len());
    assert_eq!(c.retriangulated(), c.flipped_cells > 0);
    assert_same_triangles(&c.mesh, &c.strip);
    assert_winding(&c.mesh, &c.strip);
    let before = check_mesh(grid, mesh, check).unwrap().metrics;
    let after = check_mesh(grid, &c.mesh, check).unwrap().metrics;
    // Exact: no sample inside a unit cell, so every sample's error is kept.
    assert_eq!(before.max_error_m, after.max_error_m);
    assert_eq!(before.sse_m2, after.sse_m2);
}

/// The full-resolution mesh of the real tile (every sample a vertex, with
/// its height): the cells strip needs about (2W+1)/(2W−2) references per
/// triangle, and its mesh has zero error.
#[test]
fn full_real_grid_cells() {
    // Unreferenced 1 m cells: the assertions look at samples and heights only.
    let g = crate::testing::fixture("S29W072.hgt.zip");
    let (w, h) = (g.width() as u32, g.height() as u32);
    let mut mesh = full_bitree_mesh(w, h);
    for v in &mut mesh.vertices {
        v.z_m = g.get(v.col as usize, v.row as usize);
    }
    let c = stripify_bitree(&mesh).unwrap();
    let tris = 2 * (w as usize - 1) * (h as usize - 1);
    assert_eq!(c.strip.triangles, tris);
    // Every unit cell of the "4-8" pattern is flipped in every other row.
    assert!(c.flipped_cells >= tris / 4, "{}", c.flipped_cells);
    assert_cells(&g, &mesh, &c, &CheckOptions::conforming(0.0));
    // One row strip of 2W references per row of cells, and one more per row
    // join (a repeated index fixing the parity).
    assert_eq!(c.strip.refs(), (h as usize - 1) * (2 * w as usize + 1) - 1);
    assert!(c.strip.refs_per_triangle() <= 1.05);
}

/// A rough `w × h` grid: E = 0 keeps (nearly) every unit triangle.
fn rough(w: usize, h: usize) -> HeightGrid {
    let heights: Vec<f32> = (0..w * h)
        .map(|i| {
            let mut x = i as u64 + 0x9E37_79B9_7F4A_7C15;
            x ^= x >> 31;
            x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
            x ^= x >> 29;
            (x % 100_000) as f32 * 0.01
        })
        .collect();
    HeightGrid::new(w, h, heights, GeoRef::unreferenced(30.0)).unwrap()
}

/// On a mesh large enough for neighbours more than 2^15 apart in the
/// order (kept in the map), the matched adjacency is the rows'.
#[test]
fn far_neighbours_are_the_rows() {
    let order = traversal::bitree_order(&full_bitree_mesh(257, 257)).unwrap();
    assert_eq!(guided::matched_is_rows(&order), Some(true));
}

#[test]
fn full_mesh_helper_matches_extraction() {
    let (w, h) = (129, 97);
    let g = rough(w, h);
    let mut got = full_bitree_mesh(w as u32, h as u32).triangles;
    let mut want = Bitree::build(&g)
        .unwrap()
        .extract(&ExtractOptions::max_error_m(0.0))
        .unwrap()
        .mesh
        .triangles;
    got.sort_unstable();
    want.sort_unstable();
    assert_eq!(got, want);
}

/// The counting paths (`bitree_strip_refs`, `quadtree_strip_refs`: the mesh
/// consumed, triangles reordered in place, the strip never written) give
/// the references of the strips themselves, for every method, on full,
/// adaptive and fictitious (faithful: hanging vertices) bitree meshes and on
/// restricted-quadtree meshes of the real tile's windows.
#[test]
fn counted_references_are_the_strips_own() {
    use crate::criteria::MaxVerticalError;
    use crate::mesher::{HierarchyKind, MeshPlan, Mesher};
    use crate::quadtree::QuadOptions;
    let tile = crate::testing::fixture("S29W072.hgt.zip");
    let grids = [
        rough(65, 33),
        tile.window(824, 792, 65, 65).unwrap(),
        tile.window(300, 500, 129, 100).unwrap(),
    ];
    let methods = [
        StripMethod::Traversal,
        StripMethod::Guided,
        StripMethod::Cells,
    ];
    for g in &grids {
        let mesher = Mesher::new(g);
        let mut meshes = vec![full_bitree_mesh(g.width() as u32, g.height() as u32)];
        for e in [0.0, 2.0, 20.0] {
            let crit = MaxVerticalError { max_error_m: e };
            for mode in crate::refine::Mode::ALL {
                let plan = MeshPlan::new(&crit)
                    .with_mode(mode)
                    .with_extend_odd_spans(false);
                meshes.push(mesher.mesh(&plan).unwrap().mesh);
            }
        }
        for m in &meshes {
            // The keyed order and the matched adjacency are the traversal's
            // and the compressed rows'.
            let ids = traversal::bitree_order_ids(m).unwrap();
            let keyed = traversal::order_by_keys(m.vertices.len(), &m.triangles, |i| {
                m.vertices.get(i as usize).map(|v| [v.col, v.row])
            });
            assert_eq!(keyed.as_ref(), Some(&ids));
            let order: Vec<[u32; 3]> = ids.iter().map(|&k| m.triangles[k as usize]).collect();
            assert_eq!(guided::matched_is_rows(&order), Some(true));
            for method in methods {
                let want = stripify_bitree_with(m, method).unwrap().strip.refs();
                assert_eq!(bitree_strip_refs(m.clone(), method).unwrap(), want);
            }
            assert_eq!(quadtree_strip_refs(m.clone()), stripify_quadtree(m).refs());
        }
        for q in [
            QuadOptions::DEFAULT,
            QuadOptions::DEFAULT.with_centre_when_needed(true),
        ] {
            for e in [0.0, 5.0] {
                let crit = MaxVerticalError { max_error_m: e };
                let plan = MeshPlan::new(&crit).with_hierarchy(HierarchyKind::Quadtree(q));
                let m = mesher.mesh(&plan).unwrap().mesh;
                assert_eq!(guided::matched_is_rows(&m.triangles), Some(true));
                assert_eq!(quadtree_strip_refs(m.clone()), stripify_quadtree(&m).refs());
            }
        }
    }
    // A mesh that is not the bitree's: refused alike.
    let mut bad = full_bitree_mesh(9, 9);
    bad.triangles[0] = [0, 1, 20];
    assert!(bitree_strip_refs(bad.clone(), StripMethod::Guided).is_err());
    assert!(stripify_bitree_with(&bad, StripMethod::Guided).is_err());
    let keyed = |m: &Mesh| {
        traversal::order_by_keys(m.vertices.len(), &m.triangles, |i| {
            m.vertices.get(i as usize).map(|v| [v.col, v.row])
        })
    };
    assert_eq!(keyed(&bad), None);
    // A triangle twice, and one inside another: the traversal's answer.
    let mut twice = full_bitree_mesh(9, 9);
    twice.triangles.push(twice.triangles[5]);
    assert_eq!(keyed(&twice), None);
    assert!(bitree_strip_refs(twice.clone(), StripMethod::Guided).is_err());
    assert_eq!(guided::matched_is_rows(&twice.triangles), None);
    // A directed edge held twice: the rows strip it.
    let mut order = traversal::bitree_order(&full_bitree_mesh(9, 9)).unwrap();
    order.push(order[3]);
    let refs = guided_refs(&order);
    assert_eq!(refs, stripify_guided(&order).refs());
    assert!(refs > 0);
}
