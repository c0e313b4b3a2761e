//! What the coarse levels of a void's multigrid share: the state of a cell,
//! and the frame of their arrays. The bilinear interpolation from a coarser
//! level (the prolongation of Briggs, Henson & McCormick, *A Multigrid
//! Tutorial*, 2nd ed., SIAM 2000, §3, on cell-centred 2×2 blocks, over the
//! cells that take part) is `Coarse::add_from` and `Coarse::add_to_fine`.
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
