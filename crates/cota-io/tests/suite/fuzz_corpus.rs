//! Replays every file of every fuzz target's corpus (`fuzz/corpus/<target>/`)
//! through `read_dem_bytes` under the name that target uses, so the seeds and
//! any crash reproducers saved there are exercised by plain `cargo test`
//! (no nightly, no libFuzzer). Nothing may panic; seeds named as valid must
//! decode, so that the corpus does not rot.
//!
//! Then the stable stand-in for the fuzzers (issue 23, item 8):
//! `seed_mutations_neither_panic_nor_exceed_the_limits` mutates every seed of
//! every target (bit flips, truncations, inserted bytes, size fields
//! overwritten with extreme values, duplicated chunks) with a fixed-seed
//! generator, a bounded number of times ([`MUTATIONS`], or
//! `COTA_FUZZ_MUTATIONS`), and feeds each through its reader (or the stream
//! decoder) under a sample limit of [`LIMIT_SAMPLES`]: every result must be
//! an error or a grid within the limit, never a panic. A failing input is
//! saved under `target/fuzz-failures/` to replay.
// Test helpers outside #[test] functions unwrap and panic like the tests do.
#![allow(clippy::unwrap_used, clippy::panic)]

use crate::common;

use std::path::{Path, PathBuf};

use common::workspace_root;
use cota_fixtures::formats;
use cota_io::stream_file::{decode_stream_bytes, StreamLimit};
use cota_io::{read_dem_bytes, Format, PngEncoding, ReadOptions, TileRequest};

/// (target, file name the target passes to read_dem_bytes).
const TARGETS: [(&str, &str); 9] = [
    ("read_srtm", "N10E010.hgt"),
    ("read_asc", "x.asc"),
    ("read_png", "x.png"),
    ("read_geotiff", "x.tif"),
    ("read_webp", "x.webp"),
    ("read_pmtiles", "x.pmtiles"),
    ("read_npy", "x.npy"),
    ("read_usgs_dem", "x.dem"),
    ("read_tile", "12/2048/1361.png"),
];

/// The options a target reads with: the PMTiles target asks for every tile
/// of zoom 2 (its seeds' zoom), the others take the defaults.
fn target_options(target: &str) -> ReadOptions {
    let tiles = TileRequest {
        zoom: 2,
        bbox_deg: [-180.0, -85.0, 180.0, 85.0],
    };
    // Any height: the seeds test the decoders' checks, not the height limit
    // (a seed of `i16::MAX` samples must still decode).
    let any = ReadOptions::DEFAULT.with_max_abs_height_m(f64::INFINITY);
    match target {
        "read_pmtiles" => any.with_tiles(Some(tiles)),
        _ => any,
    }
}

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
            let result = read_dem_bytes(&bytes, Path::new(name), &target_options(target));
            let seed = file.file_name().unwrap().to_string_lossy().into_owned();
            if let Some((_, format)) = VALID.iter().find(|(v, _)| *v == seed) {
                match result {
                    Ok(dem) => assert_eq!(dem.format, *format, "{seed}"),
                    Err(e) => panic!("{target}/{seed} should decode: {e}"),
                }
            } else if seed.starts_with("seed-valid") {
                if let Err(e) = result {
                    panic!("{target}/{seed} should decode: {e}");
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

/// Mutations per seed in `cargo test` (about 115 000 inputs in all, about a
/// second); `COTA_FUZZ_MUTATIONS` overrides it.
const MUTATIONS: usize = 2000;

/// The sample limit of the mutated reads: a mutated header may declare
/// anything, the readers must refuse what exceeds this before allocating.
const LIMIT_SAMPLES: u64 = 1 << 20;

/// xorshift64*: a fixed-seed generator, so a failure replays.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// A number below `n` (0 when `n` is 0).
    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }
}

/// Values a size or offset field is overwritten with.
const EXTREMES: [u64; 8] = [0, 1, 0x7f, 0xff, 0xffff, 0x7fff_ffff, 0xffff_ffff, u64::MAX];

/// One random mutation of `seed`: bit flips, a truncation, inserted bytes,
/// a 2-, 4- or 8-byte field set to an extreme value (either byte order), a
/// duplicated chunk, or a few of these at once.
fn mutate(seed: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut b = seed.to_vec();
    for _ in 0..1 + rng.below(3) {
        match rng.below(5) {
            0 => {
                for _ in 0..1 + rng.below(4) {
                    if !b.is_empty() {
                        let i = rng.below(b.len());
                        b[i] ^= 1 << rng.below(8);
                    }
                }
            }
            1 => b.truncate(rng.below(b.len() + 1)),
            2 => {
                let at = rng.below(b.len() + 1);
                let n = 1 + rng.below(16);
                let bytes: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
                b.splice(at..at, bytes);
            }
            3 => {
                let width = [2, 4, 8][rng.below(3)];
                if b.len() >= width {
                    let at = rng.below(b.len() - width + 1);
                    let v = EXTREMES[rng.below(EXTREMES.len())];
                    let bytes = match rng.below(2) {
                        0 => v.to_le_bytes(),
                        _ => v.to_be_bytes(),
                    };
                    b[at..at + width].copy_from_slice(&bytes[..width]);
                }
            }
            _ => {
                if !b.is_empty() {
                    let from = rng.below(b.len());
                    let to = (from + 1 + rng.below(64)).min(b.len());
                    let chunk = b[from..to].to_vec();
                    let at = rng.below(b.len() + 1);
                    b.splice(at..at, chunk);
                }
            }
        }
    }
    b
}

/// Grid samples a stream's head announces (as the `stream_decode` target).
fn stream_samples(data: &[u8]) -> u64 {
    let at = |i: usize| {
        data.get(i..i + 4).map_or(0, |b| {
            u64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        })
    };
    at(14) * at(18)
}

/// Feeds one input to `target`: an error or a result within the limit.
fn feed(target: &str, name: &str, data: &[u8]) -> Result<(), String> {
    if target == "stream_decode" {
        if stream_samples(data) > LIMIT_SAMPLES {
            return Ok(());
        }
        if let Ok(d) = decode_stream_bytes(data, &StreamLimit::ALL) {
            let _ = (d.decoder.mesh(), d.decoder.heights_m());
        }
        return Ok(());
    }
    let opts = target_options(target).with_max_samples(Some(LIMIT_SAMPLES));
    match read_dem_bytes(data, Path::new(name), &opts) {
        Ok(dem) if dem.grid.len() as u64 > LIMIT_SAMPLES => Err(format!(
            "a grid of {} samples, over the limit of {LIMIT_SAMPLES}",
            dem.grid.len()
        )),
        _ => Ok(()),
    }
}

/// Saves a failing input under `target/fuzz-failures/` and says where.
fn save_failure(target: &str, seed: &str, i: usize, data: &[u8]) -> String {
    let dir = workspace_root().join("target/fuzz-failures").join(target);
    let path = dir.join(format!("{seed}-mutation-{i}"));
    let saved = std::fs::create_dir_all(&dir).and_then(|()| std::fs::write(&path, data));
    match saved {
        Ok(()) => path.display().to_string(),
        Err(e) => format!("(not saved: {e})"),
    }
}

#[test]
fn seed_mutations_neither_panic_nor_exceed_the_limits() {
    let count = std::env::var("COTA_FUZZ_MUTATIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(MUTATIONS);
    let targets = TARGETS.iter().copied().chain([("stream_decode", "")]);
    let mut inputs = 0;
    for (t, (target, name)) in targets.enumerate() {
        for (k, file) in corpus_files(target).iter().enumerate() {
            let seed = std::fs::read(file).unwrap();
            let seed_name = file.file_name().unwrap().to_string_lossy().into_owned();
            let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ ((t as u64) << 32) ^ k as u64);
            for i in 0..count {
                let data = mutate(&seed, &mut rng);
                let outcome = std::panic::catch_unwind(|| feed(target, name, &data));
                let failure = match outcome {
                    Ok(Ok(())) => continue,
                    Ok(Err(e)) => e,
                    Err(_) => "a panic".to_string(),
                };
                let saved = save_failure(target, &seed_name, i, &data);
                panic!("{target}/{seed_name}, mutation {i}: {failure}; input saved as {saved}");
            }
            inputs += count;
        }
    }
    assert!(inputs >= 50 * count, "only {inputs} mutated inputs");
}

/// The mutator makes every kind of change (else the test above could pass
/// on unchanged seeds).
#[test]
fn mutations_change_the_seed_in_every_way() {
    let seed: Vec<u8> = (0..64).collect();
    let mut rng = Rng(7);
    let (mut shorter, mut longer, mut same_len_changed) = (0, 0, 0);
    for _ in 0..500 {
        let m = mutate(&seed, &mut rng);
        match m.len().cmp(&seed.len()) {
            std::cmp::Ordering::Less => shorter += 1,
            std::cmp::Ordering::Greater => longer += 1,
            std::cmp::Ordering::Equal if m != seed => same_len_changed += 1,
            std::cmp::Ordering::Equal => {}
        }
    }
    assert!(
        shorter > 50 && longer > 50 && same_len_changed > 50,
        "{shorter} {longer} {same_len_changed}"
    );
}

/// Real heights for the seeds: an n×n window of the bundled SRTM tile.
fn real_heights(n: usize) -> Vec<f32> {
    let s = cota_fixtures::bundled_tile();
    cota_fixtures::crop(&s.heights, s.width, 600, 600, n, n)
}

/// Writes the seed corpora of the readers added after the first four
/// (WebP, PMTiles, npy/npz, USGS DEM, z/x/y tiles) from real heights (run
/// with `--ignored` to refresh). Seeds named `seed-valid-*` must decode.
#[test]
#[ignore = "writes fuzz/corpus/read_{webp,pmtiles,npy,usgs_dem,tile}"]
fn write_reader_fuzz_seeds() {
    let put = |target: &str, name: &str, b: &[u8]| {
        let dir = workspace_root().join("fuzz/corpus").join(target);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join(format!("seed-{name}")), b).unwrap();
    };
    let h4 = real_heights(4);
    let rgb4 = formats::terrarium_rgb(&h4);
    let webp4 = formats::webp_lossless(&rgb4, 4, 4);
    put("read_webp", "valid-terrarium-4x4.webp", &webp4);
    put("read_webp", "truncated.webp", &webp4[..webp4.len() / 2]);
    put(
        "read_webp",
        "valid-terrarium-1x1.webp",
        &formats::webp_lossless(&rgb4[..3], 1, 1),
    );

    let tile = |x, bytes: &[u8]| formats::ArchiveTile {
        z: 2,
        x,
        y: 1,
        bytes: bytes.to_vec(),
    };
    let (archive, _) = formats::pmtiles(
        &[tile(1, &webp4), tile(2, &webp4)],
        4,
        [-90.0, 0.0, 90.0, 66.0],
    );
    put("read_pmtiles", "valid-two-webp-tiles.pmtiles", &archive);
    let (one, _) = formats::pmtiles(&[tile(1, &webp4)], 4, [-90.0, 0.0, 0.0, 66.0]);
    put("read_pmtiles", "valid-one-webp-tile.pmtiles", &one);
    put("read_pmtiles", "header-only.pmtiles", &archive[..127]);

    let npy = formats::npy_f32(&h4, 4, 4);
    put("read_npy", "valid-f32-4x4.npy", &npy);
    let le_i16: Vec<u8> = h4.iter().flat_map(|h| (*h as i16).to_le_bytes()).collect();
    put(
        "read_npy",
        "valid-i2-fortran-4x4.npy",
        &formats::npy("<i2", true, &[4, 4], &le_i16),
    );
    put("read_npy", "scalar.npy", &formats::npy_scalar(1.0));
    put(
        "read_npy",
        "valid-elevation.npz",
        &formats::npz(&[("elevation", npy.clone())]),
    );
    put(
        "read_npy",
        "ambiguous.npz",
        &formats::npz(&[("a", npy.clone()), ("b", npy)]),
    );

    let h5 = real_heights(5);
    put(
        "read_usgs_dem",
        "valid-5x5.dem",
        &formats::usgs_dem(&h5, 5, -72.0, -29.0, 3.0, 5),
    );
    put(
        "read_usgs_dem",
        "profiles-missing.dem",
        &formats::usgs_dem(&h5, 5, -72.0, -29.0, 3.0, 6),
    );

    let png = common::png_bytes(4, 4, png::ColorType::Rgb, png::BitDepth::Eight, &rgb4);
    put("read_tile", "valid-rgb-4x4.png", &png);
    put("read_tile", "valid-terrarium-4x4.webp", &webp4);
}
