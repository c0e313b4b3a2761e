//! The inverse-distance fill of one void component
//! ([`super::FillMethod::InverseDistance`]): each void sample is the
//! 1/d²-weighted mean of the component's border, d in metres (Shepard, "A
//! two-dimensional interpolation function for irregularly-spaced data", ACM
//! national conference, 1968).

use super::fine::{for_each_bit, Cell, Fine};

/// Above this many (void, border) pairs the inverse-distance border is subsampled.
const IDW_MAX_PAIRS: usize = 100_000_000;

/// Sets every unknown of `fine` to the 1/d²-weighted mean of its border
/// cells, d in metres (`dx`, `dy` per column and row); subsamples the border
/// above [`IDW_MAX_PAIRS`].
pub(super) fn inverse_distance(fine: &mut Fine<'_>, dx: f64, dy: f64) {
    let mut border: Vec<(f64, f64, f64)> = Vec::new();
    for y in 0..fine.h {
        for x in 0..fine.w {
            if fine.cell(x, y) == Cell::Border {
                let v = f64::from(fine.rows[y][x]);
                border.push((x as f64 * dx, y as f64 * dy, v));
            }
        }
    }
    let pairs = border.len().saturating_mul(fine.unknowns());
    let step = pairs.div_ceil(IDW_MAX_PAIRS).max(1);
    let mask = &fine.mask;
    for (y, row) in fine.rows.iter_mut().enumerate() {
        for_each_bit(mask.row(y), |x| {
            let (px, py) = (x as f64 * dx, y as f64 * dy);
            let (mut sum, mut wsum) = (0.0, 0.0);
            for &(bx, by, v) in border.iter().step_by(step) {
                let weight = 1.0 / ((bx - px) * (bx - px) + (by - py) * (by - py));
                sum += weight * v;
                wsum += weight;
            }
            if wsum > 0.0 {
                row[x] = (sum / wsum) as f32;
            }
        });
    }
}
