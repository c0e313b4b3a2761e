//! The restricted quadtree: the checker on real data at several tolerances, the
//! restriction on hand-made cases, and monotonicity in the tolerance.
#![allow(clippy::unwrap_used, reason = "tests")]

use crate::common;

use cota_core::quadtree::{QuadExtraction, QuadTree};
use cota_core::{check_mesh, CheckOptions, GeoRef, HeightGrid};

fn crop(g: &HeightGrid, c0: usize, r0: usize, w: usize, h: usize) -> HeightGrid {
    let v = cota_fixtures::crop(g.heights(), g.width(), c0, r0, w, h);
    HeightGrid::new(w, h, v, GeoRef::unreferenced(90.0)).unwrap()
}

/// Every pair of leaves sharing an edge differs by at most one level.
fn assert_restricted(g: &HeightGrid, x: &QuadExtraction) {
    let (w, h) = (g.width() - 1, g.height() - 1);
    let mut depth = vec![u32::MAX; w * h];
    for l in &x.leaves {
        for r in l.row..l.row + l.size {
            for c in l.col..l.col + l.size {
                let k = r as usize * w + c as usize;
                assert_eq!(depth[k], u32::MAX, "leaves overlap at cell {c},{r}");
                depth[k] = l.depth;
            }
        }
    }
    assert!(
        depth.iter().all(|&d| d != u32::MAX),
        "a cell is not covered"
    );
    for r in 0..h {
        for c in 0..w {
            let d = depth[r * w + c];
            if c + 1 < w {
                assert!(d.abs_diff(depth[r * w + c + 1]) <= 1, "cells {c},{r} east");
            }
            if r + 1 < h {
                assert!(
                    d.abs_diff(depth[(r + 1) * w + c]) <= 1,
                    "cells {c},{r} south"
                );
            }
        }
    }
}

fn check(g: &HeightGrid, x: &QuadExtraction, e: f64) {
    let report = check_mesh(g, &x.mesh, &CheckOptions::conforming(e)).unwrap();
    assert!(report.metrics.max_error_m <= x.max_leaf_error_m + 1e-9);
    assert_restricted(g, x);
    let p = x.points;
    assert_eq!(p.base + p.selected + p.added, p.vertices);
}

#[test]
fn fixture_tile_is_conforming_within_bound_and_restricted() {
    let g = common::tile();
    let qt = QuadTree::build(&g).unwrap();
    let mut last = usize::MAX;
    for e in [0.0, 1.0, 5.0, 20.0, 100.0] {
        let x = qt.extract_max_error_m(e).unwrap();
        check(&g, &x, e);
        assert!(x.mesh.triangle_count() <= last);
        last = x.mesh.triangle_count();
    }
}

#[test]
fn crops_of_odd_and_even_sizes_are_conforming() {
    let g = common::tile();
    for (c, r, w, h) in [
        (912, 752, 65, 65),
        (700, 900, 100, 37),
        (0, 0, 2, 9),
        (5, 5, 2, 2),
    ] {
        let sub = crop(&g, c, r, w, h);
        let qt = QuadTree::build(&sub).unwrap();
        for e in [0.0, 2.0, 30.0] {
            check(&sub, &qt.extract_max_error_m(e).unwrap(), e);
        }
    }
}

#[test]
fn shared_tiles_are_conforming() {
    for rel in ["srtm/N50E011.hgt.zip", "asc/boulder_srtmgl3_240x144.asc"] {
        let Some(p) = cota_fixtures::shared(rel) else {
            continue;
        };
        let g = common::filled(cota_fixtures::read(&p).unwrap());
        let qt = QuadTree::build(&g).unwrap();
        for e in [0.5, 10.0] {
            check(&g, &qt.extract_max_error_m(e).unwrap(), e);
        }
    }
}

#[test]
fn tighter_tolerance_gives_more_triangles_on_a_65_crop() {
    let g = common::tile();
    let sub = crop(&g, 912, 752, 65, 65);
    let qt = QuadTree::build(&sub).unwrap();
    let n: Vec<usize> = [0.0, 5.0, 20.0, 80.0]
        .iter()
        .map(|&e| qt.extract_max_error_m(e).unwrap().mesh.triangle_count())
        .collect();
    assert!(n.windows(2).all(|p| p[0] > p[1]), "{n:?}");
}

/// A flat 33×33 grid with one spike at (15, 15): the blocks containing the spike
/// split by the criterion and their coarser neighbours are forced to follow,
/// recursively.
#[test]
fn one_spike_forces_a_chain_of_neighbours() {
    let v = (0..33 * 33)
        .map(|i| if i == 15 * 33 + 15 { 10.0 } else { 0.0 })
        .collect();
    let g = HeightGrid::new(33, 33, v, GeoRef::unreferenced(1.0)).unwrap();
    let x = QuadTree::build(&g)
        .unwrap()
        .extract_max_error_m(0.5)
        .unwrap();
    check(&g, &x, 0.5);
    // Wanted: the root, (0,0) of side 16, (8,8) of side 8, (12,12) of side 4.
    assert_eq!(x.wanted_splits, 4);
    // Forced: the side-16 blocks east and south of the spike's, then the side-8
    // blocks next to (12,12)'s neighbours, then the south-east side-16 block.
    assert_eq!(x.forced_splits, 5);
    assert!(x.points.added > 0);
    assert_eq!(x.points.base, 5);
}

/// 9×9: a spike on the shared side of two side-2 blocks makes the south one
/// split into unit cells, which forces the east and south side-4 blocks to split.
#[test]
fn corner_refinement_forces_neighbours_on_9x9() {
    let v = (0..81)
        .map(|i| if i == 2 * 9 + 3 { 4.0 } else { 0.0 })
        .collect();
    let g = HeightGrid::new(9, 9, v, GeoRef::unreferenced(1.0)).unwrap();
    let x = QuadTree::build(&g)
        .unwrap()
        .extract_max_error_m(0.1)
        .unwrap();
    check(&g, &x, 0.1);
    assert_eq!(x.wanted_splits, 3);
    assert_eq!(x.forced_splits, 2);
    let depths: Vec<u32> = x.leaves.iter().map(|l| l.depth).collect();
    assert_eq!(depths.iter().filter(|&&d| d == 3).count(), 4);
    assert_eq!(depths.iter().filter(|&&d| d == 1).count(), 1);
    assert!(x.points.added > 0);
}

#[test]
fn centre_when_needed_is_conforming_and_never_larger() {
    use cota_core::quadtree::QuadOptions;
    use cota_core::MaxVerticalError;
    let g = common::tile();
    let sub = crop(&g, 824, 792, 65, 65);
    let qt = QuadTree::build(&sub).unwrap();
    let opts = QuadOptions::DEFAULT.with_centre_when_needed(true);
    for e in [0.0, 5.0, 40.0, 500.0] {
        let crit = MaxVerticalError { max_error_m: e };
        let fan = qt.refine(&crit);
        let x = qt.refine_with(&crit, &opts);
        check(&sub, &x, e);
        assert!(x.mesh.triangle_count() <= fan.mesh.triangle_count());
        assert!(x.leaves.iter().any(|l| l.halves) || e == 0.0);
    }
}

/// The point accounting shared by both hierarchies adds up, and a loose
/// tolerance selects nothing.
#[test]
fn point_counts_add_up_for_both_hierarchies() {
    use cota_core::{Bitree, ExtractOptions};
    let g = common::tile();
    let sub = crop(&g, 912, 752, 65, 65);
    let bt = Bitree::build(&sub).unwrap();
    let qt = QuadTree::build(&sub).unwrap();
    for e in [0.0, 10.0, 100.0, 1e6] {
        let m = bt.extract(&ExtractOptions::max_error_m(e)).unwrap().mesh;
        let c = bt.point_counts(&m, e);
        assert_eq!(c.base + c.selected + c.added, c.vertices);
        assert_eq!(c.base, 4);
        let q = bt.point_counts(&qt.extract_max_error_m(e).unwrap().mesh, e);
        assert_eq!(q.base + q.selected + q.added, q.vertices);
        if e == 1e6 {
            assert_eq!((c.selected, c.added, q.selected), (0, 0, 0));
        }
    }
}

mod random {
    use super::*;
    use cota_core::quadtree::QuadOptions;
    use cota_core::MaxVerticalError;
    use proptest::prelude::*;

    fn grid(w: usize, h: usize, seed: u64, rough: f32) -> HeightGrid {
        let v = cota_fixtures::hills_and_noise(w, h, seed, rough);
        HeightGrid::new(w, h, v, GeoRef::unreferenced(10.0)).unwrap()
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 120, .. ProptestConfig::default() })]

        /// Any size (2×2, 2×N, odd, primes), any tolerance, both variants:
        /// conforming, within the bound, restricted.
        #[test]
        fn random_grids_are_conforming_and_restricted(
            w in 2usize..60, h in 2usize..60, seed in any::<u64>(),
            rough in 0f32..30.0, e in 0f64..20.0, halves in any::<bool>(),
        ) {
            let g = grid(w, h, seed, rough);
            let qt = QuadTree::build(&g).unwrap();
            let opts = QuadOptions::DEFAULT.with_centre_when_needed(halves);
            let x = qt.refine_with(&MaxVerticalError { max_error_m: e }, &opts);
            check(&g, &x, e);
        }
    }
}
