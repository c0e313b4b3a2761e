//! The clamp-to-edge extension of a grid whose span is odd (web tiles: 256
//! or 512 samples wide), so that its hierarchy meets no unit-resolution
//! border.
//!
//! The bitree of paper `000_ebf7e3a88dffd361.txt` §2 lives on a `2^k + 1`
//! square; cota pads any grid to the smallest one and clips
//! ([`crate::hierarchy`]), which meshes the east and south borders at the
//! largest power of two dividing `W − 1` (`H − 1`): one sample when the span
//! is odd. Martini (Agafonkin 2019, <https://github.com/mapbox/martini>)
//! meshes a 256² tile as a 257² grid whose last row and column repeat the
//! tile's. cota does the same on the side that needs it
//! ([`extended_size`]), builds the hierarchy on the extended grid, and then
//! clips the mesh back to the real rectangle ([`crate::mesh::clip`]), so the
//! output covers exactly the real samples and the bound is proved on them.

use super::HeightGrid;

/// The size of the extended grid for a `width × height` grid, or `None`
/// when no extension is needed (both spans even, or a `2^k + 1` grid).
///
/// Only a side whose span is odd grows, so grids with even spans (SRTM's
/// 1201 and 3601) mesh as before. It grows to the hierarchy's square,
/// `N + 1` samples (`N = 2^k ≥ max(W − 1, H − 1)`), where its border is as
/// coarse as a `2^k + 1` grid's, when the extended grid has at most twice
/// the samples. Otherwise each odd side grows to the next multiple of the
/// largest power of two `2^j` (plus one) within a factor 2 of its length
/// (`√2` when both sides grow), at least by one sample (its span becomes
/// even). The square's side `N` never changes.
pub fn extended_size(width: usize, height: usize) -> Option<(usize, usize)> {
    let odd = |n: usize| (n - 1) % 2 == 1;
    if width < 2 || height < 2 || (!odd(width) && !odd(height)) {
        return None;
    }
    let span = width.max(height).saturating_sub(1).max(1);
    let side = span.checked_next_power_of_two()?;
    let full = |n: usize| if odd(n) { side + 1 } else { n };
    let (w, h) = (full(width), full(height));
    if (w as u128) * (h as u128) <= 2 * (width as u128) * (height as u128) {
        return Some((w, h));
    }
    let growth = if odd(width) && odd(height) {
        std::f64::consts::SQRT_2
    } else {
        2.0
    };
    let grow = |n: usize| {
        if odd(n) {
            grow_span(n, side, growth)
        } else {
            n
        }
    };
    Some((grow(width), grow(height)))
}

/// `n` samples (an odd span) grown to `m − 1` a multiple of the largest
/// power of two up to `side` with `m ≤ growth · n`, or to `n + 1`.
fn grow_span(n: usize, side: usize, growth: f64) -> usize {
    let limit = (n as f64 * growth) as usize;
    let mut step = side;
    while step > 2 {
        let m = (n - 1).next_multiple_of(step) + 1;
        if m <= limit {
            return m;
        }
        step /= 2;
    }
    n + 1
}

/// `grid` extended to `width × height` samples: sample `(c, r)` beyond the
/// grid repeats `(min(c, W − 1), min(r, H − 1))`. The georeference is the
/// grid's (same origin and pixel size).
///
/// # Errors
/// As [`HeightGrid::new`] (the extended grid too large); the sizes must not
/// be smaller than the grid's.
pub fn extend_clamped(
    grid: &HeightGrid,
    width: usize,
    height: usize,
) -> Result<HeightGrid, super::GridError> {
    let (w, h) = (grid.width(), grid.height());
    debug_assert!(width >= w && height >= h);
    super::check_dimensions(width as u64, height as u64)?;
    let src = grid.heights();
    let mut out = Vec::with_capacity(width * height);
    for r in 0..height {
        let row = &src[r.min(h - 1) * w..][..w];
        out.extend_from_slice(row);
        let last = row[w - 1];
        out.extend(std::iter::repeat_n(last, width - w));
    }
    Ok(HeightGrid {
        width,
        height,
        heights: out,
        georef: grid.georef().clone(),
    })
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::grid::GeoRef;

    #[test]
    fn sizes() {
        assert_eq!(extended_size(513, 513), None);
        assert_eq!(extended_size(1201, 1201), None);
        assert_eq!(extended_size(512, 512), Some((513, 513)));
        assert_eq!(extended_size(256, 256), Some((257, 257)));
        assert_eq!(extended_size(512, 300), Some((513, 513)));
        assert_eq!(extended_size(512, 301), Some((513, 301)));
        // The square would be 1025² for 2050 samples: one more column only.
        assert_eq!(extended_size(2, 1025), Some((3, 1025)));
        // 513 rows would be 2.35× the samples: 257 (a multiple of 256, + 1).
        assert_eq!(extended_size(333, 218), Some((333, 257)));
        // Both sides grow, each within √2: 1000 → 1025, 300 → 385 (3·128 + 1).
        assert_eq!(extended_size(1000, 300), Some((1025, 385)));
        assert_eq!(extended_size(1, 8), None);
    }

    #[test]
    fn repeats_the_last_row_and_column() {
        let g = HeightGrid::new(2, 2, vec![1.0, 2.0, 3.0, 4.0], GeoRef::unreferenced(1.0)).unwrap();
        let e = extend_clamped(&g, 3, 3).unwrap();
        assert_eq!(e.heights(), &[1.0, 2.0, 2.0, 3.0, 4.0, 4.0, 3.0, 4.0, 4.0]);
        assert_eq!(e.georef(), g.georef());
    }
}
