//! Refinement criteria behind one trait, combinable.
//!
//! Papers `000_ebf7e3a88dffd361.txt` §3.2 (Euclidean distance of the grid points
//! to the triangle), `001_49f2c365e8c41172.txt` (distance AND size AND
//! curvature), `002_9d6c1367b8962b6c.txt` (curvature with an illumination mask),
//! `003_3a32b63e0cff3a64.txt` (k·cosθ/d) and `004_ab8d08b3e6a5a70a.txt`
//! (accumulated curvature). Each criterion looks at one element of a hierarchy
//! (a bitree triangle or a quadtree block) and says whether it must be refined.
//! Both hierarchies call the same trait.
//!
//! 1. [`MaxVerticalError`]: the exact vertical error (the default).
//! 2. [`EuclideanDistance`]: paper 000 §3.2, the 3D distance to the plane.
//! 3. [`RelativeSize`]: paper 001's size factor.
//! 4. [`AccumulatedCurvature`]: papers 002–004 ([`curvature`]).
//! 5. [`IlluminationMask`]: paper 002's mask ([`light`]).
//! 6. [`ScreenSpaceError`], [`Paper001`], [`Paper003`]: view-dependent
//!    ([`view`]).
//! 7. [`All`], [`Any`]: combinations.
//!
//! Each has a validating constructor (`new`) whose defaults, data-derived
//! where the papers give none, are documented there; [`CriterionKind`] and
//! [`CriterionOptions`] name a criterion and its settings as plain data
//! (what a command line or a request holds), and [`CriterionOptions::build`]
//! makes it for a grid.
//!
//! Geometry is in the grid's local frame in metres: x east, y north, z up,
//! origin at the south-west sample ([`local_m`], [`crate::grid::LocalFrame`]),
//! with the cell size of [`HeightGrid::cell_size_m`].

mod choice;
pub mod curvature;
pub mod light;
pub mod view;
mod voids;

use crate::grid::HeightGrid;

pub use choice::{CriterionKind, CriterionOptions};
pub use curvature::{AccumulatedCurvature, CurvatureMap};
pub use light::IlluminationMask;
pub use view::{Paper001, Paper003, ScreenSpaceError};
pub use voids::AvoidVoids;

/// A criterion setting out of its range, or a missing one.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CriterionError {
    /// A setting outside its range (negative, NaN, an angle out of bounds).
    #[error("{setting}: expected {expected}, found {found}")]
    OutOfRange {
        /// The setting, as named in [`CriterionOptions`].
        setting: &'static str,
        /// What it must be.
        expected: &'static str,
        /// What it was.
        found: f64,
    },
    /// A view-dependent criterion without an observer.
    #[error("the {criterion} criterion needs an observer position (metres, local frame)")]
    NeedsObserver {
        /// The criterion's name ([`CriterionKind::name`]).
        criterion: &'static str,
    },
}

/// `Ok` when `v` is 0 or more (not NaN), else [`CriterionError::OutOfRange`]
/// naming `setting`.
pub(crate) fn non_negative(setting: &'static str, v: f64) -> Result<f64, CriterionError> {
    if v.is_nan() || v < 0.0 {
        return Err(CriterionError::OutOfRange {
            setting,
            expected: "0 or more",
            found: v,
        });
    }
    Ok(v)
}

/// The default tolerance of the curvature criteria (curvature, light and,
/// divided by the terrain's diagonal, paper 003), as a share of the grid's
/// total accumulated curvature ([`CurvatureMap::total`]): `1e-4`. The papers
/// give no value and a tolerance depends on the terrain, so the default is
/// relative to the terrain's own total.
pub const DEFAULT_TOLERANCE_SHARE: f64 = 1e-4;

/// What a criterion sees of one element of a hierarchy.
#[derive(Debug, Clone, Copy)]
pub struct Element<'a> {
    /// The element's corners: column, row (grid units) and height in metres.
    /// A bitree triangle has 3 (hypotenuse ends first, then the right-angle
    /// apex); a quadtree block has 4 (NW, NE, SE, SW).
    pub corners: &'a [[f64; 3]],
    /// Depth in the hierarchy, 0 at the roots.
    pub depth: u32,
    /// Exact largest |surface − h| over every grid sample in or on the element,
    /// in metres, where the surface is what the mesh would show if the element
    /// were not refined.
    pub vertical_error_m: f64,
    /// The grid the hierarchy is built on.
    pub grid: &'a HeightGrid,
}

/// A refinement criterion: says whether an element must be split.
///
/// Implementations must be cheap relative to the element's area or document
/// their cost.
pub trait Criterion: Sync {
    /// True when `e` must be refined.
    fn wants_split(&self, e: &Element<'_>) -> bool;

    /// A short name for reports.
    fn name(&self) -> String;

    /// `Some(E)` when this criterion is exactly the vertical bound
    /// "refine while `vertical_error_m > E`" (metres) and nothing else, so that
    /// the bitree's error map can answer it for every element at once
    /// ([`crate::mesher`] then extracts instead of refining). Default: `None`.
    fn vertical_bound_m(&self) -> Option<f64> {
        None
    }
}

/// The default criterion: refine while the exact vertical error exceeds a bound:
/// `vertical_error_m > max_error_m` (metres).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaxVerticalError {
    /// The bound in metres. Default: 1.0.
    pub max_error_m: f64,
}

impl MaxVerticalError {
    /// The bound of `max_error_m` metres.
    ///
    /// # Errors
    /// [`CriterionError::OutOfRange`] for a negative or NaN bound.
    pub fn new(max_error_m: f64) -> Result<Self, CriterionError> {
        Ok(MaxVerticalError {
            max_error_m: non_negative("max_error_m", max_error_m)?,
        })
    }
}

impl Default for MaxVerticalError {
    fn default() -> Self {
        MaxVerticalError { max_error_m: 1.0 }
    }
}

impl Criterion for MaxVerticalError {
    fn wants_split(&self, e: &Element<'_>) -> bool {
        e.vertical_error_m > self.max_error_m
    }

    fn name(&self) -> String {
        format!("max-error {} m", plain(self.max_error_m))
    }

    fn vertical_bound_m(&self) -> Option<f64> {
        Some(self.max_error_m)
    }
}

/// Refine when **every** inner criterion wants to (paper 001's AND of
/// distance, size and curvature). Never a pure vertical bound.
pub struct All<'a>(pub Vec<&'a dyn Criterion>);

impl Criterion for All<'_> {
    fn wants_split(&self, e: &Element<'_>) -> bool {
        !self.0.is_empty() && self.0.iter().all(|c| c.wants_split(e))
    }

    fn name(&self) -> String {
        let names: Vec<String> = self.0.iter().map(|c| c.name()).collect();
        format!("all({})", names.join(", "))
    }
}

/// Refine when **any** inner criterion wants to (e.g. a vertical bound that must
/// hold everywhere, plus extra detail near the observer). Never a pure
/// vertical bound: it may refine more than its inner bound asks.
pub struct Any<'a>(pub Vec<&'a dyn Criterion>);

impl Criterion for Any<'_> {
    fn wants_split(&self, e: &Element<'_>) -> bool {
        self.0.iter().any(|c| c.wants_split(e))
    }

    fn name(&self) -> String {
        let names: Vec<String> = self.0.iter().map(|c| c.name()).collect();
        format!("any({})", names.join(", "))
    }
}

/// The local frame position in metres of an element corner `[col, row, z_m]`:
/// x east = `col·dx`, y north = `(H − 1 − row)·dy`, z = height.
pub fn local_m(grid: &HeightGrid, corner: [f64; 3]) -> [f64; 3] {
    grid.local_frame().point_m(corner[0], corner[1], corner[2])
}

/// The length in metres of the horizontal diagonal of the grid's rectangle:
/// `√(((W−1)·dx)² + ((H−1)·dy)²)`.
pub fn terrain_diagonal_m(grid: &HeightGrid) -> f64 {
    let [dx, dy] = grid.cell_size_m();
    let (w, h) = (grid.width() as f64 - 1.0, grid.height() as f64 - 1.0);
    (w * dx).hypot(h * dy)
}

/// The longest horizontal edge of an element, metres: the largest distance
/// between consecutive corners (cyclically) in the local frame's x, y.
pub fn longest_edge_m(e: &Element<'_>) -> f64 {
    let n = e.corners.len();
    (0..n)
        .map(|k| {
            let p = local_m(e.grid, e.corners[k]);
            let q = local_m(e.grid, e.corners[(k + 1) % n]);
            (p[0] - q[0]).hypot(p[1] - q[1])
        })
        .fold(0.0, f64::max)
}

/// Paper 000 §3.2's measure: the largest 3D (Euclidean) distance, in metres,
/// of the grid samples in or on the element to the element's plane.
///
/// For a plane `z = z0 + gx·x + gy·y` (gradients in metres per metre, from the
/// corners in the local frame) a sample at vertical offset `Δz` is at distance
/// `|Δz| / √(1 + gx² + gy²)`, so the largest distance is exactly
/// `vertical_error_m / √(1 + gx² + gy²)`: O(1) per element. Elements with more
/// than three corners (quadtree blocks) use, of the fan triangles
/// `(c0, ck, ck+1)`, the least steep plane, which gives the largest (safest)
/// distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EuclideanDistance {
    /// Refine while the distance exceeds this many metres. Default: 1.0.
    pub max_distance_m: f64,
}

impl Default for EuclideanDistance {
    fn default() -> Self {
        EuclideanDistance {
            max_distance_m: 1.0,
        }
    }
}

impl EuclideanDistance {
    /// The bound of `max_distance_m` metres.
    ///
    /// # Errors
    /// [`CriterionError::OutOfRange`] for a negative or NaN bound.
    pub fn new(max_distance_m: f64) -> Result<Self, CriterionError> {
        Ok(EuclideanDistance {
            max_distance_m: non_negative("max_error_m", max_distance_m)?,
        })
    }

    /// The element's largest Euclidean distance in metres (see the type docs).
    pub fn distance_m(e: &Element<'_>) -> f64 {
        let p: Vec<[f64; 3]> = e.corners.iter().map(|&c| local_m(e.grid, c)).collect();
        let mut slope2 = f64::INFINITY;
        for k in 1..p.len().saturating_sub(1) {
            let (a, b, c) = (p[0], p[k], p[k + 1]);
            let (u, v) = (sub(b, a), sub(c, a));
            // Normal n = u × v; gradient = (−nx/nz, −ny/nz).
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            if n[2] != 0.0 {
                slope2 = slope2.min((n[0] * n[0] + n[1] * n[1]) / (n[2] * n[2]));
            }
        }
        if !slope2.is_finite() {
            return e.vertical_error_m;
        }
        e.vertical_error_m / (1.0 + slope2).sqrt()
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

impl Criterion for EuclideanDistance {
    fn wants_split(&self, e: &Element<'_>) -> bool {
        Self::distance_m(e) > self.max_distance_m
    }

    fn name(&self) -> String {
        format!("euclidean {} m", plain(self.max_distance_m))
    }
}

/// Paper 001's size factor: refine while the element's longest horizontal edge
/// ([`longest_edge_m`]) exceeds `factor × terrain diagonal`
/// ([`terrain_diagonal_m`]), both in metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelativeSize {
    /// Fraction of the terrain's diagonal. Default: 0.01 (1 %, paper 001).
    pub factor: f64,
}

impl Default for RelativeSize {
    fn default() -> Self {
        RelativeSize { factor: 0.01 }
    }
}

impl RelativeSize {
    /// Refine while the longest edge exceeds `factor` × the terrain's diagonal.
    ///
    /// # Errors
    /// [`CriterionError::OutOfRange`] for a negative or NaN factor.
    pub fn new(factor: f64) -> Result<Self, CriterionError> {
        Ok(RelativeSize {
            factor: non_negative("size_factor", factor)?,
        })
    }
}

impl Criterion for RelativeSize {
    fn wants_split(&self, e: &Element<'_>) -> bool {
        longest_edge_m(e) > self.factor * terrain_diagonal_m(e.grid)
    }

    fn name(&self) -> String {
        format!("size {} of the diagonal", plain(self.factor))
    }
}

/// A parameter as a criterion's name shows it: as given, but in exponent
/// form outside 10⁻⁴ to 10⁹ (a bound of 1e300 is not 301 digits).
pub fn plain(v: f64) -> String {
    let a = v.abs();
    if v.is_finite() && a != 0.0 && !(1e-4..1e9).contains(&a) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}
