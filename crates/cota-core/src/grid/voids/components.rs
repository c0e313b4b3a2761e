//! The 4-connected components of a grid's voids (step 1 of [`super`]), found
//! from runs: each row's runs of void samples are found in parallel, then the
//! runs that touch across consecutive rows are joined by union–find (the
//! standard run-based connected-component labelling, Rosenfeld & Pfaltz,
//! "Sequential operations in digital picture processing", JACM 1966).
//!
//! A component is kept as its runs, so its memory is proportional to its
//! outline, not its area: a void of millions of samples in one block of rows
//! is a few thousand runs. Its **box** is its bounding box plus a margin of
//! one sample (clipped at the grid's edge), which holds every sample that
//! touches it; its **mask** marks its samples in the box, one bit each.

use rayon::prelude::*;

use crate::grid::HeightGrid;

/// A run of void samples on one row: columns `x0..x1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Run {
    pub(super) row: u32,
    pub(super) x0: u32,
    pub(super) x1: u32,
}

/// One 4-connected set of void samples.
pub(super) struct Component {
    /// Its runs, in row order, each row's from west to east.
    pub(super) runs: Vec<Run>,
    /// Samples in it.
    pub(super) cells: usize,
    /// Bounding box: first and last column, first and last row.
    pub(super) cols: (usize, usize),
    pub(super) rows: (usize, usize),
}

/// A rectangle of the grid: `w × h` samples from column `x0`, row `y0`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct BoxArea {
    pub(super) x0: usize,
    pub(super) y0: usize,
    pub(super) w: usize,
    pub(super) h: usize,
}

impl BoxArea {
    /// Number of samples.
    pub(super) fn len(&self) -> usize {
        self.w * self.h
    }
}

impl Component {
    /// The bounding box plus a one-sample margin, clipped at the edges of a
    /// `width × height` grid.
    pub(super) fn area(&self, width: usize, height: usize) -> BoxArea {
        let x0 = self.cols.0.saturating_sub(1);
        let y0 = self.rows.0.saturating_sub(1);
        let x1 = (self.cols.1 + 1).min(width - 1);
        let y1 = (self.rows.1 + 1).min(height - 1);
        BoxArea {
            x0,
            y0,
            w: x1 - x0 + 1,
            h: y1 - y0 + 1,
        }
    }

    /// The component's samples in `area` (which must hold it), one bit each.
    pub(super) fn mask(&self, area: &BoxArea) -> Mask {
        let mut m = Mask::new(area.w, area.h);
        for r in &self.runs {
            let y = r.row as usize - area.y0;
            for x in r.x0 as usize..r.x1 as usize {
                m.set(x - area.x0, y);
            }
        }
        m
    }

    /// The grid indices of its samples, in row order.
    pub(super) fn indices(&self, width: usize) -> impl Iterator<Item = usize> + '_ {
        self.runs.iter().flat_map(move |r| {
            let base = r.row as usize * width;
            (r.x0 as usize..r.x1 as usize).map(move |x| base + x)
        })
    }
}

/// One bit per sample of a box, rows padded to whole 64-bit words.
#[derive(Debug, Clone)]
pub(super) struct Mask {
    words: Vec<u64>,
    per_row: usize,
}

impl Mask {
    /// All clear, for a `w × h` box.
    pub(super) fn new(w: usize, h: usize) -> Self {
        let per_row = w.div_ceil(64);
        Mask {
            words: vec![0; per_row * h],
            per_row,
        }
    }

    /// Sets sample (`x`, `y`).
    #[inline]
    pub(super) fn set(&mut self, x: usize, y: usize) {
        self.words[y * self.per_row + x / 64] |= 1 << (x % 64);
    }

    /// Whether sample (`x`, `y`) is set.
    #[inline]
    pub(super) fn get(&self, x: usize, y: usize) -> bool {
        self.words[y * self.per_row + x / 64] >> (x % 64) & 1 == 1
    }

    /// The words of row `y`.
    #[inline]
    pub(super) fn row(&self, y: usize) -> &[u64] {
        &self.words[y * self.per_row..(y + 1) * self.per_row]
    }
}

/// The 4-connected void components of `grid`, in raster order of their first
/// sample.
pub(super) fn find_components(grid: &HeightGrid) -> Vec<Component> {
    let (w, h) = (grid.width(), grid.height());
    let heights = grid.heights();
    let per_row: Vec<Vec<Run>> = heights
        .par_chunks(w)
        .enumerate()
        .map(|(y, row)| runs_of(row, y as u32))
        .collect();
    let mut start = Vec::with_capacity(h + 1);
    start.push(0usize);
    for r in &per_row {
        start.push(start.last().copied().unwrap_or(0) + r.len());
    }
    let runs: Vec<Run> = per_row.into_iter().flatten().collect();
    let mut sets = UnionFind::new(runs.len());
    for y in 1..h {
        join_rows(
            &runs,
            start[y - 1]..start[y],
            start[y]..start[y + 1],
            &mut sets,
        );
    }
    group(runs, &mut sets)
}

/// The runs of NaN in one row.
fn runs_of(row: &[f32], y: u32) -> Vec<Run> {
    let mut out = Vec::new();
    let mut x = 0;
    while x < row.len() {
        if row[x].is_nan() {
            let x0 = x;
            while x < row.len() && row[x].is_nan() {
                x += 1;
            }
            out.push(Run {
                row: y,
                x0: x0 as u32,
                x1: x as u32,
            });
        } else {
            x += 1;
        }
    }
    out
}

/// Joins every run of the row above (`above`) with the runs of the row
/// below (`below`) that share a column with it (4-connectivity).
fn join_rows(
    runs: &[Run],
    above: std::ops::Range<usize>,
    below: std::ops::Range<usize>,
    sets: &mut UnionFind,
) {
    let (mut i, mut j) = (above.start, below.start);
    while i < above.end && j < below.end {
        let (a, b) = (runs[i], runs[j]);
        if a.x0 < b.x1 && b.x0 < a.x1 {
            sets.union(i, j);
        }
        // Advance the run that ends first.
        if a.x1 <= b.x1 {
            i += 1;
        } else {
            j += 1;
        }
    }
}

/// The runs grouped by set, sets in order of their first run.
fn group(runs: Vec<Run>, sets: &mut UnionFind) -> Vec<Component> {
    let mut id = vec![u32::MAX; runs.len()];
    let mut out: Vec<Component> = Vec::new();
    for (k, r) in runs.into_iter().enumerate() {
        let root = sets.find(k);
        if id[root] == u32::MAX {
            id[root] = out.len() as u32;
            out.push(Component {
                runs: Vec::new(),
                cells: 0,
                cols: (r.x0 as usize, r.x1 as usize - 1),
                rows: (r.row as usize, r.row as usize),
            });
        }
        let c = &mut out[id[root] as usize];
        c.cells += (r.x1 - r.x0) as usize;
        c.cols = (c.cols.0.min(r.x0 as usize), c.cols.1.max(r.x1 as usize - 1));
        c.rows.1 = r.row as usize;
        c.runs.push(r);
    }
    out
}

/// Disjoint sets of run indices (union by index, path halving).
struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        UnionFind {
            parent: (0..n as u32).collect(),
        }
    }

    fn find(&mut self, mut i: usize) -> usize {
        while self.parent[i] as usize != i {
            let p = self.parent[i] as usize;
            self.parent[i] = self.parent[p];
            i = p;
        }
        i
    }

    /// Joins the sets of `a` and `b`, the smaller index becoming the root.
    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = (ra.min(rb), ra.max(rb));
            self.parent[hi] = lo as u32;
        }
    }
}

#[cfg(test)]
mod test {
    #![allow(clippy::unwrap_used, reason = "tests")]
    use super::*;
    use crate::grid::GeoRef;

    /// The components by flood fill, as sorted index lists.
    fn flood(g: &HeightGrid) -> Vec<Vec<usize>> {
        let (w, h) = (g.width(), g.height());
        let mut seen = vec![false; g.len()];
        let mut out = Vec::new();
        for s in 0..g.len() {
            if seen[s] || !g.heights()[s].is_nan() {
                continue;
            }
            let (mut stack, mut cells) = (vec![s], vec![]);
            seen[s] = true;
            while let Some(i) = stack.pop() {
                cells.push(i);
                let (x, y) = (i % w, i / w);
                let nbs = [
                    (x > 0).then(|| i - 1),
                    (x + 1 < w).then(|| i + 1),
                    (y > 0).then(|| i - w),
                    (y + 1 < h).then(|| i + w),
                ];
                for j in nbs.into_iter().flatten() {
                    if !seen[j] && g.heights()[j].is_nan() {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
            cells.sort_unstable();
            out.push(cells);
        }
        out
    }

    #[test]
    fn runs_join_like_a_flood_fill() {
        let (w, h) = (61, 47);
        for seed in 0..6u64 {
            let v = (0..w * h)
                .map(|i| {
                    let k = (i as u64 * 2654435761 + seed * 97) % 1000;
                    if k < 300 + 100 * seed {
                        f32::NAN
                    } else {
                        1.0
                    }
                })
                .collect();
            let g = HeightGrid::new(w, h, v, GeoRef::unreferenced(1.0)).unwrap();
            let got: Vec<Vec<usize>> = find_components(&g)
                .iter()
                .map(|c| {
                    let mut v: Vec<usize> = c.indices(w).collect();
                    assert_eq!(v.len(), c.cells);
                    v.sort_unstable();
                    v
                })
                .collect();
            assert_eq!(got, flood(&g), "seed {seed}");
        }
    }

    #[test]
    fn a_u_shape_is_one_component_with_its_box_and_mask() {
        // Two arms joined at the bottom: the runs meet only on the last row.
        let (w, h) = (9, 6);
        let mut v = vec![1.0f32; w * h];
        for y in 1..5 {
            v[y * w + 2] = f32::NAN;
            v[y * w + 6] = f32::NAN;
        }
        for x in 2..=6 {
            v[4 * w + x] = f32::NAN;
        }
        let g = HeightGrid::new(w, h, v, GeoRef::unreferenced(1.0)).unwrap();
        let cs = find_components(&g);
        assert_eq!(cs.len(), 1);
        let c = &cs[0];
        assert_eq!((c.cells, c.cols, c.rows), (11, (2, 6), (1, 4)));
        let a = c.area(w, h);
        assert_eq!(
            a,
            BoxArea {
                x0: 1,
                y0: 0,
                w: 7,
                h: 6
            }
        );
        let m = c.mask(&a);
        assert!(m.get(1, 1) && m.get(5, 2) && m.get(3, 4) && !m.get(3, 3));
    }
}
