//! Criterion benchmarks of cota side by side with martini and delatin, on the
//! same real grids in the same run (see [`cota_bench::load_cases`]; a grid
//! whose file is absent is skipped with a message).
//!
//! Groups (`<grid>` is `fuji513`, `puget1025`, `srtm1025` = the 1025²
//! north-west crop of the SRTM tile, `srtm1201` = the full tile, cota only):
//! * `build/<grid>`: cota `Bitree::build` (rayon, all threads, and one thread)
//!   vs martini `create_terrain` (the `Martini` instance, which only depends on
//!   the grid size, is made once outside the timing, as martini intends);
//! * `extract/<grid>/<E>` for E in 0.5, 1, 2, 5, 10, 20, 50 m: cota
//!   `extract(max_error_m(E))` vs martini `construct_mesh(E)` (martini's
//!   threshold is not a bound on its true error: see the `peers` report);
//! * `extract10k/<grid>`: a mesh of about 10 000 triangles: cota by error (at
//!   the threshold its budget search finds), cota by budget
//!   (`max_triangles(10000)`), martini at the threshold that gives at most
//!   10 000 triangles;
//! * `delatin/<grid>/<E>` for a few E: delatin `triangulate` (no separate
//!   preparation) vs cota build + extract.
//!
//! Run: `cargo bench -p cota-bench` (a filter such as `-- build/` selects
//! groups); `cargo run --release -p cota-bench --bin criterion-table` then
//! prints the medians as a markdown table.

#![allow(clippy::unwrap_used, reason = "benchmark harness")]

use std::hint::black_box;
use std::time::Duration;

use cota_bench::{
    delatin_mesh, heights_f64, load_cases, martini_raw, martini_threshold_for_budget, martini_tile,
    TOLERANCES_M,
};
use cota_core::{Bitree, ExtractOptions, HeightGrid};
use criterion::{criterion_group, criterion_main, BenchmarkGroup, Criterion, SamplingMode};
use martini::Martini;

/// Tolerances at which delatin runs (it is slow at small E on 1025² grids).
fn delatin_tolerances(grid: &HeightGrid) -> &'static [f64] {
    if grid.width() <= 513 {
        &[5.0, 20.0, 50.0]
    } else {
        &[20.0, 50.0]
    }
}

fn short<M: criterion::measurement::Measurement>(g: &mut BenchmarkGroup<'_, M>) {
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1));
}

fn one_thread_pool() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread rayon pool")
}

fn bench_build(c: &mut Criterion, name: &str, grid: &HeightGrid, with_martini: bool) {
    let pool = one_thread_pool();
    let mut g = c.benchmark_group(format!("build/{name}"));
    short(&mut g);
    g.sampling_mode(SamplingMode::Flat);
    g.bench_function("cota", |b| {
        b.iter(|| Bitree::build(black_box(grid)).unwrap())
    });
    g.bench_function("cota_1thread", |b| {
        pool.install(|| b.iter(|| Bitree::build(black_box(grid)).unwrap()))
    });
    if with_martini {
        let m = Martini::new(grid.width() as u32);
        g.bench_function("martini", |b| b.iter(|| martini_tile(&m, black_box(grid))));
    }
    g.finish();
}

fn bench_extract(c: &mut Criterion, name: &str, grid: &HeightGrid, with_martini: bool) {
    let tree = Bitree::build(grid).unwrap();
    // Martini only takes 2^k+1 squares: not made at all for the others.
    let mut peer = with_martini.then(|| {
        let m = Martini::new(grid.width() as u32);
        let tile = martini_tile(&m, grid);
        (m, tile)
    });
    for &e in &TOLERANCES_M {
        let mut g = c.benchmark_group(format!("extract/{name}/{e}"));
        short(&mut g);
        g.bench_function("cota", |b| {
            b.iter(|| {
                tree.extract(&ExtractOptions::max_error_m(black_box(e)))
                    .unwrap()
            })
        });
        if let Some((m, tile)) = &mut peer {
            g.bench_function("martini", |b| {
                b.iter(|| martini_raw(m, tile, grid, black_box(e)))
            });
        }
        g.finish();
    }

    let budget = 10_000;
    let e10k = tree
        .extract(&ExtractOptions::max_triangles(budget))
        .unwrap()
        .threshold_m;
    let mut g = c.benchmark_group(format!("extract10k/{name}"));
    short(&mut g);
    g.bench_function("cota_by_error", |b| {
        b.iter(|| {
            tree.extract(&ExtractOptions::max_error_m(black_box(e10k)))
                .unwrap()
        })
    });
    g.bench_function("cota_by_budget", |b| {
        b.iter(|| {
            tree.extract(&ExtractOptions::max_triangles(black_box(budget)))
                .unwrap()
        })
    });
    if let Some((m, tile)) = &mut peer {
        let (thr, _) = martini_threshold_for_budget(m, tile, grid, budget, 10_000.0);
        g.bench_function("martini", |b| {
            b.iter(|| martini_raw(m, tile, grid, black_box(thr)))
        });
    }
    g.finish();
}

fn bench_delatin(c: &mut Criterion, name: &str, grid: &HeightGrid) {
    let hf = heights_f64(grid);
    for &e in delatin_tolerances(grid) {
        let mut g = c.benchmark_group(format!("delatin/{name}/{e}"));
        short(&mut g);
        g.sampling_mode(SamplingMode::Flat);
        g.bench_function("delatin", |b| {
            b.iter(|| delatin_mesh(grid, &hf, black_box(e)).unwrap())
        });
        g.bench_function("cota_build_and_extract", |b| {
            b.iter(|| {
                let tree = Bitree::build(black_box(grid)).unwrap();
                tree.extract(&ExtractOptions::max_error_m(e)).unwrap()
            })
        });
        g.finish();
    }
}

fn benches(c: &mut Criterion) {
    let cases = load_cases(|msg| eprintln!("cota-bench: {msg}"));
    for case in &cases {
        let grid = &case.square;
        eprintln!(
            "cota-bench: {} ({}x{}): {}",
            case.name,
            grid.width(),
            grid.height(),
            case.description
        );
        bench_build(c, case.name, grid, true);
        bench_extract(c, case.name, grid, true);
        bench_delatin(c, case.name, grid);
        if let Some(native) = &case.native {
            let name = format!("srtm{}", native.width());
            bench_build(c, &name, native, false);
            bench_extract(c, &name, native, false);
        }
    }
}

criterion_group! {
    name = mesh;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1));
    targets = benches
}
criterion_main!(mesh);
