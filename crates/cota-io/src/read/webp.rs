//! WebP height images: terrain-RGB and Terrarium web tiles (Mapterhorn
//! publishes Terrarium WebP tiles of 512×512), lossless or lossy.
//!
//! # Format facts this reader relies on
//! * A WebP file is a RIFF container: `RIFF`, a 32-bit size, `WEBP`, then a
//!   `VP8 ` (lossy), `VP8L` (lossless) or `VP8X` (extended) chunk. The
//!   dimensions are in the first chunk, at most 16 383 × 16 383, so they are
//!   checked against the sample limit before the pixels are allocated, and
//!   against the file's size: lossless WebP codes a uniform image in no bits
//!   per pixel, so a tiny file may claim a quarter of a billion pixels; more
//!   than 1,024 pixels per byte of file (past 2²⁴) is refused as a bomb.
//!   Decoding is `image-webp` (pure Rust).
//! * Pixels are 8-bit RGB or RGBA and decoded with the encodings of `rgb`
//!   ([`ReadOptions::png_encoding`]; without one, the plausible encoding).
//!   A pixel whose alpha is 0 is a void.
//! * Lossy WebP (VP8) stores YUV 4:2:0 and changes pixel values. Terrarium
//!   puts 256 m in one step of R and 1 m in one step of G, so lossy coding
//!   ruins it: `cwebp -q 90` (libwebp 1.2.4) of `fixtures/terrarium.png`
//!   decodes, here and with libwebp's own `dwebp` alike (the same range,
//!   −25 028..32 686 m), to heights off by a median of 1 799 m. Lossy tiles
//!   are read, not refused; only lossless tiles give the encoder's heights
//!   (bit-identical to the PNG's, tested).
//! * Only the first frame of an animation is read.
//! * WebP carries no georeference: a file named `…/z/x/y.webp` is placed by
//!   its Web-Mercator tile bounds (`tile`), any other gets
//!   [`GeoRef::unreferenced`] with [`ReadOptions::cell_size_m`].

use std::io::Cursor;
use std::path::Path;

use cota_core::{GeoRef, HeightGrid};
use image_webp::WebPDecoder;

use super::tile::georef_for;
use crate::dem::{DataType, Dem, Format, PngEncoding, ReadOptions};
use crate::error::{malformed, ReadErrorKind};

/// True when `bytes` open like a WebP file.
pub(crate) fn is_webp(bytes: &[u8]) -> bool {
    bytes.len() >= 12 && bytes.starts_with(b"RIFF") && &bytes[8..12] == b"WEBP"
}

/// Decodes a WebP height image.
pub(crate) fn decode(bytes: &[u8], path: &Path, opts: &ReadOptions) -> Result<Dem, ReadErrorKind> {
    let (buf, w, h, channels) = decode_pixels(bytes, opts)?;
    let (heights, encoding) = heights(&buf, channels, opts.png_encoding)?;
    let georef = georef_for(path, w, h).unwrap_or_else(|| GeoRef::unreferenced(opts.cell_size_m));
    let grid = HeightGrid::new(w, h, heights, georef)?;
    Ok(Dem {
        grid,
        format: Format::WebP(encoding),
        data_type: DataType::Rgb8,
        nodata: None,
        path: path.to_path_buf(),
    })
}

/// Heights of the pixels under the requested (RGB) encoding.
fn heights(
    buf: &[u8],
    channels: usize,
    wanted: Option<PngEncoding>,
) -> Result<(Vec<f32>, PngEncoding), ReadErrorKind> {
    if wanted == Some(PngEncoding::Gray16) {
        return Err(ReadErrorKind::Unsupported {
            what: "WebP encoding gray16".into(),
            detail: "WebP holds 8-bit colour; use terrain-rgb or terrarium".into(),
        });
    }
    Ok(super::rgb::decode(buf, channels, wanted))
}

/// Decodes the first frame: pixels, width, height and channels (3 or 4).
fn decode_pixels(
    bytes: &[u8],
    opts: &ReadOptions,
) -> Result<(Vec<u8>, usize, usize, usize), ReadErrorKind> {
    check_riff_size(bytes)?;
    let mut dec = WebPDecoder::new(Cursor::new(bytes)).map_err(bad_webp)?;
    let (w, h) = dec.dimensions();
    crate::limits::check(u64::from(w), u64::from(h), opts)?;
    check_ratio(u64::from(w) * u64::from(h), bytes.len())?;
    let channels = if dec.has_alpha() { 4 } else { 3 };
    let len = dec.output_buffer_size().ok_or(ReadErrorKind::TooLarge {
        width: u64::from(w),
        height: u64::from(h),
        max: cota_core::grid::MAX_SAMPLES,
    })?;
    let mut buf = vec![0u8; len];
    dec.read_image(&mut buf).map_err(bad_webp)?;
    Ok((buf, w as usize, h as usize, channels))
}

/// Pixels a WebP file may hold whatever its size (a 4096 × 4096 tile).
const FREE_PIXELS: u64 = 1 << 24;

/// Pixels a WebP file may hold per byte of file beyond [`FREE_PIXELS`]:
/// about zlib's bound (1,032 bytes out per byte in, so PNG and GeoTIFF
/// bombs stay within it).
const PIXELS_PER_BYTE: u64 = 1024;

/// Refuses a decompression bomb before the pixels are allocated: lossless
/// WebP codes a uniform image in no bits per pixel, so 34 bytes may claim
/// 16 129 × 15 340 pixels (found by the fuzzer: 6 s and 2.7 GB to decode
/// and refuse). Real terrain tiles hold a few pixels per byte; a flat one
/// fits in [`FREE_PIXELS`].
fn check_ratio(pixels: u64, file_bytes: usize) -> Result<(), ReadErrorKind> {
    let allowed = FREE_PIXELS.max(PIXELS_PER_BYTE.saturating_mul(file_bytes as u64));
    if pixels <= allowed {
        return Ok(());
    }
    Err(malformed(
        format!(
            "at most {allowed} pixels in a WebP file of {file_bytes} bytes ({PIXELS_PER_BYTE} per byte, {FREE_PIXELS} at least)"
        ),
        format!("{pixels} pixels in its header: a decompression bomb"),
    ))
}

/// Refuses a file shorter than its RIFF header says (a truncated download).
fn check_riff_size(bytes: &[u8]) -> Result<(), ReadErrorKind> {
    let declared = bytes
        .get(4..8)
        .map(|b| u64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])) + 8);
    match declared {
        Some(d) if d <= bytes.len() as u64 => Ok(()),
        Some(d) => Err(malformed(
            format!("a valid WebP image of {d} bytes (its RIFF header's size)"),
            format!("{} bytes: the file is truncated", bytes.len()),
        )),
        None => Err(malformed("a valid WebP image", "a truncated RIFF header")),
    }
}

/// Wraps a decoder error.
fn bad_webp(e: image_webp::DecodingError) -> ReadErrorKind {
    malformed("a valid WebP image", format!("a decoding error: {e}"))
}
