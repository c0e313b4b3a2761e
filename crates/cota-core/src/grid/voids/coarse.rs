//! The coarse levels of one void component's multigrid: the error equation
//! on 2×2 blocks of the level below, with the Galerkin-style coarse operator
//! of [`super`] (step 3), and the transfers between levels.
//!
//! A block holding an unknown is unknown, else known (error 0) if it holds a
//! known cell, else absent. The operator is the product `Pᵀ A P` with the
//! piecewise-constant interpolation `P`: couplings inside a block cancel,
//! couplings between two blocks add up (scaled by
//! [`COARSE_COUPLING_SCALE`]), couplings to known cells add up on the
//! diagonal (the *Dirichlet part*, kept whole). So the boundary keeps its
//! place and strength on every level, and no coarse problem is singular.
//! Each level stores per cell its value, right-hand side, the couplings to
//! its east and south neighbours (the west and north ones are its
//! neighbours'), the Dirichlet part of its diagonal (the diagonal is summed
//! when used) and its state: 21 bytes, so all coarse levels together take
//! about 7 bytes per sample of the component's box.
//!
//! Briggs, Henson & McCormick, *A Multigrid Tutorial* (2nd ed., SIAM 2000):
//! Galerkin coarse operators, full-weighting-like summed restriction,
//! bilinear interpolation, red–black Gauss–Seidel.

use rayon::prelude::*;

use super::bands::{min_rows, row_with_neighbours, two_pass, PARALLEL_CELLS};
use super::dense::solve_dense;
use super::fine::{for_each_bit, Cell, Fine};
use super::interp::{ABSENT, KNOWN, UNKNOWN};

/// Scale of the couplings between coarse cells: 1/2 makes the product with
/// piecewise-constant interpolation agree, away from the boundary, with the
/// operator rediscretised at twice the spacing (with the summed
/// restriction). Couplings to known cells are kept whole: halving them too
/// makes the cycles diverge near the boundary.
const COARSE_COUPLING_SCALE: f64 = 0.5;

/// One coarse level (see the module docs). Arrays are framed (`interp`).
pub(super) struct Coarse {
    pub(super) w: usize,
    pub(super) h: usize,
    pub(super) stride: usize,
    pub(super) state: Vec<u8>,
    pub(super) value: Vec<f32>,
    rhs: Vec<f32>,
    east: Vec<f32>,
    south: Vec<f32>,
    /// The Dirichlet part of the diagonal at unknowns, 0 elsewhere (the
    /// diagonal is this plus the cell's four couplings, summed when used).
    dirichlet: Vec<f32>,
    /// Number of unknown cells.
    pub(super) unknowns: usize,
}

/// One block's part of a new level.
#[derive(Clone, Copy, Default)]
struct BlockCoef {
    east: f64,
    south: f64,
    dirichlet: f64,
}

impl Coarse {
    /// An all-absent level of `w × h` cells.
    fn empty(w: usize, h: usize) -> Self {
        let stride = w + 2;
        let n = stride * (h + 2);
        Coarse {
            w,
            h,
            stride,
            state: vec![ABSENT; n],
            value: vec![0.0; n],
            rhs: vec![0.0; n],
            east: vec![0.0; n],
            south: vec![0.0; n],
            dirichlet: vec![0.0; n],
            unknowns: 0,
        }
    }

    /// Framed index of (`x`, `y`).
    #[inline]
    fn at(&self, x: usize, y: usize) -> usize {
        (y + 1) * self.stride + x + 1
    }

    /// The first coarse level, from the finest.
    pub(super) fn from_fine(fine: &Fine<'_>) -> Self {
        let mut c = Coarse::empty(fine.w.div_ceil(2), fine.h.div_ceil(2));
        let (wx, wy) = (f64::from(fine.wx), f64::from(fine.wy));
        c.fill_blocks(|cx, cy| {
            let (mut unknown, mut known) = (false, false);
            let mut coef = BlockCoef::default();
            for fy in 2 * cy..(2 * cy + 2).min(fine.h) {
                for fx in 2 * cx..(2 * cx + 2).min(fine.w) {
                    match fine.cell(fx, fy) {
                        Cell::Unknown => {
                            unknown = true;
                            coef.dirichlet += fine_dirichlet(fine, fx, fy, wx, wy);
                        }
                        Cell::Border => known = true,
                        Cell::Absent => {}
                    }
                }
                let e = fine.unknown(2 * cx + 1, fy) && fine.unknown(2 * cx + 2, fy);
                coef.east += if e { wx } else { 0.0 };
            }
            for fx in 2 * cx..(2 * cx + 2).min(fine.w) {
                let s = fine.unknown(fx, 2 * cy + 1) && fine.unknown(fx, 2 * cy + 2);
                coef.south += if s { wy } else { 0.0 };
            }
            (state_of(unknown, known), coef)
        });
        c
    }

    /// The next coarser level.
    pub(super) fn coarsen(&self) -> Coarse {
        let prev = self;
        let mut c = Coarse::empty(prev.w.div_ceil(2), prev.h.div_ceil(2));
        c.fill_blocks(|cx, cy| {
            let (mut unknown, mut known) = (false, false);
            let mut coef = BlockCoef::default();
            for py in 2 * cy..(2 * cy + 2).min(prev.h) {
                for px in 2 * cx..(2 * cx + 2).min(prev.w) {
                    let i = prev.at(px, py);
                    match prev.state[i] {
                        UNKNOWN => {
                            unknown = true;
                            coef.dirichlet += f64::from(prev.dirichlet[i]);
                        }
                        KNOWN => known = true,
                        _ => {}
                    }
                }
                if 2 * cx + 1 < prev.w {
                    coef.east += f64::from(prev.east[prev.at(2 * cx + 1, py)]);
                }
            }
            if 2 * cy + 1 < prev.h {
                for px in 2 * cx..(2 * cx + 2).min(prev.w) {
                    coef.south += f64::from(prev.south[prev.at(px, 2 * cy + 1)]);
                }
            }
            (state_of(unknown, known), coef)
        });
        c
    }

    /// Sets every cell from `block(x, y)` (in parallel over rows), then the
    /// unknown count.
    fn fill_blocks(&mut self, block: impl Fn(usize, usize) -> (u8, BlockCoef) + Sync) {
        let (s, w, h) = (self.stride, self.w, self.h);
        self.state
            .par_chunks_mut(s)
            .zip(self.east.par_chunks_mut(s))
            .zip(self.south.par_chunks_mut(s))
            .zip(self.dirichlet.par_chunks_mut(s))
            .skip(1)
            .take(h)
            .with_min_len(min_rows(s))
            .enumerate()
            .for_each(|(y, (((state, east), south), dirichlet))| {
                for x in 0..w {
                    let (st, coef) = block(x, y);
                    state[x + 1] = st;
                    if st == UNKNOWN {
                        east[x + 1] = (COARSE_COUPLING_SCALE * coef.east) as f32;
                        south[x + 1] = (COARSE_COUPLING_SCALE * coef.south) as f32;
                        dirichlet[x + 1] = coef.dirichlet as f32;
                    }
                }
            });
        self.unknowns = self.state.iter().filter(|&&st| st == UNKNOWN).count();
    }

    /// The diagonal of the framed cell `j` (an unknown): its Dirichlet part
    /// plus its four couplings.
    #[inline]
    fn diag(&self, j: usize) -> f32 {
        let s = self.stride;
        self.dirichlet[j] + self.east[j - 1] + self.east[j] + self.south[j - s] + self.south[j]
    }

    /// The residual of the framed cell `j`: `rhs + Σ c·v_nb − diag·v`.
    #[inline]
    fn residual(&self, j: usize) -> f32 {
        let (s, v) = (self.stride, &self.value);
        self.rhs[j]
            + self.east[j - 1] * v[j - 1]
            + self.east[j] * v[j + 1]
            + self.south[j - s] * v[j - s]
            + self.south[j] * v[j + s]
            - self.diag(j) * v[j]
    }

    /// One red–black Gauss–Seidel sweep (by bands); returns the largest
    /// change. Inside a band the two colours go as one wavefront (the red
    /// cells of a row, then the black ones of the row above, whose
    /// neighbours are all updated by then): the same result as all red
    /// cells, then all black ones, in one pass over the memory.
    pub(super) fn sweep(&mut self) -> f32 {
        let s = self.stride;
        let zeros = vec![0f32; s];
        let (rows_start, rows_end) = (s, s * (self.h + 1));
        // The values are taken out for the while: `relax_row` reads the
        // level's coefficients only.
        let mut values = std::mem::take(&mut self.value);
        let this = &*self;
        let mut rows: Vec<&mut [f32]> = values[rows_start..rows_end].chunks_mut(s).collect();
        let change = two_pass(&mut rows, s, |first, band, above, below| {
            let mut change = 0f32;
            for step in 0..=band.len() {
                for (i, colour) in [(step, 0), (step.wrapping_sub(1), 1)] {
                    if i >= band.len() {
                        continue;
                    }
                    let (mid, up, down) = row_with_neighbours(band, i, above, below);
                    let (up, down) = (up.map_or(&zeros[..], |r| r), down.map_or(&zeros[..], |r| r));
                    change = change.max(this.relax_row(first + i, colour, mid, up, down));
                }
            }
            change
        });
        self.value = values;
        change
    }

    /// Relaxes the unknowns of row `y` (`mid`, framed) whose `(x + y) % 2`
    /// is `colour`, with the framed rows `up` and `down` around it; returns
    /// the largest change.
    #[inline]
    fn relax_row(&self, y: usize, colour: usize, mid: &mut [f32], up: &[f32], down: &[f32]) -> f32 {
        let s = self.stride;
        let base = (y + 1) * s;
        let rhs = &self.rhs[base..base + s];
        let east = &self.east[base..base + s];
        let south = &self.south[base..base + s];
        let north = &self.south[base - s..base];
        let state = &self.state[base..base + s];
        let dirichlet = &self.dirichlet[base..base + s];
        let (up, down) = (&up[..s], &down[..s]);
        let mid = &mut mid[..s];
        let mut change = 0f32;
        for j in ((y + colour) % 2 + 1..s - 1).step_by(2) {
            if state[j] != UNKNOWN {
                continue;
            }
            let d = dirichlet[j] + east[j - 1] + east[j] + north[j] + south[j];
            let t = rhs[j]
                + east[j - 1] * mid[j - 1]
                + east[j] * mid[j + 1]
                + north[j] * up[j]
                + south[j] * down[j];
            let new = t / d;
            change = change.max((new - mid[j]).abs());
            mid[j] = new;
        }
        change
    }

    /// Sets `next` (the level above) to the error equation of this one:
    /// zero values, and the summed residual of each block as right-hand side.
    pub(super) fn restrict(&self, next: &mut Coarse) {
        let (ns, nw) = (next.stride, next.w);
        next.value.fill(0.0);
        let task = |cy: usize, rhs: &mut [f32]| {
            for cx in 0..nw {
                let mut r = 0f32;
                for py in 2 * cy..(2 * cy + 2).min(self.h) {
                    for px in 2 * cx..(2 * cx + 2).min(self.w) {
                        let j = self.at(px, py);
                        if self.state[j] == UNKNOWN {
                            r += self.residual(j);
                        }
                    }
                }
                rhs[cx + 1] = r;
            }
        };
        let rows = &mut next.rhs[ns..ns * (next.h + 1)];
        if rows.len() < PARALLEL_CELLS {
            rows.chunks_mut(ns)
                .enumerate()
                .for_each(|(cy, r)| task(cy, r));
        } else {
            rows.par_chunks_mut(ns)
                .with_min_len(min_rows(ns))
                .enumerate()
                .for_each(|(cy, r)| task(cy, r));
        }
    }

    /// Sets this level (the first coarse one) to the error equation of
    /// `fine`: zero values, the summed fine residuals as right-hand side.
    pub(super) fn restrict_fine(&mut self, fine: &Fine<'_>) {
        let (s, w) = (self.stride, self.w);
        self.value.fill(0.0);
        self.rhs
            .par_chunks_mut(s)
            .skip(1)
            .take(self.h)
            .with_min_len(min_rows(s))
            .enumerate()
            .for_each(|(cy, rhs)| {
                rhs.fill(0.0);
                for fy in 2 * cy..(2 * cy + 2).min(fine.h) {
                    for_each_bit(fine.mask.row(fy), |fx| {
                        rhs[fx / 2 + 1] += fine.residual(fx, fy);
                    });
                }
                debug_assert!(rhs.len() == w + 2);
            });
    }

    /// Adds the interpolated correction of `next` (the level above) to this
    /// level's unknowns (as [`Coarse::correct_fine`] does, one direction at
    /// a time).
    pub(super) fn correct_from(&mut self, next: &Coarse) {
        self.add_from(next, ABSENT);
    }

    /// Sets this level's unknowns to the interpolation of `next`'s unknowns
    /// (its known cells left out: they hold no height): the full
    /// multigrid's start on this level, from the solution on `next`.
    pub(super) fn start_from(&mut self, next: &Coarse) {
        self.value.fill(0.0);
        self.add_from(next, KNOWN);
    }

    /// Sets `fine`'s unknowns to the interpolation of this level's unknowns
    /// (as [`Coarse::start_from`]).
    pub(super) fn start_fine(&self, fine: &mut Fine<'_>) {
        self.add_to_fine(fine, KNOWN, true);
    }

    /// Adds to this level's unknowns the interpolation of `next`, leaving
    /// out its cells whose state is `skip` (and the absent ones).
    fn add_from(&mut self, next: &Coarse, skip: u8) {
        let (s, ns) = (self.stride, next.stride);
        let state = &self.state;
        let task = |y: usize, row: &mut [f32], num: &mut Vec<f32>, den: &mut Vec<f32>| {
            next.blend_rows_of(y, num, den, skip);
            let st = &state[(y + 1) * s..(y + 2) * s];
            for j in 1..s - 1 {
                if st[j] != UNKNOWN {
                    continue;
                }
                row[j] += blend_columns(j - 1, num, den);
            }
        };
        let rows = &mut self.value[s..s * (self.h + 1)];
        if rows.len() < PARALLEL_CELLS {
            let (mut num, mut den) = (vec![0f32; ns], vec![0f32; ns]);
            for (y, row) in rows.chunks_mut(s).enumerate() {
                task(y, row, &mut num, &mut den);
            }
        } else {
            rows.par_chunks_mut(s)
                .with_min_len(min_rows(s))
                .enumerate()
                .for_each_init(
                    || (vec![0f32; ns], vec![0f32; ns]),
                    |(num, den), (y, row)| task(y, row, num, den),
                );
        }
    }

    /// Adds the interpolated correction of this level to `fine`'s unknowns;
    /// returns the largest correction. The bilinear weights of
    /// [`Coarse::blend_rows_of`], one direction at a time: each fine row
    /// first blends its two coarse rows (values of present cells, and their
    /// weights), then each unknown blends two columns of that and divides.
    pub(super) fn correct_fine(&self, fine: &mut Fine<'_>) -> f32 {
        self.add_to_fine(fine, ABSENT, false)
    }

    /// Adds (or with `set`, writes) to `fine`'s unknowns the interpolation
    /// of this level, leaving out its cells whose state is `skip`; returns
    /// the largest value interpolated.
    fn add_to_fine(&self, fine: &mut Fine<'_>, skip: u8, set: bool) -> f32 {
        let mask = &fine.mask;
        fine.rows
            .par_iter_mut()
            .with_min_len(min_rows(fine.w))
            .enumerate()
            .map_init(
                || (vec![0f32; self.stride], vec![0f32; self.stride]),
                |(num, den), (y, row)| {
                    self.blend_rows_of(y, num, den, skip);
                    let mut most = 0f32;
                    for_each_bit(mask.row(y), |x| {
                        let c = blend_columns(x, num, den);
                        row[x] = if set { c } else { row[x] + c };
                        most = most.max(c.abs());
                    });
                    most
                },
            )
            .reduce(|| 0f32, f32::max)
    }

    /// For row `y` of the level below: the blend of this level's two framed
    /// rows around it, per framed column, of the present cells' values
    /// (`num`) and weights (`den`). Row `y` lies at coarse coordinate
    /// `(y − 0.5)/2`, between the centres of blocks `y/2 − 1` and `y/2`
    /// (weights 1/4, 3/4) when `y` is even, `y/2` and `y/2 + 1` (3/4, 1/4)
    /// when odd; columns likewise (in the callers). Cells left out drop
    /// out and the weights are renormalised; a cell's own block always
    /// takes part, so an unknown always gets a value.
    /// Cells whose state is `ABSENT` or `skip` are left out.
    fn blend_rows_of(&self, y: usize, num: &mut [f32], den: &mut [f32], skip: u8) {
        let (y0, ty) = if y.is_multiple_of(2) {
            (y / 2, 0.75f32)
        } else {
            (y / 2 + 1, 0.25)
        };
        let s = self.stride;
        let (upper, lower) = (y0 * s, (y0 + 1) * s);
        for c in 0..s {
            let present = |st: u8| st != ABSENT && st != skip;
            let pu = if present(self.state[upper + c]) {
                1.0 - ty
            } else {
                0.0
            };
            let pl = if present(self.state[lower + c]) {
                ty
            } else {
                0.0
            };
            num[c] = pu * self.value[upper + c] + pl * self.value[lower + c];
            den[c] = pu + pl;
        }
    }

    /// Solves the level exactly (at most a few unknowns: dense Cholesky);
    /// should rounding make the matrix look indefinite, falls back to
    /// sweeps. Returns the sweeps done (0 for the direct solve) and whether
    /// it converged.
    pub(super) fn solve_coarsest(&mut self) -> (usize, bool) {
        if self.solve_direct() {
            return (0, true);
        }
        let first = self.sweep();
        for sweeps in 2..=10_000 {
            if self.sweep() <= 1e-9 * first {
                return (sweeps, true);
            }
        }
        (10_000, false)
    }

    /// The dense solve; false (values untouched) when it fails.
    fn solve_direct(&mut self) -> bool {
        let s = self.stride;
        let cells: Vec<usize> = (0..self.state.len())
            .filter(|&j| self.state[j] == UNKNOWN)
            .collect();
        let n = cells.len();
        let (mut a, mut b) = (vec![0f64; n * n], vec![0f64; n]);
        for (k, &j) in cells.iter().enumerate() {
            a[k * n + k] = f64::from(self.diag(j));
            b[k] = f64::from(self.rhs[j]);
            for (nb, c) in [
                (j - 1, self.east[j - 1]),
                (j + 1, self.east[j]),
                (j - s, self.south[j - s]),
                (j + s, self.south[j]),
            ] {
                if c != 0.0 {
                    if let Some(l) = cells.iter().position(|&q| q == nb) {
                        a[k * n + l] -= f64::from(c);
                    }
                }
            }
        }
        if !solve_dense(&mut a, &mut b, n) {
            return false;
        }
        for (&j, x) in cells.iter().zip(b) {
            self.value[j] = x as f32;
        }
        true
    }
}

/// The state of a block from what it holds.
fn state_of(unknown: bool, known: bool) -> u8 {
    if unknown {
        UNKNOWN
    } else if known {
        KNOWN
    } else {
        ABSENT
    }
}

/// The couplings of the fine unknown (`x`, `y`) to its known neighbours (the
/// existing ones that are not unknown).
fn fine_dirichlet(fine: &Fine<'_>, x: usize, y: usize, wx: f64, wy: f64) -> f64 {
    let mut d = 0.0;
    if x > 0 && !fine.mask.get(x - 1, y) {
        d += wx;
    }
    if x + 1 < fine.w && !fine.mask.get(x + 1, y) {
        d += wx;
    }
    if y > 0 && !fine.mask.get(x, y - 1) {
        d += wy;
    }
    if y + 1 < fine.h && !fine.mask.get(x, y + 1) {
        d += wy;
    }
    d
}

/// The value at fine column `x` of a row whose two coarse rows were blended
/// into `num` (weighted values) and `den` (weights): the bilinear weights
/// 3/4 and 1/4 of its two coarse columns, divided by their weight (0 where
/// neither coarse cell is present).
#[inline]
fn blend_columns(x: usize, num: &[f32], den: &[f32]) -> f32 {
    let (x0, tx) = if x.is_multiple_of(2) {
        (x / 2, 0.75f32)
    } else {
        (x / 2 + 1, 0.25)
    };
    let d = (1.0 - tx) * den[x0] + tx * den[x0 + 1];
    let n = (1.0 - tx) * num[x0] + tx * num[x0 + 1];
    if d > 0.0 {
        n / d
    } else {
        0.0
    }
}
