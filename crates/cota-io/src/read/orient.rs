//! Grid orientation shared by the readers: every [`cota_core::HeightGrid`]
//! has row 0 to the north and column 0 to the west. A file whose georeference
//! says otherwise (a GeoTIFF with a positive y scale, a NumPy archive whose
//! `y` coordinates run south to north) is flipped on reading, its
//! georeference adjusted, so it lands where its own coordinates say.

use cota_core::{GeoRef, PixelIs};

/// Flips a grid stored south-up (pixel_y > 0) or east-to-west (pixel_x < 0)
/// so that row 0 is north and column 0 west, adjusting the origin.
pub(crate) fn north_up(heights: &mut [f32], width: usize, height: usize, g: &mut GeoRef) {
    if width == 0 || heights.len() != width * height {
        return;
    }
    let span = |n: usize| match g.pixel_is {
        PixelIs::Area => n as f64,
        PixelIs::Point => n as f64 - 1.0,
    };
    if g.pixel_y > 0.0 {
        for r in 0..height / 2 {
            let (top, bottom) = heights.split_at_mut((height - 1 - r) * width);
            // Both rows are `width` long: `bottom` starts at row height-1-r > r.
            if let (Some(a), Some(b)) = (
                top.get_mut(r * width..(r + 1) * width),
                bottom.get_mut(..width),
            ) {
                a.swap_with_slice(b);
            }
        }
        g.origin_y += span(height) * g.pixel_y;
        g.pixel_y = -g.pixel_y;
    }
    if g.pixel_x < 0.0 {
        heights.chunks_mut(width).for_each(<[f32]>::reverse);
        g.origin_x += span(width) * g.pixel_x;
        g.pixel_x = -g.pixel_x;
    }
}
