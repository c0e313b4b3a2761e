//! The errors of meshing a grid, and the check every hierarchy starts with.
//!
//! Shared by the bitree ([`crate::bitree`]), the restricted quadtree
//! ([`crate::quadtree`]), the criterion-driven refinement ([`crate::refine`](mod@crate::refine))
//! and the one meshing entry point ([`crate::mesher`]).

use crate::grid::{GridError, HeightGrid};
use crate::hierarchy::Hierarchy;

/// The result of meshing: [`MeshError`] by default.
pub type Result<T, E = MeshError> = std::result::Result<T, E>;

/// Errors from building or extracting a mesh.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum MeshError {
    /// The grid is narrower or shorter than 2 samples.
    #[error("expected a grid of at least 2x2 samples to mesh, found {width}x{height}")]
    GridTooSmall {
        /// Grid width.
        width: usize,
        /// Grid height.
        height: usize,
    },
    /// The grid is too large for 32-bit vertex positions.
    #[error("expected a grid of at most 2^30 samples per side to mesh, found {width}x{height}")]
    GridTooLarge {
        /// Grid width.
        width: usize,
        /// Grid height.
        height: usize,
    },
    /// The grid has voids; fill them first.
    #[error(transparent)]
    Voids(#[from] GridError),
    /// A negative or NaN error bound.
    #[error("expected a maximum error of 0 m or more, found {0} m")]
    BadMaxError(f64),
    /// A triangle budget below what the grid needs.
    #[error(
        "expected a triangle budget of at least {min} for this {width}x{height} grid, found {got}"
    )]
    BudgetTooSmall {
        /// The budget asked for.
        got: usize,
        /// The smallest mesh this grid allows.
        min: usize,
        /// Grid width.
        width: usize,
        /// Grid height.
        height: usize,
    },
    /// A plan no hierarchy offers ([`crate::MeshPlan`]): the reason.
    #[error("unsupported meshing plan: {0}")]
    UnsupportedPlan(&'static str),
    /// Point marks made for a grid of another size.
    #[error(
        "expected point marks for the {width}x{height} grid being refined, found marks for a {marks_width}x{marks_height} grid"
    )]
    MarksSizeMismatch {
        /// Grid width.
        width: usize,
        /// Grid height.
        height: usize,
        /// Width of the grid the marks were made for.
        marks_width: usize,
        /// Height of the grid the marks were made for.
        marks_height: usize,
    },
}

/// The hierarchy of a grid that can be meshed: at least 2×2, at most 2^30 per
/// side, no voids. Every hierarchy (bitree, quadtree, refine) starts here.
///
/// # Errors
/// [`MeshError::GridTooSmall`], [`MeshError::GridTooLarge`], [`MeshError::Voids`].
pub(crate) fn hierarchy_for(grid: &HeightGrid) -> Result<Hierarchy, MeshError> {
    let (w, h) = (grid.width(), grid.height());
    if w < 2 || h < 2 {
        return Err(MeshError::GridTooSmall {
            width: w,
            height: h,
        });
    }
    if w > (1 << 30) || h > (1 << 30) {
        return Err(MeshError::GridTooLarge {
            width: w,
            height: h,
        });
    }
    grid.require_no_voids()?;
    Ok(Hierarchy::new(w as u32, h as u32))
}
