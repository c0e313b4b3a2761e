//! Refinement criteria behind one trait, combinable.
//!
//! Papers `000_ebf7e3a88dffd361.txt` §3.2 (Euclidean distance of the grid points
//! to the triangle), `001_49f2c365e8c41172.txt` (distance AND size AND
//! curvature), `002_9d6c1367b8962b6c.txt` (curvature with an illumination mask),
//! `003_3a32b63e0cff3a64.txt` (k·cosθ/d) and `004_ab8d08b3e6a5a70a.txt`
//! (accumulated curvature). Each criterion looks at one element of a hierarchy
//! (a bitree triangle or a quadtree block) and says whether it must be refined.
//! Both hierarchies call the same trait.

use crate::grid::HeightGrid;

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
}

/// The default criterion: refine while the exact vertical error exceeds a bound.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaxVerticalError {
    /// The bound in metres. Default: 1.0.
    pub max_error_m: f64,
}

impl Criterion for MaxVerticalError {
    fn wants_split(&self, e: &Element<'_>) -> bool {
        e.vertical_error_m > self.max_error_m
    }

    fn name(&self) -> String {
        format!("max-error {} m", self.max_error_m)
    }
}

/// Refine when **every** inner criterion wants to (paper 001's AND of
/// distance, size and curvature).
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
/// hold everywhere, plus extra detail near the observer).
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
