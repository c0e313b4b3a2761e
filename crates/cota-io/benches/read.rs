//! Criterion benchmark of the SRTM reader on a 1 arc-second (3601²) tile.
//!
//! The tile is built in a temporary directory by tiling the real 3" tile of
//! the bundled fixture `fixtures/S29W072.hgt.zip` (1201², so 3×3 copies
//! sharing their edges make 3601²), then zipped with DEFLATE like the
//! distributed tiles. It compares:
//! * `unzip`: read the file and inflate the member into a `Vec<u8>`;
//! * `unzip+copy`: the same plus one pass converting big-endian i16 to f32,
//!   the least work any reader must do;
//! * `read_dem`: `cota_io::read_dem` on the `.hgt.zip`;
//! * and the same two for the raw `.hgt` (`fs::read` vs `read_dem`).
//!
//! Run: `cargo bench -p cota-io --bench read`.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::hint::black_box;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use cota_io::{read_dem, ReadOptions};
use criterion::{criterion_group, criterion_main, Criterion};

const SMALL: usize = 1201;
const BIG: usize = 3601;

/// The 1201² big-endian samples of the bundled fixture.
fn fixture_samples() -> Vec<u8> {
    let path = cota_fixtures::fixture(cota_fixtures::BUNDLED_TILE);
    let file = std::fs::File::open(&path).expect("fixtures/S29W072.hgt.zip");
    let mut zip = zip::ZipArchive::new(file).unwrap();
    let mut data = Vec::new();
    zip.by_index(0).unwrap().read_to_end(&mut data).unwrap();
    assert_eq!(data.len(), 2 * SMALL * SMALL);
    data
}

/// A 3601² tile made of 3×3 copies of the 1201² one (edges shared).
fn tiled(small: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(2 * BIG * BIG);
    for row in 0..BIG {
        let r = row % (SMALL - 1);
        for col in 0..BIG {
            let c = col % (SMALL - 1);
            let i = 2 * (r * SMALL + c);
            out.extend_from_slice(&small[i..i + 2]);
        }
    }
    out
}

/// Writes the raw and zipped 3601² tile into `dir`.
fn make_files(dir: &Path) -> (PathBuf, PathBuf) {
    let big = tiled(&fixture_samples());
    let hgt = dir.join("S29W072.hgt");
    std::fs::write(&hgt, &big).unwrap();
    let zip_path = dir.join("S29W072.hgt.zip");
    let mut w = zip::ZipWriter::new(std::fs::File::create(&zip_path).unwrap());
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    w.start_file("S29W072.hgt", opts).unwrap();
    w.write_all(&big).unwrap();
    w.finish().unwrap();
    (hgt, zip_path)
}

fn unzip(path: &Path) -> Vec<u8> {
    let bytes = std::fs::read(path).unwrap();
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes)).unwrap();
    let mut member = zip.by_index(0).unwrap();
    let mut data = Vec::with_capacity(member.size() as usize);
    member.read_to_end(&mut data).unwrap();
    data
}

fn to_f32(data: &[u8]) -> Vec<f32> {
    data.chunks_exact(2)
        .map(|c| f32::from(i16::from_be_bytes([c[0], c[1]])))
        .collect()
}

fn bench(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let (hgt, zip_path) = make_files(dir.path());
    let opts = ReadOptions::DEFAULT;
    let dem = read_dem(&zip_path, &opts).unwrap();
    assert_eq!(dem.grid.width(), BIG);

    let mut g = c.benchmark_group("srtm_3601");
    g.sample_size(20);
    g.bench_function("zip/unzip", |b| b.iter(|| black_box(unzip(&zip_path))));
    g.bench_function("zip/unzip+copy", |b| {
        b.iter(|| black_box(to_f32(&unzip(&zip_path))))
    });
    g.bench_function("zip/read_dem", |b| {
        b.iter(|| black_box(read_dem(&zip_path, &opts).unwrap()))
    });
    g.bench_function("hgt/fs_read+copy", |b| {
        b.iter(|| black_box(to_f32(&std::fs::read(&hgt).unwrap())))
    });
    g.bench_function("hgt/read_dem", |b| {
        b.iter(|| black_box(read_dem(&hgt, &opts).unwrap()))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
