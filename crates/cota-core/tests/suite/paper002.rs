//! Paper 002's experiment (curvature with and without the illumination mask at
//! equal triangle count: volume error and illumination-weighted volume error)
//! and paper 004's distortion D(M).
#![allow(clippy::unwrap_used, reason = "tests")]

use crate::common;

use cota_core::criteria::curvature::CurvatureMap;
use cota_core::criteria::light::{received_light, IlluminationMask};
use cota_core::mesh::metrics::{distortion_m2, weighted_volume_m3};
use cota_core::refine::{refine, RefineOptions};
use cota_core::{measure, Bitree, ExtractOptions, GeoRef, HeightGrid, Mesh};

fn real_crop() -> HeightGrid {
    let g = common::tile();
    let [dx, _] = g.cell_size_m();
    let (n, x0, y0) = (257, 900, 600);
    let v = (0..n * n).map(|i| g.get(x0 + i % n, y0 + i / n)).collect();
    HeightGrid::new(n, n, v, GeoRef::unreferenced(dx)).unwrap()
}

/// D(M) by brute force: for every unit triangle of the regular grid, find a
/// mesh triangle containing its centroid by barycentric coordinates.
fn brute_distortion(g: &HeightGrid, m: &Mesh) -> f64 {
    let mut d = 0.0;
    let z = |x: usize, y: usize| g.get(x, y) as f64;
    for y in 0..g.height() - 1 {
        for x in 0..g.width() - 1 {
            let tris = if (x + y).is_multiple_of(2) {
                [
                    [(x, y), (x + 1, y), (x + 1, y + 1)],
                    [(x, y), (x, y + 1), (x + 1, y + 1)],
                ]
            } else {
                [
                    [(x, y), (x + 1, y), (x, y + 1)],
                    [(x + 1, y), (x + 1, y + 1), (x, y + 1)],
                ]
            };
            for t in tris {
                let cx = t.iter().map(|p| p.0 as f64).sum::<f64>() / 3.0;
                let cy = t.iter().map(|p| p.1 as f64).sum::<f64>() / 3.0;
                let truth = t.iter().map(|p| z(p.0, p.1)).sum::<f64>() / 3.0;
                let approx = m
                    .triangles
                    .iter()
                    .find_map(|tri| {
                        let v = tri.map(|i| m.vertices[i as usize]);
                        let (x0, y0) = (v[0].col as f64, v[0].row as f64);
                        let (x1, y1) = (v[1].col as f64 - x0, v[1].row as f64 - y0);
                        let (x2, y2) = (v[2].col as f64 - x0, v[2].row as f64 - y0);
                        let det = x1 * y2 - x2 * y1;
                        let (px, py) = (cx - x0, cy - y0);
                        let l1 = (px * y2 - x2 * py) / det;
                        let l2 = (x1 * py - px * y1) / det;
                        (l1 >= -1e-12 && l2 >= -1e-12 && l1 + l2 <= 1.0 + 1e-12).then(|| {
                            v[0].z_m as f64 * (1.0 - l1 - l2)
                                + v[1].z_m as f64 * l1
                                + v[2].z_m as f64 * l2
                        })
                    })
                    .unwrap();
                d += (truth - approx) * (truth - approx);
            }
        }
    }
    d
}

#[test]
fn distortion_is_zero_at_full_resolution_and_matches_brute_force() {
    let v = (0..33 * 21)
        .map(|i| {
            let (x, y) = ((i % 33) as f32, (i / 33) as f32);
            20.0 * (x * 0.4).sin() * (y * 0.3).cos() + ((i * 7919) % 11) as f32
        })
        .collect();
    let g = HeightGrid::new(33, 21, v, GeoRef::unreferenced(10.0)).unwrap();
    let tin = Bitree::build(&g).unwrap();
    let full = tin.extract(&ExtractOptions::max_error_m(0.0)).unwrap().mesh;
    assert!(distortion_m2(&g, &full) < 1e-9);
    for e in [1.0, 5.0, 100.0] {
        let m = tin.extract(&ExtractOptions::max_error_m(e)).unwrap().mesh;
        let (fast, slow) = (distortion_m2(&g, &m), brute_distortion(&g, &m));
        assert!(
            (fast - slow).abs() <= 1e-9 * slow.max(1.0),
            "{e}: {fast} vs {slow}"
        );
        assert!(fast > 0.0);
    }
}

#[test]
fn illumination_mask_at_equal_triangle_count() {
    let g = real_crop();
    let map = CurvatureMap::new(&g);
    let light = [1.0, 1.0, 1.0];
    let target = 4000;
    let lit = |c: u32, r: u32| received_light(&g, light, c as usize, r as usize);
    let mut rows = Vec::new();
    for alpha in [1.0, 0.5, 0.2] {
        // The smallest tolerance (log-bisection) whose mesh has ≤ target triangles.
        let mesh_at = |t: f64| {
            let c = IlluminationMask {
                map: &map,
                light_dir: light,
                alpha,
                tolerance: t,
            };
            refine(&g, &c, &RefineOptions::DEFAULT).unwrap().mesh
        };
        let (mut lo, mut hi) = ((1e-7 * map.total()).ln(), map.total().ln());
        for _ in 0..30 {
            let mid = 0.5 * (lo + hi);
            if mesh_at(mid.exp()).triangle_count() <= target {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let m = mesh_at(hi.exp());
        let met = measure(&g, &m);
        let lit_vol = weighted_volume_m3(&g, &m, lit);
        rows.push((
            alpha,
            m.triangle_count(),
            met.volume_m3,
            lit_vol,
            distortion_m2(&g, &m),
            met.rmse_m,
        ));
    }
    for (alpha, n, vol, lit_vol, dm, rmse) in &rows {
        eprintln!(
            "alpha {alpha}: {n} triangles, volume {vol:.4e} m3, lit-weighted volume {lit_vol:.4e} m3 \
             (ratio {:.3}), D(M) {dm:.4e} m2, RMSE {rmse:.2} m",
            lit_vol / vol
        );
    }
    for r in &rows {
        assert!(r.1 <= target && r.1 as f64 >= 0.9 * target as f64, "{r:?}");
    }
    // α < 1 moves the error from lit to dark regions: the lit share of the
    // volume error drops.
    let share = |r: &(f64, usize, f64, f64, f64, f64)| r.3 / r.2;
    assert!(share(&rows[2]) < share(&rows[0]), "{rows:?}");
}
