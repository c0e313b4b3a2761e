//! Triangle strips straight from the bitree hierarchy.
//!
//! Papers `000_ebf7e3a88dffd361.txt` §4 and `001_49f2c365e8c41172.txt`: the
//! leaves of the bitree are visited by a recursive traversal whose child order
//! (the sequence types A, B, C of paper 001) makes consecutive leaves share an
//! edge, and the visit order is written as one strip, with degenerate "line
//! triangles" where consecutive leaves do not share a whole edge. Strip
//! vocabulary (sequential vs generalized strips, swaps) after Evans, Skiena &
//! Varshney, "Optimizing triangle strips for fast rendering" (1996).
//!
//! 1. **Recover the hierarchy from the mesh.** Every triangle of a bitree mesh
//!    (any mode of [`crate::bitree::extract`] or [`crate::refine`](mod@crate::refine)) is a triangle of the
//!    hierarchy: its right-angle vertex and its hypotenuse identify it. The
//!    grid's extent is read from the vertices, so no grid is needed.
//! 2. **Traverse.** From the two roots, a triangle entered at one end of its
//!    hypotenuse first visits the child holding that end (entered there, left
//!    through the right-angle vertex), then the other child (entered at the
//!    right-angle vertex): the Sierpinski order of the bintree. This is paper
//!    001's A/B/C bookkeeping written as "which vertex the sequence enters
//!    through". In a conforming mesh consecutive leaves then share an edge:
//!    the last leaf of the first child and the first leaf of the second both
//!    have an edge on the common leg starting at the right-angle vertex, and
//!    without T-junctions those edges coincide.
//! 3. **Emit a standard (non-swap) strip** from that order: a triangle sharing
//!    the two newest vertices costs one index; one sharing the edge
//!    (third-newest, newest) costs two (a *swap*, emulated by repeating the
//!    pivot: one degenerate triangle); anything else restarts the strip with
//!    degenerate connectors (one index when the new triangle holds the last
//!    vertex, two otherwise). The first triangle of every run is rotated,
//!    by looking at the following triangle, so that the run continues without
//!    a swap, and its two last vertices are ordered so that the strip's parity
//!    (odd triangles are drawn reversed) yields the mesh's counter-clockwise
//!    orientation: every non-degenerate triangle of the strip is a mesh
//!    triangle, in its orientation, exactly once.
//! 4. **Guided growth** ([`StripMethod::Guided`]), a greedy
//!    pass on top of the traversal: the papers' order reaches about 1.58–1.67
//!    references per triangle, mostly swaps around long fans. Instead, grow
//!    the strip from the current triangle into the unvisited neighbour across
//!    the natural edge or the swap edge, preferring the one with fewer
//!    unvisited neighbours (Warnsdorff's rule; on ties natural, or in a
//!    second run the one whose unvisited neighbours have fewer unvisited
//!    neighbours; the shorter strip of the two is kept), so that no triangle is
//!    stranded; at a dead end restart at an unvisited triangle around the
//!    last vertex (one connector index), else at the first unvisited triangle
//!    in traversal order, which keeps the sweep local, like the traversal.
//!    About 1.41–1.45 references per triangle on adaptive SRTM meshes and
//!    1.50 on a full 1201² grid (traversal alone: 1.57–1.66, and 1.667 on a full
//!    grid, exactly paper 000's 13655 / 8192).
//! 5. **Unit cells re-triangulated** ([`StripMethod::Cells`], the default,
//!    `cells`): a 1×1 cell covered by two unit leaves has no
//!    sample but its corners, so its diagonal can be flipped without changing
//!    the error at any sample or its boundary edges. Long horizontal runs of
//!    such cells are written as row strips (one reference per triangle), the
//!    other cells get parallel diagonals, and the rest is grown as in step 4.
//!    The strip then encodes a re-triangulated mesh, returned with it
//!    ([`MeshStrip`]); when the guided strip of the unchanged mesh is shorter
//!    that one is kept. 1.0012 references per triangle on a full 1201² grid,
//!    1.24–1.44 on adaptive SRTM meshes at 0.5–20 m.
//!
//! Fictitious-faithful meshes (paper 000's variant with hanging vertices)
//! are handled the same way: their leaves still tile the grid, so the
//! traversal visits them all; where a hanging vertex breaks the shared edge
//! the emitter joins the two leaves with degenerate connectors, the role of
//! the paper's line triangles (the edge (x, hanging vertex) of one leaf is
//! not an edge of its neighbour, so no triangle of the strip closes the
//! T-junction: as in the indexed mesh, the faithful surface is not watertight).
//!
//! # Lower bound
//! In a strip one occurrence of a vertex belongs to at most three triangles
//! (the windows it is in), so a vertex in `d` triangles needs `⌈d/3⌉`
//! references. In a full bitree grid (the "4-8" pattern: diagonals alternate)
//! half the interior vertices are in 8 triangles and half in 4, so they need
//! on average `(3 + 2)/2` references for 2 triangles each: **at least 1.25
//! references per triangle** for any strip of it, whereas a grid with
//! parallel diagonals (every vertex in 6 triangles) can reach 1. Steps 1–4
//! keep the mesh, so they stay above 1.25 on a full grid; step 5 meets the
//! full-grid target of at most 1.05 by flipping diagonals (every unit cell
//! of a full grid can be flipped exactly): `(H−1)(2W+1)−1` references for
//! the `2(W−1)(H−1)` triangles of a `W × H` grid, 1.0012 per triangle at
//! 1201².
//!
//! [`drawn_triangles`] is the inverse, and [`Strip::validate`] checks a strip
//! against its mesh with it.
//!
//! # Runtime
//! Linear in the mesh when the grid has at most 16 samples per vertex (a
//! dense sample table), else `O(T log T)` (one binary search per visited
//! hierarchy triangle).

mod cells;
mod emit;
mod guided;
mod quadtree;
mod traversal;

use std::borrow::Cow;

use crate::mesh::Mesh;
use cells::{stripify_cells, CellOptions};
use emit::refs_in_order;
use guided::{guided_refs, stripify_guided};
use traversal::{bitree_order_ids, into_bitree_order};

pub use emit::{drawn_triangles, validate_indices, Strip, StripMismatch};
pub use quadtree::{quadtree_strip_refs, stripify_quadtree};
pub use traversal::{bitree_order, StripError};

pub(crate) use emit::strip_from_order;
pub(crate) use traversal::full_bitree_mesh;

/// How the strip follows the hierarchy.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StripMethod {
    /// The papers' strip: the leaves exactly in traversal order (steps 1–3).
    Traversal,
    /// The traversal order as a guide for greedy growth (step 4).
    Guided,
    /// Rows of re-triangulated unit cells (`cells`, step 5),
    /// or the [`StripMethod::Guided`] strip of the unchanged mesh when that
    /// is shorter. Default: the fewest references on every mesh measured.
    #[default]
    Cells,
}

impl StripMethod {
    /// The method's name: `traversal`, `guided` or `cells`.
    pub fn name(self) -> &'static str {
        match self {
            StripMethod::Traversal => "traversal",
            StripMethod::Guided => "guided",
            StripMethod::Cells => "cells",
        }
    }
}

/// A strip and the mesh it encodes: the input mesh, or, when
/// [`StripMethod::Cells`] re-triangulated unit cells, a copy with the same
/// vertices and those cells' diagonals flipped (the same error at every
/// sample, conforming when the input was).
#[derive(Debug, Clone, PartialEq)]
pub struct MeshStrip<'a> {
    /// The strip; its non-degenerate triangles are exactly `mesh`'s.
    pub strip: Strip,
    /// The mesh the strip encodes.
    pub mesh: Cow<'a, Mesh>,
    /// The method asked for.
    pub method: StripMethod,
    /// Unit cells whose diagonal was flipped (0: `mesh` is the input).
    pub flipped_cells: usize,
}

impl MeshStrip<'_> {
    /// True when the strip encodes a re-triangulated copy of the input mesh.
    pub fn retriangulated(&self) -> bool {
        matches!(self.mesh, Cow::Owned(_))
    }
}

/// Strips a bitree mesh (any mode) with the default method,
/// [`StripMethod::Cells`]: the strip may encode a re-triangulated mesh,
/// returned with it.
///
/// ```
/// use cota_core::{GeoRef, HeightGrid, Bitree, ExtractOptions};
/// use cota_core::strip::stripify_bitree;
/// let (w, h) = (17, 9);
/// let heights: Vec<f32> = (0..w * h).map(|i| ((i * 37) % 11) as f32).collect();
/// let grid = HeightGrid::new(w, h, heights, GeoRef::unreferenced(30.0)).unwrap();
/// let mesh = Bitree::build(&grid).unwrap().extract(&ExtractOptions::max_error_m(0.5)).unwrap().mesh;
/// let s = stripify_bitree(&mesh).unwrap();
/// s.strip.validate(&s.mesh).unwrap();
/// assert_eq!(s.mesh.vertices, mesh.vertices);
/// assert!(s.strip.refs_per_triangle() < 2.0);
/// ```
///
/// # Errors
/// [`StripError`] when the mesh is not made of bitree leaves tiling the grid.
pub fn stripify_bitree(mesh: &Mesh) -> Result<MeshStrip<'_>, StripError> {
    stripify_bitree_with(mesh, StripMethod::default())
}

/// Strips a bitree mesh (any mode) with the given method.
///
/// # Errors
/// As [`stripify_bitree`].
pub fn stripify_bitree_with(mesh: &Mesh, method: StripMethod) -> Result<MeshStrip<'_>, StripError> {
    let ids = bitree_order_ids(mesh)?;
    let order: Vec<[u32; 3]> = ids.iter().map(|&k| mesh.triangles[k as usize]).collect();
    let same = |strip| MeshStrip {
        strip,
        mesh: Cow::Borrowed(mesh),
        method,
        flipped_cells: 0,
    };
    Ok(match method {
        StripMethod::Traversal => same(strip_from_order(&order)),
        StripMethod::Guided => same(stripify_guided(&order)),
        StripMethod::Cells => {
            let (guided, cells) = rayon::join(
                || stripify_guided(&order),
                || stripify_cells(mesh, &ids, &CellOptions::DEFAULT),
            );
            if cells.strip.refs() < guided.refs() && cells.flipped_cells > 0 {
                MeshStrip {
                    strip: cells.strip,
                    mesh: Cow::Owned(Mesh {
                        vertices: mesh.vertices.clone(),
                        triangles: cells.triangles,
                    }),
                    method,
                    flipped_cells: cells.flipped_cells,
                }
            } else if cells.strip.refs() < guided.refs() {
                same(cells.strip)
            } else {
                same(guided)
            }
        }
    })
}

/// The references of the strip [`stripify_bitree_with`] makes of `mesh`,
/// counted in less memory: the mesh is consumed (its triangles put in the
/// hierarchy's order in place, its vertices dropped before the strip is
/// grown) and the strip's indices are never written. [`StripMethod::Cells`]
/// needs the mesh and its strip, and counts them as [`stripify_bitree_with`].
///
/// # Errors
/// As [`stripify_bitree`].
pub fn bitree_strip_refs(mesh: Mesh, method: StripMethod) -> Result<usize, StripError> {
    if method == StripMethod::Cells {
        return stripify_bitree_with(&mesh, method).map(|s| s.strip.refs());
    }
    let order = into_bitree_order(mesh)?;
    Ok(match method {
        StripMethod::Traversal => refs_in_order(&order),
        _ => guided_refs(&order),
    })
}

#[cfg(test)]
mod tests;
