//! The pyramid's plan: which tiles exist at each zoom, their error bound, and
//! the margin that quantization may cost.
//!
//! Reference: the quantized-mesh-1.0 specification (CesiumGS/quantized-mesh):
//! `u`, `v` and heights are integers in `0..=32767` across the tile and its
//! height range. A tile at zoom `z` spans `T_z` lattice cells, so a vertex
//! moves by at most `δ = T_z / (2·32767)` cells along each axis and its
//! height by at most half a height step `Δh / (2·32767)`.
//!
//! # The margin
//! Let `S` be a tile's mesh on the lattice (vertices on samples) and `Ŝ` the
//! decoded one. At a lattice sample `p` in decoded triangle `t̂` (the image of
//! `t`, vertices `P_i + δ_i`, heights `z_i + η_i`), with `λ` the barycentric
//! weights of `p` in `t̂` and `q = Σ λ_i P_i ∈ t`:
//! `Ŝ(p) − S(p) = Σ λ_i η_i + S(q) − S(p)`, since the plane of `t` takes
//! `Σ λ_i z_i` at `q`. Every plane of the hierarchy has `|∂h/∂col|` and
//! `|∂h/∂row|` at most `G = max|Δ_col h| + max|Δ_row h|` over the lattice (its
//! legs are axis-aligned or diagonal, and a leg's slope is a mean of the
//! lattice's steps), and `|q − p| ≤ δ` on each axis, so
//! `|Ŝ(p) − S(p)| ≤ Δh/(2·32767) + 2·G·δ`. Extracting at
//! `e_z − margin_z`, with `margin_z` that bound (plus rounding slack), keeps
//! the decoded tile within `e_z` at every sample; the checker then verifies
//! it on the decoded tile itself. The margin is the same for every tile of a
//! zoom, so that neighbours decide their shared border alike.

use rayon::prelude::*;

use super::drawn::{level_stats, LevelStats};
use super::error::TilesError;
use super::lattice::{Lattice, LatticeFrame};
use super::scheme::{ErrorSchedule, GeographicScheme, TileId};
use super::QUANTIZED_MAX;

/// Options for [`super::Prepared::new`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct TilerOptions {
    /// The coarsest zoom made. Default: 0 (the two root tiles).
    pub min_zoom: u8,
    /// The error bound per zoom. Default: [`ErrorSchedule::DEFAULT`].
    pub error: ErrorSchedule,
}

impl TilerOptions {
    /// The defaults, as documented on each field.
    pub const DEFAULT: TilerOptions = TilerOptions {
        min_zoom: 0,
        error: ErrorSchedule::DEFAULT,
    };

    /// Sets [`TilerOptions::min_zoom`].
    pub const fn with_min_zoom(mut self, z: u8) -> Self {
        self.min_zoom = z;
        self
    }

    /// Sets [`TilerOptions::error`].
    pub const fn with_error(mut self, e: ErrorSchedule) -> Self {
        self.error = e;
        self
    }
}

impl Default for TilerOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The tiles of one zoom: columns `x0..=x1`, TMS rows `y0..=y1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TileRange {
    /// First column.
    pub x0: u32,
    /// Last column.
    pub x1: u32,
    /// First row (south).
    pub y0: u32,
    /// Last row (north).
    pub y1: u32,
}

impl TileRange {
    /// Number of tiles.
    pub fn count(&self) -> u64 {
        u64::from(self.x1 - self.x0 + 1) * u64::from(self.y1 - self.y0 + 1)
    }

    /// True when `(x, y)` is in the range.
    pub fn contains(&self, x: u32, y: u32) -> bool {
        (self.x0..=self.x1).contains(&x) && (self.y0..=self.y1).contains(&y)
    }
}

/// One zoom of the pyramid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ZoomPlan {
    /// The zoom.
    pub zoom: u8,
    /// The tiles made at this zoom: those that meet the data.
    pub range: TileRange,
    /// The tiles that meet the lattice window's interior (the shard plan
    /// splits these, so that shards' parts cover the window).
    pub window_range: TileRange,
    /// The bound every tile meets after quantization, metres.
    pub max_error_m: f64,
    /// What quantization may cost (see the module docs), metres.
    pub margin_m: f64,
    /// The extraction threshold `max_error_m − margin_m`, metres.
    pub threshold_m: f64,
}

/// The tiles at zoom `z` whose square meets the data's `footprint` with a
/// positive area (its interior: a tile that only touches the footprint's
/// edge holds no data), and both root tiles at zoom 0, which CesiumJS needs
/// to draw the globe at all (`GlobeSurfaceTile`'s `upsample`: a root tile
/// that fails has no parent to stand in for it).
pub fn range_at(s: &GeographicScheme, footprint: [f64; 4], z: u8) -> TileRange {
    if z == 0 {
        return TileRange {
            x0: 0,
            x1: 1,
            y0: 0,
            y1: 0,
        };
    }
    let t = s.cells_at(z) as f64;
    let [nx, ny] = GeographicScheme::tiles_at(z);
    let [w, n, e, so] = footprint;
    let first = |v: f64, count: u32| ((v / t).floor().max(0.0) as u32).min(count - 1);
    let last = |v: f64, count: u32| (((v / t).ceil() as u32).max(1) - 1).min(count - 1);
    let (c0, c1) = (first(w, nx), last(e, nx).max(first(w, nx)));
    let (r0, r1) = (first(n, ny), last(so, ny).max(first(n, ny)));
    TileRange {
        x0: c0,
        x1: c1,
        y0: ny - 1 - r1,
        y1: ny - 1 - r0,
    }
}

/// The tiles at zoom `z` that meet the window's interior (both root tiles
/// at zoom 0).
pub fn window_range_at(s: &GeographicScheme, window: [u64; 4], z: u8) -> TileRange {
    let [x0, y0, x1, y1] = window;
    let grow = |v: u64| v as f64;
    range_at(s, [grow(x0), grow(y0), grow(x1), grow(y1)], z)
}

/// `G` of the module docs: the largest height step along a row plus the
/// largest along a column, metres per lattice cell (0 m beyond the window
/// and on its border, so no step crosses it).
pub fn max_step_m(lattice: &Lattice) -> f64 {
    let [gx, gy] = max_steps_m(lattice);
    gx + gy
}

/// The largest height step along a row and the largest along a column of
/// `lattice`'s stored heights, metres per lattice cell.
fn max_steps_m(lattice: &Lattice) -> [f64; 2] {
    let g = lattice.grid();
    let (w, h) = (g.width(), g.height());
    let hs = g.heights();
    let (gx, gy) = (0..h)
        .into_par_iter()
        .map(|r| {
            let row = &hs[r * w..(r + 1) * w];
            let gx = row
                .windows(2)
                .map(|p| (p[1] as f64 - p[0] as f64).abs())
                .fold(0.0, f64::max);
            let gy = if r + 1 < h {
                let next = &hs[(r + 1) * w..(r + 2) * w];
                row.iter()
                    .zip(next)
                    .map(|(a, b)| (*b as f64 - *a as f64).abs())
                    .fold(0.0, f64::max)
            } else {
                0.0
            };
            (gx, gy)
        })
        .reduce(|| (0.0, 0.0), |a, b| (a.0.max(b.0), a.1.max(b.1)));
    [gx, gy]
}

/// What the plan needs of the whole lattice: its height range and `G` (see
/// [`PartStats`] for reducing them from parts), and what the drawn bound
/// needs ([`super::drawn`]): the planes' slopes and spreads per level, and
/// the fitted lattice's residual at the source's samples.
#[derive(Debug, Clone, PartialEq)]
pub struct LatticeStats {
    /// The lowest height, metres (0 for an empty lattice).
    pub lo_m: f32,
    /// The highest height, metres (0 for an empty lattice).
    pub hi_m: f32,
    /// `G` of the module docs ([`max_step_m`]), metres per cell.
    pub max_step_m: f64,
    /// Per level, the steepest plane and largest vertex spread.
    pub levels: LevelStats,
    /// The largest |lattice − source| at the source's samples, metres.
    pub residual_m: f64,
}

impl LatticeStats {
    /// The statistics of `lattice`'s stored heights (the whole window): every
    /// level of the window's squares and of the coarse levels above it.
    pub fn of(lattice: &Lattice) -> LatticeStats {
        let top = lattice.scheme().cells_at(lattice.align_zoom());
        let mut part = PartStats::of(lattice, top);
        part.levels = part
            .levels
            .merge(&coarse_level_stats(lattice, 2 * top, &|x, y| {
                lattice.height_at(x, y)
            }));
        part.stats()
    }
}

/// The level statistics of the squares of side `from` and larger over the
/// window of `lattice`'s frame (the window's squares up to the alignment
/// zoom's, then the coarse levels' squares within two squares of the
/// window), heights from `height` (0 m beyond the window).
pub fn coarse_level_stats(
    lattice: &Lattice,
    from: u64,
    height: &(impl Fn(u64, u64) -> f32 + Sync),
) -> LevelStats {
    let f = lattice.frame();
    coarse_level_stats_in(&f.scheme, f.window, f.align_zoom, from, height)
}

/// [`coarse_level_stats`] of a frame given by its parts.
pub fn coarse_level_stats_in(
    scheme: &GeographicScheme,
    window: [u64; 4],
    align_zoom: u8,
    from: u64,
    height: &(impl Fn(u64, u64) -> f32 + Sync),
) -> LevelStats {
    let top = scheme.cells_at(align_zoom);
    let mut out = level_stats(scheme, window, [from, top], height);
    let mut size = (2 * top).max(from);
    while size <= scheme.root_cells() {
        let [x0, y0, x1, y1] = window;
        let (w, h) = (2 * scheme.root_cells(), scheme.root_cells());
        let grown = [
            (x0 / size).saturating_sub(2) * size,
            (y0 / size).saturating_sub(2) * size,
            ((x1 / size + 3) * size).min(w),
            ((y1 / size + 3) * size).min(h),
        ];
        out = out.merge(&level_stats(scheme, grown, [size, size], height));
        size *= 2;
    }
    out
}

/// [`LatticeStats`] of a part of the lattice, in a form that merges: the
/// height range and the largest step along rows and along columns apart
/// (`G` is their sum, so the sum of one part's two maxima would not merge).
/// Parts whose regions cover the window, and every pair of neighbouring
/// samples within one of them (regions that overlap by a sample do), merge
/// into the whole lattice's statistics bit for bit: each is a minimum or a
/// maximum of the same values.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PartStats {
    /// The lowest and highest height, metres; `None` when no sample was seen.
    pub range_m: Option<(f32, f32)>,
    /// The largest height step along a row and along a column, metres per
    /// cell.
    pub step_m: [f64; 2],
    /// The level statistics of the squares of side up to the part's limit
    /// that lie in its stored region.
    pub levels: LevelStats,
    /// The largest |lattice − source| at the source samples inside it, metres.
    pub residual_m: f64,
}

impl PartStats {
    /// The statistics of `lattice`'s stored heights (a part's or the
    /// window's), the level statistics over its squares of side up to
    /// `max_square` cells.
    pub fn of(lattice: &Lattice, max_square: u64) -> PartStats {
        let levels = level_stats(
            lattice.scheme(),
            lattice.stored(),
            [2, max_square],
            &|x, y| lattice.height_at(x, y),
        );
        PartStats {
            range_m: lattice.grid().valid_range(),
            step_m: max_steps_m(lattice),
            levels,
            residual_m: lattice.residual_m(),
        }
    }

    /// The statistics of both parts together.
    pub fn merge(self, other: PartStats) -> PartStats {
        let range_m = match (self.range_m, other.range_m) {
            (Some(a), Some(b)) => Some((a.0.min(b.0), a.1.max(b.1))),
            (a, b) => a.or(b),
        };
        PartStats {
            range_m,
            step_m: [
                self.step_m[0].max(other.step_m[0]),
                self.step_m[1].max(other.step_m[1]),
            ],
            levels: self.levels.merge(&other.levels),
            residual_m: self.residual_m.max(other.residual_m),
        }
    }

    /// The statistics the plan uses.
    pub fn stats(&self) -> LatticeStats {
        let (lo_m, hi_m) = self.range_m.unwrap_or((0.0, 0.0));
        LatticeStats {
            lo_m,
            hi_m,
            max_step_m: self.step_m[0] + self.step_m[1],
            levels: self.levels.clone(),
            residual_m: self.residual_m,
        }
    }
}

/// The plan of every zoom from `opts.min_zoom` to the lattice's maximum
/// (the lattice holds its whole window).
pub fn plan(lattice: &Lattice, opts: &TilerOptions) -> Result<Vec<ZoomPlan>, TilesError> {
    plan_with(lattice.frame(), &LatticeStats::of(lattice), opts)
}

/// The plan of every zoom from `opts.min_zoom` to the scheme's maximum, for
/// a lattice of `frame` whose statistics are `stats`.
pub fn plan_with(
    frame: &LatticeFrame,
    stats: &LatticeStats,
    opts: &TilerOptions,
) -> Result<Vec<ZoomPlan>, TilesError> {
    let s = frame.scheme;
    if opts.min_zoom > s.max_zoom {
        return Err(TilesError::BadOptions(format!(
            "expected a minimum zoom of at most the maximum zoom {}, found {}",
            s.max_zoom, opts.min_zoom
        )));
    }
    if !opts.error.is_valid() {
        return Err(TilesError::BadOptions(match opts.error {
            ErrorSchedule::Cesium { factor } => {
                format!("expected a positive, finite error factor, found {factor}")
            }
            ErrorSchedule::AtMaxZoom { max_error_m } => format!(
                "expected a positive, finite error bound at the maximum zoom, found {max_error_m} m"
            ),
        }));
    }
    let (lo, hi) = (stats.lo_m, stats.hi_m);
    let range_m = f64::from(hi.max(0.0)) - f64::from(lo.min(0.0));
    let q = f64::from(QUANTIZED_MAX);
    let step = stats.max_step_m;
    let slack = 1e-6 * f64::from(hi.abs().max(lo.abs())).max(1.0);
    (opts.min_zoom..=s.max_zoom)
        .map(|z| {
            let max_error_m = opts.error.max_error_m(z, s.max_zoom);
            let delta = s.cells_at(z) as f64 / (2.0 * q);
            let margin_m = range_m / (2.0 * q) + 2.0 * step * delta + slack;
            if margin_m >= max_error_m {
                return Err(TilesError::BelowQuantization {
                    zoom: z,
                    max_error_m,
                    margin_m,
                });
            }
            Ok(ZoomPlan {
                zoom: z,
                range: range_at(&s, frame.footprint, z),
                window_range: window_range_at(&s, frame.window, z),
                max_error_m,
                margin_m,
                threshold_m: max_error_m - margin_m,
            })
        })
        .collect()
}

/// The children of `t` at zoom `t.z + 1` that the plan makes, as a range
/// (`None` when there are none).
pub fn children_in(t: TileId, next: Option<&ZoomPlan>) -> Option<TileRange> {
    let r = next?.range;
    let c = TileRange {
        x0: (2 * t.x).max(r.x0),
        x1: (2 * t.x + 1).min(r.x1),
        y0: (2 * t.y).max(r.y0),
        y1: (2 * t.y + 1).min(r.y1),
    };
    (c.x0 <= c.x1 && c.y0 <= c.y1).then_some(c)
}
