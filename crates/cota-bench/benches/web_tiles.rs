//! Criterion benchmarks of web-tile sizes (issue 22, item 3): a grid whose
//! span is odd meshed from scratch (`Mesher::new` + `mesh`: the error map's
//! build plus one extraction) on its clamp-extended grid, clipped back
//! (`extend`), against its own hierarchy (`keep`) and against the `2^k + 1`
//! window one sample larger (`neighbour`), in the same run.
//!
//! Grids: 512², 256² and 512×300 windows of the bundled real SRTM tile
//! (`fixtures/S29W072.hgt.zip`, Andes, voids filled), at E = 5 and 20 m.
//!
//! Run: `cargo bench -p cota-bench --bench web_tiles`.

#![allow(clippy::unwrap_used, reason = "benchmark harness")]

use std::hint::black_box;
use std::time::Duration;

use cota_core::grid::voids::{fill_voids, FillOptions};
use cota_core::{GeoRef, HeightGrid, MaxVerticalError, MeshPlan, Mesher};
use criterion::{criterion_group, criterion_main, Criterion};

/// The `w × h` window at (`col`, `row`) of the bundled tile, voids filled.
fn window(col: usize, row: usize, w: usize, h: usize) -> HeightGrid {
    let s = cota_fixtures::bundled_tile();
    let heights = cota_fixtures::crop(&s.heights, s.width, col, row, w, h);
    let mut g = HeightGrid::new(w, h, heights, GeoRef::unreferenced(90.0)).unwrap();
    fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
    g
}

/// Triangles of `grid` meshed at `e` metres, extended or not.
fn mesh(grid: &HeightGrid, e: f64, extend: bool) -> usize {
    let c = MaxVerticalError::new(e).unwrap();
    let plan = MeshPlan::new(&c).with_extend_odd_spans(extend);
    Mesher::new(grid).mesh(&plan).unwrap().mesh.triangle_count()
}

fn benches(c: &mut Criterion) {
    for (name, (col, row, w, h)) in [
        ("srtm512", (600, 600, 512, 512)),
        ("srtm256", (600, 600, 256, 256)),
        ("srtm512x300", (600, 600, 512, 300)),
    ] {
        let grid = window(col, row, w, h);
        let neighbour = window(col, row, w + 1, h + 1);
        for e in [5.0, 20.0] {
            eprintln!(
                "cota-bench: {name} at {e} m: keep {} / extend {} / neighbour {} triangles",
                mesh(&grid, e, false),
                mesh(&grid, e, true),
                mesh(&neighbour, e, true),
            );
            let mut g = c.benchmark_group(format!("web_tiles/{name}/{e}"));
            g.bench_function("keep", |b| b.iter(|| mesh(black_box(&grid), e, false)));
            g.bench_function("extend", |b| b.iter(|| mesh(black_box(&grid), e, true)));
            g.bench_function("neighbour", |b| {
                b.iter(|| mesh(black_box(&neighbour), e, true))
            });
            g.finish();
        }
    }
}

criterion_group! {
    name = web_tiles;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    targets = benches
}
criterion_main!(web_tiles);
