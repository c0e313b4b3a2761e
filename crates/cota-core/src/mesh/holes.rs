//! Voids left as holes (`--voids hole`): the mesh leaves out every triangle
//! that would touch a void, so it has boundaries where the data has.
//!
//! How: the voids are filled with a constant ([`fill_flat`]: any fill
//! would do, no kept triangle reads a filled height), then the grid is refined with
//! [`AvoidVoids`](crate::criteria::AvoidVoids), which wraps the
//! user's criterion and also splits every triangle larger than a unit
//! triangle whose bounding box holds a void sample. The hierarchy's rules
//! (paper `000_ebf7e3a88dffd361.txt` §2: a split needs its diamond's
//! splits) keep the mesh conforming. Then [`cut_holes`] drops the unit
//! triangles with a void vertex (a unit triangle's samples are its three
//! vertices) and the vertices no triangle uses any more.
//!
//! So every kept triangle holds no void sample and satisfies the criterion
//! with the true heights; the cells whose four corners are valid are all
//! covered; open edges off the grid's border lie next to a void. The
//! checker proves these with [`super::check::CheckOptions::holes`].
//! The bounding-box test is conservative (a triangle is half its box): a
//! few triangles next to a void are split that need not be.

use crate::grid::HeightGrid;

use super::{Mesh, MeshVertex};

/// The void samples of a grid, as a summed-area table of void counts: any
/// rectangle's count in O(1).
#[derive(Debug, Clone)]
pub struct VoidMask {
    width: usize,
    height: usize,
    /// `(width + 1) × (height + 1)`, entry (x, y) the voids in columns `< x`,
    /// rows `< y`.
    sums: Vec<u32>,
}

impl VoidMask {
    /// The voids (NaN samples) of `grid`.
    pub fn new(grid: &HeightGrid) -> Self {
        let (w, h) = (grid.width(), grid.height());
        let mut sums = vec![0u32; (w + 1) * (h + 1)];
        for y in 0..h {
            let mut row = 0u32;
            for x in 0..w {
                row += u32::from(grid.get(x, y).is_nan());
                sums[(y + 1) * (w + 1) + x + 1] = sums[y * (w + 1) + x + 1] + row;
            }
        }
        VoidMask {
            width: w,
            height: h,
            sums,
        }
    }

    /// Void samples in columns `x0..=x1`, rows `y0..=y1` (clipped to the grid).
    pub fn count(&self, x0: usize, y0: usize, x1: usize, y1: usize) -> u32 {
        let (x1, y1) = ((x1 + 1).min(self.width), (y1 + 1).min(self.height));
        if x0 >= x1 || y0 >= y1 {
            return 0;
        }
        let s = |x: usize, y: usize| self.sums[y * (self.width + 1) + x];
        s(x1, y1) + s(x0, y0) - s(x0, y1) - s(x1, y0)
    }

    /// Whether sample (`x`, `y`) is void.
    pub fn is_void(&self, x: usize, y: usize) -> bool {
        self.count(x, y, x, y) > 0
    }

    /// Total void samples.
    pub fn total(&self) -> u32 {
        self.count(
            0,
            0,
            self.width.saturating_sub(1),
            self.height.saturating_sub(1),
        )
    }
}

/// Sets every void of `grid` to its lowest valid height (so the height
/// range stays the data's) and returns how many there were; what hole
/// meshing needs instead of a true fill. A grid with no valid sample is
/// left as it is.
pub fn fill_flat(grid: &mut HeightGrid) -> usize {
    let Some((lo, _)) = grid.valid_range() else {
        return 0;
    };
    let mut n = 0;
    for h in grid.heights_mut() {
        if h.is_nan() {
            *h = lo;
            n += 1;
        }
    }
    n
}

/// What [`cut_holes`] left out.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct HoleReport {
    /// Triangles dropped (they had a void vertex).
    pub triangles_left_out: usize,
    /// Area left out, in grid cells (the rectangle's `(W−1)(H−1)` cells
    /// minus the kept triangles' area).
    pub cells_left_out: f64,
}

/// Drops the triangles of `mesh` with a vertex on a void of `voids` and the
/// vertices left unused (the others keep their order).
pub fn cut_holes(mesh: &Mesh, voids: &VoidMask) -> (Mesh, HoleReport) {
    let void_vertex: Vec<bool> = mesh
        .vertices
        .iter()
        .map(|v| voids.is_void(v.col as usize, v.row as usize))
        .collect();
    let mut used = vec![false; mesh.vertices.len()];
    let mut kept: Vec<[u32; 3]> = Vec::with_capacity(mesh.triangles.len());
    let mut area2 = 0i64;
    for t in &mesh.triangles {
        if t.iter().any(|&i| void_vertex[i as usize]) {
            continue;
        }
        for &i in t {
            used[i as usize] = true;
        }
        area2 += mesh.signed_area2(*t);
        kept.push(*t);
    }
    let mut index = vec![u32::MAX; mesh.vertices.len()];
    let mut vertices: Vec<MeshVertex> = Vec::new();
    for (k, v) in mesh.vertices.iter().enumerate() {
        if used[k] {
            index[k] = vertices.len() as u32;
            vertices.push(*v);
        }
    }
    for t in &mut kept {
        *t = t.map(|i| index[i as usize]);
    }
    let cells = (voids.width.saturating_sub(1) * voids.height.saturating_sub(1)) as f64;
    let report = HoleReport {
        triangles_left_out: mesh.triangles.len() - kept.len(),
        cells_left_out: cells - area2 as f64 / 2.0,
    };
    (
        Mesh {
            vertices,
            triangles: kept,
        },
        report,
    )
}
