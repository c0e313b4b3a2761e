//! Void filling: replacing the NaN samples of a [`HeightGrid`] by heights
//! estimated from the valid samples around them, under a stated policy.
//!
//! Real DEMs have voids (SRTM radar shadows in steep mountains, nodata outside a
//! clipped area, mosaic holes). Meshing needs a height everywhere, so a void is
//! either an error ([`VoidPolicy::Refuse`]) or filled ([`VoidPolicy::Fill`]).
//!
//! # Harmonic fill (the default)
//! Each void sample gets the value of the discrete harmonic (Laplace) function
//! over the void with the valid samples around it as Dirichlet boundary: every
//! filled sample is the weighted mean of its four neighbours, the weights being
//! 1/dx² and 1/dy² with the cell size in metres at the void (so non-square
//! geographic cells are handled). A void touching the grid edge just has fewer
//! neighbours there (a Neumann, zero-slope, boundary). The fill is continuous
//! with the surrounding terrain, reproduces planes exactly, and by the maximum
//! principle stays within the lowest and highest border values of its void.
//!
//! Steps:
//! 1. Find the 4-connected void components (from runs, joined by union–find).
//!    They are independent (no two share a neighbour), so each is solved on its
//!    own bounding box plus a one-sample margin: small ones on a copy of their
//!    box, many at once; large ones in the grid's own rows, each in parallel
//!    over bands of rows (rayon). The finest level is matrix-free (it reads the
//!    heights and a one-bit mask), so a void costs a few bytes per sample.
//! 2. Start (full multigrid): the fine equations' right-hand side (the
//!    pull of the border heights, with the unknowns at 0) is summed down
//!    the coarse levels (2×2 blocks, until at most 16 unknowns remain), the
//!    coarsest is solved exactly, and each finer level starts from the
//!    interpolation of the one below (from its unknowns only) improved by
//!    one cycle, up to the fine unknowns.
//! 3. Multigrid cycles on the error equation: red–black Gauss–Seidel
//!    smoothing (2 sweeps before and after; the two colours go as one
//!    wavefront per band of rows, in one pass over the memory), the summed
//!    residual of each 2×2 block as the coarse right-hand side, one W-cycle
//!    on the coarse levels, a Galerkin coarse operator (see `coarse`: the
//!    boundary keeps its true place on every level, so irregular voids
//!    converge as fast as rectangles), bilinear interpolation of the
//!    correction. Each cycle divides the error by about 3 (measured: 0.30 to
//!    0.36 per cycle on the half-plane void below). The coarsest level (at
//!    most 16 unknowns) is solved exactly by a dense Cholesky factorisation,
//!    and so is a component of at most 16 samples, without cycles. Levels
//!    of fewer than 32 768 cells are worked on by one thread: they are
//!    visited hundreds of times per cycle.
//! 4. Stop when the estimated remaining error (from the change of the last
//!    cycle and the observed contraction, see [`FillOptions::tolerance_m`]) is
//!    below the tolerance, or the changes are down to the heights' `f32`
//!    rounding, or after [`FillOptions::max_iterations`] cycles.
//! 5. Clamp to the component's border range (the exact solution lies in it;
//!    this only removes what is left of the iteration's overshoot) and write back.
//!
//! **The stated tolerance:** the default fill (`tolerance_m` 1 mm) is within
//! 2 mm of the exact solution of the discrete Laplace problem at every filled
//! sample (1 mm for the iteration, the rest for the `f32` heights). The test
//! `void_fill_real` checks it against an independent `f64`
//! conjugate-gradient solve (2.4e-4 m on a 301² real window with its
//! northern half void). On a 3601² tile with its northern half blanked (one
//! void of 6.5 M samples, `cota-bench --bin void-fill`) the default fill
//! takes 8 cycles and is within 6.1e-4 m of the same fill run for 25 cycles
//! (down to the `f32` rounding), and within 4e-4 m of the previous version
//! (pull–push start, two coarse W-cycles per fine cycle), at 0.4 to 0.5 of
//! its time. On the shared SRTM tile N42E001 (7652 voids in 760
//! components, the largest 1406) the default fill takes about 10 ms.
//!
//! # Inverse-distance fill
//! [`FillMethod::InverseDistance`]: each void sample is the mean of its
//! component's border samples weighted by 1/d² (d in metres). It is O(voids ×
//! border) per component; above 10⁸ pairs the border is subsampled evenly.
//! It is smooth but not continuous in slope and can form plateaus; it exists as
//! a cheap, non-iterative alternative.
//!
//! A grid whose every sample is void has nothing to fill from: [`VoidError::AllVoid`].
//!
//! The papers in `../shared/seeds/` assume void-free grids; the methods are
//! the standard ones: multigrid after Briggs, Henson & McCormick, *A
//! Multigrid Tutorial* (2nd ed., SIAM 2000), inverse distance after Shepard
//! (1968). The files: `components` (the voids' 4-connected components),
//! `fine` (the finest level, matrix-free), `coarse` (the coarse error
//! levels and the interpolation), `interp` (what the coarse levels share),
//! `bands` (parallel Gauss–Seidel over bands of rows), `dense` (the
//! coarsest solve), `harmonic` (the start and the cycles), `idw`.
//!
//! ```
//! use cota_core::{GeoRef, HeightGrid};
//! use cota_core::grid::voids::{fill_voids, FillOptions};
//! let mut g = HeightGrid::new(3, 3, vec![1.0, 2.0, 3.0, 4.0, f32::NAN, 6.0, 7.0, 8.0, 9.0],
//!                             GeoRef::unreferenced(30.0)).unwrap();
//! let report = fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
//! assert_eq!(report.filled, 1);
//! assert!((g.get(1, 1) - 5.0).abs() < 1e-3);
//! ```

mod bands;
mod coarse;
mod components;
mod dense;
mod fine;
mod harmonic;
mod idw;
mod interp;

use rayon::prelude::*;

use crate::grid::{GridError, HeightGrid};
use crate::progress::{Counter, Progress};
use components::{find_components, BoxArea, Component};
use fine::Fine;
use harmonic::{harmonic, Solved};
use idw::inverse_distance;

/// How void samples are estimated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum FillMethod {
    /// Harmonic (Laplace) interpolation from the void's border. The default.
    #[default]
    Harmonic,
    /// Inverse-distance-weighted (1/d²) mean of the void's border samples.
    InverseDistance,
}

/// What to do with voids.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum VoidPolicy {
    /// Fill them with the given method.
    Fill(FillMethod),
    /// Refuse a grid with voids: [`VoidError::Refused`] with the count and the first one.
    Refuse,
}

impl Default for VoidPolicy {
    /// `Fill(FillMethod::Harmonic)`.
    fn default() -> Self {
        VoidPolicy::Fill(FillMethod::Harmonic)
    }
}

/// Options for [`fill_voids`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct FillOptions {
    /// The policy. Default: `Fill(Harmonic)`.
    pub policy: VoidPolicy,
    /// The harmonic fill stops when its estimated remaining error is below this,
    /// metres. The estimate is 2·c·ρ/(1 − ρ) for the largest change c of the last
    /// cycle and the observed contraction ρ per cycle (taken in [0.5, 0.99]), so
    /// it is never below twice the last change. Default: 1e-3.
    pub tolerance_m: f64,
    /// Most multigrid cycles per component. Default: 200.
    pub max_iterations: usize,
}

impl FillOptions {
    /// The defaults, as documented on each field.
    pub const DEFAULT: FillOptions = FillOptions {
        policy: VoidPolicy::Fill(FillMethod::Harmonic),
        tolerance_m: 1e-3,
        max_iterations: 200,
    };

    /// Sets [`FillOptions::policy`].
    pub const fn with_policy(mut self, policy: VoidPolicy) -> Self {
        self.policy = policy;
        self
    }

    /// Sets [`FillOptions::tolerance_m`].
    pub const fn with_tolerance_m(mut self, tolerance_m: f64) -> Self {
        self.tolerance_m = tolerance_m;
        self
    }

    /// Sets [`FillOptions::max_iterations`].
    pub const fn with_max_iterations(mut self, max_iterations: usize) -> Self {
        self.max_iterations = max_iterations;
        self
    }
}

impl Default for FillOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Why voids could not be handled.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum VoidError {
    /// The policy is [`VoidPolicy::Refuse`] and the grid has voids
    /// ([`GridError::HasVoids`] with their count and the first one).
    #[error(transparent)]
    Refused(GridError),
    /// Every sample is void.
    #[error("all {width}x{height} samples are void: there is nothing to fill them from")]
    AllVoid {
        /// Grid width.
        width: usize,
        /// Grid height.
        height: usize,
    },
}

/// What [`fill_voids`] did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FillReport {
    /// Samples filled (the grid's voids before the call).
    pub filled: usize,
    /// Number of 4-connected void components.
    pub components: usize,
    /// Samples in the largest component.
    pub largest_component: usize,
    /// Most multigrid cycles needed by any component (1 for components of at
    /// most 16 samples, solved directly; 0 for the inverse-distance method).
    pub max_iterations_used: usize,
    /// Gauss–Seidel sweeps summed over every level of every component, a
    /// measure of the work.
    pub total_sweeps: usize,
    /// True when every component reached [`FillOptions::tolerance_m`] before
    /// [`FillOptions::max_iterations`].
    pub converged: bool,
    /// Largest change of a sample in the last iteration, over all components, metres.
    pub last_change_m: f64,
}

/// Fills (or refuses) the voids of `grid` in place, as `opts.policy` says. A
/// grid without voids is left untouched.
///
/// # Errors
/// [`VoidError::Refused`] under [`VoidPolicy::Refuse`] when there are voids;
/// [`VoidError::AllVoid`] when every sample is void.
///
/// # Runtime
/// Harmonic: linear in the number of voids (multigrid; a full multigrid
/// start and about eight cycles for the default tolerance). Memory: the voids' runs, one bit per sample of a
/// component's box (its mask) and about 7 bytes per box sample for the coarse
/// levels; a component whose box has at most 65 536 samples also works on a
/// copy of it (4 bytes per sample).
pub fn fill_voids(grid: &mut HeightGrid, opts: &FillOptions) -> Result<FillReport, VoidError> {
    fill_voids_with_progress(grid, opts, crate::progress::NONE)
}

/// [`fill_voids`], telling `progress(voids_filled, voids)` as each
/// component of voids is filled.
///
/// # Errors
/// As [`fill_voids`].
pub fn fill_voids_with_progress(
    grid: &mut HeightGrid,
    opts: &FillOptions,
    progress: Progress<'_>,
) -> Result<FillReport, VoidError> {
    let method = match opts.policy {
        VoidPolicy::Refuse => {
            grid.require_no_voids().map_err(VoidError::Refused)?;
            return Ok(FillReport {
                converged: true,
                ..FillReport::default()
            });
        }
        VoidPolicy::Fill(method) => method,
    };
    let voids = grid.void_count();
    if voids == 0 {
        return Ok(FillReport {
            converged: true,
            ..FillReport::default()
        });
    }
    if voids == grid.len() {
        return Err(VoidError::AllVoid {
            width: grid.width(),
            height: grid.height(),
        });
    }
    let filled = Counter::new(progress, voids);
    let components = find_components(grid);
    let (small, large): (Vec<&Component>, Vec<&Component>) = components
        .iter()
        .partition(|c| c.area(grid.width(), grid.height()).len() <= LOCAL_CELLS);
    let shared: &HeightGrid = grid;
    let solved_small: Vec<(Vec<f32>, Solved)> = small
        .par_iter()
        .map(|c| {
            let solved = solve_on_copy(shared, c, method, opts);
            filled.add(c.cells);
            solved
        })
        .collect();
    let mut report = FillReport {
        filled: voids,
        components: components.len(),
        converged: true,
        ..FillReport::default()
    };
    let width = grid.width();
    for (c, (values, s)) in small.iter().zip(solved_small) {
        report.add(c, &s);
        let heights = grid.heights_mut();
        for (i, v) in c.indices(width).zip(values) {
            heights[i] = v;
        }
    }
    for c in large {
        // Credited cycle by cycle, up to the usual count; the rest at the end.
        let credited = std::cell::Cell::new(0);
        let on_cycle = |k: usize| {
            let share = c.cells * k.min(USUAL_CYCLES) / (USUAL_CYCLES + 1);
            filled.add(share.saturating_sub(credited.replace(share)));
        };
        let s = solve_in_place(grid, c, method, opts, &on_cycle);
        report.add(c, &s);
        filled.add(c.cells - credited.get());
    }
    Ok(report)
}

/// Components whose box holds at most this many samples are solved on a
/// copy of their box, many at once; larger ones in place, one at a time,
/// each in parallel over bands of rows.
const LOCAL_CELLS: usize = 1 << 16;

/// The multigrid cycles a component usually takes (see [`fill_voids`]'s
/// runtime): what its progress is counted against.
const USUAL_CYCLES: usize = 8;

impl FillReport {
    /// Counts one solved component.
    fn add(&mut self, c: &Component, s: &Solved) {
        self.largest_component = self.largest_component.max(c.cells);
        self.max_iterations_used = self.max_iterations_used.max(s.iterations);
        self.total_sweeps += s.total_sweeps;
        self.converged &= s.converged;
        self.last_change_m = self.last_change_m.max(s.last_change_m);
    }
}

/// Fills one component on a copy of its box; returns its values in the
/// order of [`Component::indices`].
fn solve_on_copy(
    grid: &HeightGrid,
    c: &Component,
    method: FillMethod,
    opts: &FillOptions,
) -> (Vec<f32>, Solved) {
    let width = grid.width();
    let area = c.area(width, grid.height());
    let mut copy = Vec::with_capacity(area.len());
    for y in area.y0..area.y0 + area.h {
        let start = y * width + area.x0;
        copy.extend_from_slice(&grid.heights()[start..start + area.w]);
    }
    let rows: Vec<&mut [f32]> = copy.chunks_mut(area.w).collect();
    let s = solve_rows(c, &area, rows, pixel_size(grid, c), method, opts, &|_| {});
    let values = c
        .runs
        .iter()
        .flat_map(|r| {
            let base = (r.row as usize - area.y0) * area.w;
            let (x0, x1) = (r.x0 as usize - area.x0, r.x1 as usize - area.x0);
            copy[base + x0..base + x1].iter().copied()
        })
        .collect();
    (values, s)
}

/// Fills one component in place, in the grid's own rows.
fn solve_in_place(
    grid: &mut HeightGrid,
    c: &Component,
    method: FillMethod,
    opts: &FillOptions,
    on_cycle: &dyn Fn(usize),
) -> Solved {
    let (width, height) = (grid.width(), grid.height());
    let area = c.area(width, height);
    let cell = pixel_size(grid, c);
    let heights = &mut grid.heights_mut()[area.y0 * width..(area.y0 + area.h) * width];
    let rows: Vec<&mut [f32]> = heights
        .chunks_mut(width)
        .map(|r| &mut r[area.x0..area.x0 + area.w])
        .collect();
    solve_rows(c, &area, rows, cell, method, opts, on_cycle)
}

/// The solve proper: the fine level over `rows`, the method, then the clamp
/// to the border range (the exact solution lies in it; this only removes
/// what is left of the iteration's overshoot). `on_cycle(cycles)` after
/// each multigrid cycle.
fn solve_rows(
    c: &Component,
    area: &BoxArea,
    rows: Vec<&mut [f32]>,
    (dx, dy): (f64, f64),
    method: FillMethod,
    opts: &FillOptions,
    on_cycle: &dyn Fn(usize),
) -> Solved {
    let wx = (1.0 / (dx * dx)) as f32;
    let wy = (1.0 / (dy * dy)) as f32;
    let mut fine = Fine::new(rows, c.mask(area), wx, wy);
    let range = fine.border_range();
    let solved = match method {
        FillMethod::InverseDistance => {
            inverse_distance(&mut fine, dx, dy);
            Solved {
                converged: true,
                ..Solved::default()
            }
        }
        FillMethod::Harmonic => {
            harmonic(&mut fine, opts.tolerance_m, opts.max_iterations, on_cycle)
        }
    };
    fine.clamp(range);
    solved
}

/// The cell size in metres at the centre of the component's bounding box
/// (1 m where the georeference gives none).
fn pixel_size(grid: &HeightGrid, c: &Component) -> (f64, f64) {
    let centre = (
        (c.cols.0 + c.cols.1) as f64 / 2.0,
        (c.rows.0 + c.rows.1) as f64 / 2.0,
    );
    let [dx, dy] = grid.georef().pixel_size_m_at(centre.0, centre.1);
    if dx.is_finite() && dy.is_finite() && dx > 0.0 && dy > 0.0 {
        (dx, dy)
    } else {
        (1.0, 1.0)
    }
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::grid::GeoRef;

    fn grid(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> HeightGrid {
        let mut v = Vec::with_capacity(w * h);
        for r in 0..h {
            for c in 0..w {
                v.push(f(c, r));
            }
        }
        HeightGrid::new(w, h, v, GeoRef::unreferenced(30.0)).unwrap()
    }

    fn plane(c: usize, r: usize) -> f32 {
        100.0 + 0.7 * c as f32 - 1.3 * r as f32
    }

    /// Punches a void rectangle into `g`.
    fn punch(g: &mut HeightGrid, cols: std::ops::Range<usize>, rows: std::ops::Range<usize>) {
        let w = g.width();
        for r in rows {
            for c in cols.clone() {
                g.heights_mut()[r * w + c] = f32::NAN;
            }
        }
    }

    fn max_error(g: &HeightGrid, f: impl Fn(usize, usize) -> f32) -> f32 {
        let mut e = 0.0f32;
        for r in 0..g.height() {
            for c in 0..g.width() {
                e = e.max((g.get(c, r) - f(c, r)).abs());
            }
        }
        e
    }

    #[test]
    fn plane_with_a_hole_is_reproduced() {
        for (w, h, cols, rows) in [
            (64, 48, 10..50, 5..40),
            (300, 300, 20..280, 30..290),
            (40, 40, 18..19, 1..39),
            (40, 40, 3..37, 17..19),
        ] {
            let mut g = grid(w, h, plane);
            punch(&mut g, cols.clone(), rows.clone());
            let voids = g.void_count();
            let report = fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
            assert_eq!(report.filled, voids);
            assert_eq!(g.void_count(), 0);
            assert!(report.converged, "{report:?}");
            let e = max_error(&g, plane);
            assert!(
                e < 1e-3,
                "{w}x{h} hole {cols:?} x {rows:?}: error {e} m, {report:?}"
            );
        }
    }

    #[test]
    fn round_hole_in_a_harmonic_quadratic_is_reproduced() {
        // x² − y² is exactly harmonic for the 5-point stencil, and a round hole
        // gives the multigrid levels an irregular boundary.
        let f = |c: usize, r: usize| {
            let (x, y) = (c as f32 - 90.0, r as f32 - 110.0);
            (x * x - y * y) / 50.0 + 300.0
        };
        let mut g = grid(200, 220, f);
        let w = g.width();
        for r in 0..220 {
            for c in 0..200 {
                let (x, y) = (c as f32 - 100.0, r as f32 - 105.0);
                if x * x + y * y < 85.0 * 85.0 {
                    g.heights_mut()[r * w + c] = f32::NAN;
                }
            }
        }
        let report = fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
        assert!(report.filled > 20_000 && report.converged, "{report:?}");
        assert!(report.max_iterations_used <= 10, "{report:?}");
        let e = max_error(&g, f);
        assert!(e < 1e-3, "error {e} m, {report:?}");
    }

    #[test]
    fn iteration_cap_is_reported() {
        let mut g = grid(100, 100, plane);
        punch(&mut g, 5..95, 5..95);
        let opts = FillOptions::DEFAULT.with_max_iterations(1);
        let report = fill_voids(&mut g, &opts).unwrap();
        assert!(!report.converged);
        assert_eq!(report.max_iterations_used, 1);
        assert_eq!(g.void_count(), 0, "even an unconverged fill leaves no void");
    }

    #[test]
    fn anisotropic_cells_still_reproduce_a_plane() {
        let mut g = grid(80, 60, plane);
        let mut geo = GeoRef::unreferenced(1.0);
        geo.pixel_x = 20.0;
        geo.pixel_y = -35.0;
        g.set_georef(geo);
        punch(&mut g, 5..70, 10..50);
        fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
        assert!(max_error(&g, plane) < 1e-3);
    }

    #[test]
    fn single_void_is_the_mean_of_its_neighbours() {
        let mut g = grid(5, 5, |c, r| (c * 10 + r) as f32);
        g.heights_mut()[2 * 5 + 2] = f32::NAN;
        g.heights_mut()[2 * 5 + 1] = 0.0;
        let report = fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
        assert_eq!(
            (report.filled, report.components, report.largest_component),
            (1, 1, 1)
        );
        // Neighbours: west 0, east 32, north 21, south 23.
        assert!((g.get(2, 2) - 19.0).abs() < 1e-4, "{}", g.get(2, 2));
    }

    #[test]
    fn voids_on_the_edge_and_corner_have_fewer_neighbours() {
        // A plane in x only is harmonic with zero slope across the bottom edge.
        let f = |c: usize, _r: usize| 5.0 * c as f32;
        let mut g = grid(30, 20, f);
        punch(&mut g, 10..20, 12..20); // touches the south edge
        punch(&mut g, 5..25, 0..4); // touches the north edge
        let report = fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
        assert_eq!(report.components, 2);
        assert_eq!(g.void_count(), 0);
        assert!(max_error(&g, f) < 1e-3, "{}", max_error(&g, f));

        // A corner void of a constant surface is that constant.
        let mut g = grid(4, 4, |_, _| 7.0);
        punch(&mut g, 3..4, 3..4);
        fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
        assert_eq!(g.get(3, 3), 7.0);
    }

    #[test]
    fn whole_grid_void_is_an_error() {
        let mut g = grid(4, 3, |_, _| f32::NAN);
        let err = fill_voids(&mut g, &FillOptions::DEFAULT).unwrap_err();
        assert_eq!(
            err,
            VoidError::AllVoid {
                width: 4,
                height: 3
            }
        );
    }

    #[test]
    fn refuse_reports_count_and_first_void() {
        let mut g = grid(6, 6, plane);
        punch(&mut g, 2..4, 3..5);
        let opts = FillOptions::DEFAULT.with_policy(VoidPolicy::Refuse);
        let err = fill_voids(&mut g, &opts).unwrap_err();
        assert_eq!(
            err,
            VoidError::Refused(GridError::HasVoids {
                count: 4,
                col: 2,
                row: 3
            })
        );
        assert!(err.to_string().contains("4 void samples"), "{err}");
        assert_eq!(g.void_count(), 4, "refusing leaves the grid alone");
        let mut clean = grid(3, 3, plane);
        assert!(fill_voids(&mut clean, &opts).is_ok());
    }

    #[test]
    fn fill_obeys_the_maximum_principle() {
        // A bumpy surface with a ring-shaped void around an island.
        let f = |c: usize, r: usize| {
            ((c as f32 * 0.3).sin() * 50.0 + (r as f32 * 0.2).cos() * 30.0) + 200.0
        };
        let mut g = grid(120, 100, f);
        punch(&mut g, 10..110, 10..90);
        let w = g.width();
        for r in 40..60 {
            for c in 40..80 {
                g.heights_mut()[r * w + c] = f(c, r) + 500.0; // a high island inside
            }
        }
        let before = g.clone();
        let report = fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
        assert_eq!(report.components, 1);
        let (lo, hi) = border_range(&before);
        for r in 0..g.height() {
            for c in 0..w {
                if before.get(c, r).is_nan() {
                    let v = g.get(c, r);
                    assert!(v >= lo && v <= hi, "({c},{r}) {v} outside [{lo},{hi}]");
                }
            }
        }
    }

    /// Range of the valid samples 4-adjacent to a void.
    fn border_range(g: &HeightGrid) -> (f32, f32) {
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for r in 0..g.height() {
            for c in 0..g.width() {
                let v = g.get(c, r);
                if v.is_nan() {
                    continue;
                }
                let nb = [
                    (c.wrapping_sub(1), r),
                    (c + 1, r),
                    (c, r.wrapping_sub(1)),
                    (c, r + 1),
                ];
                if nb
                    .iter()
                    .any(|&(x, y)| x < g.width() && y < g.height() && g.get(x, y).is_nan())
                {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
        }
        (lo, hi)
    }

    #[test]
    fn inverse_distance_fills_within_the_border_range() {
        let mut g = grid(50, 40, plane);
        punch(&mut g, 10..30, 5..25);
        let before = g.clone();
        let opts = FillOptions::DEFAULT.with_policy(VoidPolicy::Fill(FillMethod::InverseDistance));
        let report = fill_voids(&mut g, &opts).unwrap();
        assert_eq!(report.filled, 400);
        assert_eq!(g.void_count(), 0);
        let (lo, hi) = border_range(&before);
        assert!(g
            .heights()
            .iter()
            .zip(before.heights())
            .all(|(v, b)| !b.is_nan() || (*v >= lo && *v <= hi)));
        // A single void between equal neighbours.
        let mut g = grid(3, 3, |_, _| 4.0);
        g.heights_mut()[4] = f32::NAN;
        fill_voids(&mut g, &opts).unwrap();
        assert_eq!(g.get(1, 1), 4.0);
    }

    #[test]
    fn no_voids_is_a_no_op() {
        let mut g = grid(5, 5, plane);
        let before = g.clone();
        let report = fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
        assert_eq!(report.filled, 0);
        assert_eq!(g, before);
    }
}
