//! `cota mesh --mode … --criterion …`: flags to a criterion and a mode, then
//! `cota_core::refine::refine`.

use anyhow::bail;
use cota_core::criteria::curvature::{AccumulatedCurvature, CurvatureMap};
use cota_core::criteria::light::IlluminationMask;
use cota_core::criteria::terrain_diagonal_m;
use cota_core::criteria::view::{Paper001, Paper003, ScreenSpaceError};
use cota_core::refine::{refine, Mode, RefineOptions};
use cota_core::{
    CheckOptions, Criterion, EuclideanDistance, HeightGrid, MaxVerticalError, Mesh, RelativeSize,
};

use crate::args::{CriterionArg, ModeArg, RefineArgs};

/// What the generic path produced.
pub struct Outcome {
    pub mesh: Mesh,
    /// The vertical bound in metres, for `--criterion max-error` only.
    pub threshold_m: Option<f64>,
    pub transmitted_points: usize,
    pub fictitious_points: usize,
    pub line_triangles: usize,
    pub criterion: String,
    pub rounds: usize,
    /// What `--check` must verify.
    pub check: CheckOptions,
}

/// True for the default conforming max-error extraction (fast error-map path).
pub fn is_fast(r: &RefineArgs) -> bool {
    r.mode == ModeArg::Conforming && r.criterion == CriterionArg::MaxError
}

pub fn mode(r: &RefineArgs) -> Mode {
    match r.mode {
        ModeArg::Conforming => Mode::Conforming,
        ModeArg::Fictitious => Mode::Fictitious { watertight: true },
        ModeArg::FictitiousFaithful => Mode::Fictitious { watertight: false },
    }
}

/// Validates the flags before any long work.
pub fn validate(r: &RefineArgs, max_triangles: Option<usize>) -> anyhow::Result<()> {
    if is_fast(r) {
        return Ok(());
    }
    if max_triangles.is_some() {
        bail!(
            "--max-triangles works with the default --mode conforming --criterion max-error only"
        );
    }
    let needs_observer = matches!(
        r.criterion,
        CriterionArg::View | CriterionArg::Paper001 | CriterionArg::Paper003
    );
    if needs_observer && r.observer.is_none() {
        bail!(
            "--criterion {:?} needs --observer X,Y,Z (metres, local frame)",
            r.criterion
        );
    }
    if !(0.0..=1.0).contains(&r.alpha) {
        bail!("--alpha: expected a weight in [0, 1], found {}", r.alpha);
    }
    if !(r.fov_deg > 0.0 && r.fov_deg < 180.0) {
        bail!(
            "--fov-deg: expected an angle in (0, 180) degrees, found {}",
            r.fov_deg
        );
    }
    for (name, v) in [
        ("--viewport-px", r.viewport_px),
        ("--max-error-px", r.max_error_px),
        ("--size-factor", r.size_factor),
        ("--distance-factor", r.distance_factor),
        ("--curvature-factor", r.curvature_factor),
    ] {
        if v.is_nan() || v < 0.0 {
            bail!("{name}: expected 0 or more, found {v}");
        }
    }
    if let Some(t) = r.tolerance {
        if t.is_nan() || t < 0.0 {
            bail!("--tolerance: expected 0 or more, found {t}");
        }
    }
    Ok(())
}

/// Runs the generic refinement on a void-free grid.
pub fn run(r: &RefineArgs, max_error_m: f64, grid: &HeightGrid) -> anyhow::Result<Outcome> {
    let mode = mode(r);
    let (out, name) = with_criterion(r, max_error_m, grid, |criterion| {
        refine(grid, criterion, &RefineOptions::DEFAULT.with_mode(mode))
            .map(|o| (o, criterion.name()))
    })??;
    let threshold_m = (r.criterion == CriterionArg::MaxError).then_some(max_error_m);
    let check = CheckOptions::DEFAULT
        .with_max_error_m(threshold_m)
        .with_conforming(mode.is_conforming())
        .with_allow_fictitious(mode != Mode::Conforming);
    Ok(Outcome {
        mesh: out.mesh,
        threshold_m,
        transmitted_points: out.transmitted_points,
        fictitious_points: out.fictitious_points,
        line_triangles: out.line_triangles,
        criterion: name,
        rounds: out.rounds,
        check,
    })
}

/// Builds the criterion the flags describe and hands it to `f` (the criteria
/// borrow a curvature map, so they live only inside this call). Both
/// hierarchies use it.
pub fn with_criterion<R>(
    r: &RefineArgs,
    max_error_m: f64,
    grid: &HeightGrid,
    f: impl FnOnce(&dyn Criterion) -> R,
) -> anyhow::Result<R> {
    let needs_map = matches!(
        r.criterion,
        CriterionArg::Curvature
            | CriterionArg::Light
            | CriterionArg::Paper001
            | CriterionArg::Paper003
    );
    let map = needs_map.then(|| CurvatureMap::new(grid));
    let total = map.as_ref().map(|m| m.total()).unwrap_or(0.0);
    let observer = r.observer.unwrap_or([0.0; 3]);
    let curvature_tol = r.tolerance.unwrap_or(1e-4 * total);
    let max_error = MaxVerticalError { max_error_m };
    let euclidean = EuclideanDistance {
        max_distance_m: max_error_m,
    };
    let size = RelativeSize {
        factor: r.size_factor,
    };
    let view = ScreenSpaceError {
        look_dir: r.look,
        fov_y_deg: r.fov_deg,
        viewport_height_px: r.viewport_px,
        max_error_px: r.max_error_px,
        ..ScreenSpaceError::at(observer)
    };
    let map_criteria = map.as_ref().map(|m| {
        (
            AccumulatedCurvature {
                map: m,
                tolerance: curvature_tol,
            },
            IlluminationMask {
                map: m,
                light_dir: r.light,
                alpha: r.alpha,
                tolerance: curvature_tol,
            },
            Paper001 {
                distance_factor: r.distance_factor,
                size_factor: r.size_factor,
                curvature_factor: r.curvature_factor,
                ..Paper001::new(m, observer)
            },
            Paper003 {
                map: m,
                observer_m: observer,
                motion_dir: r.look,
                tolerance: r
                    .tolerance
                    .unwrap_or(1e-4 * total / terrain_diagonal_m(grid).max(1e-9)),
            },
        )
    });
    let criterion: &dyn Criterion = match (r.criterion, &map_criteria) {
        (CriterionArg::MaxError, _) => &max_error,
        (CriterionArg::Euclidean, _) => &euclidean,
        (CriterionArg::Size, _) => &size,
        (CriterionArg::View, _) => &view,
        (CriterionArg::Curvature, Some((c, _, _, _))) => c,
        (CriterionArg::Light, Some((_, l, _, _))) => l,
        (CriterionArg::Paper001, Some((_, _, p, _))) => p,
        (CriterionArg::Paper003, Some((_, _, _, p))) => p,
        (_, None) => bail!("internal: curvature map missing"),
    };
    Ok(f(criterion))
}
