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
//! timings (`strip/<E>`) of cota's cells and guided methods and
//! meshoptimizer.
//!
//! Run: `cargo bench -p cota-bench --bench strip`.

#![allow(clippy::unwrap_used, reason = "benchmark harness")]

use std::hint::black_box;
use std::path::PathBuf;

use cota_core::refine::{refine, Mode, RefineOptions};
use cota_core::strip::{stripify_bitree, stripify_bitree_with, StripMethod};
use cota_core::voids::{fill_voids, FillOptions};
use cota_core::{Bitree, ExtractOptions, GeoRef, HeightGrid, MaxVerticalError, Mesh};
use criterion::{criterion_group, criterion_main, Criterion};

fn srtm() -> HeightGrid {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/S29W072.hgt.zip");
    let mut g = cota_io::read_dem(&p, &cota_io::ReadOptions::DEFAULT)
        .unwrap()
        .grid;
    fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
    g
}

/// A rough grid: every unit triangle survives E = 0.
fn rough(w: usize, h: usize) -> HeightGrid {
    let heights: Vec<f32> = (0..w * h)
        .map(|i| {
            let mut x = i as u64 + 0x9E37_79B9_7F4A_7C15;
            x ^= x >> 31;
            x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
            x ^= x >> 29;
            (x % 100_000) as f32 * 0.01
        })
        .collect();
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

fn bench(c: &mut Criterion) {
    let g = srtm();
    let tree = Bitree::build(&g).unwrap();
    report(&g, &tree);
    let mut group = c.benchmark_group("strip");
    group.sample_size(10);
    for e in [1.0, 10.0] {
        let mesh = tree.extract(&ExtractOptions::max_error_m(e)).unwrap().mesh;
        let idx = flat(&mesh);
        group.bench_function(format!("cota-cells/{e}"), |b| {
            b.iter(|| stripify_bitree(black_box(&mesh)).unwrap().strip.refs())
        });
        group.bench_function(format!("cota-guided/{e}"), |b| {
            b.iter(|| {
                stripify_bitree_with(black_box(&mesh), StripMethod::Guided)
                    .unwrap()
                    .strip
                    .refs()
            })
        });
        group.bench_function(format!("meshopt/{e}"), |b| {
            b.iter(|| meshopt::stripify(black_box(&idx), mesh.vertices.len(), 0).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
