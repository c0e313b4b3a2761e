//! The 4-connected components of a grid's voids, found by a flood fill in
//! raster order: each is filled on its own (step 1 of [`super`], the
//! standard connected-component labelling).

use crate::grid::HeightGrid;

/// One 4-connected set of void samples.
pub(super) struct Component {
    /// Its samples (row-major grid indices), in search order.
    pub(super) cells: Vec<usize>,
    /// Bounding box: first and last column, first and last row.
    pub(super) cols: (usize, usize),
    pub(super) rows: (usize, usize),
}

/// The 4-connected void components of `grid`, in raster order of their first sample.
pub(super) fn find_components(grid: &HeightGrid) -> Vec<Component> {
    let (w, h) = (grid.width(), grid.height());
    let heights = grid.heights();
    let mut seen = vec![false; heights.len()];
    let mut stack = Vec::new();
    let mut out = Vec::new();
    for start in 0..heights.len() {
        if seen[start] || !heights[start].is_nan() {
            continue;
        }
        seen[start] = true;
        stack.push(start);
        let mut c = Component {
            cells: Vec::new(),
            cols: (start % w, start % w),
            rows: (start / w, start / w),
        };
        while let Some(i) = stack.pop() {
            let (x, y) = (i % w, i / w);
            c.cells.push(i);
            c.cols = (c.cols.0.min(x), c.cols.1.max(x));
            c.rows = (c.rows.0.min(y), c.rows.1.max(y));
            let mut visit = |j: usize| {
                if !seen[j] && heights[j].is_nan() {
                    seen[j] = true;
                    stack.push(j);
                }
            };
            if x > 0 {
                visit(i - 1);
            }
            if x + 1 < w {
                visit(i + 1);
            }
            if y > 0 {
                visit(i - w);
            }
            if y + 1 < h {
                visit(i + w);
            }
        }
        out.push(c);
    }
    out
}
