//! Voids as holes (`cota_core::mesh::holes`) on real tiles: the mesh leaves
//! out every triangle that touches a void, the bound holds at every valid
//! sample, and the one checker (`check_mesh` with `CheckOptions::holes`)
//! proves it; the checker also rejects what a hole mesh must not be.

#![allow(clippy::unwrap_used, clippy::panic, reason = "tests fail loudly")]

use crate::common;

use cota_core::criteria::AvoidVoids;
use cota_core::mesh::check::Violation;
use cota_core::mesh::holes::{cut_holes, fill_flat, HoleReport, VoidMask};
use cota_core::{check_mesh, CheckOptions, HeightGrid, MaxVerticalError, Mesh, MeshPlan, Mesher};

/// The hole mesh of `voided` at `e` metres, and the uncut mesh.
fn hole_mesh(voided: &HeightGrid, e: f64) -> (Mesh, Mesh, HoleReport) {
    let mask = VoidMask::new(voided);
    let mut filled = voided.clone();
    assert!(fill_flat(&mut filled) > 0);
    let inner = MaxVerticalError::new(e).unwrap();
    let crit = AvoidVoids {
        inner: &inner,
        voids: &mask,
    };
    let uncut = Mesher::new(&filled)
        .mesh(&MeshPlan::new(&crit))
        .unwrap()
        .mesh;
    let (mesh, report) = cut_holes(&uncut, &mask);
    (mesh, uncut, report)
}

/// A 257² window of the bundled real tile (SRTM 3", Andes) with its own
/// voids, plus a blanked disc and its north-west corner blanked.
fn void_heavy() -> HeightGrid {
    let s = cota_fixtures::bundled_tile();
    let mut g = common::grid(s.crop(850, 600, 257, 257));
    let w = g.width();
    for r in 0..257 {
        for c in 0..257 {
            let (x, y) = (c as f64 - 150.0, r as f64 - 170.0);
            if x * x + y * y < 40.0 * 40.0 || (r < 60 && c < 90) || (r + c) % 97 == 0 {
                g.heights_mut()[r * w + c] = f32::NAN;
            }
        }
    }
    g
}

#[test]
fn a_void_heavy_tile_meshes_with_holes_and_passes_the_checker() {
    let g = void_heavy();
    let voids = g.void_count();
    assert!(voids > 10_000, "{voids}");
    for e in [0.0, 2.0, 20.0] {
        let (mesh, _, report) = hole_mesh(&g, e);
        let opts = CheckOptions::conforming(e).with_holes(true);
        let r = check_mesh(&g, &mesh, &opts).unwrap_or_else(|err| panic!("E = {e}: {err}"));
        assert!(r.metrics.max_error_m <= e + 1e-9);
        assert!(report.triangles_left_out > 0 && report.cells_left_out >= voids as f64 / 2.0);
        for v in &mesh.vertices {
            assert!(!g.get(v.col as usize, v.row as usize).is_nan());
        }
        println!(
            "E = {e} m: {} triangles, {} left out, {:.0} cells left out",
            mesh.triangle_count(),
            report.triangles_left_out,
            report.cells_left_out
        );
    }
}

#[test]
fn the_checker_rejects_what_a_hole_mesh_must_not_be() {
    let g = void_heavy();
    let (mesh, uncut, _) = hole_mesh(&g, 5.0);
    let opts = CheckOptions::conforming(5.0).with_holes(true);
    // The uncut mesh has vertices on voids.
    let err = check_mesh(&g, &uncut, &opts).unwrap_err();
    assert!(
        matches!(err.violations[0], Violation::VertexOnVoid { .. }),
        "{err}"
    );
    // A triangle far from any void removed: an open edge, or a cell left bare.
    let mask = VoidMask::new(&g);
    let far = mesh
        .triangles
        .iter()
        .position(|t| {
            t.iter().all(|&i| {
                let v = mesh.vertices[i as usize];
                let (x, y) = (v.col as usize, v.row as usize);
                mask.count(x.saturating_sub(3), y.saturating_sub(3), x + 3, y + 3) == 0
                    && x > 0
                    && y > 0
                    && x + 1 < g.width()
                    && y + 1 < g.height()
            })
        })
        .unwrap();
    let mut broken = mesh.clone();
    broken.triangles.remove(far);
    let err = check_mesh(&g, &broken, &opts).unwrap_err();
    assert!(
        err.violations.iter().any(|v| matches!(
            v,
            Violation::OpenEdge { .. } | Violation::UncoveredCells { .. }
        )),
        "{err}"
    );
    // A big triangle over a void (made of valid corners): touches the void.
    let mut over = mesh.clone();
    let corner = |c: u32, r: u32| {
        over.vertices
            .iter()
            .position(|v| v.col == c && v.row == r)
            .map(|i| i as u32)
    };
    if let (Some(a), Some(b), Some(c)) = (corner(0, 256), corner(256, 256), corner(0, 0)) {
        over.triangles = vec![[a, b, c]];
        let err = check_mesh(&g, &over, &opts).unwrap_err();
        assert!(
            err.violations
                .iter()
                .any(|v| matches!(v, Violation::TriangleOnVoid { .. })),
            "{err}"
        );
    }
    // Without holes, the same cut mesh fails the whole-rectangle coverage.
    assert!(check_mesh(&g, &mesh, &CheckOptions::conforming(5.0)).is_err());
}

#[test]
fn a_shared_tile_with_its_own_voids() {
    let Some(g) = common::shared_srtm("N42E001.hgt.zip") else {
        return;
    };
    let voids = g.void_count();
    assert!(voids > 5_000, "{voids}");
    let (mesh, _, report) = hole_mesh(&g, 20.0);
    let opts = CheckOptions::conforming(20.0).with_holes(true);
    check_mesh(&g, &mesh, &opts).unwrap();
    assert!(report.triangles_left_out > 0);
}
