//! The checker's tests for a mesh whose voids are holes
//! ([`super::CheckOptions::holes`], [`crate::mesh::holes`]): no triangle
//! touches a void, the valid region is covered, and open edges lie next to
//! voids.

use super::{Found, Violation};
use crate::grid::HeightGrid;
use crate::mesh::holes::VoidMask;
use crate::mesh::raster::for_each_span_in;
use crate::mesh::{Mesh, MeshVertex};

/// True when the edge `a`–`b` is at most one sample long in each direction
/// and a void lies within one sample of its bounding box: an edge a hole
/// may leave open.
pub(super) fn next_to_void(voids: &VoidMask, a: &MeshVertex, b: &MeshVertex) -> bool {
    let (x0, x1) = (a.col.min(b.col) as usize, a.col.max(b.col) as usize);
    let (y0, y1) = (a.row.min(b.row) as usize, a.row.max(b.row) as usize);
    x1 - x0 <= 1
        && y1 - y0 <= 1
        && voids.count(x0.saturating_sub(1), y0.saturating_sub(1), x1 + 1, y1 + 1) > 0
}

/// Every triangle is free of void samples (in or on it), and every cell
/// with four valid corners is covered: two points of it, a quarter of a
/// cell in from its west and east sides on its middle row, lie in
/// triangles (on either side of both diagonals, so each half of a cell cut
/// along either diagonal has one).
pub(super) fn check_holes(grid: &HeightGrid, mesh: &Mesh, found: &mut Found) {
    let (w, h) = (grid.width(), grid.height());
    let cells = (w - 1) * (h - 1);
    let mut west = vec![false; cells];
    let mut east = vec![false; cells];
    for (k, t) in mesh.triangles.iter().enumerate() {
        let p = t.map(|i| {
            let v = mesh.vertices[i as usize];
            [v.col, v.row]
        });
        let mut void = None;
        for_each_span_in(p, (0, h as i64 - 1), |y, x0, x1| {
            if void.is_none() {
                void = (x0..=x1)
                    .find(|&x| grid.get(x as usize, y as usize).is_nan())
                    .map(|x| (x, y));
            }
        });
        if let Some((col, row)) = void {
            found.push(Violation::TriangleOnVoid { tri: k, col, row });
        }
        let q = p.map(|v| [4 * v[0], 4 * v[1]]);
        for_each_span_in(q, (0, 4 * h as i64), |y, x0, x1| {
            if y % 4 != 2 {
                return;
            }
            let row = (y / 4) as usize;
            for x in x0..=x1 {
                let (col, part) = ((x / 4) as usize, x % 4);
                if col + 1 < w && row + 1 < h {
                    match part {
                        1 => west[row * (w - 1) + col] = true,
                        3 => east[row * (w - 1) + col] = true,
                        _ => {}
                    }
                }
            }
        });
    }
    let (mut count, mut first) = (0, None);
    for row in 0..h - 1 {
        for col in 0..w - 1 {
            let c = row * (w - 1) + col;
            let valid = [(0, 0), (1, 0), (0, 1), (1, 1)]
                .iter()
                .all(|&(dx, dy)| !grid.get(col + dx, row + dy).is_nan());
            if valid && !(west[c] && east[c]) {
                count += 1;
                first.get_or_insert((col as u32, row as u32));
            }
        }
    }
    if let Some((col, row)) = first {
        found.push(Violation::UncoveredCells { count, col, row });
    }
}
