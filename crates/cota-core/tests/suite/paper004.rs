//! Paper 004 on real data: the mesh list (bitree and restricted quadtree),
//! the texture quadtree on an image made from real heights, and the pair
//! chosen from both lists.
#![allow(clippy::unwrap_used, reason = "tests")]

use crate::common;

use cota_core::pair::{choose, mesh_list, Candidate, MeshListOptions, PairOptions};
use cota_core::texture::{RgbImage, TextureQuadtree};
use cota_core::{check_mesh, CheckOptions, GeoRef, HeightGrid, Mesher};

/// A 129x97 window of the bundled real tile.
fn real_crop() -> HeightGrid {
    let g = common::tile();
    let [dx, _] = g.cell_size_m();
    let (w, h, x0, y0) = (129, 97, 900, 600);
    let v = (0..w * h).map(|i| g.get(x0 + i % w, y0 + i / w)).collect();
    HeightGrid::new(w, h, v, GeoRef::unreferenced(dx)).unwrap()
}

/// An image from real heights (a 301x233 window): hypsometric colours with
/// the slope in blue, so it has flat and busy parts as a photograph does.
fn real_image() -> RgbImage {
    let g = common::tile();
    let (w, h, x0, y0) = (301, 233, 820, 560);
    let px = (0..w * h)
        .map(|i| {
            let (x, y) = (x0 + i % w, y0 + i / w);
            let z = g.get(x, y);
            let s = (g.get(x + 1, y) - z).abs() + (g.get(x, y + 1) - z).abs();
            [
                (z / 8.0).clamp(0.0, 255.0) as u8,
                (z / 3.0 % 256.0) as u8,
                (s * 4.0).min(255.0) as u8,
            ]
        })
        .collect();
    RgbImage::new(w, h, px).unwrap()
}

#[test]
fn the_mesh_list_is_measured_and_checked() {
    let grid = real_crop();
    let mesher = Mesher::new(&grid);
    let opts = MeshListOptions::for_grid(&mesher);
    let list = mesh_list(&mesher, &opts, &|m| 20 * m.vertex_count() as u64).unwrap();
    assert!(list.len() >= 12, "{} meshes", list.len());
    for c in &list {
        let report = check_mesh(&grid, &c.mesh, &CheckOptions::conforming(c.tolerance_m)).unwrap();
        assert!(report.metrics.max_error_m <= c.tolerance_m);
        assert_eq!(c.bytes, 20 * c.mesh.vertex_count() as u64);
        if c.tolerance_m == 0.0 {
            // Both exact meshes are planar wherever they are coarser than the
            // unit triangles, so D(M) = 0 (to the rounding of the planes).
            assert!(c.distortion_m2 < 1e-9, "{}", c.hierarchy.name());
        }
    }
    // Within a hierarchy, a smaller tolerance never has a larger D(M) by
    // much (meshes are not nested across tolerances, but close).
    for name in ["bitree", "quadtree"] {
        let d: Vec<f64> = list
            .iter()
            .filter(|c| c.hierarchy.name() == name)
            .map(|c| c.distortion_m2)
            .collect();
        assert!(d.first() > d.last(), "{name}: {d:?}");
    }
}

#[test]
fn texture_quadtree_on_a_real_image() {
    let img = real_image();
    let t = TextureQuadtree::build(&img);
    let exact = t.extract(0.0);
    assert_eq!(exact.distortion, 0);
    assert_eq!(exact.render(), img);
    let mut last = exact.leaves.len();
    for tol in [2.0, 8.0, 32.0, 128.0] {
        let x = t.extract(tol);
        let area: u64 = x.leaves.iter().map(|l| u64::from(l.width * l.height)).sum();
        assert_eq!(area, (img.width() * img.height()) as u64);
        assert!(x.leaves.len() <= last && x.distortion > 0);
        last = x.leaves.len();
    }
}

#[test]
fn the_pair_is_feasible_and_optimal_among_the_lists() {
    let grid = real_crop();
    let mesher = Mesher::new(&grid);
    let list = mesh_list(&mesher, &MeshListOptions::for_grid(&mesher), &|m| {
        20 * m.vertex_count() as u64 + 6 * m.triangle_count() as u64
    })
    .unwrap();
    let meshes: Vec<Candidate> = list.iter().map(|c| c.candidate()).collect();
    let img = real_image();
    let t = TextureQuadtree::build(&img);
    let textures: Vec<Candidate> = [0.0, 1.0, 4.0, 16.0, 64.0, 256.0]
        .iter()
        .map(|&tol| {
            let x = t.extract(tol);
            Candidate {
                bytes: x.bytes(),
                distortion: x.distortion as f64,
                elements: x.leaves.len() as u64,
            }
        })
        .collect();
    let max = meshes.iter().map(|m| m.bytes).max().unwrap()
        + textures.iter().map(|t| t.bytes).max().unwrap();
    for opts in [
        PairOptions::DEFAULT,
        PairOptions::DEFAULT.with_weights(1e3, 1.0),
    ] {
        for k in 0..=40 {
            let budget = max * k / 40;
            let Ok(c) = choose(&meshes, &textures, budget, &opts) else {
                continue;
            };
            let p = c.optimum;
            assert!(p.bytes <= budget);
            for (i, m) in meshes.iter().enumerate() {
                for (j, tx) in textures.iter().enumerate() {
                    if m.bytes + tx.bytes <= budget {
                        let d = opts.alpha * m.distortion + opts.beta * tx.distortion;
                        assert!(p.distortion <= d, "({i},{j}) beats the optimum at {budget}");
                    }
                }
            }
            assert!(c.gap().is_none_or(|g| g >= 0.0));
        }
    }
}
