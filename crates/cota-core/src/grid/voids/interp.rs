//! What the coarse levels of a void's multigrid share: the state of a cell
//! and the bilinear interpolation from a coarser level (the prolongation of
//! Briggs, Henson & McCormick, *A Multigrid Tutorial*, 2nd ed., SIAM 2000,
//! §3, on cell-centred 2×2 blocks, over the cells that take part).
//!
//! Coarse arrays have a frame of one absent cell around their `w × h`
//! cells: cell (`x`, `y`) is at `(y + 1)·stride + x + 1`, `stride = w + 2`.

/// A cell with a value and no equation: a border height (or, on the error
/// levels, an error of 0).
pub(super) const KNOWN: u8 = 0;
/// A cell with an equation.
pub(super) const UNKNOWN: u8 = 1;
/// A cell that takes no part (and the frame).
pub(super) const ABSENT: u8 = 2;

/// Levels with at most this many unknowns are solved directly, not
/// coarsened further.
pub(super) const COARSEST_UNKNOWNS: usize = 16;

/// The interpolation at cell (`x`, `y`) of the level below (finer) from this
/// coarse level's `state` and `value` (framed, `stride` wide): fine cell `x`
/// lies at coarse coordinate `(x − 0.5)/2`, between the centres of blocks
/// `x/2 − 1` and `x/2` (weights 1/4, 3/4) when `x` is even, `x/2` and
/// `x/2 + 1` (3/4, 1/4) when odd; absent cells drop out and the weights are
/// renormalised. Its own block always takes part, so the result is defined
/// for every cell of an unknown or known block.
#[inline]
pub(super) fn bilinear(state: &[u8], value: &[f32], stride: usize, x: usize, y: usize) -> f32 {
    let (x0, tx) = if x.is_multiple_of(2) {
        (x / 2, 0.75f32)
    } else {
        (x / 2 + 1, 0.25)
    };
    let (y0, ty) = if y.is_multiple_of(2) {
        (y / 2, 0.75f32)
    } else {
        (y / 2 + 1, 0.25)
    };
    // Framed indices of coarse cells (x0 − 1, y0 − 1) .. (x0, y0).
    let base = y0 * stride + x0;
    let (mut sum, mut wsum) = (0f32, 0f32);
    for (off, w) in [
        (0, (1.0 - tx) * (1.0 - ty)),
        (1, tx * (1.0 - ty)),
        (stride, (1.0 - tx) * ty),
        (stride + 1, tx * ty),
    ] {
        if state[base + off] != ABSENT {
            sum += w * value[base + off];
            wsum += w;
        }
    }
    if wsum > 0.0 {
        sum / wsum
    } else {
        0.0
    }
}
