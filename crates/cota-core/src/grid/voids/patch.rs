//! One component's linear problem on one level of the multigrid hierarchy:
//! the patch of cells around a void, its unknowns and their equations, the
//! red–black Gauss–Seidel sweep, the transfers between levels (restriction,
//! interpolation, the Galerkin coarse operator) and the direct solve of the
//! coarsest level.
//!
//! The standard geometric multigrid of Briggs, Henson & McCormick, *A
//! Multigrid Tutorial* (2nd ed., SIAM 2000), on the irregular domains of
//! voids; the choices are documented in [`super`].

use super::components::Component;
use crate::grid::HeightGrid;

/// Cell states of a [`Level`].
pub(super) const KNOWN: u8 = 0;
pub(super) const UNKNOWN: u8 = 1;
pub(super) const ABSENT: u8 = 2;

/// Levels with at most this many unknowns are not coarsened further.
pub(super) const COARSEST_UNKNOWNS: usize = 16;
/// Gauss–Seidel sweeps before and after each coarse-grid correction.
pub(super) const SMOOTHING_SWEEPS: usize = 2;
/// Scale of the couplings between coarse cells in the Galerkin product with
/// piecewise-constant interpolation: 1/2 makes it agree, away from the
/// boundary, with the operator rediscretised at twice the spacing (with the
/// summed restriction). Couplings to known cells are kept whole: halving them
/// too makes the cycles diverge near the boundary; of the factors tried on
/// them (0.5 to 2) 1 converged fastest on the unit tests' holes.
pub(super) const COARSE_COUPLING_SCALE: f64 = 0.5;

/// An unknown cell of a [`Level`].
#[derive(Clone, Copy)]
pub(super) struct Unknown {
    /// Index in the level's (padded) arrays.
    pub(super) at: usize,
    /// Column and row inside the level (without the padding).
    pub(super) x: u32,
    pub(super) y: u32,
    /// Coupling to the west, east, north and south neighbours (0 for absent ones).
    pub(super) w: [f32; 4],
    /// Diagonal of its equation: the couplings to all non-absent neighbours.
    pub(super) diag: f64,
    /// Right-hand side of its equation.
    pub(super) rhs: f64,
}

/// A rectangular problem on one level of the multigrid hierarchy: known cells
/// (Dirichlet values), unknown cells, and absent cells that take no part
/// (outside the component and its border).
///
/// At unknown cell i the equation is dᵢ uᵢ − Σⱼ wᵢⱼ uⱼ = fᵢ over its
/// 4-neighbours j. On the finest level wᵢⱼ = 1/dx² across columns and 1/dy²
/// across rows for non-absent neighbours, dᵢ = Σⱼ wᵢⱼ, f = 0 and the known
/// cells hold the border heights. Coarser levels hold the error equation: known
/// cells hold 0, f is the restricted residual and the coefficients are the
/// Galerkin product of the finer ones (see [`Level::coarsen_error`]).
///
/// The arrays have a frame of absent cells around the `width`×`height` box so
/// that every unknown has four neighbours in range, and absent cells hold 0, so
/// a sweep needs no bounds checks and no branches.
pub(super) struct Level {
    pub(super) width: usize,
    pub(super) height: usize,
    /// Row length of the padded arrays, `width + 2`.
    pub(super) stride: usize,
    pub(super) state: Vec<u8>,
    pub(super) value: Vec<f64>,
    /// The unknowns, red cells ((x + y) even) first, each colour in raster order:
    /// one pass in this order is a red–black Gauss–Seidel sweep.
    pub(super) unknowns: Vec<Unknown>,
}

impl Level {
    /// An all-absent level of `width`×`height` cells.
    pub(super) fn new(width: usize, height: usize) -> Level {
        let stride = width + 2;
        Level {
            width,
            height,
            stride,
            state: vec![ABSENT; stride * (height + 2)],
            value: vec![0.0; stride * (height + 2)],
            unknowns: Vec::new(),
        }
    }

    /// Index of cell (`x`, `y`) in the padded arrays.
    #[inline]
    pub(super) fn at(&self, x: usize, y: usize) -> usize {
        (y + 1) * self.stride + x + 1
    }

    /// Marks (`x`, `y`) known with value `v`.
    pub(super) fn set_known(&mut self, x: usize, y: usize, v: f64) {
        let i = self.at(x, y);
        self.state[i] = KNOWN;
        self.value[i] = v;
    }

    /// Marks (`x`, `y`) unknown (call [`Level::collect_unknowns`] once all
    /// cells are set).
    pub(super) fn set_unknown(&mut self, x: usize, y: usize) {
        let i = self.at(x, y);
        self.state[i] = UNKNOWN;
    }

    /// Lists the unknown cells in red–black order (red, (x + y) even, first;
    /// each colour in raster order), without coefficients yet.
    pub(super) fn collect_unknowns(&mut self) {
        self.unknowns.clear();
        for parity in 0..2 {
            for y in 0..self.height {
                for x in ((y + parity) % 2..self.width).step_by(2) {
                    let at = self.at(x, y);
                    if self.state[at] == UNKNOWN {
                        self.unknowns.push(Unknown {
                            at,
                            x: x as u32,
                            y: y as u32,
                            w: [0.0; 4],
                            diag: 0.0,
                            rhs: 0.0,
                        });
                    }
                }
            }
        }
    }

    /// Padded index offsets of the west, east, north and south neighbours.
    pub(super) fn offsets(&self) -> [isize; 4] {
        let s = self.stride as isize;
        [-1, 1, -s, s]
    }

    /// Lists the unknowns and sets the Laplace coefficients of the finest level
    /// (weights `wx` across columns and `wy` across rows to non-absent neighbours).
    pub(super) fn finish(&mut self, wx: f64, wy: f64) {
        self.collect_unknowns();
        let offsets = self.offsets();
        for u in &mut self.unknowns {
            let mut diag = 0.0;
            for (k, off) in offsets.iter().enumerate() {
                let j = u.at.wrapping_add_signed(*off);
                if self.state[j] != ABSENT {
                    let w = if k < 2 { wx } else { wy };
                    u.w[k] = w as f32;
                    diag += f64::from(w as f32);
                }
            }
            u.diag = diag;
        }
    }

    /// One red–black Gauss–Seidel sweep; returns
    /// the largest difference between an unknown and the value its equation asks for.
    pub(super) fn sweep(&mut self) -> f64 {
        let s = self.stride;
        let v = &mut self.value;
        let mut max_change = 0.0f64;
        for u in &self.unknowns {
            let i = u.at;
            if u.diag <= 0.0 {
                continue;
            }
            let [ww, we, wn, ws] = u.w.map(f64::from);
            let sum = u.rhs + ww * v[i - 1] + we * v[i + 1] + wn * v[i - s] + ws * v[i + s];
            let d = sum / u.diag - v[i];
            v[i] += d;
            max_change = max_change.max(d.abs());
        }
        max_change
    }

    /// The residual fᵢ − Σⱼ wᵢⱼ (uᵢ − uⱼ) of unknown `u`.
    #[inline]
    pub(super) fn residual(&self, u: &Unknown) -> f64 {
        let (i, s, v) = (u.at, self.stride, &self.value);
        let [ww, we, wn, ws] = u.w.map(f64::from);
        u.rhs + ww * v[i - 1] + we * v[i + 1] + wn * v[i - s] + ws * v[i + s] - u.diag * v[i]
    }

    /// Counts of known and unknown cells in the 2×2 block of coarse cell
    /// (`cx`, `cy`), and the sum of the known values.
    pub(super) fn block(&self, cx: usize, cy: usize) -> (u32, u32, f64) {
        let (mut known, mut unknown, mut sum) = (0, 0, 0.0);
        for (fx, fy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let (x, y) = (2 * cx + fx, 2 * cy + fy);
            if x < self.width && y < self.height {
                let i = self.at(x, y);
                match self.state[i] {
                    KNOWN => {
                        known += 1;
                        sum += self.value[i];
                    }
                    UNKNOWN => unknown += 1,
                    _ => {}
                }
            }
        }
        (known, unknown, sum)
    }

    /// The pull step of [`start_estimate`]: a coarse level of half the size
    /// where a block with any known cell is known with their mean, else unknown
    /// if it holds unknowns, else absent.
    pub(super) fn coarsen_values(&self) -> Level {
        let mut coarse = Level::new(self.width.div_ceil(2), self.height.div_ceil(2));
        for cy in 0..coarse.height {
            for cx in 0..coarse.width {
                match self.block(cx, cy) {
                    (0, 0, _) => {}
                    (0, _, _) => coarse.set_unknown(cx, cy),
                    (known, _, sum) => coarse.set_known(cx, cy, sum / f64::from(known)),
                }
            }
        }
        coarse.collect_unknowns();
        coarse
    }

    /// The coarse level of the error equation, or `None` when this level is
    /// small enough to solve directly.
    ///
    /// A 2×2 block holding an unknown is unknown, else known (error 0) if it
    /// holds known cells, else absent. The coefficients come from the Galerkin
    /// product Pᵀ A P with the piecewise-constant interpolation P: couplings
    /// inside a block cancel, couplings between two blocks add up (scaled by
    /// [`COARSE_COUPLING_SCALE`]), couplings to known cells add up on the
    /// diagonal. So the Dirichlet boundary keeps its place and strength on every
    /// level, and no coarse problem is singular (each has its diagonal at least
    /// the sum of its couplings, strictly where the boundary is near).
    pub(super) fn coarsen_error(&self) -> Option<Level> {
        if self.unknowns.len() <= COARSEST_UNKNOWNS {
            return None;
        }
        let mut coarse = Level::new(self.width.div_ceil(2), self.height.div_ceil(2));
        for cy in 0..coarse.height {
            for cx in 0..coarse.width {
                match self.block(cx, cy) {
                    (0, 0, _) => {}
                    (_, 0, _) => coarse.set_known(cx, cy, 0.0),
                    _ => coarse.set_unknown(cx, cy),
                }
            }
        }
        coarse.collect_unknowns();
        // Accumulate the coefficients by coarse cell, in f64.
        let mut off = vec![[0.0f64; 4]; coarse.value.len()];
        let offsets = self.offsets();
        let mut dirichlet = vec![0.0f64; coarse.value.len()];
        for u in &self.unknowns {
            let (x, y) = (u.x as usize, u.y as usize);
            let c = coarse.at(x / 2, y / 2);
            // The part of the diagonal from known neighbours (absent ones have
            // no coupling): on coarse levels they have no coefficient of their own.
            let mut dir = u.diag;
            for (k, &d) in offsets.iter().enumerate() {
                let w = f64::from(u.w[k]);
                let j = u.at.wrapping_add_signed(d);
                if w == 0.0 || self.state[j] != UNKNOWN {
                    continue;
                }
                dir -= w;
                // An unknown neighbour is inside the box (the frame is absent).
                let (nx, ny) = match k {
                    0 => (x - 1, y),
                    1 => (x + 1, y),
                    2 => (x, y - 1),
                    _ => (x, y + 1),
                };
                if coarse.at(nx / 2, ny / 2) != c {
                    off[c][k] += w;
                }
            }
            dirichlet[c] += dir;
        }
        for cu in &mut coarse.unknowns {
            let o = off[cu.at];
            cu.diag = dirichlet[cu.at] + COARSE_COUPLING_SCALE * (o[0] + o[1] + o[2] + o[3]);
            cu.w = o.map(|w| (COARSE_COUPLING_SCALE * w) as f32);
        }
        Some(coarse)
    }

    /// Sets (`add` false) or corrects (`add` true) every unknown with the
    /// bilinear interpolation of the coarser level's non-absent cells (a cell's
    /// own block always takes part).
    pub(super) fn interpolate_from(&mut self, coarse: &Level, add: bool) {
        for k in 0..self.unknowns.len() {
            let u = self.unknowns[k];
            // Fine cell x lies at coarse coordinate (x − 0.5) / 2: between the
            // centres of blocks x/2 − 1 and x/2 (weights 1/4, 3/4) when x is
            // even, x/2 and x/2 + 1 (3/4, 1/4) when odd. Coarse index −1 and
            // width are the padding frame, absent.
            let (x, y) = (u.x as usize, u.y as usize);
            let (x0, tx) = if x % 2 == 0 {
                (x / 2, 0.75)
            } else {
                (x / 2 + 1, 0.25)
            };
            let (y0, ty) = if y % 2 == 0 {
                (y / 2, 0.75)
            } else {
                (y / 2 + 1, 0.25)
            };
            // Padded indices of coarse cells (x0 − 1, y0 − 1) .. (x0, y0), i.e.
            // unpadded x0 − 1 and x0.
            let base = y0 * coarse.stride + x0;
            let (mut sum, mut wsum) = (0.0, 0.0);
            for (off, w) in [
                (0, (1.0 - tx) * (1.0 - ty)),
                (1, tx * (1.0 - ty)),
                (coarse.stride, (1.0 - tx) * ty),
                (coarse.stride + 1, tx * ty),
            ] {
                let ci = base + off;
                if coarse.state[ci] != ABSENT {
                    sum += w * coarse.value[ci];
                    wsum += w;
                }
            }
            if wsum > 0.0 {
                let v = sum / wsum;
                self.value[u.at] = if add { self.value[u.at] + v } else { v };
            }
        }
    }

    /// Sets `coarse` to the error equation of this level: zero values, and as
    /// right-hand side the summed residual of each block (Pᵀ r).
    pub(super) fn restrict_residual(&self, coarse: &mut Level) {
        // Accumulate in coarse.value (then cleared): it is indexed by cell.
        coarse.value.fill(0.0);
        for u in &self.unknowns {
            let ci = coarse.at(u.x as usize / 2, u.y as usize / 2);
            coarse.value[ci] += self.residual(u);
        }
        for cu in &mut coarse.unknowns {
            cu.rhs = coarse.value[cu.at];
        }
        coarse.value.fill(0.0);
    }

    /// Solves a level of at most [`COARSEST_UNKNOWNS`] unknowns exactly
    /// (Cholesky factorisation of its dense matrix). Should rounding make the
    /// matrix look indefinite, falls back to Gauss–Seidel sweeps. Returns the
    /// sweeps done (0 for the direct solve) and whether it converged.
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

    /// Solves the level's equations by a dense Cholesky factorisation; false
    /// (values untouched) when a pivot is not positive.
    pub(super) fn solve_direct(&mut self) -> bool {
        let n = self.unknowns.len();
        let offsets = self.offsets();
        let mut a = vec![0.0f64; n * n];
        let mut b = vec![0.0f64; n];
        for (k, u) in self.unknowns.iter().enumerate() {
            a[k * n + k] = u.diag;
            b[k] = u.rhs;
            for (dir, &d) in offsets.iter().enumerate() {
                let w = f64::from(u.w[dir]);
                let j = u.at.wrapping_add_signed(d);
                if w == 0.0 {
                    continue;
                }
                if self.state[j] == UNKNOWN {
                    if let Some(l) = self.unknowns.iter().position(|v| v.at == j) {
                        a[k * n + l] -= w;
                    }
                } else {
                    b[k] += w * self.value[j];
                }
            }
        }
        // A = L Lᵀ, L stored in the lower triangle of `a`.
        for i in 0..n {
            for j in 0..=i {
                let mut sum = a[i * n + j];
                for k in 0..j {
                    sum -= a[i * n + k] * a[j * n + k];
                }
                if i == j {
                    if sum <= 0.0 || !sum.is_finite() {
                        return false;
                    }
                    a[i * n + i] = sum.sqrt();
                } else {
                    a[i * n + j] = sum / a[j * n + j];
                }
            }
        }
        // L y = b, then Lᵀ x = y, in place in `b`.
        for i in 0..n {
            let mut sum = b[i];
            for k in 0..i {
                sum -= a[i * n + k] * b[k];
            }
            b[i] = sum / a[i * n + i];
        }
        for i in (0..n).rev() {
            let mut sum = b[i];
            for k in i + 1..n {
                sum -= a[k * n + i] * b[k];
            }
            b[i] = sum / a[i * n + i];
        }
        for (u, x) in self.unknowns.iter().zip(b) {
            self.value[u.at] = x;
        }
        true
    }
}

/// The component's finest level: its bounding box plus a one-sample margin
/// (clipped at the grid edge), the component's samples unknown, their valid
/// 4-neighbours known, everything else absent. Also returns the box's origin
/// (column, row) in the grid and the range of the border values.
pub(super) fn fine_level(
    grid: &HeightGrid,
    c: &Component,
    wx: f64,
    wy: f64,
) -> (Level, (usize, usize), (f64, f64)) {
    let x0 = c.cols.0.saturating_sub(1);
    let y0 = c.rows.0.saturating_sub(1);
    let x1 = (c.cols.1 + 1).min(grid.width() - 1);
    let y1 = (c.rows.1 + 1).min(grid.height() - 1);
    let mut level = Level::new(x1 - x0 + 1, y1 - y0 + 1);
    let mut range = (f64::INFINITY, f64::NEG_INFINITY);
    for &i in &c.cells {
        let (col, row) = (i % grid.width(), i / grid.width());
        level.set_unknown(col - x0, row - y0);
        let mut border = |nc: usize, nr: usize| {
            let v = grid.get(nc, nr);
            if !v.is_nan() {
                let v = f64::from(v);
                level.set_known(nc - x0, nr - y0, v);
                range = (range.0.min(v), range.1.max(v));
            }
        };
        if col > 0 {
            border(col - 1, row);
        }
        if col + 1 < grid.width() {
            border(col + 1, row);
        }
        if row > 0 {
            border(col, row - 1);
        }
        if row + 1 < grid.height() {
            border(col, row + 1);
        }
    }
    level.finish(wx, wy);
    (level, (x0, y0), range)
}
