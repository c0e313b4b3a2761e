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
//! neighbours'), its diagonal and its state: 21 bytes, so all coarse levels
//! together take about 7 bytes per sample of the component's box.
//!
//! Briggs, Henson & McCormick, *A Multigrid Tutorial* (2nd ed., SIAM 2000):
//! Galerkin coarse operators, full-weighting-like summed restriction,
//! bilinear interpolation, red–black Gauss–Seidel.

use rayon::prelude::*;

use super::bands::{row_with_neighbours, two_pass};
use super::dense::solve_dense;
use super::fine::{for_each_bit, Cell, Fine};
use super::interp::{bilinear, ABSENT, KNOWN, UNKNOWN};

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
    /// The diagonal at unknowns, 0 elsewhere.
    diag: Vec<f32>,
    /// The Dirichlet part of the diagonal, kept until the next level is built.
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
            diag: vec![0.0; n],
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

    /// The next coarser level. Frees this level's Dirichlet parts.
    pub(super) fn coarsen(&mut self) -> Coarse {
        let prev = &*self;
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
        self.dirichlet = Vec::new();
        c
    }

    /// Sets every cell from `block(x, y)` (in parallel over rows), then the
    /// diagonals and the unknown count.
    fn fill_blocks(&mut self, block: impl Fn(usize, usize) -> (u8, BlockCoef) + Sync) {
        let (s, w, h) = (self.stride, self.w, self.h);
        self.state
            .par_chunks_mut(s)
            .zip(self.east.par_chunks_mut(s))
            .zip(self.south.par_chunks_mut(s))
            .zip(self.dirichlet.par_chunks_mut(s))
            .skip(1)
            .take(h)
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
        let mut unknowns = 0;
        for i in s..s * (h + 1) {
            if self.state[i] == UNKNOWN {
                unknowns += 1;
                let sum = f64::from(self.dirichlet[i])
                    + f64::from(self.east[i])
                    + f64::from(self.east[i - 1])
                    + f64::from(self.south[i])
                    + f64::from(self.south[i - s]);
                self.diag[i] = sum as f32;
            }
        }
        self.unknowns = unknowns;
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
            - self.diag[j] * v[j]
    }

    /// One red–black Gauss–Seidel sweep (by bands); returns the largest change.
    pub(super) fn sweep(&mut self) -> f32 {
        let (s, w) = (self.stride, self.w);
        let (rhs, east, south, diag) = (&self.rhs, &self.east, &self.south, &self.diag);
        let mut rows: Vec<&mut [f32]> = self.value[s..s * (self.h + 1)].chunks_mut(s).collect();
        two_pass(&mut rows, |first, band, above, below| {
            let mut change = 0f32;
            for colour in 0..2 {
                for i in 0..band.len() {
                    let y = first + i;
                    let (mid, up, down) = row_with_neighbours(band, i, above, below);
                    let base = (y + 1) * s;
                    for x in ((y + colour) % 2..w).step_by(2) {
                        let j = base + x + 1;
                        let d = diag[j];
                        if d <= 0.0 {
                            continue;
                        }
                        let mut t = rhs[j] + east[j - 1] * mid[x] + east[j] * mid[x + 2];
                        if let Some(u) = up {
                            t += south[j - s] * u[x + 1];
                        }
                        if let Some(dn) = down {
                            t += south[j] * dn[x + 1];
                        }
                        let new = t / d;
                        change = change.max((new - mid[x + 1]).abs());
                        mid[x + 1] = new;
                    }
                }
            }
            change
        })
    }

    /// Sets `next` (the level above) to the error equation of this one:
    /// zero values, and the summed residual of each block as right-hand side.
    pub(super) fn restrict(&self, next: &mut Coarse) {
        let (ns, nw) = (next.stride, next.w);
        next.value.fill(0.0);
        next.rhs
            .par_chunks_mut(ns)
            .skip(1)
            .take(next.h)
            .enumerate()
            .for_each(|(cy, rhs)| {
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
            });
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
    /// level's unknowns.
    pub(super) fn correct_from(&mut self, next: &Coarse) {
        let (s, w) = (self.stride, self.w);
        let state = &self.state;
        self.value
            .par_chunks_mut(s)
            .skip(1)
            .take(self.h)
            .enumerate()
            .for_each(|(y, row)| {
                for x in 0..w {
                    if state[(y + 1) * s + x + 1] == UNKNOWN {
                        row[x + 1] += bilinear(&next.state, &next.value, next.stride, x, y);
                    }
                }
            });
    }

    /// Adds the interpolated correction of this level to `fine`'s unknowns;
    /// returns the largest correction.
    pub(super) fn correct_fine(&self, fine: &mut Fine<'_>) -> f32 {
        let mask = &fine.mask;
        fine.rows
            .par_iter_mut()
            .enumerate()
            .map(|(y, row)| {
                let mut most = 0f32;
                for_each_bit(mask.row(y), |x| {
                    let c = bilinear(&self.state, &self.value, self.stride, x, y);
                    row[x] += c;
                    most = most.max(c.abs());
                });
                most
            })
            .reduce(|| 0f32, f32::max)
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
            a[k * n + k] = f64::from(self.diag[j]);
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
