//! The restricted quadtree's prepared data: for every inside block of side
//! 2 or more and each of its sides, the exact error of the side's fan piece
//! without and with the side's midpoint (step 1 of [`super`]; Pajarola 1998,
//! as described in paper `000_ebf7e3a88dffd361.txt` §2.2).

use rayon::prelude::*;

use super::templates::side_pieces;
use crate::bitree::error_code::{encode_up, INFINITE};
use crate::bitree::round_up_f32;
use crate::error::MeshError;
use crate::grid::HeightGrid;
use crate::hierarchy::{Hierarchy, Pt};
use crate::mesh::raster::max_deviation;
use crate::progress::Progress;

/// Per-level data: block counts and the 8 side errors of every block.
#[derive(Debug, Clone)]
pub(super) struct Level {
    pub(super) size: u32,
    pub(super) cols: u32,
    pub(super) rows: u32,
    /// `[side·2 + with_midpoint]`: the error in metres rounded up to an
    /// `f32`, stored as its 16-bit code ([`crate::bitree::error_code`]: an
    /// upper bound within 0.4 %, never below it; the exact value is
    /// recomputed where a decision needs it, [`QuadTree::exact_side`]);
    /// `+∞` for straddling blocks; empty for unit blocks.
    pub(super) side_err: Vec<[u16; 8]>,
}

/// A restricted quadtree with exact per-side errors, ready for refinement.
///
/// ```
/// use cota_core::{check_mesh, CheckOptions, GeoRef, HeightGrid};
/// use cota_core::quadtree::QuadTree;
/// let (w, h) = (33, 20);
/// let heights: Vec<f32> = (0..w * h)
///     .map(|i| ((i % w) as f32 * 0.4).sin() * 30.0 + (i / w) as f32)
///     .collect();
/// let grid = HeightGrid::new(w, h, heights, GeoRef::unreferenced(30.0)).unwrap();
/// let qt = QuadTree::build(&grid).unwrap();
/// let x = qt.extract_max_error_m(2.0).unwrap();
/// check_mesh(&grid, &x.mesh, &CheckOptions::conforming(2.0)).unwrap();
/// ```
#[derive(Debug, Clone)]
pub struct QuadTree<'g> {
    pub(super) grid: &'g HeightGrid,
    pub(super) hier: Hierarchy,
    pub(super) levels: Vec<Level>,
}

impl<'g> QuadTree<'g> {
    /// Computes the side errors of every inside block of `grid`.
    ///
    /// # Errors
    /// [`MeshError::GridTooSmall`], [`MeshError::GridTooLarge`], or
    /// [`MeshError::Voids`] when a sample is NaN (fill voids first).
    pub fn build(grid: &'g HeightGrid) -> Result<Self, MeshError> {
        QuadTree::build_with_progress(grid, crate::progress::NONE)
    }

    /// [`QuadTree::build`], telling `progress(done, total)` after each
    /// level, each level counted by its work (a level of blocks of side
    /// `s` visits about `1/s` of the samples' sides).
    ///
    /// # Errors
    /// As [`QuadTree::build`].
    pub fn build_with_progress(
        grid: &'g HeightGrid,
        progress: Progress<'_>,
    ) -> Result<Self, MeshError> {
        let hier = crate::error::hierarchy_for(grid)?;
        let mut levels = Vec::new();
        let mut size = hier.size();
        // Level of side s: work size / s (their sum size - 1); the sides 1
        // have none.
        let total = hier.size().saturating_sub(1).max(1) as usize;
        let mut done = 0;
        progress(0, total);
        loop {
            let cols = (hier.width() - 1).div_ceil(size);
            let rows = (hier.height() - 1).div_ceil(size);
            let side_err = if size >= 2 {
                (0..rows)
                    .into_par_iter()
                    .flat_map_iter(|j| {
                        (0..cols).map(move |i| block_side_errors(grid, &hier, size, i, j))
                    })
                    .collect()
            } else {
                Vec::new()
            };
            levels.push(Level {
                size,
                cols,
                rows,
                side_err,
            });
            if size == 1 {
                break;
            }
            done += (hier.size() / size) as usize;
            progress(done.min(total), total);
            size /= 2;
        }
        progress(total, total);
        Ok(QuadTree { grid, hier, levels })
    }

    /// The grid this tree was built on.
    pub fn grid(&self) -> &'g HeightGrid {
        self.grid
    }

    /// The padded hierarchy's shape (shared with the bitree).
    pub fn hierarchy(&self) -> &Hierarchy {
        &self.hier
    }

    pub(super) fn inside(&self, d: usize, i: u32, j: u32) -> bool {
        let s = self.levels[d].size as u64;
        (i as u64 + 1) * s < self.hier.width() as u64
            && (j as u64 + 1) * s < self.hier.height() as u64
    }

    /// The exact error (rounded up to `f32`) of side `side` of the inside
    /// block `(i, j)` of depth `d`, with or without its midpoint: the value
    /// [`Level::side_err`] holds the code of.
    pub(super) fn exact_side(&self, d: usize, i: u32, j: u32, side: usize, with_mid: bool) -> f32 {
        side_error(self.grid, self.levels[d].size, i, j, side, with_mid)
    }

    pub(super) fn in_range(&self, d: usize, i: i64, j: i64) -> Option<(u32, u32)> {
        let l = &self.levels[d];
        (i >= 0 && j >= 0 && i < l.cols as i64 && j < l.rows as i64).then_some((i as u32, j as u32))
    }
}

/// The codes of the 8 side errors of block `(i, j)` of side `size` (`+∞`
/// when it straddles).
fn block_side_errors(grid: &HeightGrid, hier: &Hierarchy, size: u32, i: u32, j: u32) -> [u16; 8] {
    let (x0, y0) = (i as u64 * size as u64, j as u64 * size as u64);
    if x0 + size as u64 >= hier.width() as u64 || y0 + size as u64 >= hier.height() as u64 {
        return [INFINITE; 8];
    }
    let mut out = [0u16; 8];
    for side in 0..4 {
        for with_mid in [false, true] {
            let e = side_error(grid, size, i, j, side, with_mid);
            out[side * 2 + usize::from(with_mid)] = encode_up(e);
        }
    }
    out
}

/// The error of one side's fan piece of the inside block `(i, j)` of side
/// `size`, rounded up to `f32`.
fn side_error(grid: &HeightGrid, size: u32, i: u32, j: u32, side: usize, with_mid: bool) -> f32 {
    let half = size / 2;
    let at = |p: Pt| [i * size + p[0] * half, j * size + p[1] * half];
    let (a, b) = side_pieces(side, with_mid);
    let mut e = piece_error(grid, a.map(at));
    if let Some(b) = b {
        e = e.max(piece_error(grid, b.map(at)));
    }
    round_up_f32(e)
}

/// Largest |plane − h| over the samples in or on triangle `t` (grid
/// positions), the plane through its corners' sample heights.
pub(super) fn piece_error(grid: &HeightGrid, t: [Pt; 3]) -> f64 {
    max_deviation(
        grid,
        t,
        t.map(|p| grid.get(p[0] as usize, p[1] as usize) as f64),
    )
}
