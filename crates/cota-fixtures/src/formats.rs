//! Writers of small files in the formats cota reads but that the shared data
//! lacks, built from real heights in a test's set-up: Terrarium tiles (WebP,
//! lossless, by the pure-Rust `image-webp` encoder), PMTiles v3 archives of
//! such tiles, NumPy `.npy`/`.npz` and USGS ASCII DEMs. Each writer follows
//! the format's specification independently of `cota-io`'s readers.

use std::io::Write;

/// Terrarium RGB pixels of `heights` (h + 32768 = R·256 + G + B/256, B
/// rounded); a void becomes 0 m.
pub fn terrarium_rgb(heights: &[f32]) -> Vec<u8> {
    heights
        .iter()
        .flat_map(|&h| {
            let h = if h.is_nan() { 0.0 } else { f64::from(h) };
            let v = ((h + 32768.0) * 256.0).round().clamp(0.0, 16_777_215.0) as u32;
            [(v >> 16) as u8, (v >> 8) as u8, v as u8]
        })
        .collect()
}

/// A lossless WebP of 8-bit RGB pixels.
///
/// # Panics
/// When the encoder fails (bad dimensions): this is for tests.
#[allow(clippy::panic, reason = "test data")]
pub fn webp_lossless(rgb: &[u8], width: u32, height: u32) -> Vec<u8> {
    let mut out = Vec::new();
    image_webp::WebPEncoder::new(&mut out)
        .encode(rgb, width, height, image_webp::ColorType::Rgb8)
        .unwrap_or_else(|e| panic!("webp encoding: {e}"));
    out
}

/// One tile of a PMTiles archive.
#[derive(Debug, Clone)]
pub struct ArchiveTile {
    /// Zoom.
    pub z: u8,
    /// Column.
    pub x: u32,
    /// Row (from the north).
    pub y: u32,
    /// The encoded tile (PNG or WebP).
    pub bytes: Vec<u8>,
}

/// The PMTiles tile id (zoom offset plus Hilbert index) of z/x/y.
pub fn pmtiles_tile_id(z: u8, x: u32, y: u32) -> u64 {
    let n = 1u64 << z;
    let mut id = ((1u64 << (2 * u32::from(z))) - 1) / 3;
    let (mut x, mut y) = (u64::from(x), u64::from(y));
    let mut s = n >> 1;
    while s > 0 {
        let (rx, ry) = (u64::from(x & s != 0), u64::from(y & s != 0));
        id += s * s * ((3 * rx) ^ ry);
        if ry == 0 {
            if rx == 1 {
                (x, y) = (n - 1 - x, n - 1 - y);
            }
            (x, y) = (y, x);
        }
        s >>= 1;
    }
    id
}

/// Appends an unsigned LEB128 varint.
fn varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

/// A PMTiles v3 archive of `tiles` (tile type 2 PNG or 4 WebP, uncompressed
/// tiles), its root directory gzip-compressed; bounds are `bounds_deg`
/// (west, south, east, north). Returns the archive and the byte range of its
/// root directory (for corruption tests).
///
/// # Panics
/// When gzip fails in memory: this is for tests.
#[allow(clippy::panic, reason = "test data")]
pub fn pmtiles(
    tiles: &[ArchiveTile],
    tile_type: u8,
    bounds_deg: [f64; 4],
) -> (Vec<u8>, std::ops::Range<usize>) {
    let mut sorted: Vec<(u64, &ArchiveTile)> = tiles
        .iter()
        .map(|t| (pmtiles_tile_id(t.z, t.x, t.y), t))
        .collect();
    sorted.sort_by_key(|(id, _)| *id);
    let mut dir = Vec::new();
    varint(&mut dir, sorted.len() as u64);
    let mut last = 0;
    for (id, _) in &sorted {
        varint(&mut dir, id - last);
        last = *id;
    }
    sorted.iter().for_each(|_| varint(&mut dir, 1));
    sorted
        .iter()
        .for_each(|(_, t)| varint(&mut dir, t.bytes.len() as u64));
    let mut offset = 0u64;
    for (_, t) in &sorted {
        varint(&mut dir, offset + 1);
        offset += t.bytes.len() as u64;
    }
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    gz.write_all(&dir).unwrap_or_else(|e| panic!("gzip: {e}"));
    let dir = gz.finish().unwrap_or_else(|e| panic!("gzip: {e}"));
    let data: Vec<u8> = sorted.iter().flat_map(|(_, t)| t.bytes.clone()).collect();
    let root_at = 127u64;
    let data_at = root_at + dir.len() as u64;
    let mut h = Vec::with_capacity(127);
    h.extend_from_slice(b"PMTiles\x03");
    for v in [
        root_at,
        dir.len() as u64,
        data_at + data.len() as u64,
        0,
        data_at,
        0,
        data_at,
        data.len() as u64,
    ] {
        h.extend_from_slice(&v.to_le_bytes());
    }
    for v in [sorted.len() as u64; 3] {
        h.extend_from_slice(&v.to_le_bytes());
    }
    let zooms = (
        tiles.iter().map(|t| t.z).min().unwrap_or(0),
        tiles.iter().map(|t| t.z).max().unwrap_or(0),
    );
    h.extend_from_slice(&[1, 2, 1, tile_type, zooms.0, zooms.1]);
    for d in bounds_deg {
        h.extend_from_slice(&((d * 1e7).round() as i32).to_le_bytes());
    }
    h.push(zooms.1);
    for d in [
        (bounds_deg[0] + bounds_deg[2]) / 2.0,
        (bounds_deg[1] + bounds_deg[3]) / 2.0,
    ] {
        h.extend_from_slice(&((d * 1e7).round() as i32).to_le_bytes());
    }
    let range = h.len()..h.len() + dir.len();
    h.extend_from_slice(&dir);
    h.extend_from_slice(&data);
    (h, range)
}

/// A version 1 `.npy` file: `descr` (e.g. `<f4`), C or Fortran order, `shape`
/// and the raw data.
pub fn npy(descr: &str, fortran: bool, shape: &[usize], data: &[u8]) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(ToString::to_string).collect();
    let tuple = match dims.len() {
        1 => format!("({},)", dims[0]),
        _ => format!("({})", dims.join(", ")),
    };
    let order = if fortran { "True" } else { "False" };
    let mut dict = format!("{{'descr': '{descr}', 'fortran_order': {order}, 'shape': {tuple}, }}");
    while (10 + dict.len() + 1) % 64 != 0 {
        dict.push(' ');
    }
    dict.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out.extend_from_slice(data);
    out
}

/// A `.npy` of little-endian f32 heights, `height` rows of `width`.
pub fn npy_f32(heights: &[f32], width: usize, height: usize) -> Vec<u8> {
    let data: Vec<u8> = heights.iter().flat_map(|h| h.to_le_bytes()).collect();
    npy("<f4", false, &[height, width], &data)
}

/// A `.npy` holding one f64 scalar (shape `()`).
pub fn npy_scalar(v: f64) -> Vec<u8> {
    npy("<f8", false, &[], &v.to_le_bytes())
}

/// A `.npz` (deflated ZIP) of `(name, npy bytes)` members.
///
/// # Panics
/// When zip writing fails in memory: this is for tests.
#[allow(clippy::panic, reason = "test data")]
pub fn npz(members: &[(&str, Vec<u8>)]) -> Vec<u8> {
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    for (name, bytes) in members {
        zip.start_file(format!("{name}.npy"), opts)
            .unwrap_or_else(|e| panic!("zip: {e}"));
        zip.write_all(bytes).unwrap_or_else(|e| panic!("zip: {e}"));
    }
    zip.finish()
        .unwrap_or_else(|e| panic!("zip: {e}"))
        .into_inner()
}

/// A USGS ASCII DEM (geographic, arc-seconds, metres, WGS 84) of an n×n
/// SRTM-style grid whose south-west sample is at (`lon`, `lat`) degrees with
/// `step_arcsec` between samples: the type A record, then one profile per
/// column (south to north) in 1024-byte blocks; voids as −32767. `profiles`
/// overrides the count written in the A record (for bad-input tests).
pub fn usgs_dem(
    heights: &[f32],
    n: usize,
    lon: f64,
    lat: f64,
    step_arcsec: f64,
    profiles: usize,
) -> Vec<u8> {
    let mut a = vec![b' '; 1024];
    let mut put = |at: usize, s: &str| a[at - 1..at - 1 + s.len()].copy_from_slice(s.as_bytes());
    put(1, "COTA TEST DEM FROM AN SRTM TILE");
    put(145, &format!("{:>6}{:>6}{:>6}{:>6}", 1, 1, 0, 0));
    put(529, &format!("{:>6}{:>6}{:>6}", 3, 2, 4));
    let (x0, y0) = (lon * 3600.0, lat * 3600.0);
    let side = (n as f64 - 1.0) * step_arcsec;
    let corners = [
        (x0, y0),
        (x0, y0 + side),
        (x0 + side, y0 + side),
        (x0 + side, y0),
    ];
    let mut at = 547;
    for (x, y) in corners {
        put(at, &fortran(x));
        put(at + 24, &fortran(y));
        at += 48;
    }
    put(
        817,
        &format!("{:>12.6E}{:>12.6E}{:>12.6E}", step_arcsec, step_arcsec, 1.0),
    );
    put(853, &format!("{:>6}{:>6}", 1, profiles));
    put(891, &format!("{:>6}", 3));
    let mut out = a;
    for c in 0..n {
        out.extend_from_slice(&profile(heights, n, c, x0 + c as f64 * step_arcsec, y0));
    }
    out
}

/// A Fortran D24.15-style real.
fn fortran(v: f64) -> String {
    format!("{:>24}", format!("{v:.15E}").replace('E', "D"))
}

/// One B record: column `c` of the n×n grid, south to north, in 1024-byte blocks.
fn profile(heights: &[f32], n: usize, c: usize, x: f64, y: f64) -> Vec<u8> {
    let mut head = format!("{:>6}{:>6}{:>6}{:>6}", 1, c + 1, n, 1);
    let col: Vec<f32> = (0..n).rev().map(|r| heights[r * n + c]).collect();
    let valid = col.iter().filter(|h| !h.is_nan());
    let lo = valid.clone().fold(f32::INFINITY, |a, &b| a.min(b));
    let hi = valid.fold(f32::NEG_INFINITY, |a, &b| a.max(b));
    for v in [x, y, 0.0, f64::from(lo), f64::from(hi)] {
        head.push_str(&fortran(v));
    }
    let mut out = Vec::new();
    let mut block = head.into_bytes();
    for h in col {
        let v = if h.is_nan() { -32767 } else { h.round() as i32 };
        let cell = format!("{v:>6}");
        if block.len() + 6 > 1024 {
            block.resize(1024, b' ');
            out.append(&mut block);
        }
        block.extend_from_slice(cell.as_bytes());
    }
    block.resize(1024, b' ');
    out.extend_from_slice(&block);
    out
}
