//! The largest deviation of a plane from a row of lattice heights, skipping
//! the runs of samples that cannot hold it.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §2: a coarse triangle's own error is the
//! largest `|plane − h|` over its samples ([`super::cap`]). Its coarse
//! levels read the whole window once per level and per pass, the largest
//! part of preparing a pyramid's coarse tiles. The answer is a maximum, so
//! a run of samples whose deviations are all at most the maximum already
//! found can be left out without changing it.
//!
//! Per row of the lattice's grid, per run of [`BLOCK`] columns and per long
//! run of 16 runs (256 columns), the lowest and highest heights and their
//! columns are kept once. Along a row the
//! plane is linear, so over a run it lies between its values at the run's
//! two ends `p_a`, `p_b`, and every deviation in the run is at most
//! `max(max(p_a, p_b) − h_lo, h_hi − min(p_a, p_b))`. A row span is read as:
//!
//! 1. [`RowBlocks::row_seed`]: the columns before the first whole run and
//!    after the last, one by one, and at each whole run the deviations at
//!    its lowest and highest samples: a lower bound of the answer, usually
//!    close to it. [`super::cap::own_rows`] takes it over every row of the
//!    triangle first;
//!    (Within a long run wholly in the span, only its lowest and highest.)
//! 2. [`RowBlocks::row_rest`]: each whole run whose bound, plus a rounding
//!    margin, exceeds the triangle's maximum so far, one by one; a long
//!    run's runs only when the long run's own bound exceeds it.
//!
//! Every deviation is computed by the same expression as in the one-by-one
//! loop ([`max_deviation`]), and a run is left out only when its bound is
//! below the maximum by more than the rounding of the plane's evaluation
//! (`ε·(1 + |z| + |h|)` with `ε = 10⁻⁹`, about 10⁷ times the double's
//! relative rounding), so the result is the loop's, bit for bit.

use rayon::prelude::*;

use crate::grid::HeightGrid;
use crate::mesh::raster::Plane;

/// Columns per run.
pub(crate) const BLOCK: usize = 16;

/// Runs per long run (256 columns: offsets still fit a byte).
const LONG: usize = 16;

/// Relative rounding margin of a run's bound (see the module docs).
const MARGIN: f64 = 1e-9;

/// One run's lowest and highest heights, and their offsets in the run.
#[derive(Debug, Clone, Copy, Default)]
struct Run {
    lo: f32,
    hi: f32,
    at_lo: u8,
    at_hi: u8,
}

/// The runs of every row of a grid (whole runs only), and the long runs
/// of [`LONG`] runs.
#[derive(Debug, Clone)]
pub(crate) struct RowBlocks {
    per_row: usize,
    runs: Vec<Run>,
    long_per_row: usize,
    long: Vec<Run>,
}

/// The columns `i..=j` of the grid's row `r` (heights `row`), column `i`
/// being lattice column `x_i`, at lattice row `y`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct RowSpan<'a> {
    pub(crate) row: &'a [f32],
    pub(crate) r: usize,
    pub(crate) i: usize,
    pub(crate) j: usize,
    pub(crate) x_i: i64,
    pub(crate) y: f64,
}

/// Where a row span's whole runs lie: runs `k0..k1`, of which the long
/// runs `l0..l1` cover runs `LONG·l0..LONG·l1` (none when `l0 == l1`).
#[derive(Debug, Clone, Copy)]
struct Layout {
    k0: usize,
    k1: usize,
    l0: usize,
    l1: usize,
}

impl Layout {
    /// The runs outside the long runs.
    fn loose(&self) -> impl Iterator<Item = usize> {
        let (a, b) = (LONG * self.l0, LONG * self.l1);
        (self.k0..a.max(self.k0).min(self.k1)).chain(b.max(self.k0).min(self.k1)..self.k1)
    }
}

impl RowBlocks {
    /// The runs of `grid`'s rows.
    pub(crate) fn new(grid: &HeightGrid) -> RowBlocks {
        let (w, h) = (grid.width(), grid.height());
        let per_row = w / BLOCK;
        let mut runs = vec![Run::default(); per_row * h];
        if per_row > 0 {
            runs.par_chunks_mut(per_row)
                .zip(grid.heights().par_chunks(w))
                .for_each(|(out, row)| {
                    for (run, s) in out.iter_mut().zip(row.chunks_exact(BLOCK)) {
                        *run = summarise(s);
                    }
                });
        }
        let long_per_row = per_row / LONG;
        let long = if long_per_row > 0 {
            runs.chunks_exact(per_row)
                .flat_map(|row| row.chunks_exact(LONG).take(long_per_row).map(merge))
                .collect()
        } else {
            Vec::new()
        };
        RowBlocks {
            per_row,
            runs,
            long_per_row,
            long,
        }
    }

    /// The whole runs of columns `i..=j`, or `None` when there are fewer
    /// than two (the span is then read one by one).
    fn layout(&self, (i, j): (usize, usize)) -> Option<Layout> {
        let (k0, k1) = (i.div_ceil(BLOCK), ((j + 1) / BLOCK).min(self.per_row));
        if k1 < k0 + 2 {
            return None;
        }
        let (l0, l1) = (k0.div_ceil(LONG), (k1 / LONG).min(self.long_per_row));
        let (l0, l1) = if l1 > l0 { (l0, l1) } else { (0, 0) };
        Some(Layout { k0, k1, l0, l1 })
    }

    /// First pass over `span`: `|plane − h|` at the columns outside whole runs and at each run's
    /// lowest and highest samples (every column when there are fewer than
    /// two whole runs). A lower bound of the span's largest deviation, and
    /// with [`Self::row_rest`] over the same span, equal to it.
    pub(crate) fn row_seed(&self, plane: &Plane, span: RowSpan<'_>) -> f64 {
        let RowSpan {
            row,
            r,
            i,
            j,
            x_i,
            y,
        } = span;
        let Some(at) = self.layout((i, j)) else {
            return max_deviation(plane, x_i, y, &row[i..=j]);
        };
        let (s, t) = (at.k0 * BLOCK, at.k1 * BLOCK);
        let x = |c: usize| x_i + (c - i) as i64;
        let dev = |c: usize| (plane.at(x(c) as f64, y) - f64::from(row[c])).abs();
        let mut e = max_deviation(plane, x_i, y, &row[i..s]);
        if t <= j {
            e = e.max(max_deviation(plane, x(t), y, &row[t..=j]));
        }
        let extremes = |c: usize, run: &Run| {
            dev(c + usize::from(run.at_lo)).max(dev(c + usize::from(run.at_hi)))
        };
        for k in at.loose() {
            e = e.max(extremes(k * BLOCK, &self.runs[r * self.per_row + k]));
        }
        for l in at.l0..at.l1 {
            e = e.max(extremes(
                l * LONG * BLOCK,
                &self.long[r * self.long_per_row + l],
            ));
        }
        e
    }

    /// Second pass over the same span: the largest `|plane − h|` of the
    /// whole runs whose bound can exceed `floor` (a value of the first
    /// pass, or of any sample), read one by one; `floor` when none can.
    /// `z_abs` is the largest |height| of the plane's corners.
    pub(crate) fn row_rest(
        &self,
        plane: &Plane,
        span: RowSpan<'_>,
        (z_abs, floor): (f64, f64),
    ) -> f64 {
        let RowSpan {
            row,
            r,
            i,
            j,
            x_i,
            y,
        } = span;
        let Some(at) = self.layout((i, j)) else {
            return floor;
        };
        let x = |c: usize| x_i + (c - i) as i64;
        // Can a run of `n` columns from column `c` exceed `e`?
        let open = |c: usize, n: usize, run: &Run, e: f64| {
            let (pa, pb) = (plane.at(x(c) as f64, y), plane.at(x(c + n - 1) as f64, y));
            let (lo, hi) = (f64::from(run.lo), f64::from(run.hi));
            let bound = (pa.max(pb) - lo).max(hi - pa.min(pb));
            bound + MARGIN * (1.0 + z_abs + lo.abs() + hi.abs()) > e
        };
        let read = |k: usize, e: f64| {
            let c = k * BLOCK;
            if open(c, BLOCK, &self.runs[r * self.per_row + k], e) {
                e.max(max_deviation(plane, x(c), y, &row[c..c + BLOCK]))
            } else {
                e
            }
        };
        let mut e = at.loose().fold(floor, |e, k| read(k, e));
        for l in at.l0..at.l1 {
            if open(
                l * LONG * BLOCK,
                LONG * BLOCK,
                &self.long[r * self.long_per_row + l],
                e,
            ) {
                e = (l * LONG..(l + 1) * LONG).fold(e, |e, k| read(k, e));
            }
        }
        e
    }
}

/// A run's lowest and highest heights (the first of equal ones).
fn summarise(s: &[f32]) -> Run {
    let mut run = Run {
        lo: s[0],
        hi: s[0],
        at_lo: 0,
        at_hi: 0,
    };
    for (k, &h) in s.iter().enumerate().skip(1) {
        if h < run.lo {
            (run.lo, run.at_lo) = (h, k as u8);
        }
        if h > run.hi {
            (run.hi, run.at_hi) = (h, k as u8);
        }
    }
    run
}

/// The long run of `LONG` runs: their lowest and highest, offsets from the
/// long run's first column.
fn merge(runs: &[Run]) -> Run {
    let mut out = runs[0];
    for (m, run) in runs.iter().enumerate().skip(1) {
        let base = (m * BLOCK) as u8;
        if run.lo < out.lo {
            (out.lo, out.at_lo) = (run.lo, base + run.at_lo);
        }
        if run.hi > out.hi {
            (out.hi, out.at_hi) = (run.hi, base + run.at_hi);
        }
    }
    out
}

/// Largest `|plane(x, y) − h|` over `heights`, the samples of row `y` from
/// column `x0` on: each value computed as `Plane::at` computes it, in four
/// independent lanes (so the compiler can use vector registers) whose
/// maxima are then merged; a maximum does not depend on the order it is
/// taken in, so the result is the one-by-one loop's, bit for bit.
pub(crate) fn max_deviation(plane: &Plane, x0: i64, y: f64, heights: &[f32]) -> f64 {
    let mut lanes = [0f64; 4];
    let mut chunks = heights.chunks_exact(4);
    let mut x = x0;
    for c in &mut chunks {
        for (k, (m, h)) in lanes.iter_mut().zip(c).enumerate() {
            let d = (plane.at((x + k as i64) as f64, y) - f64::from(*h)).abs();
            *m = if d > *m { d } else { *m };
        }
        x += 4;
    }
    let mut e = lanes[0].max(lanes[1]).max(lanes[2].max(lanes[3]));
    for (k, h) in chunks.remainder().iter().enumerate() {
        e = e.max((plane.at((x + k as i64) as f64, y) - f64::from(*h)).abs());
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{GeoRef, HeightGrid};

    /// A rough row pattern: the blocked maximum equals the one-by-one one
    /// for every span, over planes of many slopes.
    #[test]
    fn runs_give_the_one_by_one_maximum_bit_for_bit() {
        let w = 1000;
        let heights: Vec<f32> = (0..w * 3)
            .map(|k| {
                let x = k as f32;
                (x * 0.37).sin() * 40.0
                    + (x * 0.05).cos() * 300.0
                    + if k % 17 == 3 { 90.0 } else { 0.0 }
            })
            .collect();
        let grid = HeightGrid::new(w, 3, heights, GeoRef::unreferenced(30.0)).expect("grid");
        let blocks = RowBlocks::new(&grid);
        let mut checked = 0;
        for (n, z) in [
            [0.0, 0.0, 0.0],
            [300.0, -200.0, 50.0],
            [-20.0, 400.0, 380.0],
        ]
        .into_iter()
        .enumerate()
        {
            let p = [[0, 0], [2 * w as u32, 0], [0, 2 * w as u32]];
            let plane = Plane::new(p, z).expect("plane");
            let r = n % 3;
            let row = &grid.heights()[r * w..(r + 1) * w];
            for i in (0..w).step_by(37) {
                for j in (i..w).step_by(23) {
                    let a = max_deviation(&plane, 1000 + i as i64, 7.0, &row[i..=j]);
                    let (x_i, y) = (1000 + i as i64, 7.0);
                    let span = RowSpan {
                        row,
                        r,
                        i,
                        j,
                        x_i,
                        y,
                    };
                    let seed = blocks.row_seed(&plane, span);
                    let b = seed.max(blocks.row_rest(&plane, span, (400.0, seed)));
                    assert_eq!(a.to_bits(), b.to_bits(), "span {i}..={j}");
                    checked += 1;
                }
            }
        }
        assert!(checked > 300);
    }
}
