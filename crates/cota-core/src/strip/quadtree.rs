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
use super::guided::{guided_refs, stripify_guided};
use crate::mesh::{Mesh, MeshVertex};

/// Strips `mesh` (steps 1–2 of the module docs).
pub fn stripify_quadtree(mesh: &Mesh) -> Strip {
    let mut order = mesh.triangles.clone();
    sweep(&mut order, &mesh.vertices);
    stripify_guided(&order)
}

/// The references of [`stripify_quadtree`]'s strip of `mesh`, which is
/// consumed: its triangles sorted in place, its vertices dropped before the
/// strip is grown, and the strip counted, not written.
pub fn quadtree_strip_refs(mesh: Mesh) -> usize {
    let Mesh {
        vertices,
        mut triangles,
    } = mesh;
    sweep(&mut triangles, &vertices);
    drop(vertices);
    guided_refs(&triangles)
}

/// Step 1: the triangles west to east within rows, north to south, by
/// their centroids (stable); left as they are when an index is out of
/// range (the validator will show the strip as it is).
fn sweep(order: &mut [[u32; 3]], vertices: &[MeshVertex]) {
    let nv = vertices.len();
    if order.iter().flatten().any(|&i| i as usize >= nv) {
        return;
    }
    order.sort_by_key(|t| {
        let v = t.map(|i| vertices[i as usize]);
        let row: u64 = v.iter().map(|x| x.row as u64).sum();
        let col: u64 = v.iter().map(|x| x.col as u64).sum();
        (row, col)
    });
}
