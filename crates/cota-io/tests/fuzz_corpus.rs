//! Replays every file of every fuzz target's corpus (`fuzz/corpus/<target>/`)
//! through `read_dem_bytes` under the name that target uses, so the seeds and
//! any crash reproducers saved there are exercised by plain `cargo test`
//! (no nightly, no libFuzzer). Nothing may panic; seeds named as valid must
//! decode, so that the corpus does not rot.
// Test helpers outside #[test] functions unwrap and panic like the tests do.
#![allow(clippy::unwrap_used, clippy::panic)]

mod common;

use std::path::{Path, PathBuf};

use common::workspace_root;
use cota_io::{read_dem_bytes, Format, PngEncoding, ReadOptions};

/// (target, file name the target passes to read_dem_bytes).
const TARGETS: [(&str, &str); 4] = [
    ("read_srtm", "N10E010.hgt"),
    ("read_asc", "x.asc"),
    ("read_png", "x.png"),
    ("read_geotiff", "x.tif"),
];

/// Seeds of the readers owned here that must decode, and their format.
const VALID: [(&str, Format); 11] = [
    ("seed-3x3.hgt", Format::SrtmHgt),
    ("seed-2x2-void.hgt", Format::SrtmHgt),
    ("seed-3x3.hgt.zip", Format::SrtmHgtZip),
    ("seed-stored.hgt.zip", Format::SrtmHgtZip),
    ("seed-corner.asc", Format::EsriAscii),
    ("seed-center-float.asc", Format::EsriAscii),
    ("seed-dxdy.asc", Format::EsriAscii),
    (
        "seed-terrain-rgb-2x2.png",
        Format::Png(PngEncoding::TerrainRgb),
    ),
    ("seed-rgba-alpha0.png", Format::Png(PngEncoding::TerrainRgb)),
    ("seed-gray16.png", Format::Png(PngEncoding::Gray16)),
    ("seed-rgb-trns.png", Format::Png(PngEncoding::TerrainRgb)),
];

fn corpus_files(target: &str) -> Vec<PathBuf> {
    let dir = workspace_root().join("fuzz/corpus").join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
}

#[test]
fn every_corpus_file_reads_without_panicking() {
    let mut seen = 0;
    for (target, name) in TARGETS {
        let files = corpus_files(target);
        assert!(!files.is_empty(), "no seeds for {target}");
        for file in files {
            let bytes = std::fs::read(&file).unwrap();
            let result = read_dem_bytes(&bytes, Path::new(name), &ReadOptions::DEFAULT);
            let seed = file.file_name().unwrap().to_string_lossy().into_owned();
            if let Some((_, format)) = VALID.iter().find(|(v, _)| *v == seed) {
                match result {
                    Ok(dem) => assert_eq!(dem.format, *format, "{seed}"),
                    Err(e) => panic!("{target}/{seed} should decode: {e}"),
                }
            }
            seen += 1;
        }
    }
    assert!(seen >= 20, "only {seen} corpus files");
}

#[test]
fn srtm_seed_values() {
    let bytes = std::fs::read(workspace_root().join("fuzz/corpus/read_srtm/seed-3x3.hgt")).unwrap();
    let dem = read_dem_bytes(&bytes, Path::new("N10E010.hgt"), &ReadOptions::DEFAULT).unwrap();
    let h = dem.grid.heights();
    assert_eq!(h.len(), 9);
    assert_eq!(h[3], -4.0);
    assert!(h[4].is_nan());
}

/// The TIFF seeds are made by hand (fuzz/make_seeds.py); check with the tiff
/// crate itself that the valid ones are well-formed TIFFs.
#[test]
fn tiff_seeds_are_real_tiffs() {
    for seed in [
        "seed-i16-le-geo.tif",
        "seed-f32-be-geo.tif",
        "seed-u8-plain.tif",
    ] {
        let path = workspace_root().join("fuzz/corpus/read_geotiff").join(seed);
        let bytes = std::fs::read(&path).unwrap();
        let mut dec = tiff::decoder::Decoder::new(std::io::Cursor::new(bytes)).unwrap();
        let (w, h) = dec.dimensions().unwrap();
        assert!(w * h >= 4, "{seed}");
        dec.read_image().unwrap_or_else(|e| panic!("{seed}: {e}"));
    }
}
