//! Paper 002's perceptual mask: accumulated curvature weighted by illumination.
//!
//! Paper `002_9d6c1367b8962b6c.txt`: the per-vertex illumination `I = cos θ =
//! N·L` for a light `L`, interpolated over the polygon, combined with the
//! accumulated curvature by a weight `α ∈ [0, 1]` (its eq. 3 is garbled in the
//! text). cota's reading (`../shared/design/PAPERS.md`):
//!
//! 1. `N` at a vertex is the grid's unit normal there, from central differences
//!    in metres in the local frame (x east, y north, z up):
//!    `N ∝ (−∂z/∂x, −∂z/∂y, 1)` with `∂z/∂x = (h[c+1] − h[c−1]) / (2·dx)` and
//!    `∂z/∂y = (h[r−1] − h[r+1]) / (2·dy)` (row 0 is north); one-sided
//!    differences on the border.
//! 2. `I(S) = mean over the element's corners of max(0, N·L̂)`, `L̂` the unit
//!    direction towards the light, so `I ∈ [0, 1]`.
//! 3. `K(S)` is the accumulated curvature of [`super::curvature`] (1/m).
//! 4. The element is **accepted** when `K(S)·(α + (1 − α)·I(S)) ≤ T` and
//!    refined otherwise: `α = 1` is pure curvature; for `α < 1` dark elements
//!    are simplified more while lit ones keep their density.

use super::curvature::{default_tolerance, CurvatureMap};
use super::{Criterion, CriterionError, Element};
use crate::grid::HeightGrid;

/// The grid's unit normal at a sample, local frame (x east, y north, z up).
pub fn grid_normal(grid: &HeightGrid, col: usize, row: usize) -> [f64; 3] {
    let (w, h) = (grid.width(), grid.height());
    let [dx, dy] = grid.cell_size_m();
    let z = |c: usize, r: usize| grid.get(c, r) as f64;
    let (c0, c1) = (col.saturating_sub(1), (col + 1).min(w - 1));
    let (r0, r1) = (row.saturating_sub(1), (row + 1).min(h - 1));
    let gx = if c1 > c0 {
        (z(c1, row) - z(c0, row)) / ((c1 - c0) as f64 * dx)
    } else {
        0.0
    };
    // North is towards row 0.
    let gy = if r1 > r0 {
        (z(col, r0) - z(col, r1)) / ((r1 - r0) as f64 * dy)
    } else {
        0.0
    };
    let n = [-gx, -gy, 1.0];
    let len = (n[0] * n[0] + n[1] * n[1] + 1.0).sqrt();
    if !len.is_finite() {
        return [0.0, 0.0, 1.0];
    }
    [n[0] / len, n[1] / len, n[2] / len]
}

/// Normalises `v`; `None` for a zero or non-finite vector.
pub fn unit(v: [f64; 3]) -> Option<[f64; 3]> {
    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    (len.is_finite() && len > 0.0).then(|| [v[0] / len, v[1] / len, v[2] / len])
}

/// Paper 002's criterion (see the module docs): refine while
/// `K(S)·(α + (1 − α)·I(S)) > tolerance`.
#[derive(Debug, Clone, Copy)]
pub struct IlluminationMask<'a> {
    /// The grid's curvature map.
    pub map: &'a CurvatureMap,
    /// Direction towards the light, local frame (any length; normalised).
    /// Suggested: `[1, 1, 1]` (a light high in the north-east).
    pub light_dir: [f64; 3],
    /// Weight of pure curvature, in `[0, 1]`. Default
    /// ([`super::CriterionOptions`]): 0.5, dark and lit weighted alike.
    pub alpha: f64,
    /// Tolerance `T`, 1/m. Default ([`IlluminationMask::new`] without one):
    /// [`super::DEFAULT_TOLERANCE_SHARE`] of [`CurvatureMap::total`].
    pub tolerance: f64,
}

impl<'a> IlluminationMask<'a> {
    /// The mask on `map` with the light towards `light_dir`, weight `alpha`
    /// and `tolerance` (1/m), or by default
    /// [`super::DEFAULT_TOLERANCE_SHARE`] × [`CurvatureMap::total`].
    ///
    /// # Errors
    /// [`CriterionError::OutOfRange`] for an `alpha` outside `[0, 1]` or a
    /// negative or NaN tolerance.
    pub fn new(
        map: &'a CurvatureMap,
        light_dir: [f64; 3],
        alpha: f64,
        tolerance: Option<f64>,
    ) -> Result<Self, CriterionError> {
        Ok(IlluminationMask {
            map,
            light_dir,
            alpha: weight(alpha)?,
            tolerance: default_tolerance(map, tolerance)?,
        })
    }
}

/// `alpha` when it is a weight in `[0, 1]`.
pub(super) fn weight(alpha: f64) -> Result<f64, CriterionError> {
    if !(0.0..=1.0).contains(&alpha) {
        return Err(CriterionError::OutOfRange {
            setting: "alpha",
            expected: "a weight in [0, 1]",
            found: alpha,
        });
    }
    Ok(alpha)
}

impl IlluminationMask<'_> {
    /// `I(S)`: the mean over the corners of `max(0, N·L̂)`, in `[0, 1]`.
    pub fn illumination(&self, e: &Element<'_>) -> f64 {
        let Some(l) = unit(self.light_dir) else {
            return 0.0;
        };
        if e.corners.is_empty() {
            return 0.0;
        }
        let (w, h) = (e.grid.width(), e.grid.height());
        let sum: f64 = e
            .corners
            .iter()
            .map(|c| {
                let col = (c[0].round().max(0.0) as usize).min(w - 1);
                let row = (c[1].round().max(0.0) as usize).min(h - 1);
                let n = grid_normal(e.grid, col, row);
                (n[0] * l[0] + n[1] * l[1] + n[2] * l[2]).max(0.0)
            })
            .sum();
        sum / e.corners.len() as f64
    }

    /// The masked measure `K(S)·(α + (1 − α)·I(S))`, 1/m.
    pub fn masked(&self, e: &Element<'_>) -> f64 {
        let k = self.map.accumulate(e.corners);
        k * (self.alpha + (1.0 - self.alpha) * self.illumination(e))
    }
}

impl Criterion for IlluminationMask<'_> {
    fn wants_split(&self, e: &Element<'_>) -> bool {
        self.masked(e) > self.tolerance
    }

    fn name(&self) -> String {
        format!(
            "light alpha {} tolerance {} 1/m towards {:?}",
            self.alpha, self.tolerance, self.light_dir
        )
    }
}

/// The light a sample receives, `max(0, N·L̂)` in `[0, 1]` ([`grid_normal`];
/// 0 for a zero light direction): the weight of paper 002's
/// illumination-weighted volume error ([`crate::mesh::metrics::weighted_volume_m3`]).
pub fn received_light(grid: &HeightGrid, light_dir: [f64; 3], col: usize, row: usize) -> f64 {
    let Some(l) = unit(light_dir) else {
        return 0.0;
    };
    let n = grid_normal(grid, col, row);
    (n[0] * l[0] + n[1] * l[1] + n[2] * l[2]).max(0.0)
}
