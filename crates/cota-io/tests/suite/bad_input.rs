//! Bad input for the SRTM, ESRI ASCII and PNG readers and for format
//! detection: every case must return an error (never panic) whose one-line
//! message names the file and says what was expected and what was found.
//! The bad files are generated in a temporary directory.
// Test helpers outside #[test] functions unwrap and panic like the tests do.
#![allow(clippy::unwrap_used, clippy::panic)]

use crate::common;

use std::path::{Path, PathBuf};

use common::{assert_contains, fixture, hgt_bytes, png_bytes, write_file, zip_bytes};
use cota_io::{read_dem, PngEncoding, ReadErrorKind, ReadOptions};

/// Reads `path`, expecting an error; returns its message after checking that
/// it is one line and names the file.
fn error_of(path: &Path, opts: &ReadOptions) -> (String, ReadErrorKind) {
    let err = match read_dem(path, opts) {
        Ok(dem) => panic!("{} read as {:?}", path.display(), dem.format),
        Err(e) => e,
    };
    let msg = err.to_string();
    eprintln!("{msg}");
    let name = path.file_name().unwrap().to_string_lossy();
    assert!(msg.contains(&*name), "{msg:?} does not name {name}");
    assert!(!msg.contains('\n'), "{msg:?} is not one line");
    assert_eq!(err.path, path);
    (msg, err.kind)
}

fn error(path: &Path) -> String {
    error_of(path, &ReadOptions::DEFAULT).0
}

/// Deterministic noise that starts with no known magic.
fn noise(len: usize) -> Vec<u8> {
    let mut x: u32 = 0x2545_f491;
    let mut v: Vec<u8> = (0..len)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 24) as u8
        })
        .collect();
    if let Some(b) = v.first_mut() {
        *b = 0xde;
    }
    v
}

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

#[test]
fn odd_sized_and_truncated_hgt() {
    let dir = tmp();
    let p = write_file(dir.path(), "N10E010.hgt", &[0u8; 1001]);
    assert_contains(
        &error(&p),
        &["expected 2·n² bytes", "2884802", "found 1001 bytes"],
    );
    // A standard tile that lost its last sample.
    let p = write_file(dir.path(), "N00E010.hgt", &vec![0u8; 2 * 1201 * 1201 - 2]);
    assert_contains(
        &error(&p),
        &["expected 2·n²", "found 2884800 bytes", "2884802 for 1201²"],
    );
    // A single sample is not a tile (n ≥ 2).
    let p = write_file(dir.path(), "N10E011.hgt", &[0, 1]);
    assert_contains(&error(&p), &["found 2 bytes", "8 for 2²"]);
}

#[test]
fn empty_files() {
    let dir = tmp();
    for name in [
        "N00E010.hgt",
        "N00E010.hgt.zip",
        "x.png",
        "x.asc",
        "x.tif",
        "x",
    ] {
        let p = write_file(dir.path(), name, b"");
        let (msg, kind) = error_of(&p, &ReadOptions::DEFAULT);
        assert!(matches!(kind, ReadErrorKind::Empty), "{msg}");
        assert_contains(&msg, &["expected a DEM", "empty file"]);
    }
}

#[test]
fn random_bytes_with_a_dem_extension() {
    let dir = tmp();
    let bytes = noise(1000);
    let p = write_file(dir.path(), "S10W020.hgt", &bytes);
    assert_contains(&error(&p), &["expected 2·n² bytes", "found 1000 bytes"]);
    for (name, hint) in [
        ("x.tif", "not a TIFF"),
        ("x.tiff", "not a TIFF"),
        ("x.png", "not a PNG"),
        ("x.asc", "not an ESRI ASCII grid"),
        ("x.hgt.zip", "not a ZIP"),
        ("x.dem", "found bytes de"),
    ] {
        let p = write_file(dir.path(), name, &bytes);
        let (msg, kind) = error_of(&p, &ReadOptions::DEFAULT);
        assert!(matches!(kind, ReadErrorKind::UnknownFormat { .. }), "{msg}");
        assert_contains(
            &msg,
            &[
                "expected an SRTM .hgt",
                "found bytes de",
                "(1000 bytes)",
                hint,
            ],
        );
    }
}

#[test]
fn text_named_png() {
    let dir = tmp();
    let p = write_file(dir.path(), "tile.png", b"<html>Not Found</html>\n");
    assert_contains(
        &error(&p),
        &[
            "expected",
            "PNG",
            "found text starting \"<html>Not Found</html>\"",
            "not a PNG",
        ],
    );
}

#[test]
fn asc_with_fewer_values_than_promised() {
    let dir = tmp();
    let head = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n";
    let p = write_file(
        dir.path(),
        "short.asc",
        format!("{head}1 2 3\n4\n").as_bytes(),
    );
    assert_contains(
        &error(&p),
        &["expected 6 values", "3 columns × 2 rows", "found 4"],
    );
    let p = write_file(
        dir.path(),
        "long.asc",
        format!("{head}1 2 3\n4 5 6\n7\n").as_bytes(),
    );
    assert_contains(
        &error(&p),
        &["expected 6 values", "found 7", "\"7\" on line 8"],
    );
    let p = write_file(
        dir.path(),
        "word.asc",
        format!("{head}1 2 3\n4 five 6\n").as_bytes(),
    );
    assert_contains(
        &error(&p),
        &[
            "expected a finite number",
            "column 1, row 1",
            "found \"five\" on line 7",
        ],
    );
    let p = write_file(dir.path(), "nohead.asc", b"ncols 3\nnrows 2\n1 2 3 4 5 6\n");
    assert_contains(&error(&p), &["expected the header key", "xllcorner"]);
    let p = write_file(dir.path(), "badkey.asc", b"ncols three\nnrows 2\n");
    assert_contains(
        &error(&p),
        &[
            "expected a number after the header key ncols",
            "\"three\" on line 1",
        ],
    );
}

#[test]
fn missing_file() {
    let dir = tmp();
    let p = dir.path().join("N00E010.hgt");
    assert_contains(&error(&p), &["cannot read the file"]);
}

#[test]
fn asc_with_absurd_dimensions() {
    let dir = tmp();
    let tail = "xllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n";
    let text = format!("ncols 100000000\nnrows 100000000\n{tail}");
    let p = write_file(dir.path(), "huge.asc", text.as_bytes());
    let (msg, kind) = error_of(&p, &ReadOptions::DEFAULT);
    assert!(matches!(kind, ReadErrorKind::TooLarge { .. }), "{msg}");
    assert_contains(
        &msg,
        &["too large", "over the limit of", "100000000x100000000"],
    );
    // Within the limit but far beyond the file: counted, not allocated.
    let text = format!("ncols 40000\nnrows 40000\n{tail}");
    let p = write_file(dir.path(), "big.asc", text.as_bytes());
    let all = ReadOptions::DEFAULT.with_max_samples(Some(cota_core::grid::MAX_SAMPLES));
    assert_contains(
        &error_of(&p, &all).0,
        &["expected 1600000000 values", "found 3"],
    );
}

/// A CRC-32 (ISO-HDLC), for hand-made PNG chunks.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// A PNG signature and IHDR chunk claiming `w`×`h` RGB pixels, then IEND.
fn png_header_only(w: u32, h: u32) -> Vec<u8> {
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut chunk = |kind: &[u8], data: &[u8]| {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        out.extend_from_slice(&body);
        out.extend_from_slice(&crc32(&body).to_be_bytes());
    };
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&w.to_be_bytes());
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]); // 8-bit RGB, deflate, no filter, no interlace
    chunk(b"IHDR", &ihdr);
    chunk(b"IEND", &[]);
    out
}

#[test]
fn png_with_absurd_dimensions() {
    let dir = tmp();
    let p = write_file(dir.path(), "huge.png", &png_header_only(100_000, 100_000));
    let (msg, kind) = error_of(&p, &ReadOptions::DEFAULT);
    assert!(matches!(kind, ReadErrorKind::TooLarge { .. }), "{msg}");
    assert_contains(&msg, &["too large", "over the limit of", "100000x100000"]);
    let p = write_file(dir.path(), "big.png", &png_header_only(40_000, 40_000));
    let all = ReadOptions::DEFAULT.with_max_samples(Some(cota_core::grid::MAX_SAMPLES));
    assert_contains(
        &error_of(&p, &all).0,
        &["40000x40000 pixels", "found a file of 45 bytes"],
    );
}

#[test]
fn damaged_and_unsupported_pngs() {
    let dir = tmp();
    let good = std::fs::read(fixture("terrarium.png")).unwrap();
    let p = write_file(dir.path(), "cut.png", good.get(..good.len() / 2).unwrap());
    assert_contains(
        &error(&p),
        &["expected a valid PNG", "found a decoding error"],
    );

    let mut pal = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut pal, 1, 1);
        enc.set_color(png::ColorType::Indexed);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_palette(vec![1, 2, 3]);
        enc.write_header().unwrap().write_image_data(&[0]).unwrap();
    }
    let p = write_file(dir.path(), "pal.png", &pal);
    let (msg, kind) = error_of(&p, &ReadOptions::DEFAULT);
    assert!(matches!(kind, ReadErrorKind::Unsupported { .. }), "{msg}");
    assert_contains(&msg, &["palette"]);

    let gray = png_bytes(1, 1, png::ColorType::Grayscale, png::BitDepth::Four, &[0]);
    let p = write_file(dir.path(), "g4.png", &gray);
    assert_contains(&error(&p), &["unsupported", "4-bit"]);

    let rgb = png_bytes(1, 1, png::ColorType::Rgb, png::BitDepth::Eight, &[1, 2, 3]);
    let p = write_file(dir.path(), "rgb.png", &rgb);
    let opts = ReadOptions::DEFAULT.with_png_encoding(Some(PngEncoding::Gray16));
    assert_contains(&error_of(&p, &opts).0, &["gray16", "grayscale", "Rgb"]);
}

fn zip_case(dir: &Path, name: &str, members: &[(&str, &[u8])]) -> PathBuf {
    write_file(dir, name, &zip_bytes(members))
}

#[test]
fn zips_without_one_good_hgt() {
    let dir = tmp();
    let tile = hgt_bytes(&[0; 9]);
    let p = zip_case(
        dir.path(),
        "N00E010.hgt.zip",
        &[("readme.txt", b"hi"), ("N00E010.tif", b"x")],
    );
    assert_contains(
        &error(&p),
        &[
            "expected a ZIP archive holding one SRTM .hgt tile",
            "no .hgt member among 2 members (\"readme.txt\", \"N00E010.tif\")",
        ],
    );
    let p = zip_case(dir.path(), "two.zip", &[("a.hgt", &tile), ("b.HGT", &tile)]);
    assert_contains(&error(&p), &["found 2 .hgt members (\"a.hgt\", \"b.HGT\")"]);
    let p = zip_case(dir.path(), "odd.hgt.zip", &[("N00E010.hgt", &[0u8; 7])]);
    assert_contains(
        &error(&p),
        &[
            "expected 2·n² bytes",
            "found 7 bytes declared for ZIP member N00E010.hgt",
        ],
    );
    let p = zip_case(dir.path(), "none.zip", &[]);
    assert_contains(&error(&p), &["no .hgt member among 0 members"]);

    let good = std::fs::read(fixture("S29W072.hgt.zip")).unwrap();
    let p = write_file(
        dir.path(),
        "S29W072.hgt.zip",
        good.get(..good.len() / 2).unwrap(),
    );
    assert_contains(
        &error(&p),
        &["expected a ZIP archive", "found an unreadable ZIP archive"],
    );
}

/// Replaces the 4-byte little-endian field at `offset` after each `signature`.
fn patch_u32_after(bytes: &mut [u8], signature: &[u8], offset: usize, value: u32) {
    let starts: Vec<usize> = bytes
        .windows(signature.len())
        .enumerate()
        .filter(|(_, w)| *w == signature)
        .map(|(i, _)| i)
        .collect();
    assert!(!starts.is_empty());
    for s in starts {
        bytes[s + offset..s + offset + 4].copy_from_slice(&value.to_le_bytes());
    }
}

#[test]
fn zips_with_forged_sizes() {
    let dir = tmp();
    let tile = hgt_bytes(&[5; 9]);
    // Declared 2·46000² bytes (a 46000² tile) from an archive of ~150 bytes.
    let mut z = zip_bytes(&[("N00E010.hgt", &tile)]);
    let forged = 2 * 46_000u32 * 46_000;
    patch_u32_after(&mut z, b"PK\x03\x04", 22, forged);
    patch_u32_after(&mut z, b"PK\x01\x02", 24, forged);
    let p = write_file(dir.path(), "bomb.hgt.zip", &z);
    assert_contains(
        &error(&p),
        &["too large", "46000x46000", "over the limit of"],
    );
    let all = ReadOptions::DEFAULT.with_max_samples(Some(cota_core::grid::MAX_SAMPLES));
    assert_contains(
        &error_of(&p, &all).0,
        &["expected at most", "found 4232000000 bytes declared"],
    );
    // Declared a 5×5 tile, holding a 3×3 one.
    let mut z = zip_bytes(&[("N00E010.hgt", &tile)]);
    patch_u32_after(&mut z, b"PK\x03\x04", 22, 50);
    patch_u32_after(&mut z, b"PK\x01\x02", 24, 50);
    let p = write_file(dir.path(), "liar.hgt.zip", &z);
    let msg = error(&p);
    assert_contains(&msg, &["expected", "N00E010.hgt"]);
}

/// A file larger than any DEM within the sample limit is refused from its
/// size, before it is read: the message names the file, its size and the
/// limit. (The file is sparse: 8 GiB on disk cost nothing, and reading it
/// whole would need 8 GiB of memory.)
#[test]
fn file_over_the_byte_budget_is_refused_unread() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("huge.tif");
    let f = std::fs::File::create(&path).unwrap();
    if f.set_len(8 << 30).is_err() {
        eprintln!("skipped: this file system refuses an 8 GiB sparse file");
        return;
    }
    let opts = ReadOptions::DEFAULT.with_max_samples(Some(1_000_000));
    let t0 = std::time::Instant::now();
    let (msg, kind) = error_of(&path, &opts);
    assert!(matches!(kind, ReadErrorKind::FileTooLarge { .. }), "{msg}");
    assert_contains(
        &msg,
        &[
            "too large",
            "8589934592 bytes",
            "1000000 samples",
            "--max-samples",
        ],
    );
    assert!(t0.elapsed() < std::time::Duration::from_secs(2), "{msg}");
}

/// A reader that counts the bytes taken from it: a stand-in for a device,
/// a pipe or a file that grows, whose size says nothing.
struct Counted<R> {
    inner: R,
    read: u64,
}

impl<R: std::io::Read> std::io::Read for Counted<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.read += n as u64;
        Ok(n)
    }
}

// Issue 31: `cota info /dev/zero` grew to 9 GB and 3 GB on standard input
// were held whole before refusal. Readers stop at the limit while reading.
#[test]
fn endless_inputs_stop_at_the_limit_while_reading() {
    use std::io::Read;
    // No magic number: only a raw .hgt, so one 3601² tile at most.
    let mut zeros = Counted {
        inner: std::io::repeat(0),
        read: 0,
    };
    let e = cota_io::read_dem_from(&mut zeros, Path::new("<stdin>"), &ReadOptions::DEFAULT)
        .unwrap_err()
        .to_string();
    assert!(e.contains("longer than a raw .hgt"), "{e}");
    assert_eq!(zeros.read, cota_io::limits::HGT_MAX_BYTES + 1);
    // A format with a magic number: its byte limit from the sample limit.
    let opts = ReadOptions::DEFAULT.with_max_samples(Some(1000));
    let head = png_header_only(10, 10);
    let mut png = Counted {
        inner: head.as_slice().chain(std::io::repeat(0)),
        read: 0,
    };
    let e = cota_io::read_dem_from(&mut png, Path::new("x.png"), &opts).unwrap_err();
    assert!(matches!(e.kind, ReadErrorKind::FileTooLarge { .. }), "{e}");
    assert_eq!(png.read, cota_io::limits::max_file_bytes(&opts) + 1);
    #[cfg(target_os = "linux")]
    {
        let t = std::time::Instant::now();
        let e = read_dem(Path::new("/dev/zero"), &ReadOptions::DEFAULT).unwrap_err();
        assert!(e.to_string().starts_with("/dev/zero: "), "{e}");
        assert!(t.elapsed().as_secs() < 10);
    }
}

#[test]
fn capped_file_reads_say_too_large() {
    let dir = tmp();
    let f = dir.path().join("big.bin");
    std::fs::write(&f, vec![7u8; 100]).unwrap();
    assert_eq!(
        cota_io::limits::read_file_capped(&f, 100).unwrap().len(),
        100
    );
    let e = cota_io::limits::read_file_capped(&f, 99).unwrap_err();
    assert_eq!(e.kind(), std::io::ErrorKind::FileTooLarge);
}
