//! The finest level of one void component's harmonic problem, matrix-free:
//! the heights of the component's box (its own rows of the grid, or a copy),
//! the component's mask, and the two weights `wx = 1/dx²`, `wy = 1/dy²`.
//!
//! At an unknown sample the equation is `Σ w (v_j − v_i) = 0` over its
//! 4-neighbours inside the grid (a neighbour outside the grid is absent: the
//! Neumann edge of [`super`]); a neighbour is either unknown (in the
//! component) or a valid sample of its border, which is where the known
//! values come in. So the level needs no stored coefficients: the red–black
//! sweep, the residual and the transfers read the heights and the mask.
//!
//! Multigrid after Briggs, Henson & McCormick, *A Multigrid Tutorial* (2nd
//! ed., SIAM 2000); the coarse levels are in `coarse`.

use super::bands::{row_with_neighbours, two_pass};
use super::components::Mask;
use super::dense::solve_dense;

/// One colour's bits in a mask word: even columns (`0x55…`) or odd (`0xAA…`).
const COLOUR: [u64; 2] = [0x5555_5555_5555_5555, 0xAAAA_AAAA_AAAA_AAAA];

/// A component's finest level (see the module docs).
pub(super) struct Fine<'a> {
    /// The box's rows, `w` samples each, north first.
    pub(super) rows: Vec<&'a mut [f32]>,
    /// The unknown samples (the component's).
    pub(super) mask: Mask,
    pub(super) w: usize,
    pub(super) h: usize,
    /// Weight of a coupling across columns (1/dx²) and across rows (1/dy²).
    pub(super) wx: f32,
    pub(super) wy: f32,
}

/// A sample of the box and how it relates to the component.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Cell {
    /// In the component.
    Unknown,
    /// A valid sample with an unknown 4-neighbour.
    Border,
    /// Anything else: takes no part.
    Absent,
}

impl<'a> Fine<'a> {
    /// The level over `rows` (each `w` long) with `mask`; the unknowns are
    /// set to 0 so that no NaN is ever read.
    pub(super) fn new(mut rows: Vec<&'a mut [f32]>, mask: Mask, wx: f32, wy: f32) -> Self {
        let (w, h) = (rows.first().map_or(0, |r| r.len()), rows.len());
        for (y, row) in rows.iter_mut().enumerate() {
            for_each_bit(mask.row(y), |x| row[x] = 0.0);
        }
        Fine {
            rows,
            mask,
            w,
            h,
            wx,
            wy,
        }
    }

    /// Whether (`x`, `y`) is unknown; false outside the box.
    #[inline]
    pub(super) fn unknown(&self, x: usize, y: usize) -> bool {
        x < self.w && y < self.h && self.mask.get(x, y)
    }

    /// How (`x`, `y`) takes part.
    pub(super) fn cell(&self, x: usize, y: usize) -> Cell {
        if x >= self.w || y >= self.h {
            Cell::Absent
        } else if self.mask.get(x, y) {
            Cell::Unknown
        } else if (x > 0 && self.mask.get(x - 1, y))
            || self.unknown(x + 1, y)
            || (y > 0 && self.mask.get(x, y - 1))
            || self.unknown(x, y + 1)
        {
            Cell::Border
        } else {
            Cell::Absent
        }
    }

    /// Number of unknowns.
    pub(super) fn unknowns(&self) -> usize {
        (0..self.h)
            .map(|y| {
                self.mask
                    .row(y)
                    .iter()
                    .map(|w| w.count_ones() as usize)
                    .sum::<usize>()
            })
            .sum()
    }

    /// The lowest and highest border value (the maximum principle's range).
    pub(super) fn border_range(&self) -> (f32, f32) {
        let mut range = (f32::INFINITY, f32::NEG_INFINITY);
        for y in 0..self.h {
            for x in 0..self.w {
                if self.cell(x, y) == Cell::Border {
                    let v = self.rows[y][x];
                    range = (range.0.min(v), range.1.max(v));
                }
            }
        }
        range
    }

    /// Clamps every unknown to `range`.
    pub(super) fn clamp(&mut self, range: (f32, f32)) {
        for (y, row) in self.rows.iter_mut().enumerate() {
            // max/min rather than clamp: no panic even for an empty range.
            for_each_bit(self.mask.row(y), |x| {
                row[x] = row[x].max(range.0).min(range.1)
            });
        }
    }

    /// One red–black Gauss–Seidel sweep (by bands, see `bands`); returns the
    /// largest change of an unknown. The same result as all red cells, then
    /// all black ones.
    pub(super) fn sweep(&mut self) -> f32 {
        let (mask, w, h, wx, wy) = (&self.mask, self.w, self.h, self.wx, self.wy);
        two_pass(&mut self.rows, w, |first, band, above, below| {
            let mut change = 0f32;
            // One wavefront (as `Coarse::sweep`): the red cells of a row,
            // then the black ones of the row above.
            for step in 0..=band.len() {
                for (i, colour) in [(step, 0), (step.wrapping_sub(1), 1)] {
                    if i >= band.len() {
                        continue;
                    }
                    let y = first + i;
                    let (mid, up, down) = row_with_neighbours(band, i, above, below);
                    let parity = (y + colour) % 2;
                    let k = Kernel {
                        wx,
                        wy,
                        w,
                        up: up.map(|r| &**r),
                        down: down.filter(|_| y + 1 < h).map(|r| &**r),
                    };
                    change = change.max(k.relax(mid, mask.row(y), parity));
                }
            }
            change
        })
    }

    /// Sum of `w·(v_j − v_i)` over the existing neighbours of unknown
    /// (`x`, `y`): its residual.
    #[inline]
    pub(super) fn residual(&self, x: usize, y: usize) -> f32 {
        let (row, v) = (&self.rows[y], self.rows[y][x]);
        let mut r = 0f32;
        if x > 0 {
            r += self.wx * (row[x - 1] - v);
        }
        if x + 1 < self.w {
            r += self.wx * (row[x + 1] - v);
        }
        if y > 0 {
            r += self.wy * (self.rows[y - 1][x] - v);
        }
        if y + 1 < self.h {
            r += self.wy * (self.rows[y + 1][x] - v);
        }
        r
    }

    /// The direct solve of a level of few unknowns (dense Cholesky, see
    /// [`solve_dense`]); false when the factorisation fails.
    pub(super) fn solve_direct(&mut self) -> bool {
        let mut cells = Vec::new();
        for y in 0..self.h {
            for_each_bit(self.mask.row(y), |x| cells.push((x, y)));
        }
        let n = cells.len();
        let (mut a, mut b) = (vec![0f64; n * n], vec![0f64; n]);
        for (k, &(x, y)) in cells.iter().enumerate() {
            let nbs = [
                (x.wrapping_sub(1), y, self.wx),
                (x + 1, y, self.wx),
                (x, y.wrapping_sub(1), self.wy),
                (x, y + 1, self.wy),
            ];
            for (nx, ny, wgt) in nbs {
                if nx >= self.w || ny >= self.h {
                    continue;
                }
                let wgt = f64::from(wgt);
                a[k * n + k] += wgt;
                if self.mask.get(nx, ny) {
                    if let Some(l) = cells.iter().position(|&c| c == (nx, ny)) {
                        a[k * n + l] -= wgt;
                    }
                } else {
                    b[k] += wgt * f64::from(self.rows[ny][nx]);
                }
            }
        }
        if !solve_dense(&mut a, &mut b, n) {
            return false;
        }
        for (&(x, y), v) in cells.iter().zip(b) {
            self.rows[y][x] = v as f32;
        }
        true
    }
}

/// The red–black update of one row.
struct Kernel<'r> {
    wx: f32,
    wy: f32,
    w: usize,
    up: Option<&'r [f32]>,
    down: Option<&'r [f32]>,
}

impl Kernel<'_> {
    /// Relaxes the unknowns of `mid` whose column has `parity`; returns the
    /// largest change.
    #[inline]
    fn relax(&self, mid: &mut [f32], bits: &[u64], parity: usize) -> f32 {
        let mut change = 0f32;
        let (wx, wy, w) = (self.wx, self.wy, self.w);
        let inner = match (self.up, self.down) {
            (Some(u), Some(d)) => Some((u, d)),
            _ => None,
        };
        let full = 1.0 / (2.0 * wx + 2.0 * wy);
        for (k, &word) in bits.iter().enumerate() {
            let mut b = word & COLOUR[parity];
            while b != 0 {
                let x = 64 * k + b.trailing_zeros() as usize;
                b &= b - 1;
                let old = mid[x];
                let new = match inner {
                    Some((u, d)) if x > 0 && x + 1 < w => {
                        (wx * (mid[x - 1] + mid[x + 1]) + wy * (u[x] + d[x])) * full
                    }
                    _ => self.edge(mid, x),
                };
                mid[x] = new;
                change = change.max((new - old).abs());
            }
        }
        change
    }

    /// The update of an unknown with a neighbour outside the grid.
    #[cold]
    fn edge(&self, mid: &[f32], x: usize) -> f32 {
        let (mut s, mut d) = (0f32, 0f32);
        if x > 0 {
            s += self.wx * mid[x - 1];
            d += self.wx;
        }
        if x + 1 < self.w {
            s += self.wx * mid[x + 1];
            d += self.wx;
        }
        for r in [self.up, self.down].into_iter().flatten() {
            s += self.wy * r[x];
            d += self.wy;
        }
        if d > 0.0 {
            s / d
        } else {
            mid[x]
        }
    }
}

/// Calls `f(x)` for every set bit of a mask row.
#[inline]
pub(super) fn for_each_bit(words: &[u64], mut f: impl FnMut(usize)) {
    for (k, &word) in words.iter().enumerate() {
        let mut b = word;
        while b != 0 {
            f(64 * k + b.trailing_zeros() as usize);
            b &= b - 1;
        }
    }
}
