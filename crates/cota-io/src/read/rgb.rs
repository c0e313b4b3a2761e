//! Heights from 8-bit RGB pixels: the two web terrain-tile encodings, shared
//! by the PNG and WebP readers.
//!
//! * Mapbox terrain-RGB: h = −10000 + (R·65536 + G·256 + B)·0.1 m.
//! * Mapzen/AWS Terrarium: h = R·256 + G + B/256 − 32768 m.
//!
//! Without a choice, terrain-RGB is used unless it gives heights no terrain on
//! Earth has (outside [`PLAUSIBLE_M`]) while Terrarium gives plausible ones.
//! A pixel whose alpha is 0 is a void.

use crate::dem::PngEncoding;

/// Heights on Earth: the Dead Sea shore to above Everest, with room for
/// bathymetry down to −12 000 m.
pub(crate) const PLAUSIBLE_M: std::ops::RangeInclusive<f32> = -12_000.0..=9_000.0;

/// True when every valid height lies in [`PLAUSIBLE_M`].
pub(crate) fn plausible(heights: &[f32]) -> bool {
    heights
        .iter()
        .all(|h| h.is_nan() || PLAUSIBLE_M.contains(h))
}

/// Mapbox terrain-RGB: −10000 + (R·65536 + G·256 + B)·0.1 m.
pub(crate) fn terrain_rgb(r: u8, g: u8, b: u8) -> f32 {
    let v = u32::from(r) << 16 | u32::from(g) << 8 | u32::from(b);
    (-10_000.0 + f64::from(v) * 0.1) as f32
}

/// Mapzen Terrarium: R·256 + G + B/256 − 32768 m.
pub(crate) fn terrarium(r: u8, g: u8, b: u8) -> f32 {
    (f64::from(r) * 256.0 + f64::from(g) + f64::from(b) / 256.0 - 32_768.0) as f32
}

/// Heights of RGB (`channels` = 3) or RGBA (4) pixels under `encoding`.
fn heights(buf: &[u8], channels: usize, encoding: PngEncoding) -> Vec<f32> {
    let f = match encoding {
        PngEncoding::Terrarium => terrarium,
        _ => terrain_rgb,
    };
    buf.chunks_exact(channels)
        .map(|p| match p {
            [_, _, _, 0] => f32::NAN,
            [r, g, b, ..] => f(*r, *g, *b),
            _ => f32::NAN,
        })
        .collect()
}

/// Decodes RGB or RGBA pixels with `wanted` (an RGB encoding), or with the
/// plausible one when `wanted` is `None`; returns the heights and the encoding used.
pub(crate) fn decode(
    buf: &[u8],
    channels: usize,
    wanted: Option<PngEncoding>,
) -> (Vec<f32>, PngEncoding) {
    if let Some(e) = wanted {
        return (heights(buf, channels, e), e);
    }
    let rgb = heights(buf, channels, PngEncoding::TerrainRgb);
    if plausible(&rgb) {
        return (rgb, PngEncoding::TerrainRgb);
    }
    let other = heights(buf, channels, PngEncoding::Terrarium);
    if plausible(&other) {
        (other, PngEncoding::Terrarium)
    } else {
        (rgb, PngEncoding::TerrainRgb)
    }
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn encodings() {
        assert_eq!(terrain_rgb(1, 134, 160), 0.0);
        assert_eq!(terrarium(128, 0, 0), 0.0);
        assert_eq!(terrarium(128, 1, 128), 1.5);
    }

    #[test]
    fn picks_the_plausible_encoding() {
        let px = [128u8, 10, 0, 255, 128, 20, 128, 0];
        let (h, e) = decode(&px, 4, None);
        assert_eq!(e, PngEncoding::Terrarium);
        assert_eq!(h[0], 10.0);
        assert!(h[1].is_nan());
        let (_, e) = decode(&[1, 134, 160], 3, None);
        assert_eq!(e, PngEncoding::TerrainRgb);
    }
}
