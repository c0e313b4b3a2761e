//! PNG height images: Mapbox terrain-RGB, Mapzen Terrarium and gray levels.
//!
//! # Format facts this reader relies on
//! * The IHDR chunk gives width, height, colour type and bit depth before any
//!   pixel data, so the dimensions are checked (against the sample limit, and
//!   against what DEFLATE — at most 1032:1 — can expand the file to) before
//!   the pixel buffer is allocated.
//! * Encodings ([`PngEncoding`], chosen by [`ReadOptions::png_encoding`]):
//!   - terrain-RGB: h = −10000 + (R·65536 + G·256 + B)·0.1 m;
//!   - Terrarium: h = R·256 + G + B/256 − 32768 m;
//!   - gray: h = v·`gray_scale_m` + `gray_offset_m`, for 8- and 16-bit gray.
//!
//!   Without a choice, grayscale images are read as gray and RGB/RGBA images
//!   as terrain-RGB, unless terrain-RGB gives heights no terrain on Earth has
//!   (outside −12 000..9 000 m) while Terrarium gives plausible ones: then
//!   Terrarium. The two encodings put the bulk of the value in different
//!   channels, so a real tile is plausible under one and absurd under the other
//!   (a Terrarium tile at 1 000 m reads as ~860 km in terrain-RGB; a terrain-RGB
//!   tile reads as ~−32 000 m in Terrarium). The chosen encoding is reported.
//! * Alpha: a pixel whose alpha is 0 is a void (NaN); other alpha values are
//!   ignored. A `tRNS` chunk counts as alpha (its colour becomes a void).
//! * Not read (an `Unsupported` error): palette images, gray below 8 bits,
//!   16-bit RGB(A) (both RGB encodings are defined on 8-bit channels), and an
//!   encoding that does not fit the image (RGB encodings on gray, gray on RGB).
//! * PNG carries no georeference. A file named as a web tile (`…/z/x/y.png`)
//!   is placed by its Web-Mercator tile bounds (see `tile`); any other gets
//!   [`GeoRef::unreferenced`] with [`ReadOptions::cell_size_m`]. Only the
//!   first frame of an APNG is read.

use std::io::Cursor;
use std::path::Path;

use cota_core::grid::MAX_SAMPLES;
use cota_core::{GeoRef, HeightGrid};
use png::{BitDepth, ColorType, Transformations};

use super::rgb::{plausible, terrain_rgb, terrarium};
use super::tile::georef_for;
use crate::dem::{DataType, Dem, Format, PngEncoding, ReadOptions};
use crate::error::{malformed, ReadErrorKind};

/// Largest expansion ratio of DEFLATE.
const MAX_DEFLATE_RATIO: u64 = 1032;

/// Decodes a PNG height image.
pub(crate) fn decode(bytes: &[u8], path: &Path, opts: &ReadOptions) -> Result<Dem, ReadErrorKind> {
    let mut decoder = png::Decoder::new(Cursor::new(bytes));
    // EXPAND turns a tRNS chunk into an alpha channel (palettes are refused).
    decoder.set_transformations(Transformations::EXPAND);
    let info = decoder.read_header_info().map_err(bad_png)?;
    let (width, height) = (info.width, info.height);
    check_layout(info.color_type, info.bit_depth)?;
    check_size(
        width,
        height,
        info.color_type,
        info.bit_depth,
        bytes.len(),
        opts,
    )?;
    let encoding = choose_encoding(opts.png_encoding, info.color_type, info.bit_depth)?;
    let mut reader = decoder.read_info().map_err(bad_png)?;
    let len = reader
        .output_buffer_size()
        .ok_or_else(|| too_large_png(width, height))?;
    let mut buf = crate::limits::try_vec(len, &format!("the {width}x{height} image's pixels"))?;
    buf.resize(len, 0u8);
    let out = reader.next_frame(&mut buf).map_err(bad_png)?;
    let used = buf.get(..out.buffer_size()).unwrap_or(&buf);
    let mut encoding = encoding;
    let mut heights = to_heights(used, out.color_type, out.bit_depth, encoding, opts)?;
    if opts.png_encoding.is_none() && encoding == PngEncoding::TerrainRgb && !plausible(&heights) {
        let other = to_heights(
            used,
            out.color_type,
            out.bit_depth,
            PngEncoding::Terrarium,
            opts,
        )?;
        if plausible(&other) {
            heights = other;
            encoding = PngEncoding::Terrarium;
        }
    }
    let (w, h) = (out.width as usize, out.height as usize);
    let georef = georef_for(path, w, h).unwrap_or_else(|| GeoRef::unreferenced(opts.cell_size_m));
    let grid = HeightGrid::new(w, h, heights, georef)?;
    Ok(Dem {
        grid,
        format: Format::Png(encoding),
        data_type: data_type(out.color_type, out.bit_depth),
        nodata: None,
        path: path.to_path_buf(),
    })
}

/// Wraps a decoder error.
fn bad_png(e: png::DecodingError) -> ReadErrorKind {
    malformed("a valid PNG", format!("a decoding error: {e}"))
}

/// The error for an image too large to hold.
fn too_large_png(width: u32, height: u32) -> ReadErrorKind {
    ReadErrorKind::TooLarge {
        width: u64::from(width),
        height: u64::from(height),
        max: MAX_SAMPLES,
    }
}

/// Refuses colour types and depths that do not hold heights.
fn check_layout(color: ColorType, depth: BitDepth) -> Result<(), ReadErrorKind> {
    let unsupported = |detail: String| ReadErrorKind::Unsupported {
        what: "PNG layout".into(),
        detail,
    };
    match (color, depth) {
        (ColorType::Indexed, _) => Err(unsupported(
            "a palette (indexed-colour) image; cota reads 8/16-bit gray, 8-bit RGB and RGBA".into(),
        )),
        (ColorType::Grayscale | ColorType::GrayscaleAlpha, BitDepth::Eight | BitDepth::Sixteen) => {
            Ok(())
        }
        (ColorType::Rgb | ColorType::Rgba, BitDepth::Eight) => Ok(()),
        (c, d) => Err(unsupported(format!(
            "{} {c:?} image; cota reads 8/16-bit gray, 8-bit RGB and RGBA",
            depth_name(d)
        ))),
    }
}

/// "8-bit" and the like.
fn depth_name(d: BitDepth) -> String {
    format!("{}-bit", d as u8)
}

/// Checks the header dimensions before anything is allocated: the sample
/// limit, and whether the file is large enough to hold that many pixels.
fn check_size(
    width: u32,
    height: u32,
    color: ColorType,
    depth: BitDepth,
    file_len: usize,
    opts: &ReadOptions,
) -> Result<(), ReadErrorKind> {
    crate::limits::check(u64::from(width), u64::from(height), opts)?;
    let bits_per_pixel = color.samples() as u64 * depth as u64;
    let row = 1 + (u64::from(width) * bits_per_pixel).div_ceil(8);
    let raw = row.saturating_mul(u64::from(height));
    let possible = (file_len as u64).saturating_mul(MAX_DEFLATE_RATIO);
    if raw > possible {
        return Err(malformed(
            format!(
                "a PNG of at least {} bytes for {width}x{height} pixels (DEFLATE packs at most {MAX_DEFLATE_RATIO}:1)",
                raw.div_ceil(MAX_DEFLATE_RATIO)
            ),
            format!("a file of {file_len} bytes"),
        ));
    }
    Ok(())
}

/// The encoding to use: the requested one if it fits the image, else the
/// default for the colour type.
fn choose_encoding(
    wanted: Option<PngEncoding>,
    color: ColorType,
    depth: BitDepth,
) -> Result<PngEncoding, ReadErrorKind> {
    let gray = matches!(color, ColorType::Grayscale | ColorType::GrayscaleAlpha);
    match (wanted, gray) {
        (None, true) => Ok(PngEncoding::Gray16),
        (None, false) => Ok(PngEncoding::TerrainRgb),
        (Some(PngEncoding::Gray16), true) => Ok(PngEncoding::Gray16),
        (Some(e @ (PngEncoding::TerrainRgb | PngEncoding::Terrarium)), false) => Ok(e),
        (Some(e), _) => Err(ReadErrorKind::Unsupported {
            what: format!("PNG encoding {e}"),
            detail: format!(
                "it needs {} image, this one is {} {color:?}",
                if gray {
                    "an RGB or RGBA"
                } else {
                    "a grayscale"
                },
                depth_name(depth)
            ),
        }),
    }
}

/// The data type reported for the decoded layout.
fn data_type(color: ColorType, depth: BitDepth) -> DataType {
    match (color, depth) {
        (ColorType::Rgb | ColorType::Rgba, _) => DataType::Rgb8,
        (_, BitDepth::Sixteen) => DataType::U16,
        _ => DataType::U8,
    }
}

/// Converts decoded pixels to heights.
fn to_heights(
    buf: &[u8],
    color: ColorType,
    depth: BitDepth,
    encoding: PngEncoding,
    opts: &ReadOptions,
) -> Result<Vec<f32>, ReadErrorKind> {
    let (scale, offset) = (opts.gray_scale_m, opts.gray_offset_m);
    let gray = |v: u16| (f64::from(v) * scale + offset) as f32;
    let rgb = match encoding {
        PngEncoding::Terrarium => terrarium,
        _ => terrain_rgb,
    };
    let heights = match (color, depth) {
        (ColorType::Grayscale, BitDepth::Eight) => map_pixels(buf, |[v]| gray(v.into())),
        (ColorType::Grayscale, BitDepth::Sixteen) => {
            map_pixels(buf, |v: [u8; 2]| gray(u16::from_be_bytes(v)))
        }
        (ColorType::GrayscaleAlpha, BitDepth::Eight) => {
            map_pixels(buf, |[v, a]| if a == 0 { f32::NAN } else { gray(v.into()) })
        }
        (ColorType::GrayscaleAlpha, BitDepth::Sixteen) => map_pixels(buf, |[v0, v1, a0, a1]| {
            if a0 | a1 == 0 {
                f32::NAN
            } else {
                gray(u16::from_be_bytes([v0, v1]))
            }
        }),
        (ColorType::Rgb, BitDepth::Eight) => map_pixels(buf, |[r, g, b]| rgb(r, g, b)),
        (ColorType::Rgba, BitDepth::Eight) => {
            map_pixels(
                buf,
                |[r, g, b, a]| if a == 0 { f32::NAN } else { rgb(r, g, b) },
            )
        }
        (c, d) => {
            return Err(ReadErrorKind::Unsupported {
                what: "PNG layout".into(),
                detail: format!("decoded {} {c:?} pixels", depth_name(d)),
            })
        }
    };
    Ok(heights)
}

/// Maps every N-byte pixel of `buf` to a height.
fn map_pixels<const N: usize>(buf: &[u8], f: impl Fn([u8; N]) -> f32) -> Vec<f32> {
    let (pixels, _) = buf.as_chunks::<N>();
    pixels.iter().map(|&p| f(p)).collect()
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn size_guard() {
        let e = check_size(
            40_000,
            40_000,
            ColorType::Rgba,
            BitDepth::Eight,
            100,
            &ReadOptions::DEFAULT.with_max_samples(Some(MAX_SAMPLES)),
        )
        .unwrap_err();
        assert!(e.to_string().contains("a file of 100 bytes"), "{e}");
        assert!(check_size(
            256,
            256,
            ColorType::Rgb,
            BitDepth::Eight,
            200,
            &ReadOptions::DEFAULT
        )
        .is_ok());
        let e = check_size(
            u32::MAX,
            u32::MAX,
            ColorType::Rgb,
            BitDepth::Eight,
            100,
            &ReadOptions::DEFAULT,
        )
        .unwrap_err();
        assert!(matches!(e, ReadErrorKind::TooLarge { .. }), "{e}");
    }
}
