//! The harmonic void fill (`cota_core::grid::voids`) on a real tile with its
//! northern half blanked, against an independent solve of the same discrete
//! Laplace problem: conjugate gradients in `f64` on the 5-point equations
//! (weights 1, a void sample's neighbours outside the grid left out), run
//! until the residual is 1e-10 of the start.
//!
//! The stated tolerance: the default fill (`tolerance_m` 1 mm) is within
//! 2 mm of the converged solution at every filled sample (1 mm for the
//! iteration, the rest for the `f32` heights and the reference's own error).

#![allow(clippy::unwrap_used, clippy::panic, reason = "tests fail loudly")]

use crate::common;

use cota_core::grid::voids::{fill_voids, FillOptions};
use cota_core::HeightGrid;

/// The reference: for every void sample i, Σⱼ (uᵢ − uⱼ) = 0 over its
/// in-grid 4-neighbours j, valid neighbours fixed.
fn reference(g: &HeightGrid) -> Vec<f64> {
    let (w, h) = (g.width(), g.height());
    let hs: Vec<f64> = g.heights().iter().map(|&v| f64::from(v)).collect();
    let void: Vec<bool> = g.heights().iter().map(|v| v.is_nan()).collect();
    let nbs = |i: usize| {
        let (x, y) = (i % w, i / w);
        [
            (x > 0).then(|| i - 1),
            (x + 1 < w).then(|| i + 1),
            (y > 0).then(|| i - w),
            (y + 1 < h).then(|| i + w),
        ]
        .into_iter()
        .flatten()
    };
    // A x for x zero outside the voids.
    let apply = |x: &[f64], out: &mut [f64]| {
        for i in 0..x.len() {
            if void[i] {
                out[i] = nbs(i)
                    .map(|j| x[i] - if void[j] { x[j] } else { 0.0 })
                    .sum();
            }
        }
    };
    let mut b = vec![0.0; hs.len()];
    for i in 0..hs.len() {
        if void[i] {
            b[i] = nbs(i).filter(|&j| !void[j]).map(|j| hs[j]).sum();
        }
    }
    let mut x = vec![0.0; hs.len()];
    let (mut r, mut p, mut ap) = (b.clone(), b.clone(), vec![0.0; hs.len()]);
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let (start, mut rr) = (dot(&r, &r), dot(&r, &r));
    for _ in 0..20_000 {
        if rr <= 1e-20 * start {
            break;
        }
        apply(&p, &mut ap);
        let alpha = rr / dot(&p, &ap);
        for i in 0..x.len() {
            x[i] += alpha * p[i];
            r[i] -= alpha * ap[i];
        }
        let next = dot(&r, &r);
        for i in 0..p.len() {
            p[i] = r[i] + next / rr * p[i];
        }
        rr = next;
    }
    assert!(rr <= 1e-20 * start, "reference did not converge");
    x
}

#[test]
fn north_half_blanked_matches_a_converged_solve() {
    // A 301² window of the bundled real tile, in the Andes foothills.
    let s = cota_fixtures::bundled_tile().crop(850, 600, 301, 301);
    let mut g = common::grid(s);
    let w = g.width();
    g.heights_mut()[..150 * w].fill(f32::NAN);
    // The border row is far from flat: the test can fail.
    let border = &g.heights()[150 * w..151 * w];
    let lo = border.iter().copied().fold(f32::INFINITY, f32::min);
    let hi = border.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    assert!(hi - lo > 100.0, "border heights {lo}..{hi} m");
    let voids = g.void_count();
    let exact = reference(&g);
    let before = g.clone();
    let report = fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
    assert!(report.converged && report.filled == voids, "{report:?}");
    let mut worst = 0f64;
    for (i, v) in before.heights().iter().enumerate() {
        let got = f64::from(g.heights()[i]);
        if v.is_nan() {
            worst = worst.max((got - exact[i]).abs());
        } else {
            assert_eq!(got, f64::from(*v), "a valid sample changed at {i}");
        }
    }
    println!("{voids} voids, {report:?}: largest difference {worst:.2e} m");
    assert!(
        worst <= 2e-3,
        "fill is {worst} m from the converged solution"
    );
}
