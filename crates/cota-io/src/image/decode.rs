//! Decoding an image file into bands of 8-bit values: GeoTIFF through the
//! DEM reader's GeoTIFF code (one band at a time, so its layouts,
//! compressions and GeoKeys are all read), PNG through `png`, JPEG through
//! the pure-Rust `zune-jpeg`.
//!
//! Samples that are not 8-bit (16-bit Landsat, floats) are stretched
//! linearly from the smallest to the largest value of the selected bands to
//! 0–255; voids (nodata, NaN) become 0.

use std::path::Path;

use cota_core::GeoRef;

use super::error::ImageErrorKind;
use crate::dem::{DataType, ReadOptions};

/// Largest image read, in pixels (3 bytes each once decoded).
pub const MAX_PIXELS: u64 = 1 << 28;

/// What a file decoded to: every band (8-bit, row-major) and what the file said.
pub(super) struct Decoded {
    pub width: usize,
    pub height: usize,
    /// One `Vec<u8>` per band of the file (only the selected ones for TIFF:
    /// `None` for the others).
    pub bands: Vec<Option<Vec<u8>>>,
    pub georef: Option<GeoRef>,
    pub data_type: &'static str,
}

fn check_size(width: u64, height: u64) -> Result<(), ImageErrorKind> {
    if width.saturating_mul(height) > MAX_PIXELS {
        return Err(ImageErrorKind::TooLarge {
            width,
            height,
            max: MAX_PIXELS,
        });
    }
    Ok(())
}

/// The number of bands of a TIFF.
pub(super) fn tiff_bands(bytes: &[u8]) -> Result<u16, ImageErrorKind> {
    Ok(crate::read::tiff_band_count(bytes)?)
}

/// Reads the 1-based `wanted` bands of a TIFF (others `None`).
pub(super) fn tiff(
    bytes: &[u8],
    path: &Path,
    count: u16,
    wanted: &[u16],
) -> Result<Decoded, ImageErrorKind> {
    let mut bands: Vec<Option<Vec<f32>>> = vec![None; usize::from(count)];
    let mut out = Decoded {
        width: 0,
        height: 0,
        bands: Vec::new(),
        georef: None,
        data_type: "UInt8",
    };
    let mut eight_bit = true;
    for &b in wanted {
        if bands[usize::from(b - 1)].is_some() {
            continue;
        }
        let opts = ReadOptions::DEFAULT.with_band(Some(b));
        let dem = crate::read::read_dem_bytes(bytes, path, &opts).map_err(|e| e.kind)?;
        eight_bit &= dem.data_type == DataType::U8;
        out.data_type = if eight_bit {
            "UInt8"
        } else {
            "stretched to 8 bits"
        };
        out.width = dem.grid.width();
        out.height = dem.grid.height();
        out.georef = dem.grid.georef().known.then(|| dem.grid.georef().clone());
        bands[usize::from(b - 1)] = Some(dem.grid.into_heights());
    }
    out.bands = to_bytes(bands, eight_bit);
    Ok(out)
}

/// f32 bands to bytes: 8-bit values as they are, others stretched.
fn to_bytes(bands: Vec<Option<Vec<f32>>>, eight_bit: bool) -> Vec<Option<Vec<u8>>> {
    let valid = bands.iter().flatten().flatten().filter(|v| v.is_finite());
    let (lo, hi) = valid.fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
        (a.min(v), b.max(v))
    });
    let (lo, scale) = if eight_bit || hi <= lo {
        (0.0, 1.0)
    } else {
        (lo, 255.0 / (hi - lo))
    };
    bands
        .into_iter()
        .map(|b| {
            b.map(|v| {
                v.iter()
                    .map(|&x| {
                        if x.is_finite() {
                            ((x - lo) * scale).round().clamp(0.0, 255.0) as u8
                        } else {
                            0
                        }
                    })
                    .collect()
            })
        })
        .collect()
}

/// Splits interleaved 8-bit samples into bands.
fn deinterleave(data: &[u8], channels: usize) -> Vec<Option<Vec<u8>>> {
    (0..channels)
        .map(|c| Some(data.iter().skip(c).step_by(channels).copied().collect()))
        .collect()
}

/// Decodes a PNG to 8-bit bands (gray, gray+alpha, RGB or RGBA; palettes
/// expanded, 16-bit samples reduced to their high byte).
pub(super) fn png(bytes: &[u8]) -> Result<Decoded, ImageErrorKind> {
    let bad = |e: png::DecodingError| ImageErrorKind::Decode {
        format: "PNG",
        detail: e.to_string(),
    };
    let mut dec = png::Decoder::new(std::io::Cursor::new(bytes));
    dec.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = dec.read_info().map_err(bad)?;
    let (w, h) = (reader.info().width, reader.info().height);
    check_size(u64::from(w), u64::from(h))?;
    let size = reader
        .output_buffer_size()
        .ok_or(ImageErrorKind::TooLarge {
            width: u64::from(w),
            height: u64::from(h),
            max: MAX_PIXELS,
        })?;
    let mut buf = vec![0u8; size];
    let frame = reader.next_frame(&mut buf).map_err(bad)?;
    let channels = frame.color_type.samples();
    buf.truncate(frame.buffer_size());
    Ok(Decoded {
        width: w as usize,
        height: h as usize,
        bands: deinterleave(&buf, channels),
        georef: None,
        data_type: "UInt8",
    })
}

/// Decodes a JPEG to 8-bit RGB (or gray) bands.
pub(super) fn jpeg(bytes: &[u8]) -> Result<Decoded, ImageErrorKind> {
    use zune_core::bytestream::ZCursor;
    use zune_core::options::DecoderOptions;
    let bad = |e: zune_jpeg::errors::DecodeErrors| ImageErrorKind::Decode {
        format: "JPEG",
        detail: e.to_string(),
    };
    let side = 1 << 16;
    let opts = DecoderOptions::default()
        .set_max_width(side)
        .set_max_height(side);
    let mut dec = zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(bytes), opts);
    dec.decode_headers().map_err(bad)?;
    let (w, h) = dec.dimensions().unwrap_or((0, 0));
    check_size(w as u64, h as u64)?;
    let data = dec.decode().map_err(bad)?;
    let channels = data.len().checked_div(w * h).unwrap_or(0);
    if channels == 0 || data.len() != channels * w * h {
        return Err(ImageErrorKind::Decode {
            format: "JPEG",
            detail: format!("{} bytes for {w}x{h} pixels", data.len()),
        });
    }
    Ok(Decoded {
        width: w,
        height: h,
        bands: deinterleave(&data, channels),
        georef: None,
        data_type: "UInt8",
    })
}
