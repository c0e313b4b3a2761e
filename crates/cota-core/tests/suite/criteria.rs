//! Each refinement criterion moves the mesh in the direction it should, and
//! every mesh it drives passes the invariant checker in every mode.
#![allow(clippy::unwrap_used, reason = "tests")]

use crate::common;

use cota_core::criteria::curvature::{AccumulatedCurvature, CurvatureMap};
use cota_core::criteria::light::IlluminationMask;
use cota_core::criteria::view::{Paper001, Paper003, ScreenSpaceError};
use cota_core::criteria::{
    local_m, longest_edge_m, terrain_diagonal_m, Element, EuclideanDistance, RelativeSize,
};
use cota_core::refine::{refine, Mode, RefineOptions, Refined};
use cota_core::{check_mesh, CheckOptions, Criterion, GeoRef, HeightGrid, MaxVerticalError, Mesh};

const MODES: [Mode; 3] = [
    Mode::Conforming,
    Mode::Fictitious { watertight: true },
    Mode::Fictitious { watertight: false },
];

/// A mountainous 257×257 crop of the bundled SRTM tile (3″ cells, about 81 m).
fn real_crop() -> HeightGrid {
    let g = common::tile();
    let [dx, _] = g.cell_size_m();
    let (n, x0, y0) = (257, 900, 600);
    let v = (0..n * n).map(|i| g.get(x0 + i % n, y0 + i / n)).collect();
    let g = HeightGrid::new(n, n, v, GeoRef::unreferenced(dx)).unwrap();
    let (lo, hi) = g.valid_range().unwrap();
    assert!(
        hi - lo > 500.0,
        "the crop should be mountainous: {lo}..{hi} m"
    );
    g
}

fn run(g: &HeightGrid, c: &dyn Criterion, mode: Mode) -> Refined {
    let r = refine(g, c, &RefineOptions::DEFAULT.with_mode(mode)).unwrap();
    let opts = CheckOptions::DEFAULT
        .with_conforming(mode.is_conforming())
        .with_allow_fictitious(mode != Mode::Conforming);
    let rep = check_mesh(g, &r.mesh, &opts);
    assert!(rep.is_ok(), "{} {}: {:?}", c.name(), mode.name(), rep.err());
    r
}

fn tris(g: &HeightGrid, c: &dyn Criterion) -> usize {
    run(g, c, Mode::Conforming).mesh.triangle_count()
}

/// Triangle centroids (local metres, x, y).
fn centroids<'a>(g: &'a HeightGrid, m: &'a Mesh) -> impl Iterator<Item = [f64; 2]> + 'a {
    m.triangles.iter().map(move |t| {
        let mut s = [0.0; 2];
        for &i in t {
            let v = m.vertices[i as usize];
            let p = local_m(g, [v.col as f64, v.row as f64, 0.0]);
            s[0] += p[0] / 3.0;
            s[1] += p[1] / 3.0;
        }
        s
    })
}

fn extent_m(g: &HeightGrid) -> [f64; 2] {
    let [dx, dy] = g.cell_size_m();
    [(g.width() - 1) as f64 * dx, (g.height() - 1) as f64 * dy]
}

#[test]
fn every_criterion_passes_the_checker_in_every_mode() {
    let g = real_crop();
    let map = CurvatureMap::new(&g);
    let [xm, ym] = extent_m(&g);
    let top = g.valid_range().unwrap().1 as f64;
    let obs = [0.1 * xm, 0.1 * ym, top + 50.0];
    let k = map.total();
    let crits: Vec<Box<dyn Criterion + '_>> = vec![
        Box::new(MaxVerticalError { max_error_m: 8.0 }),
        Box::new(EuclideanDistance {
            max_distance_m: 8.0,
        }),
        Box::new(RelativeSize { factor: 0.02 }),
        Box::new(AccumulatedCurvature {
            map: &map,
            tolerance: 1e-3 * k,
        }),
        Box::new(IlluminationMask {
            map: &map,
            light_dir: [1.0, 1.0, 1.0],
            alpha: 0.3,
            tolerance: 1e-3 * k,
        }),
        Box::new(ScreenSpaceError {
            max_error_px: 2.0,
            ..ScreenSpaceError::at(obs)
        }),
        Box::new(Paper001 {
            curvature_factor: 0.01,
            ..Paper001::new(&map, obs)
        }),
        Box::new(Paper003 {
            map: &map,
            observer_m: obs,
            motion_dir: [1.0, 1.0, 0.0],
            tolerance: 1e-7 * k,
        }),
    ];
    for c in &crits {
        for mode in MODES {
            let r = run(&g, c.as_ref(), mode);
            eprintln!(
                "{} {}: {} triangles, {} transmitted, {} fictitious",
                c.name(),
                mode.name(),
                r.mesh.triangle_count(),
                r.transmitted_points,
                r.fictitious_points
            );
            assert!(r.mesh.triangle_count() > 2, "{} refined nothing", c.name());
        }
    }
}

#[test]
fn generic_max_error_meets_the_bound_like_the_error_map() {
    let g = real_crop();
    let tin = cota_core::Bitree::build(&g).unwrap();
    for e in [0.0, 2.0, 15.0] {
        let r = refine(
            &g,
            &MaxVerticalError { max_error_m: e },
            &RefineOptions::DEFAULT,
        )
        .unwrap();
        check_mesh(&g, &r.mesh, &CheckOptions::conforming(e)).unwrap();
        let fast = tin
            .extract(&cota_core::ExtractOptions::max_error_m(e))
            .unwrap()
            .mesh;
        // Not identical (the error map is monotone), but comparable.
        let (a, b) = (r.mesh.triangle_count() as f64, fast.triangle_count() as f64);
        assert!(a <= b * 1.05, "generic {a} vs error map {b}");
    }
}

#[test]
fn euclidean_distance_is_the_vertical_error_over_the_slope() {
    // A 45° plane (1 m per 1 m cell eastward) with one bump of 2 m: vertical
    // error 2 m, Euclidean distance 2/√2 m.
    let (w, h) = (9, 9);
    let v = (0..w * h)
        .map(|i| (i % w) as f32 + if i == 4 * w + 3 { 2.0 } else { 0.0 })
        .collect();
    let g = HeightGrid::new(w, h, v, GeoRef::unreferenced(1.0)).unwrap();
    let corners = [[0.0, 0.0, 0.0], [8.0, 8.0, 8.0], [8.0, 0.0, 8.0]];
    let e = Element {
        corners: &corners,
        depth: 1,
        vertical_error_m: 2.0,
        grid: &g,
    };
    let d = EuclideanDistance::distance_m(&e);
    assert!((d - 2f64.sqrt()).abs() < 1e-12, "{d}");
    // On real, steep terrain a distance bound keeps fewer triangles than the
    // same vertical bound.
    let g = real_crop();
    let n_euc = tris(
        &g,
        &EuclideanDistance {
            max_distance_m: 5.0,
        },
    );
    let n_ver = tris(&g, &MaxVerticalError { max_error_m: 5.0 });
    assert!(n_euc < n_ver, "euclidean {n_euc} vs vertical {n_ver}");
}

#[test]
fn size_bounds_every_edge_and_smaller_factor_refines_more() {
    let g = real_crop();
    let diag = terrain_diagonal_m(&g);
    let mut last = 0;
    for f in [0.2, 0.05, 0.02] {
        let r = run(&g, &RelativeSize { factor: f }, Mode::Conforming);
        for t in &r.mesh.triangles {
            let corners = t.map(|i| {
                let v = r.mesh.vertices[i as usize];
                [v.col as f64, v.row as f64, v.z_m as f64]
            });
            let e = Element {
                corners: &corners,
                depth: 0,
                vertical_error_m: 0.0,
                grid: &g,
            };
            assert!(longest_edge_m(&e) <= f * diag);
        }
        assert!(r.mesh.triangle_count() > last);
        last = r.mesh.triangle_count();
    }
}

#[test]
fn larger_curvature_tolerance_gives_fewer_triangles() {
    let g = real_crop();
    let map = CurvatureMap::new(&g);
    let k = map.total();
    let counts: Vec<usize> = [1e-4, 1e-3, 1e-2]
        .iter()
        .map(|f| {
            tris(
                &g,
                &AccumulatedCurvature {
                    map: &map,
                    tolerance: f * k,
                },
            )
        })
        .collect();
    assert!(counts[0] > counts[1] && counts[1] > counts[2], "{counts:?}");
}

/// A ridge along north–south, symmetric east/west, with curved flanks.
fn ridge() -> HeightGrid {
    let n = 129;
    let v = (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f64, (i / n) as f64);
            let d = (x - 64.0).abs();
            (300.0 - 0.04 * d * d + 8.0 * (y * 0.3).sin() * (d * 0.25).cos()) as f32
        })
        .collect();
    HeightGrid::new(n, n, v, GeoRef::unreferenced(10.0)).unwrap()
}

#[test]
fn the_light_mask_keeps_lit_slopes_and_alpha_one_is_pure_curvature() {
    let g = ridge();
    let map = CurvatureMap::new(&g);
    let tol = 1e-3 * map.total();
    let light = |alpha| IlluminationMask {
        map: &map,
        light_dir: [1.0, 0.0, 0.3],
        alpha,
        tolerance: tol,
    };
    let n: Vec<usize> = [0.0, 0.5, 1.0]
        .iter()
        .map(|&a| tris(&g, &light(a)))
        .collect();
    // K·(α + (1−α)·I) grows with α (I ≤ 1): more triangles as α grows.
    assert!(n[0] < n[1] && n[1] <= n[2], "{n:?}");
    assert_eq!(
        n[2],
        tris(
            &g,
            &AccumulatedCurvature {
                map: &map,
                tolerance: tol
            }
        )
    );
    // At α = 0 the east flank (facing the light) keeps more than the west.
    let r = run(&g, &light(0.0), Mode::Conforming);
    let mid = extent_m(&g)[0] / 2.0;
    let east = centroids(&g, &r.mesh).filter(|c| c[0] > mid).count();
    let west = centroids(&g, &r.mesh).filter(|c| c[0] < mid).count();
    assert!(east > 2 * west, "east {east} west {west}");
}

#[test]
fn a_closer_observer_gets_more_triangles_near_it() {
    let g = real_crop();
    let [xm, ym] = extent_m(&g);
    let top = g.valid_range().unwrap().1 as f64;
    let near_sw = |c: &[f64; 2]| c[0] < 0.25 * xm && c[1] < 0.25 * ym;
    let count = |obs: [f64; 3]| {
        let c = ScreenSpaceError {
            look_dir: [1.0, 1.0, -0.2],
            max_error_px: 1.0,
            ..ScreenSpaceError::at(obs)
        };
        let r = run(&g, &c, Mode::Conforming);
        let near = centroids(&g, &r.mesh).filter(near_sw).count();
        let ne = centroids(&g, &r.mesh)
            .filter(|c| c[0] > 0.75 * xm && c[1] > 0.75 * ym)
            .count();
        (near, ne, r.mesh.triangle_count())
    };
    let far = count([-20.0 * xm, -20.0 * ym, top + 5000.0]);
    let close = count([0.05 * xm, 0.05 * ym, top + 20.0]);
    assert!(close.0 > far.0, "close {close:?} far {far:?}");
    // Close to the south-west corner: denser there than in the north-east.
    assert!(close.0 > close.1, "{close:?}");
    // Looking away (south-west, from the south-west corner): nothing to refine.
    let away = ScreenSpaceError {
        look_dir: [-1.0, -1.0, 0.0],
        ..ScreenSpaceError::at([-10.0 * xm, -10.0 * ym, top])
    };
    assert!(tris(&g, &away) < far.2.max(3));
}

#[test]
fn paper001_refines_near_the_observer_and_paper003_ahead_of_it() {
    let g = real_crop();
    let map = CurvatureMap::new(&g);
    let [xm, ym] = extent_m(&g);
    let top = g.valid_range().unwrap().1 as f64;
    let obs = [0.0, 0.0, top + 100.0];
    let p1 = Paper001 {
        curvature_factor: 0.002,
        distance_factor: 0.5,
        ..Paper001::new(&map, obs)
    };
    let r = run(&g, &p1, Mode::Conforming);
    let sw = centroids(&g, &r.mesh)
        .filter(|c| c[0] < 0.5 * xm && c[1] < 0.5 * ym)
        .count();
    let ne = centroids(&g, &r.mesh)
        .filter(|c| c[0] > 0.5 * xm && c[1] > 0.5 * ym)
        .count();
    assert!(sw > 2 * ne, "sw {sw} ne {ne}");
    // Each factor of the AND binds: a larger size factor or a larger
    // curvature factor refines less, a smaller curvature factor more.
    let n = r.mesh.triangle_count();
    let coarse_size = tris(
        &g,
        &Paper001 {
            size_factor: 0.1,
            ..p1
        },
    );
    let coarse_k = tris(
        &g,
        &Paper001 {
            curvature_factor: 0.01,
            ..p1
        },
    );
    let fine_k = tris(
        &g,
        &Paper001 {
            curvature_factor: 0.0005,
            ..p1
        },
    );
    assert!(
        coarse_size < n && coarse_k < n && fine_k > n,
        "{coarse_size} {coarse_k} {n} {fine_k}"
    );

    // Paper 003: from the centre moving east, only what lies ahead refines.
    let centre = [0.5 * xm, 0.5 * ym, top + 100.0];
    let p3 = Paper003 {
        map: &map,
        observer_m: centre,
        motion_dir: [1.0, 0.0, 0.0],
        tolerance: 1e-8 * map.total(),
    };
    let r = run(&g, &p3, Mode::Conforming);
    let east = centroids(&g, &r.mesh).filter(|c| c[0] > 0.5 * xm).count();
    let west = centroids(&g, &r.mesh).filter(|c| c[0] < 0.5 * xm).count();
    assert!(east > 4 * west, "east {east} west {west}");
    // A larger tolerance refines less.
    let coarser = Paper003 {
        tolerance: 1e-6 * map.total(),
        ..p3
    };
    assert!(tris(&g, &coarser) < r.mesh.triangle_count());
}

#[test]
fn formulas_give_their_documented_values() {
    // A paraboloid bowl h = 0.01·(x² + y²) in metres on 1 m cells: k = 0.04 1/m
    // everywhere (Gxx = Gyy = 0.02).
    let n = 11;
    let v = (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f32, (i / n) as f32);
            0.01 * (x * x + y * y)
        })
        .collect();
    let g = HeightGrid::new(n, n, v, GeoRef::unreferenced(1.0)).unwrap();
    let map = CurvatureMap::new(&g);
    let corners = [[0.0, 0.0, 0.0], [4.0, 4.0, 0.0], [4.0, 0.0, 0.0]];
    let e = Element {
        corners: &corners,
        depth: 3,
        vertical_error_m: 2.0,
        grid: &g,
    };
    // 15 samples in the triangle.
    let k = map.accumulate(&corners);
    assert!((k - 15.0 * 0.04).abs() < 1e-6, "{k}");
    // The light mask: I ∈ [0, 1]; from straight below I = 0, so K·α.
    let below = IlluminationMask {
        map: &map,
        light_dir: [0.0, 0.0, -1.0],
        alpha: 0.25,
        tolerance: 0.0,
    };
    assert!((below.masked(&e) - 0.25 * k).abs() < 1e-12);
    let above = IlluminationMask {
        light_dir: [0.0, 0.0, 1.0],
        ..below
    };
    let i = above.illumination(&e);
    assert!(i > 0.99 && i <= 1.0, "{i}");
    assert!((above.masked(&e) - k * (0.25 + 0.75 * i)).abs() < 1e-12);
    // Screen-space error: δ·P / (2·d·tan(fov/2)); observer 100 m above the
    // element's box top (z widened by δ = 2 m), fov 90°: 2·1000/(2·100·1) = 10 px.
    let top = corners.iter().map(|c| c[2]).fold(f64::MIN, f64::max) + 2.0;
    let o = local_m(&g, [2.0, 2.0, top + 100.0]);
    let s = ScreenSpaceError {
        fov_y_deg: 90.0,
        viewport_height_px: 1000.0,
        look_dir: [0.0, 0.0, -1.0],
        ..ScreenSpaceError::at(o)
    };
    assert!((s.error_px(&e) - 10.0).abs() < 1e-9, "{}", s.error_px(&e));
    assert!(s.in_view(&e));
    let s_up = ScreenSpaceError {
        look_dir: [0.0, 0.0, 1.0],
        ..s
    };
    assert!(!s_up.in_view(&e) && !s_up.wants_split(&e));
    // Paper 003: K·cosθ/d with the motion towards the centroid: cosθ = 1.
    let c = cota_core::criteria::view::centroid_m(&e);
    let from = [c[0] - 30.0, c[1] - 40.0, c[2]];
    let p3 = Paper003 {
        map: &map,
        observer_m: from,
        motion_dir: [3.0, 4.0, 0.0],
        tolerance: 0.0,
    };
    assert!((p3.indicator(&e) - k / 50.0).abs() < 1e-12);
    let p3_back = Paper003 {
        motion_dir: [-3.0, -4.0, 0.0],
        ..p3
    };
    assert!(!p3_back.wants_split(&e));
}
