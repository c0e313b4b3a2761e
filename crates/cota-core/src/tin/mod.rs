//! # TIN: irregular triangulations with a guaranteed maximum error
//!
//! [`build`] makes a triangulated irregular network over a grid: vertices on
//! grid samples (with their true heights), triangles of any shape, no
//! T-junction, covering the grid exactly, and a true vertical error of at
//! most `E` at **every** sample, like the bitree's meshes but with fewer
//! triangles. A minimum-vertex TIN for a given error is NP-hard (Agarwal &
//! Suri 1998, "Surface approximation and geometric partitions"), so this is
//! a heuristic, as greedy insertion is (Garland & Heckbert 1995, "Fast
//! polygonal approximation of terrains and height fields"; the Delatin of
//! hmm, pydelatin and the `delatin` crate).
//!
//! ## The algorithm: exact-checked decimation of the bitree mesh
//! 1. **Seed**: the conforming bitree mesh at `E` ([`crate::Bitree::extract`],
//!    papers `000_ebf7e3a88dffd361.txt` and `001_49f2c365e8c41172.txt`): already
//!    within `E` everywhere, built in `O(n log n)` and extracted in time
//!    proportional to its size.
//! 2. **Locked border** (option, `tin/border.rs`): the border re-meshed from the
//!    border samples alone, so adjacent tiles share their border vertices.
//! 3. **Decimation** (`tin/decimate.rs`): vertices are removed, and their star
//!    re-triangulated by the best valid fan from a link vertex, while every
//!    sample of the star stays within `E`, checked exactly over every sample
//!    of every new triangle (vertex decimation, Schroeder, Zarge & Lorensen
//!    1992, "Decimation of triangle meshes"; the drop heuristic of Lee 1991,
//!    "Comparison of existing methods for building triangular irregular
//!    network models of terrain from grid digital elevation models").
//! 4. **In parallel** (`tin/bands.rs`): bands of rows decimated independently with
//!    their borders locked, merged, then relaxed across the band borders.
//!
//! Every accepted change is verified against every sample it affects
//! (`tin/span.rs`: exact integer spans, closed triangles, so samples on shared
//! edges are checked on both sides), so the bound holds by construction;
//! [`crate::check_mesh`] with [`crate::CheckOptions::tin`] proves it again.
//! The optional flip pass ([`TinOptions::flips`]) is the data-dependent
//! triangulation of Dyn, Levin & Rippa (1990, "Data dependent
//! triangulations for piecewise linear interpolation") with the largest exact
//! error as the cost.
//!
//! ## The routes tried, measured
//! Issue 21 lists three routes: exact-checked decimation of the bitree mesh,
//! data-dependent diagonal flips, greedy insertion seeded from a coarse
//! bitree mesh. Decimation alone already leaves 0.48–0.92× the triangles of
//! greedy Delaunay insertion (Delatin) at the same true error on the
//! benchmark grids (`bench/README.md`), so the others were measured against
//! it. Fuji 513², one thread, triangles and CPU milliseconds at 5 m / 20 m
//! (a loaded machine: ratios within one column are what count):
//!
//! | variant | 5 m | 20 m |
//! |---|---:|---:|
//! | 1 sweep, first fitting fan (**default**) | 82,225 / 69 | 12,597 / 22 |
//! | 2 sweeps | 75,942 / 87 | 11,481 / 24 |
//! | sweeps until none removes anything | 75,480 / 97 | 11,403 / 29 |
//! | 1 sweep, then flips ([`TinOptions::flips`]) and a sweep of their vertices | 77,145 / 114 | 11,585 / 29 |
//! | sweeps until none, then flips and a sweep | 74,152 / 167 | 11,199 / 48 |
//! | priority queue, smallest resulting error first, best fan | 77,270 / ≈ 3.5× | 11,535 / ≈ 3× |
//! | seed at 1.5 E repaired by greedy insertion, then 1 sweep | 84,756 / more | 13,514 / more |
//!
//! The first sweep does most of the work (at 5 m it removes 54,314 of the
//! 57,713 vertices the sweeps until none remove, in two thirds of their
//! assessments), so the default is one sweep; [`TinOptions::sweeps`] and
//! [`TinOptions::flips`] buy the last few percent. Greedy insertion needs a
//! full scan of each new triangle, and seeding it from a coarser bitree mesh
//! left more triangles after decimation than seeding decimation with the
//! bitree mesh at `E` itself, which is already exact.
//!
//! ## Budget
//! With [`TinOptions::max_triangles`], the bound is found by bisection: the
//! bitree's own budget threshold gives a mesh within the budget (decimation
//! only removes), and 14 halvings of `[0, that]` find the smallest bound
//! whose TIN fits (the count is not strictly monotone in the bound, so this
//! is the smallest bound found, not necessarily the smallest possible).

pub(crate) mod bands;
pub(crate) mod border;
pub(crate) mod decimate;
pub(crate) mod exact;
pub(crate) mod span;
pub(crate) mod topo;

use crate::bitree::{Bitree, ExtractOptions, Extraction};
use crate::error::MeshError;
use crate::grid::HeightGrid;
use crate::mesh::Mesh;

/// Options for [`build`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct TinOptions {
    /// Maximum vertical error in metres at every grid sample. Ignored when
    /// [`TinOptions::max_triangles`] is set. Default: 1 m.
    pub max_error_m: f64,
    /// A triangle budget: the mesh with the smallest bound found (by
    /// bisection) that has at most this many triangles. Default: `None`.
    pub max_triangles: Option<usize>,
    /// Keep the border as simplified from the border samples alone (a
    /// vertical Douglas–Peucker at the bound on each side, see `tin/border.rs`):
    /// the border vertices then depend only on the border's samples and the
    /// bound, so tiles that share a side, meshed at the same bound, share
    /// their vertices there exactly. Default: false (border vertices are
    /// removed like any other where the bound allows).
    pub lock_border: bool,
    /// Bands of rows decimated in parallel; 0 picks one band per 4096 seed
    /// vertices, at most 32, whatever the thread count, so that the mesh is
    /// the same on any number of threads. Default: 0.
    pub bands: usize,
    /// Sweeps of the decimation over the vertices: the first visits every
    /// vertex, each later one only those whose star changed since they were
    /// last visited; 0 sweeps until one removes nothing. More sweeps remove
    /// a few percent more vertices for about a third more time each (see the
    /// module docs). Default: 1.
    pub sweeps: u32,
    /// After the sweeps, flip every interior edge whose flip lowers the
    /// larger exact error of its two triangles (data-dependent
    /// triangulation), then sweep once more over the flipped edges' vertices:
    /// a few percent fewer triangles for about half as much time again (see
    /// the module docs). Default: false.
    pub flips: bool,
}

impl TinOptions {
    /// The defaults: 1 m, no budget, free border, automatic bands.
    pub const DEFAULT: TinOptions = TinOptions {
        max_error_m: 1.0,
        max_triangles: None,
        lock_border: false,
        bands: 0,
        sweeps: 1,
        flips: false,
    };

    /// A TIN within `e` metres.
    pub const fn max_error_m(e: f64) -> Self {
        TinOptions {
            max_error_m: e,
            ..Self::DEFAULT
        }
    }

    /// A TIN of at most `n` triangles.
    pub const fn max_triangles(n: usize) -> Self {
        TinOptions {
            max_triangles: Some(n),
            ..Self::DEFAULT
        }
    }

    /// Sets [`TinOptions::lock_border`].
    pub const fn with_lock_border(mut self, yes: bool) -> Self {
        self.lock_border = yes;
        self
    }

    /// Sets [`TinOptions::sweeps`].
    pub const fn with_sweeps(mut self, sweeps: u32) -> Self {
        self.sweeps = sweeps;
        self
    }

    /// Sets [`TinOptions::flips`].
    pub const fn with_flips(mut self, yes: bool) -> Self {
        self.flips = yes;
        self
    }

    /// Sets [`TinOptions::bands`].
    pub const fn with_bands(mut self, bands: usize) -> Self {
        self.bands = bands;
        self
    }
}

impl Default for TinOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Builds a TIN of `grid` (no voids): the bitree, then [`build_from`].
///
/// # Errors
/// As [`Bitree::build`]; [`MeshError::BadMaxError`] for a negative or NaN
/// bound; [`MeshError::BudgetTooSmall`] for a budget no TIN meets.
///
/// # Runtime
/// The bitree's build, plus time proportional to the seed mesh (each
/// removal scans its star once per fan tried), on all cores.
pub fn build(grid: &HeightGrid, opts: &TinOptions) -> Result<Extraction, MeshError> {
    crate::par::on_pool(|| build_from(&Bitree::build(grid)?, opts))
}

/// Builds a TIN from a prepared bitree (see the module docs). The result's
/// `threshold_m` is the bound the mesh meets at every sample.
///
/// ```
/// use cota_core::{tin, check_mesh, CheckOptions, GeoRef, HeightGrid};
/// let (w, h) = (40, 30);
/// let heights: Vec<f32> = (0..w * h)
///     .map(|i| {
///         let (x, y) = ((i % w) as f32, (i / w) as f32);
///         100.0 + 20.0 * (x * 0.3).sin() * (y * 0.2).cos()
///     })
///     .collect();
/// let grid = HeightGrid::new(w, h, heights, GeoRef::unreferenced(30.0)).unwrap();
/// let t = tin::build(&grid, &tin::TinOptions::max_error_m(2.0)).unwrap();
/// check_mesh(&grid, &t.mesh, &CheckOptions::tin(2.0)).unwrap();
/// ```
///
/// # Errors
/// As [`build`].
pub fn build_from(tree: &Bitree<'_>, opts: &TinOptions) -> Result<Extraction, MeshError> {
    crate::par::on_pool(|| match opts.max_triangles {
        Some(n) => for_budget(tree, n, opts),
        None => {
            let e = opts.max_error_m;
            if e.is_nan() || e < 0.0 {
                return Err(MeshError::BadMaxError(e));
            }
            Ok(Extraction {
                mesh: tin_at(tree, e, opts)?,
                threshold_m: e,
            })
        }
    })
}

/// The TIN at bound `e`.
fn tin_at(tree: &Bitree<'_>, e: f64, opts: &TinOptions) -> Result<Mesh, MeshError> {
    let grid = tree.grid();
    let seed = tree.extract(&ExtractOptions::max_error_m(e))?.mesh;
    let size = [grid.width() as i32, grid.height() as i32];
    let seed = if opts.lock_border {
        let b = border::Border::new(grid, e);
        border::reborder(&seed, grid, &b, e)
    } else {
        seed
    };
    let seed = bands::row_major(seed, grid.width());
    let on_border = |v: &crate::mesh::MeshVertex| {
        v.col == 0 || v.row == 0 || v.col as i32 == size[0] - 1 || v.row as i32 == size[1] - 1
    };
    let locked: Vec<bool> = seed
        .vertices
        .iter()
        .map(|v| opts.lock_border && on_border(v))
        .collect();
    let k = match opts.bands {
        0 => (seed.vertices.len() / 4096).min(32),
        k => k,
    };
    let hs = span::Heights::of(grid);
    let params = decimate::Params {
        bound: e,
        size,
        sweeps: opts.sweeps,
        flips: opts.flips,
    };
    Ok(bands::decimate_in_bands(
        &seed,
        &hs,
        &params,
        &locked,
        k.max(1),
    ))
}

/// Budget mode: bisection on the bound (see the module docs).
fn for_budget(tree: &Bitree<'_>, n: usize, opts: &TinOptions) -> Result<Extraction, MeshError> {
    let grid = tree.grid();
    let too_small = |min: usize| MeshError::BudgetTooSmall {
        got: n,
        min,
        width: grid.width(),
        height: grid.height(),
    };
    if n < 2 {
        return Err(too_small(2));
    }
    // Any triangle is within the height range of every sample it covers.
    let range = grid
        .valid_range()
        .map_or(0.0, |(lo, hi)| (hi as f64 - lo as f64).max(0.0));
    let hi = match tree.extract(&ExtractOptions::max_triangles(n)) {
        Ok(x) => x.threshold_m.min(range),
        Err(MeshError::BudgetTooSmall { .. }) => range,
        Err(e) => return Err(e),
    };
    let mut best = (hi, tin_at(tree, hi, opts)?);
    if best.1.triangle_count() > n && hi < range {
        // A locked border can add vertices to the bitree's mesh.
        best = (range, tin_at(tree, range, opts)?);
    }
    if best.1.triangle_count() > n {
        // One sweep can leave a vertex whose star was not yet removable when
        // it was visited; at the loosest bound, sweep until none is removed.
        let stable = opts.with_sweeps(0);
        best = (range, tin_at(tree, range, &stable)?);
    }
    if best.1.triangle_count() > n {
        return Err(too_small(best.1.triangle_count()));
    }
    let mut lo = 0.0;
    for _ in 0..14 {
        let mid = 0.5 * (lo + best.0);
        let mesh = tin_at(tree, mid, opts)?;
        if mesh.triangle_count() <= n {
            best = (mid, mesh);
        } else {
            lo = mid;
        }
    }
    Ok(Extraction {
        mesh: best.1,
        threshold_m: best.0,
    })
}
