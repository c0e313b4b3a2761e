//! Geometry of the implicit bitree over any W×H grid.
//!
//! Paper `000_ebf7e3a88dffd361.txt` ("Triangulación jerárquica sin
//! restricciones") §2: two root right triangles cover a square; a triangle splits
//! into two by the midpoint of its hypotenuse; every grid point gets its level
//! from its position alone, so no tree is stored. This is the right-triangulated
//! irregular network (RTIN) of Evans, Kirkpatrick & Townsend (1997) and the
//! bintree of ROAM (Duchaineau et al. 1997). Paper `001_49f2c365e8c41172.txt`
//! uses the same tree over a mosaic of SRTM tiles.
//!
//! # Any W×H grid: virtual padding with exact clipping
//! The hierarchy lives on the smallest square of side `N = 2^k ≥ max(W−1, H−1)`
//! whose north-west corner is sample (0, 0). The grid occupies
//! `[0, W−1] × [0, H−1]` of it. Every triangle is classified against that
//! rectangle:
//! 1. **inside**: its three vertices are samples of the grid;
//! 2. **outside**: its bounding box does not meet the rectangle's interior; it is
//!    never emitted and never looked at;
//! 3. **straddling**: anything else. It is always split. Its children are again
//!    classified, so the recursion stops where triangles fit the rectangle, at
//!    the latest at unit cells (a unit cell meeting the interior lies inside).
//!
//! No height is ever invented: only inside triangles are emitted, all their
//! vertices are grid samples, and together they tile the rectangle exactly.
//! The price is that the east and south borders are meshed at the resolution of
//! the largest power of two dividing `W−1` (resp. `H−1`): 16 samples for a
//! 1201-wide SRTM tile, 1 for an even width. No square hierarchy can do better,
//! since any tiling of `[0, W−1]` by power-of-two blocks needs a block of that size.
//!
//! # Levels
//! With `s` a power of two (2 ≤ s ≤ N), the triangles come in two kinds:
//! * `A(s)`: halves of an axis-aligned `s × s` square cut by its diagonal. The
//!   square `(i, j)` (corner `(i·s, j·s)`) is cut along `\` when `i + j` is even
//!   and along `/` when odd. The split point is the square's centre.
//! * `B(s)`: the children of `A(s)`: hypotenuse one side of an `s`-square, apex at
//!   its centre. The split point is the side's midpoint.
//!
//! Coarse to fine: `A(N), B(N), A(N/2), B(N/2), …, A(2), B(2)`; the children of
//! `B(2)` are the unit triangles `A(1)`, which are leaves. A split point is shared
//! by the two triangles of its *diamond* (the two halves of a square for `A`, the
//! two triangles on either side of a side for `B`), which is what makes a
//! consistent decision per split point crack-free.
mod level;
mod padded;
mod spans;
mod tri;
mod walk;

pub(crate) use level::{
    diagonal_of, diamond, first_col, level_of, level_rows, level_side, levels, parent, Level,
};
pub use padded::{Hierarchy, Placement};
pub(crate) use spans::RowSpans;
pub use tri::{orient_up, Pt, Tri};
pub(crate) use walk::{walk, Visitor};
