//! The restricted quadtree triangulation: the baseline the bitree is compared
//! against.
//!
//! Pajarola 1998, "Large scale terrain visualization using the restricted
//! quadtree triangulation", as described in paper `000_ebf7e3a88dffd361.txt` §2.2
//! (figures 5–7: vertex dependencies; adjacent blocks differ by at most one
//! level) and used by papers `002_9d6c1367b8962b6c.txt`,
//! `003_3a32b63e0cff3a64.txt` and `004_ab8d08b3e6a5a70a.txt`.
//!
//! # Geometry: any W×H grid
//! The same virtual padding as the bitree ([`crate::hierarchy`]): the root block
//! is the square of side `N = 2^k ≥ max(W−1, H−1)` with the grid in its
//! north-west corner. A block of depth `d` has side `s = N >> d`; block `(i, j)`
//! has its north-west corner at sample `(i·s, j·s)`. A block is *inside* when
//! its whole square lies in `[0, W−1] × [0, H−1]`, *outside* when it misses the
//! rectangle's interior (never created), *straddling* otherwise (always split).
//! Only inside blocks become leaves, so every vertex is a sample and the mesh
//! covers exactly the grid's extent.
//!
//! # Overview
//! 1. **Build** ([`QuadTree::build`], once): for every inside block of side
//!    `s ≥ 2` and each of its 4 sides, the exact error of the side's fan piece
//!    without the side's midpoint (triangle corner–corner–centre) and with it
//!    (two triangles). The error of a leaf under any of the 16 templates
//!    ([`templates`]) is then the maximum of 4 of these 8
//!    numbers: **exact** for the template the leaf really has, no worst case.
//!    Errors are the largest `|plane − h|` over every sample in or on a piece
//!    ([`crate::mesh::raster::max_deviation`]), rounded up to
//!    `f32`.
//! 2. **Refine** ([`QuadTree::refine`], per criterion): top-down from the root,
//!    coarse levels first. A leaf is split when it straddles the border or when
//!    the [`crate::Criterion`] wants it, given the leaf's *current* template (the
//!    midpoints of the sides whose same-size neighbour is split).
//! 3. **Restriction**: before a block of depth `d` splits, its 4 edge
//!    neighbours of depth `d` must exist; a missing one is created by splitting
//!    its parent (a *forced* split), recursively. Hence adjacent leaves differ by
//!    at most one level.
//! 4. A split changes its neighbours' templates, so those leaves are evaluated
//!    again. Splits are never undone, so this terminates, and at the end every
//!    leaf has been judged with its final template: with
//!    [`crate::MaxVerticalError`] every leaf's exact error is within the bound.
//! 5. **Emit**: each leaf by its template (4 to 8 triangles around the centre,
//!    counter-clockwise seen from above); unit blocks (side 1, only along a
//!    border whose length is odd) as two triangles with the diagonal through
//!    their parent's centre. With [`QuadOptions::centre_when_needed`], a leaf
//!    with no finer neighbour whose two halves satisfy the criterion is
//!    emitted as those 2 triangles (no centre): Pajarola's blocks whose centre
//!    is not selected. Its sides are whole on both sides, so conformity holds.
//!
//! The result is a valid restricted quadtree meeting the criterion at every
//! leaf. It is greedy (a leaf judged with fewer midpoints than it ends up with
//! may split where the final template would have sufficed), like Pajarola's
//! vertex-selection; it is not claimed to be the smallest such mesh.
//!
//! # Selected and added points
//! [`QuadExtraction::points`] counts by splits, for any criterion (the
//! point-level definition shared with the bitree, for the max-error criterion,
//! is [`crate::Bitree::point_counts`], see [`crate::bitree::points`]). A split of a
//! block introduces its 4 side midpoints and the centres of its 4 children
//! (children of side 1 have none). A mesh vertex is
//! * **base**: a corner or the centre of the root block (present before any split);
//! * **selected**: introduced by at least one split the criterion wanted;
//! * **added**: introduced only by forced splits (the restriction, or a block
//!   straddling the grid's border), paper 000's "puntos agregados".
//!
//! # Runtime
//! Build: `O(n log n)`, each level touching every sample about twice, in
//! parallel over rows of blocks. Refine: proportional to the number of blocks
//! created. Memory: 16 bytes per block of side ≥ 2 (about `n·16/3` bytes):
//! each side error is kept as the 16-bit code of [`crate::bitree::error_code`]
//! (an upper bound within 0.4 %), and a decision the code cannot settle
//! (a pure vertical bound between the code's value and the one below it,
//! or any other criterion) recomputes the leaf's exact error, so every
//! mesh is the one of the exact errors.

mod refine;
pub mod templates;
mod tree;

use crate::bitree::PointCounts;
use crate::mesh::Mesh;

pub use tree::QuadTree;

/// Options for [`QuadTree::refine_with`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub struct QuadOptions {
    /// Emit a leaf without finer neighbours as its 2 halves (cut along the
    /// bitree's diagonal for that square) when the criterion accepts them, so
    /// its centre is not a vertex: Pajarola 1998's blocks whose centre is not
    /// selected. Default: false (every leaf is a fan around its centre, the
    /// templates of papers 002–004).
    pub centre_when_needed: bool,
}

impl QuadOptions {
    /// The defaults: every leaf uses its centre.
    pub const DEFAULT: QuadOptions = QuadOptions {
        centre_when_needed: false,
    };

    /// `templates`, or `centre-when-needed` with
    /// [`QuadOptions::centre_when_needed`], for reports.
    pub fn name(&self) -> &'static str {
        if self.centre_when_needed {
            "centre-when-needed"
        } else {
            "templates"
        }
    }

    /// Sets [`QuadOptions::centre_when_needed`].
    pub const fn with_centre_when_needed(mut self, yes: bool) -> Self {
        self.centre_when_needed = yes;
        self
    }
}

/// A block of the restricted quadtree that is a leaf of the mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Leaf {
    /// Depth, 0 at the root.
    pub depth: u32,
    /// Side in grid cells (a power of two).
    pub size: u32,
    /// Column of the north-west corner.
    pub col: u32,
    /// Row of the north-west corner.
    pub row: u32,
    /// The template: which sides carry their midpoint
    /// ([`templates::NORTH`] etc.); 0 for unit blocks.
    pub mask: u8,
    /// True when emitted as 2 halves without its centre
    /// ([`QuadOptions::centre_when_needed`], and unit blocks).
    pub halves: bool,
}

/// A restricted-quadtree mesh and its accounting.
#[derive(Debug, Clone)]
pub struct QuadExtraction {
    /// The mesh (vertices on samples, triangles counter-clockwise from above).
    pub mesh: Mesh,
    /// Base, selected and added points by splits (see the module docs).
    pub points: PointCounts,
    /// The leaves.
    pub leaves: Vec<Leaf>,
    /// Splits the criterion wanted.
    pub wanted_splits: usize,
    /// Splits forced by the restriction or by the grid's border.
    pub forced_splits: usize,
    /// The largest exact leaf error (final templates), metres: an upper bound of
    /// the mesh's error at every sample.
    pub max_leaf_error_m: f64,
}
