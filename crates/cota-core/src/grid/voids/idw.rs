//! The inverse-distance fill of one void component
//! ([`super::FillMethod::InverseDistance`]): each void sample is the
//! 1/d²-weighted mean of the component's border, d in metres (Shepard, "A
//! two-dimensional interpolation function for irregularly-spaced data", ACM
//! national conference, 1968).

use super::patch::{Level, KNOWN};

/// Above this many (void, border) pairs the inverse-distance border is subsampled.
const IDW_MAX_PAIRS: usize = 100_000_000;

/// Sets every unknown to the 1/d²-weighted mean of the known cells (the
/// component's border), d in metres; subsamples the border above [`IDW_MAX_PAIRS`].
pub(super) fn inverse_distance(level: &mut Level, dx: f64, dy: f64) {
    let s = level.stride;
    let border: Vec<(f64, f64, f64)> = level
        .state
        .iter()
        .enumerate()
        .filter(|(_, st)| **st == KNOWN)
        .map(|(i, _)| ((i % s) as f64 * dx, (i / s) as f64 * dy, level.value[i]))
        .collect();
    let pairs = border.len().saturating_mul(level.unknowns.len());
    let step = pairs.div_ceil(IDW_MAX_PAIRS).max(1);
    for u in &level.unknowns {
        let (x, y) = ((u.at % s) as f64 * dx, (u.at / s) as f64 * dy);
        let (mut sum, mut wsum) = (0.0, 0.0);
        for &(bx, by, v) in border.iter().step_by(step) {
            let weight = 1.0 / ((bx - x) * (bx - x) + (by - y) * (by - y));
            sum += weight * v;
            wsum += weight;
        }
        if wsum > 0.0 {
            level.value[u.at] = sum / wsum;
        }
    }
}
