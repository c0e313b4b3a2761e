//! Triangle strips: cota's bitree traversal strip (`cota_core::strip`) against
//! meshoptimizer's `stripify` (through the `meshopt` crate, benchmarks only),
//! on the same meshes of the bundled SRTM tile.
//!
//! First a report (stderr): references per triangle of cota's three methods
//! (the default, rows of re-triangulated unit cells; the guided strip of the
//! unchanged mesh; the papers' pure traversal order) at several tolerances,
//! conforming and fictitious, and on a full grid; meshoptimizer
//! gets the mesh's triangles as extracted and, as its documentation advises,
//! after `optimize_vertex_cache`, and joins its strips with degenerate
//! triangles (no restart index), like cota. meshoptimizer strips the mesh
//! as given: only cota's cells method changes diagonals. Then criterion
//! timings `strip/<grid>/<E>` of cota's cells (`cota-cells`, the default) and
//! guided (`cota-guided`) methods and `meshopt::stripify` of the triangles as
//! extracted (`meshopt`), on the same meshes,
//! `Bitree::extract(max_error_m(E))` of the shared grids `srtm1201` (N00E010,
//! or the fixture when the shared data is absent) and `puget1025`, at E = 1
//! and 10 m.
//!
//! The report is printed when no filter is given, or with the filter `report`.
//!
//! Run: `cargo bench -p cota-bench --bench strip [-- strip/puget1025]`.

#![allow(clippy::unwrap_used, reason = "benchmark harness")]

use std::hint::black_box;

use cota_bench::{bench_filters, load_cases, wanted};
use cota_core::refine::{refine, Mode, RefineOptions};
use cota_core::strip::{stripify_bitree, stripify_bitree_with, StripMethod};
use cota_core::{Bitree, ExtractOptions, GeoRef, HeightGrid, MaxVerticalError, Mesh};
use criterion::{criterion_group, criterion_main, Criterion};
use std::time::Duration;

fn srtm() -> HeightGrid {
    let tile = [cota_fixtures::fixture(cota_fixtures::BUNDLED_TILE)];
    cota_io::read_region(&tile, &cota_io::RegionOptions::DEFAULT)
        .unwrap()
        .grid
}

/// A rough grid: every unit triangle survives E = 0.
fn rough(w: usize, h: usize) -> HeightGrid {
    let heights = cota_fixtures::rough_terrain(w, h, 1);
    HeightGrid::new(w, h, heights, GeoRef::unreferenced(30.0)).unwrap()
}

fn flat(mesh: &Mesh) -> Vec<u32> {
    mesh.triangles.iter().flatten().copied().collect()
}

/// meshoptimizer's strip length (degenerate joins), raw and cache-optimized,
/// each checked to hold every triangle.
fn meshopt_refs(mesh: &Mesh) -> (usize, usize) {
    let idx = flat(mesh);
    let nv = mesh.vertices.len();
    let raw = meshopt::stripify(&idx, nv, 0).unwrap();
    let opt = meshopt::optimize_vertex_cache(&idx, nv);
    let cached = meshopt::stripify(&opt, nv, 0).unwrap();
    for s in [&raw, &cached] {
        let back = meshopt::unstripify(s, 0).unwrap();
        assert_eq!(back.len(), idx.len());
    }
    (raw.len(), cached.len())
}

fn row(label: &str, mesh: &Mesh) {
    let t = mesh.triangles.len() as f64;
    let cells = stripify_bitree(mesh).unwrap();
    let guided = stripify_bitree_with(mesh, StripMethod::Guided).unwrap();
    let traversal = stripify_bitree_with(mesh, StripMethod::Traversal).unwrap();
    let (raw, cached) = meshopt_refs(mesh);
    eprintln!(
        "| {label} | {} | {:.3} | {} | {:.3} | {:.3} | {:.3} | {:.3} |",
        mesh.triangles.len(),
        cells.strip.refs_per_triangle(),
        cells.flipped_cells,
        guided.strip.refs_per_triangle(),
        traversal.strip.refs_per_triangle(),
        raw as f64 / t,
        cached as f64 / t
    );
}

fn report(g: &HeightGrid, tree: &Bitree<'_>) {
    eprintln!(
        "| mesh | triangles | cota cells refs/tri | cells flipped | cota guided | cota traversal | meshopt | meshopt (cache-optimized) |"
    );
    eprintln!("|---|---|---|---|---|---|---|---|");
    for e in [0.0, 1.0, 5.0, 20.0, 100.0] {
        let mesh = tree.extract(&ExtractOptions::max_error_m(e)).unwrap().mesh;
        row(&format!("conforming E={e} m"), &mesh);
    }
    for mode in [
        Mode::Fictitious { watertight: true },
        Mode::Fictitious { watertight: false },
    ] {
        for e in [2.0, 10.0] {
            let r = refine(
                g,
                &MaxVerticalError { max_error_m: e },
                &RefineOptions::DEFAULT.with_mode(mode),
            )
            .unwrap();
            row(&format!("{} E={e} m", mode.name()), &r.mesh);
        }
    }
    let r = rough(257, 257);
    let full = Bitree::build(&r)
        .unwrap()
        .extract(&ExtractOptions::max_error_m(0.0))
        .unwrap()
        .mesh;
    row("full grid 257x257", &full);
}

fn bench_grid(c: &mut Criterion, name: &str, grid: &HeightGrid) {
    let tree = Bitree::build(grid).unwrap();
    for e in [1.0, 10.0] {
        let mesh = tree.extract(&ExtractOptions::max_error_m(e)).unwrap().mesh;
        let idx = flat(&mesh);
        let mut group = c.benchmark_group(format!("strip/{name}/{e}"));
        group
            .sample_size(10)
            .warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_secs(1));
        group.bench_function("cota-cells", |b| {
            b.iter(|| stripify_bitree(black_box(&mesh)).unwrap().strip.refs())
        });
        group.bench_function("cota-guided", |b| {
            b.iter(|| {
                stripify_bitree_with(black_box(&mesh), StripMethod::Guided)
                    .unwrap()
                    .strip
                    .refs()
            })
        });
        group.bench_function("meshopt", |b| {
            b.iter(|| meshopt::stripify(black_box(&idx), mesh.vertices.len(), 0).unwrap())
        });
        group.finish();
    }
}

fn bench(c: &mut Criterion) {
    let f = bench_filters();
    if f.is_empty() || f.iter().any(|x| x == "report") {
        let g = srtm();
        let tree = Bitree::build(&g).unwrap();
        report(&g, &tree);
    }
    for case in load_cases(|m| eprintln!("cota-bench: {m}")) {
        let (name, grid) = match &case.native {
            Some(native) => (format!("srtm{}", native.width()), native),
            None => (case.name.to_string(), &case.square),
        };
        if name != "fuji513" && wanted(&f, &format!("strip/{name}")) {
            bench_grid(c, &name, grid);
        }
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
