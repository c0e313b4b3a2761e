//! The harmonic fill's starting estimate (step 2 of [`super`]): pull–push.
//! The border heights are averaged down a pyramid of 2×2 blocks (a block
//! with any known cell is known, with their mean) until few unknowns remain,
//! which start at the mean of the known cells; the estimate is then
//! interpolated back up bilinearly.
//!
//! The pull–push scheme of Gortler, Grzeszczuk, Szeliski & Cohen, "The
//! Lumigraph" (SIGGRAPH 1996), here only as the multigrid's first guess.

use rayon::prelude::*;

use super::fine::{for_each_bit, Cell, Fine};
use super::interp::{bilinear, ABSENT, COARSEST_UNKNOWNS, KNOWN, UNKNOWN};

/// One level of the pyramid (framed arrays, see `interp`).
struct Values {
    w: usize,
    h: usize,
    stride: usize,
    state: Vec<u8>,
    value: Vec<f32>,
    unknowns: usize,
}

impl Values {
    /// A level of `w × h` blocks, each from `block(x, y)`: its state and value.
    fn of(w: usize, h: usize, block: impl Fn(usize, usize) -> (u8, f32) + Sync) -> Self {
        let stride = w + 2;
        let n = stride * (h + 2);
        let (mut state, mut value) = (vec![ABSENT; n], vec![0f32; n]);
        state
            .par_chunks_mut(stride)
            .zip(value.par_chunks_mut(stride))
            .skip(1)
            .take(h)
            .enumerate()
            .for_each(|(y, (s, v))| {
                for x in 0..w {
                    (s[x + 1], v[x + 1]) = block(x, y);
                }
            });
        let unknowns = state.iter().filter(|&&s| s == UNKNOWN).count();
        Values {
            w,
            h,
            stride,
            state,
            value,
            unknowns,
        }
    }

    /// The first level: a block is known with the mean of its border cells,
    /// else unknown if it holds an unknown, else absent.
    fn pull_fine(fine: &Fine<'_>) -> Self {
        Values::of(fine.w.div_ceil(2), fine.h.div_ceil(2), |cx, cy| {
            let (mut sum, mut n, mut unknown) = (0f64, 0u32, false);
            for fy in 2 * cy..(2 * cy + 2).min(fine.h) {
                for fx in 2 * cx..(2 * cx + 2).min(fine.w) {
                    match fine.cell(fx, fy) {
                        Cell::Border => {
                            sum += f64::from(fine.rows[fy][fx]);
                            n += 1;
                        }
                        Cell::Unknown => unknown = true,
                        Cell::Absent => {}
                    }
                }
            }
            block_of(sum, n, unknown)
        })
    }

    /// The next level: known blocks average their known cells.
    fn pull(&self) -> Self {
        Values::of(self.w.div_ceil(2), self.h.div_ceil(2), |cx, cy| {
            let (mut sum, mut n, mut unknown) = (0f64, 0u32, false);
            for py in 2 * cy..(2 * cy + 2).min(self.h) {
                for px in 2 * cx..(2 * cx + 2).min(self.w) {
                    let i = (py + 1) * self.stride + px + 1;
                    match self.state[i] {
                        KNOWN => {
                            sum += f64::from(self.value[i]);
                            n += 1;
                        }
                        UNKNOWN => unknown = true,
                        _ => {}
                    }
                }
            }
            block_of(sum, n, unknown)
        })
    }

    /// Sets every unknown to the mean of the known cells.
    fn set_mean(&mut self) {
        let (mut sum, mut n) = (0f64, 0usize);
        for (s, v) in self.state.iter().zip(&self.value) {
            if *s == KNOWN {
                sum += f64::from(*v);
                n += 1;
            }
        }
        let mean = if n > 0 { (sum / n as f64) as f32 } else { 0.0 };
        for (s, v) in self.state.iter().zip(self.value.iter_mut()) {
            if *s == UNKNOWN {
                *v = mean;
            }
        }
    }

    /// Sets every unknown by interpolation from `coarse`.
    fn push_from(&mut self, coarse: &Values) {
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
                        row[x + 1] = bilinear(&coarse.state, &coarse.value, coarse.stride, x, y);
                    }
                }
            });
    }
}

/// A block's state and value from its known sum and count and whether it
/// holds an unknown.
fn block_of(sum: f64, n: u32, unknown: bool) -> (u8, f32) {
    if n > 0 {
        (KNOWN, (sum / f64::from(n)) as f32)
    } else if unknown {
        (UNKNOWN, 0.0)
    } else {
        (ABSENT, 0.0)
    }
}

/// Sets the unknowns of `fine` (more than [`COARSEST_UNKNOWNS`] of them) to
/// the pull–push estimate.
pub(super) fn start_estimate(fine: &mut Fine<'_>) {
    let mut levels = vec![Values::pull_fine(fine)];
    while let Some(last) = levels.last() {
        if last.unknowns <= COARSEST_UNKNOWNS {
            break;
        }
        let next = last.pull();
        let done = next.unknowns == 0;
        levels.push(next);
        if done {
            break;
        }
    }
    if let Some(last) = levels.last_mut() {
        last.set_mean();
    }
    for k in (0..levels.len().saturating_sub(1)).rev() {
        let (lo, hi) = levels.split_at_mut(k + 1);
        lo[k].push_from(&hi[0]);
    }
    let Some(first) = levels.first() else { return };
    let mask = &fine.mask;
    fine.rows.par_iter_mut().enumerate().for_each(|(y, row)| {
        for_each_bit(mask.row(y), |x| {
            row[x] = bilinear(&first.state, &first.value, first.stride, x, y);
        });
    });
}
