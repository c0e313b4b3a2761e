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
//! Two more grids (see [`cota_bench::big`]): `mosaic2`, the real adjacent
//! SRTM tiles N00E010 + N00E011 read and mosaicked (2401×1201, cota only, and
//! delatin at 50 m), and `big4097`, a 4097² grid of real SRTM samples (by
//! default relabelled tiles, artificial adjacency; real tiles from
//! `$COTA_BIG_DATA` when given), where martini runs too, at E = 5 and 50 m
//! only; `COTA_BENCH_FULL=1` adds the other tolerances and delatin at 50 m
//! (about 14 s a run there), some 6 more minutes.
//!
//! A filter also skips the set-up (reading, building, martini's tables) of the
//! grids it excludes, so `-- big4097` or `-- extract/mosaic2` start quickly.
//!
//! Run: `cargo bench -p cota-bench` (a filter such as `-- build/` selects
//! groups); `cargo run --release -p cota-bench --bin criterion-table` then
//! prints the medians as a markdown table.

#![allow(clippy::unwrap_used, reason = "benchmark harness")]

use std::hint::black_box;
use std::time::Duration;

use cota_bench::big::{big_files, load_big, load_mosaic2, seam_line};
use cota_bench::{
    bench_filters, delatin_mesh, heights_f64, load_cases, martini_raw,
    martini_threshold_for_budget, martini_tile, wanted, TOLERANCES_M,
};
use cota_core::{Bitree, ExtractOptions, HeightGrid};
use criterion::{
    criterion_group, criterion_main, BenchmarkGroup, Criterion, SamplingMode, Throughput,
};
use martini::Martini;

/// Tolerances at which delatin runs (it is slow at small E on 1025² grids).
fn delatin_tolerances(grid: &HeightGrid) -> &'static [f64] {
    if grid.width() <= 513 {
        &[5.0, 20.0, 50.0]
    } else if grid.len() <= 1025 * 1025 {
        &[20.0, 50.0]
    } else {
        &[50.0]
    }
}

fn short<M: criterion::measurement::Measurement>(g: &mut BenchmarkGroup<'_, M>) {
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1));
}

/// The extraction groups: a 50 m extraction takes 0.2–40 ms and its first
/// samples after a group change ran up to 1.5× slower here (workers asleep,
/// allocator not yet at its steady size), so these warm up for 1 s and
/// measure for 2 s.
fn steady<M: criterion::measurement::Measurement>(g: &mut BenchmarkGroup<'_, M>) {
    g.sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
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

fn bench_extract(
    c: &mut Criterion,
    name: &str,
    grid: &HeightGrid,
    with_martini: bool,
    tolerances: &[f64],
) {
    let tree = Bitree::build(grid).unwrap();
    // Martini only takes 2^k+1 squares: not made at all for the others.
    let mut peer = with_martini.then(|| {
        let m = Martini::new(grid.width() as u32);
        let tile = martini_tile(&m, grid);
        (m, tile)
    });
    for &e in tolerances {
        let mut g = c.benchmark_group(format!("extract/{name}/{e}"));
        steady(&mut g);
        // Throughput in cota's output triangles (criterion-table turns it
        // into the M triangles/s table).
        let tris = tree
            .extract(&ExtractOptions::max_error_m(e))
            .unwrap()
            .mesh
            .triangle_count();
        g.throughput(Throughput::Elements(tris as u64));
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
    steady(&mut g);
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

/// True when `$COTA_BENCH_FULL` is `1`: every tolerance and delatin on
/// `big4097` too (about 6 more minutes on 2 cores).
fn full() -> bool {
    std::env::var("COTA_BENCH_FULL").is_ok_and(|v| v == "1")
}

/// The groups of one grid, each only when the filters may want it.
fn bench_grid(c: &mut Criterion, f: &[String], name: &str, grid: &HeightGrid, martini: bool) {
    // On the 4097² grid one extraction takes seconds (martini's up to 8 s at
    // 1 m): two tolerances unless COTA_BENCH_FULL=1.
    let tolerances: &[f64] = if grid.len() > 2401 * 2401 && !full() {
        &[5.0, 50.0]
    } else {
        &TOLERANCES_M
    };
    if wanted(f, &format!("build/{name}")) {
        bench_build(c, name, grid, martini);
    }
    if wanted(f, &format!("extract/{name}")) || wanted(f, &format!("extract10k/{name}")) {
        bench_extract(c, name, grid, martini, tolerances);
    }
}

fn benches(c: &mut Criterion) {
    let f = bench_filters();
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
        bench_grid(c, &f, case.name, grid, true);
        if wanted(&f, &format!("delatin/{}", case.name)) {
            bench_delatin(c, case.name, grid);
        }
        if let Some(native) = &case.native {
            let name = format!("srtm{}", native.width());
            bench_grid(c, &f, &name, native, false);
        }
    }
    let kinds = ["build", "extract", "extract10k", "delatin"];
    if kinds.iter().any(|k| wanted(&f, &format!("{k}/mosaic2"))) {
        match load_mosaic2() {
            Ok(m) => {
                eprintln!("cota-bench: {}", m.description);
                if let Some(s) = &m.seams {
                    eprintln!("cota-bench: mosaic2 {}", seam_line(s));
                }
                bench_grid(c, &f, "mosaic2", &m.grid, false);
                if wanted(&f, "delatin/mosaic2") {
                    bench_delatin(c, "mosaic2", &m.grid);
                }
            }
            Err(e) => eprintln!("cota-bench: skipping mosaic2: {e}"),
        }
    }
    if kinds.iter().any(|k| wanted(&f, &format!("{k}/big4097"))) {
        let scratch = tempfile::tempdir().unwrap();
        let big = big_files(scratch.path(), |m| eprintln!("cota-bench: {m}"))
            .and_then(|b| load_big("big4097", &b.big4097, &b.big4097_note));
        match big {
            Ok(b) => {
                eprintln!("cota-bench: {}", b.description);
                if let Some(s) = &b.seams {
                    eprintln!("cota-bench: big4097 (before the crop) {}", seam_line(s));
                }
                drop(scratch);
                bench_grid(c, &f, "big4097", &b.grid, true);
                // delatin takes about 14 s per run at 50 m here.
                if full() && wanted(&f, "delatin/big4097") {
                    bench_delatin(c, "big4097", &b.grid);
                }
            }
            Err(e) => eprintln!("cota-bench: skipping big4097: {e}"),
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
