//! Triangle strips for restricted-quadtree meshes, guided by paper 003's
//! west-to-east traversal.
//!
//! Paper `003_3a32b63e0cff3a64.txt` (Algorithm 1) builds strips by visiting
//! the active quadtree leaves west to east and north to south, stepping to
//! the east neighbour and queueing chain starts where the level changes.
//! Strip vocabulary after Evans, Skiena & Varshney (1996).
//!
//! 1. Order the mesh's triangles west to east within rows, north to south
//!    (by their centroid: row first, then column), the paper's sweep at the
//!    resolution of the triangles.
//! 2. Grow one standard strip greedily from that order with the guided
//!    growth of [`super`] (step 4 there): natural or swap neighbour,
//!    the one with fewer unvisited neighbours first, restarts around the last
//!    vertex or at the next triangle of the sweep. Orientation and parity are
//!    handled as there: every non-degenerate triangle of the strip is a mesh
//!    triangle, counter-clockwise from above, exactly once.
//!
//! Works for any conforming mesh whose vertices sit on samples (it never
//! looks at the tree), so it also strips the leaves of
//! [`crate::quadtree::QuadTree`] whatever their templates.
//!
//! # Runtime
//! `O(T log T)` for the sort, then linear.

use super::emit::Strip;
use super::guided::stripify_guided;
use crate::mesh::Mesh;

/// Strips `mesh` (steps 1–2 of the module docs).
pub fn stripify_quadtree(mesh: &Mesh) -> Strip {
    let mut order = mesh.triangles.clone();
    let nv = mesh.vertices.len();
    if order.iter().flatten().any(|&i| i as usize >= nv) {
        // Out-of-range indices: keep the given order (the validator will
        // show the strip as it is).
        return stripify_guided(&order);
    }
    order.sort_by_key(|t| {
        let v = t.map(|i| mesh.vertices[i as usize]);
        let row: u64 = v.iter().map(|x| x.row as u64).sum();
        let col: u64 = v.iter().map(|x| x.col as u64).sum();
        (row, col)
    });
    stripify_guided(&order)
}
