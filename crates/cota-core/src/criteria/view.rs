//! View-dependent refinement criteria.
//!
//! Papers `000_ebf7e3a88dffd361.txt` §3 (level of detail from the distance to
//! the viewpoint and the view direction), `001_49f2c365e8c41172.txt` (refine
//! only if near AND large AND curved) and `003_3a32b63e0cff3a64.txt`
//! (`k·cosθ/d`). Positions are in the grid's local frame in metres (x east,
//! y north, z up, origin at the south-west sample, [`super::local_m`]).
//!
//! 1. [`ScreenSpaceError`]: the element's vertical error projected at its
//!    nearest distance, in pixels.
//! 2. [`Paper001`]: distance AND size AND curvature.
//! 3. [`Paper003`]: accumulated curvature times `cosθ/d`.
//!
//! The nearest distance of an element ([`nearest_distance_m`]) is the distance
//! from the observer to the element's axis-aligned bounding box (x, y from its
//! corners, z widened by its vertical error): a lower bound on the distance to
//! any terrain sample the element covers, so the projected error is never
//! understated.

use super::curvature::CurvatureMap;
use super::light::unit;
use super::{
    local_m, longest_edge_m, non_negative, terrain_diagonal_m, Criterion, CriterionError, Element,
    DEFAULT_TOLERANCE_SHARE,
};
use crate::grid::HeightGrid;

/// The element's bounding box in the local frame: `(lo, hi)` metres, z widened
/// by the vertical error.
fn bbox_m(e: &Element<'_>) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &c in e.corners {
        let p = local_m(e.grid, c);
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    lo[2] -= e.vertical_error_m;
    hi[2] += e.vertical_error_m;
    (lo, hi)
}

/// Distance in metres from `observer_m` to the element's bounding box (0
/// inside it). See the module docs.
pub fn nearest_distance_m(e: &Element<'_>, observer_m: [f64; 3]) -> f64 {
    let (lo, hi) = bbox_m(e);
    let mut d2 = 0.0;
    for k in 0..3 {
        let d = (lo[k] - observer_m[k]).max(observer_m[k] - hi[k]).max(0.0);
        d2 += d * d;
    }
    d2.sqrt()
}

/// The mean of the element's corners in the local frame, metres.
pub fn centroid_m(e: &Element<'_>) -> [f64; 3] {
    let mut s = [0.0; 3];
    for &c in e.corners {
        let p = local_m(e.grid, c);
        for k in 0..3 {
            s[k] += p[k];
        }
    }
    let n = e.corners.len().max(1) as f64;
    [s[0] / n, s[1] / n, s[2] / n]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Screen-space error: refine while `δ·P / (2·d·tan(fov_y/2)) > max_error_px`,
/// with `δ` the element's exact vertical error (m), `P` the viewport height
/// (px), `d` its nearest distance (m, at least 1 cm) and `fov_y` the vertical
/// field of view, for elements that meet the view cone.
///
/// The view cone has its apex at the observer, axis `look_dir`, and half-angle
/// `atan(tan(fov_y/2)·√(1 + aspect²))` (the half-diagonal of the viewport). An
/// element whose bounding sphere (around its bounding box) lies outside the cone
/// is never refined by this criterion; one containing the observer always
/// meets it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScreenSpaceError {
    /// Observer position, local frame, metres.
    pub observer_m: [f64; 3],
    /// View direction (any length). Default: `[0, 1, 0]` (north).
    pub look_dir: [f64; 3],
    /// Vertical field of view, degrees. Default: 60.
    pub fov_y_deg: f64,
    /// Viewport height, pixels. Default: 1080.
    pub viewport_height_px: f64,
    /// Viewport width / height. Default: 16/9.
    pub aspect: f64,
    /// Largest projected error, pixels. Default: 1.
    pub max_error_px: f64,
}

impl ScreenSpaceError {
    /// The defaults with an observer at `observer_m`.
    pub fn at(observer_m: [f64; 3]) -> Self {
        ScreenSpaceError {
            observer_m,
            look_dir: [0.0, 1.0, 0.0],
            fov_y_deg: 60.0,
            viewport_height_px: 1080.0,
            aspect: 16.0 / 9.0,
            max_error_px: 1.0,
        }
    }

    /// `self` when its settings are in range.
    ///
    /// # Errors
    /// [`CriterionError::OutOfRange`] for a field of view outside
    /// `(0, 180)` degrees or a negative or NaN viewport height, aspect or
    /// pixel error.
    pub fn validated(self) -> Result<Self, CriterionError> {
        fov(self.fov_y_deg)?;
        non_negative("viewport_height_px", self.viewport_height_px)?;
        non_negative("aspect", self.aspect)?;
        non_negative("max_error_px", self.max_error_px)?;
        Ok(self)
    }

    /// The element's projected vertical error in pixels (ignores the cone).
    pub fn error_px(&self, e: &Element<'_>) -> f64 {
        let d = nearest_distance_m(e, self.observer_m).max(0.01);
        let half = (self.fov_y_deg.to_radians() / 2.0).tan();
        e.vertical_error_m * self.viewport_height_px / (2.0 * d * half)
    }

    /// True when the element's bounding sphere meets the view cone.
    pub fn in_view(&self, e: &Element<'_>) -> bool {
        let Some(look) = unit(self.look_dir) else {
            return true;
        };
        let (lo, hi) = bbox_m(e);
        let centre = [
            (lo[0] + hi[0]) / 2.0,
            (lo[1] + hi[1]) / 2.0,
            (lo[2] + hi[2]) / 2.0,
        ];
        let radius = dot(sub(hi, lo), sub(hi, lo)).sqrt() / 2.0;
        let v = sub(centre, self.observer_m);
        let dist = dot(v, v).sqrt();
        if dist <= radius {
            return true;
        }
        let half = ((self.fov_y_deg.to_radians() / 2.0).tan()
            * (1.0 + self.aspect * self.aspect).sqrt())
        .atan();
        let angle = (dot(v, look) / dist).clamp(-1.0, 1.0).acos();
        angle <= half + (radius / dist).asin()
    }
}

impl Criterion for ScreenSpaceError {
    fn wants_split(&self, e: &Element<'_>) -> bool {
        self.error_px(e) > self.max_error_px && self.in_view(e)
    }

    fn name(&self) -> String {
        format!(
            "view {} px from {:?} looking {:?}, fov {} deg, {} px high",
            self.max_error_px,
            self.observer_m,
            self.look_dir,
            self.fov_y_deg,
            self.viewport_height_px
        )
    }
}

/// `fov_y_deg` when it is an angle in `(0, 180)` degrees.
pub(super) fn fov(fov_y_deg: f64) -> Result<f64, CriterionError> {
    if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) {
        return Err(CriterionError::OutOfRange {
            setting: "fov_y_deg",
            expected: "an angle in (0, 180) degrees",
            found: fov_y_deg,
        });
    }
    Ok(fov_y_deg)
}

/// Paper 001's indicator: refine only when the element is
/// 1. **near**: its nearest distance ([`nearest_distance_m`]) is at most
///    `distance_factor × D`, `D` the largest distance from the observer to a
///    corner of the terrain's bounding box (x, y over the grid, z over its
///    height range), metres;
/// 2. **large**: its longest horizontal edge exceeds `size_factor` × the
///    terrain's diagonal (metres, [`super::RelativeSize`]);
/// 3. **curved**: its accumulated curvature `K` ([`super::curvature`], 1/m)
///    exceeds `curvature_factor × K_max`, `K_max` the accumulated curvature of
///    the whole grid (the largest any element can have; the paper's
///    "extensive indicator, proportional to the surface").
#[derive(Debug, Clone, Copy)]
pub struct Paper001<'a> {
    /// The grid's curvature map.
    pub map: &'a CurvatureMap,
    /// Observer position, local frame, metres.
    pub observer_m: [f64; 3],
    /// Fraction of the largest distance. Default: 0.8.
    pub distance_factor: f64,
    /// Fraction of the terrain's diagonal. Default: 0.01.
    pub size_factor: f64,
    /// Fraction of the largest accumulated curvature. Default: 0.2.
    pub curvature_factor: f64,
}

impl<'a> Paper001<'a> {
    /// Paper 001's settings (80 %, 1 %, 20 %) for an observer at `observer_m`.
    pub fn new(map: &'a CurvatureMap, observer_m: [f64; 3]) -> Self {
        Paper001 {
            map,
            observer_m,
            distance_factor: 0.8,
            size_factor: 0.01,
            curvature_factor: 0.2,
        }
    }

    /// `self` when its factors are 0 or more (not NaN).
    ///
    /// # Errors
    /// [`CriterionError::OutOfRange`] naming the first factor out of range.
    pub fn validated(self) -> Result<Self, CriterionError> {
        non_negative("size_factor", self.size_factor)?;
        non_negative("distance_factor", self.distance_factor)?;
        non_negative("curvature_factor", self.curvature_factor)?;
        Ok(self)
    }

    /// `D`: the largest distance from the observer to a corner of the
    /// terrain's bounding box, metres.
    pub fn max_distance_m(&self, e: &Element<'_>) -> f64 {
        let g = e.grid;
        let [dx, dy] = g.cell_size_m();
        let (xm, ym) = ((g.width() - 1) as f64 * dx, (g.height() - 1) as f64 * dy);
        let (zlo, zhi) = g.valid_range().unwrap_or((0.0, 0.0));
        let o = self.observer_m;
        let far = |lo: f64, hi: f64, v: f64| (v - lo).abs().max((hi - v).abs());
        let (fx, fy, fz) = (
            far(0.0, xm, o[0]),
            far(0.0, ym, o[1]),
            far(zlo as f64, zhi as f64, o[2]),
        );
        (fx * fx + fy * fy + fz * fz).sqrt()
    }
}

impl Criterion for Paper001<'_> {
    fn wants_split(&self, e: &Element<'_>) -> bool {
        longest_edge_m(e) > self.size_factor * terrain_diagonal_m(e.grid)
            && nearest_distance_m(e, self.observer_m)
                <= self.distance_factor * self.max_distance_m(e)
            && self.map.accumulate(e.corners) > self.curvature_factor * self.map.total()
    }

    fn name(&self) -> String {
        format!(
            "paper001 from {:?}: distance {}, size {}, curvature {}",
            self.observer_m, self.distance_factor, self.size_factor, self.curvature_factor
        )
    }
}

/// Paper 003's indicator: refine while `K·cosθ / d > tolerance`, with `K` the
/// element's accumulated curvature (1/m, [`super::curvature`]), `d` the
/// distance from the observer to the element's centroid ([`centroid_m`],
/// metres, at least 1 cm) and `θ` the angle between the observer's motion
/// direction and the direction from the observer to that centroid. Units of
/// the tolerance: 1/m². Elements behind the motion (`cosθ ≤ 0`) never refine.
#[derive(Debug, Clone, Copy)]
pub struct Paper003<'a> {
    /// The grid's curvature map.
    pub map: &'a CurvatureMap,
    /// Observer position, local frame, metres.
    pub observer_m: [f64; 3],
    /// Direction of motion (any length).
    pub motion_dir: [f64; 3],
    /// Tolerance `T`, 1/m². Default ([`Paper003::new`] without one):
    /// [`DEFAULT_TOLERANCE_SHARE`] × [`CurvatureMap::total`] divided by the
    /// terrain's diagonal in metres ([`terrain_diagonal_m`]), the curvature
    /// criteria's default over the distance across the whole terrain.
    pub tolerance: f64,
}

impl<'a> Paper003<'a> {
    /// The indicator on `map` (of `grid`) for an observer at `observer_m`
    /// moving along `motion_dir`, with `tolerance` (1/m²) or the default of
    /// [`Paper003::tolerance`].
    ///
    /// # Errors
    /// [`CriterionError::OutOfRange`] for a negative or NaN tolerance.
    pub fn new(
        map: &'a CurvatureMap,
        grid: &HeightGrid,
        observer_m: [f64; 3],
        motion_dir: [f64; 3],
        tolerance: Option<f64>,
    ) -> Result<Self, CriterionError> {
        let tolerance = match tolerance {
            Some(t) => non_negative("tolerance", t)?,
            None => DEFAULT_TOLERANCE_SHARE * map.total() / terrain_diagonal_m(grid).max(1e-9),
        };
        Ok(Paper003 {
            map,
            observer_m,
            motion_dir,
            tolerance,
        })
    }
}

impl Paper003<'_> {
    /// `K·cosθ/d` of the element, 1/m².
    pub fn indicator(&self, e: &Element<'_>) -> f64 {
        let Some(m) = unit(self.motion_dir) else {
            return 0.0;
        };
        let v = sub(centroid_m(e), self.observer_m);
        let d = dot(v, v).sqrt().max(0.01);
        let cos = dot(v, m) / d;
        self.map.accumulate(e.corners) * cos / d
    }
}

impl Criterion for Paper003<'_> {
    fn wants_split(&self, e: &Element<'_>) -> bool {
        self.indicator(e) > self.tolerance
    }

    fn name(&self) -> String {
        format!(
            "paper003 from {:?} moving {:?}, tolerance {} 1/m2",
            self.observer_m, self.motion_dir, self.tolerance
        )
    }
}
