//! Criterion benchmarks of the steps around meshing: reading DEMs and the
//! progressive stream.
//!
//! * `read/<input>`: `cota_io::read_dem` of one real file of each kind in the
//!   shared data (`N00E010.hgt` raw SRTM, `N00E011.hgt.zip`, the Puget Sound
//!   16-bit PNG, the Fuji terrain-RGB PNG, the tiled GeoTIFF
//!   `mt_fuji_90m.tif`), then read + `cota_core::mosaic` + void fill of
//!   `mosaic2` (the two real adjacent tiles), `srtm3601` (one 3601² `.hgt`)
//!   and `mosaic8` (eight `.hgt` files), the large grids of
//!   [`cota_bench::big`] (written once into a temporary directory; the read
//!   is timed).
//! * `stream/<grid>`: `cota_core::stream::encode` (`encode`, every step down
//!   to the lossless `E = 0` mesh, quantum 1 m for SRTM, 0.1 m for the
//!   0.1 m-resolution PNGs) and `StreamDecoder` applying every step then
//!   building the final mesh (`decode`).
//!
//! Run: `cargo bench -p cota-bench --bench pipeline [-- read/]`.

#![allow(clippy::unwrap_used, reason = "benchmark harness")]

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;

use cota_bench::big::{big_files, read_mosaic};
use cota_bench::{bench_filters, data_dir, load_cases, wanted};
use cota_core::stream::{encode, StreamDecoder, StreamOptions};
use cota_core::HeightGrid;
use cota_io::{read_dem, PngEncoding, ReadOptions};
use criterion::{criterion_group, criterion_main, Criterion, SamplingMode};

fn bench_read_files(c: &mut Criterion, f: &[String]) {
    let d = data_dir();
    let gray = ReadOptions::DEFAULT
        .with_png_encoding(Some(PngEncoding::Gray16))
        .with_gray(0.1, 0.0);
    let rgb = ReadOptions::DEFAULT.with_png_encoding(Some(PngEncoding::TerrainRgb));
    let files: [(&str, PathBuf, ReadOptions); 5] = [
        (
            "N00E010.hgt",
            d.join("srtm/N00E010.hgt"),
            ReadOptions::DEFAULT,
        ),
        (
            "N00E011.hgt.zip",
            d.join("srtm/N00E011.hgt.zip"),
            ReadOptions::DEFAULT,
        ),
        ("ps_height_1k.png", d.join("png/ps_height_1k.png"), gray),
        ("fuji.png", d.join("png/fuji.png"), rgb),
        (
            "mt_fuji_90m.tif",
            d.join("geotiff/mt_fuji_90m.tif"),
            ReadOptions::DEFAULT,
        ),
    ];
    for (name, path, opts) in files {
        if !wanted(f, &format!("read/{name}")) {
            continue;
        }
        if !path.exists() {
            eprintln!(
                "cota-bench: skipping read/{name}: {} is absent",
                path.display()
            );
            continue;
        }
        let mut g = c.benchmark_group(format!("read/{name}"));
        g.sample_size(10)
            .warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_secs(1));
        g.bench_function("read_dem", |b| {
            b.iter(|| read_dem(black_box(&path), &opts).unwrap())
        });
        g.finish();
    }
}

fn bench_read_mosaic(c: &mut Criterion, name: &str, files: &[PathBuf]) {
    let mut g = c.benchmark_group(format!("read/{name}"));
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2))
        .sampling_mode(SamplingMode::Flat);
    g.bench_function("read_mosaic_fill", |b| {
        b.iter(|| read_mosaic(black_box(files)).unwrap())
    });
    g.finish();
}

fn bench_read(c: &mut Criterion, f: &[String]) {
    bench_read_files(c, f);
    if wanted(f, "read/mosaic2") {
        let d = data_dir().join("srtm");
        let files = [d.join("N00E010.hgt"), d.join("N00E011.hgt.zip")];
        if files.iter().all(|p| p.exists()) {
            bench_read_mosaic(c, "mosaic2", &files);
        }
    }
    if wanted(f, "read/srtm3601") || wanted(f, "read/mosaic8") {
        let scratch = tempfile::tempdir().unwrap();
        match big_files(scratch.path(), |m| eprintln!("cota-bench: {m}")) {
            Ok(b) => {
                eprintln!(
                    "cota-bench: srtm3601: {}; mosaic8: {}",
                    b.tile3601_note, b.mosaic8_note
                );
                if wanted(f, "read/srtm3601") {
                    bench_read_mosaic(c, "srtm3601", &b.tile3601);
                }
                if wanted(f, "read/mosaic8") {
                    bench_read_mosaic(c, "mosaic8", &b.mosaic8);
                }
            }
            Err(e) => eprintln!("cota-bench: skipping the large reads: {e}"),
        }
    }
}

fn bench_stream(c: &mut Criterion, name: &str, grid: &HeightGrid, quantum_m: f64) {
    let opts = StreamOptions::default().with_quantum_m(quantum_m);
    let enc = encode(grid, &opts).unwrap();
    let bytes: usize = enc.steps.iter().map(|s| s.payload.len()).sum();
    eprintln!(
        "cota-bench: stream/{name}: {} steps, {bytes} bytes ({:.2} bits/sample), lattice exact: {}",
        enc.steps.len(),
        8.0 * bytes as f64 / grid.len() as f64,
        enc.lattice_exact
    );
    let mut g = c.benchmark_group(format!("stream/{name}"));
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2))
        .sampling_mode(SamplingMode::Flat);
    g.bench_function("encode", |b| {
        b.iter(|| encode(black_box(grid), &opts).unwrap())
    });
    g.bench_function("decode", |b| {
        b.iter(|| {
            let mut dec = StreamDecoder::new(enc.header.clone());
            for s in &enc.steps {
                dec.apply_step(black_box(&s.payload)).unwrap();
            }
            dec.mesh()
        })
    });
    g.finish();
}

fn benches(c: &mut Criterion) {
    let f = bench_filters();
    bench_read(c, &f);
    if !wanted(&f, "stream/") {
        return;
    }
    for case in load_cases(|m| eprintln!("cota-bench: {m}")) {
        // SRTM heights are integer metres; the PNGs' are multiples of 0.1 m.
        let (grid, name, q) = match &case.native {
            Some(native) => (native, format!("srtm{}", native.width()), 1.0),
            None => (&case.square, case.name.to_string(), 0.1),
        };
        if wanted(&f, &format!("stream/{name}")) {
            bench_stream(c, &name, grid, q);
        }
    }
}

criterion_group!(pipeline, benches);
criterion_main!(pipeline);
