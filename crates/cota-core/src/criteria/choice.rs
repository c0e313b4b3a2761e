//! A criterion and its settings as plain data: what a command line, a request
//! or a configuration names, validated and turned into a [`Criterion`] for
//! one grid by [`CriterionOptions::build`].
//!
//! Papers `000_ebf7e3a88dffd361.txt` to `004_ab8d08b3e6a5a70a.txt` (see
//! [`super`]): the defaults below are the papers' where they give one
//! (paper 001's 80 %, 1 %, 20 %) and otherwise the constructors' documented
//! ones.

use super::curvature::{AccumulatedCurvature, CurvatureMap};
use super::light::{weight, IlluminationMask};
use super::view::{fov, Paper001, Paper003, ScreenSpaceError};
use super::RelativeSize;
use super::{non_negative, Criterion, CriterionError, EuclideanDistance, MaxVerticalError};
use crate::grid::HeightGrid;

/// Which criterion drives a refinement.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum CriterionKind {
    /// [`MaxVerticalError`] at [`CriterionOptions::max_error_m`]. Default.
    #[default]
    MaxError,
    /// [`EuclideanDistance`] at [`CriterionOptions::max_error_m`].
    Euclidean,
    /// [`AccumulatedCurvature`] at [`CriterionOptions::tolerance`].
    Curvature,
    /// [`RelativeSize`] at [`CriterionOptions::size_factor`].
    Size,
    /// [`IlluminationMask`]: light, alpha and tolerance.
    Light,
    /// [`ScreenSpaceError`] from the observer along the look direction.
    View,
    /// [`Paper001`]: near AND large AND curved.
    Paper001,
    /// [`Paper003`]: curvature × cos θ / distance.
    Paper003,
}

impl CriterionKind {
    /// The name on the command line: `max-error`, `euclidean`, `curvature`,
    /// `size`, `light`, `view`, `paper001` or `paper003`.
    pub fn name(self) -> &'static str {
        match self {
            CriterionKind::MaxError => "max-error",
            CriterionKind::Euclidean => "euclidean",
            CriterionKind::Curvature => "curvature",
            CriterionKind::Size => "size",
            CriterionKind::Light => "light",
            CriterionKind::View => "view",
            CriterionKind::Paper001 => "paper001",
            CriterionKind::Paper003 => "paper003",
        }
    }

    /// True for the view-dependent criteria, which need
    /// [`CriterionOptions::observer_m`].
    pub fn needs_observer(self) -> bool {
        matches!(
            self,
            CriterionKind::View | CriterionKind::Paper001 | CriterionKind::Paper003
        )
    }

    /// True for the criteria that read the grid's [`CurvatureMap`].
    pub fn needs_curvature_map(self) -> bool {
        matches!(
            self,
            CriterionKind::Curvature
                | CriterionKind::Light
                | CriterionKind::Paper001
                | CriterionKind::Paper003
        )
    }
}

/// The settings of every criterion, each used by the kinds its doc names.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct CriterionOptions {
    /// Vertical bound (max-error) or distance bound (euclidean), metres.
    /// Default: 1.0.
    pub max_error_m: f64,
    /// Tolerance of curvature and light (1/m) and of paper003 (1/m²).
    /// Default: `None`, data-derived: [`super::DEFAULT_TOLERANCE_SHARE`] of
    /// the grid's total accumulated curvature (paper003: divided by the
    /// terrain's diagonal in metres).
    pub tolerance: Option<f64>,
    /// Observer position, local frame, metres (view, paper001, paper003).
    /// Default: `None`; those criteria require one.
    pub observer_m: Option<[f64; 3]>,
    /// View direction (view) or direction of motion (paper003), any length.
    /// Default: `[0, 1, 0]` (north).
    pub look_dir: [f64; 3],
    /// Vertical field of view, degrees (view). Default: 60.
    pub fov_y_deg: f64,
    /// Viewport height, pixels (view). Default: 1080.
    pub viewport_height_px: f64,
    /// Largest projected vertical error, pixels (view). Default: 1.
    pub max_error_px: f64,
    /// Direction towards the light (light), any length. Default: `[1, 1, 1]`
    /// (high in the north-east).
    pub light_dir: [f64; 3],
    /// Weight of pure curvature in `[0, 1]` (light). Default: 0.5.
    pub alpha: f64,
    /// Fraction of the terrain's diagonal (size, paper001). Default: 0.01
    /// (paper 001's 1 %).
    pub size_factor: f64,
    /// Fraction of the largest distance (paper001). Default: 0.8 (paper
    /// 001's 80 %).
    pub distance_factor: f64,
    /// Fraction of the grid's accumulated curvature (paper001). Default: 0.2
    /// (paper 001's 20 %).
    pub curvature_factor: f64,
}

impl CriterionOptions {
    /// The defaults, as documented on each field.
    pub const DEFAULT: CriterionOptions = CriterionOptions {
        max_error_m: 1.0,
        tolerance: None,
        observer_m: None,
        look_dir: [0.0, 1.0, 0.0],
        fov_y_deg: 60.0,
        viewport_height_px: 1080.0,
        max_error_px: 1.0,
        light_dir: [1.0, 1.0, 1.0],
        alpha: 0.5,
        size_factor: 0.01,
        distance_factor: 0.8,
        curvature_factor: 0.2,
    };

    /// Sets [`CriterionOptions::max_error_m`].
    pub const fn with_max_error_m(mut self, e: f64) -> Self {
        self.max_error_m = e;
        self
    }

    /// Sets [`CriterionOptions::tolerance`].
    pub const fn with_tolerance(mut self, t: Option<f64>) -> Self {
        self.tolerance = t;
        self
    }

    /// Sets [`CriterionOptions::observer_m`].
    pub const fn with_observer_m(mut self, o: Option<[f64; 3]>) -> Self {
        self.observer_m = o;
        self
    }

    /// Sets [`CriterionOptions::look_dir`].
    pub const fn with_look_dir(mut self, d: [f64; 3]) -> Self {
        self.look_dir = d;
        self
    }

    /// Sets the view's field of view (degrees), viewport height and pixel
    /// error (pixels).
    pub const fn with_view(mut self, fov_y_deg: f64, viewport_px: f64, max_error_px: f64) -> Self {
        self.fov_y_deg = fov_y_deg;
        self.viewport_height_px = viewport_px;
        self.max_error_px = max_error_px;
        self
    }

    /// Sets the light's direction and weight.
    pub const fn with_light(mut self, light_dir: [f64; 3], alpha: f64) -> Self {
        self.light_dir = light_dir;
        self.alpha = alpha;
        self
    }

    /// Sets paper 001's size, distance and curvature factors.
    pub const fn with_factors(mut self, size: f64, distance: f64, curvature: f64) -> Self {
        self.size_factor = size;
        self.distance_factor = distance;
        self.curvature_factor = curvature;
        self
    }

    /// Checks every setting, whichever criterion uses it, in this order: the
    /// observer (when `kind` needs one), alpha, the field of view, the
    /// viewport height, the pixel error, the three factors, the tolerance.
    ///
    /// # Errors
    /// [`CriterionError::NeedsObserver`], or [`CriterionError::OutOfRange`]
    /// for the first setting out of range.
    pub fn validate(&self, kind: CriterionKind) -> Result<(), CriterionError> {
        if kind.needs_observer() && self.observer_m.is_none() {
            return Err(CriterionError::NeedsObserver {
                criterion: kind.name(),
            });
        }
        weight(self.alpha)?;
        fov(self.fov_y_deg)?;
        for (setting, v) in [
            ("viewport_height_px", self.viewport_height_px),
            ("max_error_px", self.max_error_px),
            ("size_factor", self.size_factor),
            ("distance_factor", self.distance_factor),
            ("curvature_factor", self.curvature_factor),
        ] {
            non_negative(setting, v)?;
        }
        if let Some(t) = self.tolerance {
            non_negative("tolerance", t)?;
        }
        Ok(())
    }

    /// The criterion `kind` with these settings for `grid`, through its
    /// validating constructor (only the settings it uses are checked).
    /// `map` gives the grid's curvature map when the kind needs one
    /// ([`CriterionKind::needs_curvature_map`]): computing it costs `O(W·H)`,
    /// so callers that build several criteria share one.
    ///
    /// ```
    /// use cota_core::{CriterionKind, CriterionOptions, GeoRef, HeightGrid};
    /// use cota_core::criteria::CurvatureMap;
    /// let g = HeightGrid::new(5, 5, (0..25).map(|i| (i * i) as f32).collect(),
    ///                         GeoRef::unreferenced(30.0)).unwrap();
    /// let map = CurvatureMap::new(&g);
    /// let opts = CriterionOptions::DEFAULT.with_max_error_m(2.0);
    /// let c = opts.build(CriterionKind::MaxError, &g, || &map).unwrap();
    /// assert_eq!(c.vertical_bound_m(), Some(2.0));
    /// let c = opts.build(CriterionKind::Curvature, &g, || &map).unwrap();
    /// assert_eq!(c.vertical_bound_m(), None);
    /// ```
    ///
    /// # Errors
    /// As [`CriterionOptions::validate`], for the settings `kind` uses.
    pub fn build<'a>(
        &self,
        kind: CriterionKind,
        grid: &'a HeightGrid,
        map: impl FnOnce() -> &'a CurvatureMap,
    ) -> Result<Box<dyn Criterion + 'a>, CriterionError> {
        let observer = match (kind.needs_observer(), self.observer_m) {
            (true, None) => {
                return Err(CriterionError::NeedsObserver {
                    criterion: kind.name(),
                })
            }
            (_, o) => o.unwrap_or([0.0; 3]),
        };
        Ok(match kind {
            CriterionKind::MaxError => Box::new(MaxVerticalError::new(self.max_error_m)?),
            CriterionKind::Euclidean => Box::new(EuclideanDistance::new(self.max_error_m)?),
            CriterionKind::Size => Box::new(RelativeSize::new(self.size_factor)?),
            CriterionKind::View => Box::new(
                ScreenSpaceError {
                    look_dir: self.look_dir,
                    fov_y_deg: self.fov_y_deg,
                    viewport_height_px: self.viewport_height_px,
                    max_error_px: self.max_error_px,
                    ..ScreenSpaceError::at(observer)
                }
                .validated()?,
            ),
            CriterionKind::Curvature => Box::new(AccumulatedCurvature::new(map(), self.tolerance)?),
            CriterionKind::Light => Box::new(IlluminationMask::new(
                map(),
                self.light_dir,
                self.alpha,
                self.tolerance,
            )?),
            CriterionKind::Paper001 => Box::new(
                Paper001 {
                    distance_factor: self.distance_factor,
                    size_factor: self.size_factor,
                    curvature_factor: self.curvature_factor,
                    ..Paper001::new(map(), observer)
                }
                .validated()?,
            ),
            CriterionKind::Paper003 => Box::new(Paper003::new(
                map(),
                grid,
                observer,
                self.look_dir,
                self.tolerance,
            )?),
        })
    }
}

impl Default for CriterionOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}
