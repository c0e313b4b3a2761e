//! Property tests: on random grids of random sizes (including 2×2, 2×N and
//! primes), every extraction passes the invariant checker with its bound, and
//! budgets are respected.
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use cota_core::{check_mesh, Bitree, CheckOptions, ExtractOptions, GeoRef, HeightGrid};
use proptest::prelude::*;

fn grid(w: usize, h: usize, seed: u64, rough: f32) -> HeightGrid {
    // A smooth surface plus seeded noise, so errors vary across levels.
    let v = cota_fixtures::hills_and_noise(w, h, seed, rough);
    HeightGrid::new(w, h, v, GeoRef::unreferenced(10.0)).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, .. ProptestConfig::default() })]

    #[test]
    fn every_extraction_is_conforming_and_within_bound(
        w in 2usize..70, h in 2usize..70, seed in any::<u64>(),
        rough in 0f32..30.0, e in 0f64..20.0,
    ) {
        let g = grid(w, h, seed, rough);
        let tin = Bitree::build(&g).unwrap();
        let mesh = tin.extract(&ExtractOptions::max_error_m(e)).unwrap().mesh;
        let r = check_mesh(&g, &mesh, &CheckOptions::conforming(e));
        prop_assert!(r.is_ok(), "{w}x{h} e={e}: {:?}", r.err());
        prop_assert!(tin.count_at(e) == mesh.triangle_count());
    }

    #[test]
    fn budgets_are_respected(
        w in 2usize..50, h in 2usize..50, seed in any::<u64>(), frac in 0.05f64..1.0,
    ) {
        let g = grid(w, h, seed, 10.0);
        let tin = Bitree::build(&g).unwrap();
        let full = 2 * (w - 1) * (h - 1);
        let n = ((full as f64 * frac) as usize).max(tin.count_at(f64::MAX));
        let x = tin.extract(&ExtractOptions::max_triangles(n)).unwrap();
        prop_assert!(x.mesh.triangle_count() <= n);
        let r = check_mesh(&g, &x.mesh, &CheckOptions::conforming(x.threshold_m));
        prop_assert!(r.is_ok(), "{:?}", r.err());
    }
}

#[test]
fn primes_and_slivers() {
    for (w, h) in [
        (2, 2),
        (2, 3),
        (3, 2),
        (2, 97),
        (97, 2),
        (101, 103),
        (127, 2),
        (257, 129),
    ] {
        let g = grid(w, h, 42, 5.0);
        let tin = Bitree::build(&g).unwrap();
        for e in [0.0, 0.5, 3.0, 1e9] {
            let mesh = tin.extract(&ExtractOptions::max_error_m(e)).unwrap().mesh;
            check_mesh(&g, &mesh, &CheckOptions::conforming(e))
                .unwrap_or_else(|err| panic!("{w}x{h} e={e}: {err}"));
        }
    }
}

#[test]
fn lossless_of_a_plane_is_two_triangles() {
    let v = (0..17 * 17)
        .map(|i| (i % 17) as f32 * 2.0 + (i / 17) as f32)
        .collect();
    let g = HeightGrid::new(17, 17, v, GeoRef::unreferenced(1.0)).unwrap();
    let mesh = Bitree::build(&g)
        .unwrap()
        .extract(&ExtractOptions::max_error_m(0.0))
        .unwrap()
        .mesh;
    assert_eq!(mesh.triangle_count(), 2);
    assert_eq!(mesh.vertex_count(), 4);
}

#[test]
fn bad_arguments() {
    let g = grid(9, 9, 1, 1.0);
    let tin = Bitree::build(&g).unwrap();
    assert!(tin.extract(&ExtractOptions::max_error_m(-1.0)).is_err());
    assert!(tin.extract(&ExtractOptions::max_error_m(f64::NAN)).is_err());
    assert!(tin.extract(&ExtractOptions::max_triangles(0)).is_err());
    assert!(tin.extract(&ExtractOptions::max_triangles(1)).is_err());
    assert_eq!(
        tin.extract(&ExtractOptions::max_triangles(2))
            .unwrap()
            .mesh
            .triangle_count(),
        2
    );
}
