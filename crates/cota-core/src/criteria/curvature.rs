//! Accumulated local curvature from finite-difference gradients.
//!
//! Papers `002_9d6c1367b8962b6c.txt` (a matrix of local curvatures from the
//! gradients Gx, Gy of the height field; regions merge while their accumulated
//! curvature stays within a tolerance), `003_3a32b63e0cff3a64.txt` (curvature
//! accumulated per quadtree level as the sum of the four children) and
//! `004_ab8d08b3e6a5a70a.txt` (subdivide while the accumulated curvature exceeds
//! the tolerance). The formula itself was lost from the papers' text; cota uses:
//!
//! 1. **Per-sample curvature**, in 1/m, from central second differences in
//!    metres (`dx`, `dy` from [`HeightGrid::cell_size_m`]):
//!    `k = |Gxx| + |Gyy| + 2·|Gxy|` with
//!    `Gxx = (h[c+1] − 2h[c] + h[c−1]) / dx²`,
//!    `Gyy = (h[r+1] − 2h[r] + h[r−1]) / dy²`,
//!    `Gxy = (h[c+1,r+1] − h[c+1,r−1] − h[c−1,r+1] + h[c−1,r−1]) / (4·dx·dy)`
//!    (the L1 norm of the Hessian, entries counted once each). A border sample
//!    takes the value at the nearest interior sample (the stencil's centre is
//!    clamped to `[1, W−2] × [1, H−2]`); a grid narrower than 3 samples in a
//!    direction has no second difference there (0). Non-finite values count 0.
//! 2. **Accumulated curvature** of an element, `K`, in 1/m: the sum of `k` over
//!    the grid samples in or on it (a triangle: its exact integer spans,
//!    [`crate::mesh::raster::for_each_span`]; a block with four corners: the samples of
//!    its bounding rectangle).
//! 3. A summed-area table (prefix sums over rows and columns, `f64`) built once
//!    in `O(W·H)` makes a rectangle `O(1)` and a triangle `O(rows)`.

use super::{non_negative, Criterion, CriterionError, Element, DEFAULT_TOLERANCE_SHARE};
use crate::grid::HeightGrid;
use crate::mesh::raster::for_each_span;

/// Per-sample curvature of a grid with its summed-area table.
#[derive(Debug, Clone)]
pub struct CurvatureMap {
    width: usize,
    height: usize,
    /// `sat[r·(W+1) + c]` = sum of `k` over rows `< r` and columns `< c`.
    sat: Vec<f64>,
    max_sample: f64,
}

impl CurvatureMap {
    /// Computes `k` at every sample and its summed-area table.
    ///
    /// # Runtime
    /// `O(W·H)`; memory 8 bytes per sample.
    pub fn new(grid: &HeightGrid) -> Self {
        let (w, h) = (grid.width(), grid.height());
        let [dx, dy] = grid.cell_size_m();
        let hs = grid.heights();
        let at = |c: usize, r: usize| hs[r * w + c] as f64;
        let k_at = |c: usize, r: usize| -> f64 {
            let cc = c.clamp(1, w.saturating_sub(2).max(1));
            let rc = r.clamp(1, h.saturating_sub(2).max(1));
            let mut k = 0.0;
            if w >= 3 {
                k += ((at(cc + 1, r) - 2.0 * at(cc, r) + at(cc - 1, r)) / (dx * dx)).abs();
            }
            if h >= 3 {
                k += ((at(c, rc + 1) - 2.0 * at(c, rc) + at(c, rc - 1)) / (dy * dy)).abs();
            }
            if w >= 3 && h >= 3 {
                let gxy = (at(cc + 1, rc + 1) - at(cc + 1, rc - 1) - at(cc - 1, rc + 1)
                    + at(cc - 1, rc - 1))
                    / (4.0 * dx * dy);
                k += 2.0 * gxy.abs();
            }
            if k.is_finite() {
                k
            } else {
                0.0
            }
        };
        let mut sat = vec![0f64; (w + 1) * (h + 1)];
        let mut max_sample = 0f64;
        for r in 0..h {
            let mut row_sum = 0f64;
            for c in 0..w {
                let k = k_at(c, r);
                max_sample = max_sample.max(k);
                row_sum += k;
                sat[(r + 1) * (w + 1) + c + 1] = sat[r * (w + 1) + c + 1] + row_sum;
            }
        }
        CurvatureMap {
            width: w,
            height: h,
            sat,
            max_sample,
        }
    }

    /// Sum of `k` over columns `c0..=c1` and rows `r0..=r1` (clamped to the grid).
    pub fn sum_rect(&self, c0: usize, r0: usize, c1: usize, r1: usize) -> f64 {
        if self.width == 0 || self.height == 0 {
            return 0.0;
        }
        let (c1, r1) = (c1.min(self.width - 1), r1.min(self.height - 1));
        if c0 > c1 || r0 > r1 {
            return 0.0;
        }
        let s = |r: usize, c: usize| self.sat[r * (self.width + 1) + c];
        s(r1 + 1, c1 + 1) - s(r0, c1 + 1) - s(r1 + 1, c0) + s(r0, c0)
    }

    /// The curvature `k` of one sample, 1/m.
    pub fn at(&self, col: usize, row: usize) -> f64 {
        self.sum_rect(col, row, col, row)
    }

    /// The largest per-sample `k`, 1/m.
    pub fn max_sample(&self) -> f64 {
        self.max_sample
    }

    /// `K` of the whole grid, 1/m: the largest value any element can reach.
    pub fn total(&self) -> f64 {
        self.sum_rect(
            0,
            0,
            self.width.saturating_sub(1),
            self.height.saturating_sub(1),
        )
    }

    /// Accumulated curvature `K` of an element, 1/m (see the module docs).
    /// Corners are `[col, row, …]`, rounded to the nearest sample.
    pub fn accumulate(&self, corners: &[[f64; 3]]) -> f64 {
        let pt = |c: &[f64; 3]| [c[0].round().max(0.0) as u32, c[1].round().max(0.0) as u32];
        if let [a, b, c] = corners {
            let mut k = 0.0;
            for_each_span([pt(a), pt(b), pt(c)], |y, x0, x1| {
                k += self.sum_rect(x0 as usize, y as usize, x1 as usize, y as usize);
            });
            return k;
        }
        let Some(first) = corners.first() else {
            return 0.0;
        };
        let (mut lo, mut hi) = (pt(first), pt(first));
        for c in corners {
            let p = pt(c);
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
        }
        self.sum_rect(
            lo[0] as usize,
            lo[1] as usize,
            hi[0] as usize,
            hi[1] as usize,
        )
    }
}

/// Refine while the accumulated curvature exceeds a tolerance:
/// `K(element) > tolerance` (both in 1/m, see the module docs).
#[derive(Debug, Clone, Copy)]
pub struct AccumulatedCurvature<'a> {
    /// The grid's curvature map.
    pub map: &'a CurvatureMap,
    /// The tolerance, 1/m. Default ([`AccumulatedCurvature::new`] without
    /// one): [`DEFAULT_TOLERANCE_SHARE`] of [`CurvatureMap::total`].
    pub tolerance: f64,
}

impl<'a> AccumulatedCurvature<'a> {
    /// The criterion on `map` with `tolerance` (1/m), or by default
    /// [`DEFAULT_TOLERANCE_SHARE`] × [`CurvatureMap::total`].
    ///
    /// # Errors
    /// [`CriterionError::OutOfRange`] for a negative or NaN tolerance.
    pub fn new(map: &'a CurvatureMap, tolerance: Option<f64>) -> Result<Self, CriterionError> {
        Ok(AccumulatedCurvature {
            map,
            tolerance: default_tolerance(map, tolerance)?,
        })
    }
}

/// `tolerance`, validated, or [`DEFAULT_TOLERANCE_SHARE`] of the map's total.
pub(super) fn default_tolerance(
    map: &CurvatureMap,
    tolerance: Option<f64>,
) -> Result<f64, CriterionError> {
    match tolerance {
        Some(t) => non_negative("tolerance", t),
        None => Ok(DEFAULT_TOLERANCE_SHARE * map.total()),
    }
}

impl Criterion for AccumulatedCurvature<'_> {
    fn wants_split(&self, e: &Element<'_>) -> bool {
        self.map.accumulate(e.corners) > self.tolerance
    }

    fn name(&self) -> String {
        format!("curvature {} 1/m", super::plain(self.tolerance))
    }
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::grid::GeoRef;

    #[test]
    fn paraboloid_has_constant_curvature_and_sums_match() {
        // h = x² + 2y² with 2 m cells: Gxx = 2, Gyy = 4, Gxy = 0 → k = 6 1/m.
        let (w, h) = (7, 6);
        let v = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32 * 2.0, (i / w) as f32 * 2.0);
                x * x + 2.0 * y * y
            })
            .collect();
        let g = HeightGrid::new(w, h, v, GeoRef::unreferenced(2.0)).unwrap();
        let m = CurvatureMap::new(&g);
        for r in 0..h {
            for c in 0..w {
                assert!((m.at(c, r) - 6.0).abs() < 1e-9, "{c} {r} {}", m.at(c, r));
            }
        }
        assert!((m.total() - 6.0 * (w * h) as f64).abs() < 1e-6);
        // The triangle (0,0), (4,0), (0,4) has 15 samples.
        let k = m.accumulate(&[[0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [0.0, 4.0, 0.0]]);
        assert!((k - 90.0).abs() < 1e-9);
        let k = m.accumulate(&[
            [1.0, 1.0, 0.0],
            [3.0, 1.0, 0.0],
            [3.0, 2.0, 0.0],
            [1.0, 2.0, 0.0],
        ]);
        assert!((k - 36.0).abs() < 1e-9);
    }
}
