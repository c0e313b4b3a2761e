//! Exact approximation metrics of a mesh against its grid, over every sample.
//!
//! Paper `001_49f2c365e8c41172.txt` measures quality by the sum of squared height
//! differences between the approximation and the original grid; paper
//! `002_9d6c1367b8962b6c.txt` by the volume enclosed between them and by RMSE.
//! cota reports all of them, exactly:
//! * every sample is visited once, in the first triangle (in mesh order) that
//!   contains it; on a shared edge both triangles interpolate the same two
//!   endpoints, so the choice does not matter;
//! * in parallel and deterministically: the grid is cut into bands of
//!   [`BAND_ROWS`] rows (a fixed size, whatever the number of threads); each
//!   band walks the triangles in mesh order (skipping runs of triangles whose
//!   rows miss it) and sums its samples in `f64`; the bands' maxima and sums
//!   are combined in row order, so the figures are the same on any number of
//!   threads (the sums' rounding is that of this fixed order);
//! * `volume_m3` is `∫ |mesh − grid| dA` by the trapezoidal rule on the sample
//!   lattice: each sample stands for its share of the cells around it
//!   (`dx·dy`, halved on a border, quartered at a corner), with the cell size
//!   in metres from [`HeightGrid::cell_size_m`].
//!
//! Samples not covered by any triangle are counted in `uncovered` and left out of
//! the sums (a mesh from cota covers all of them; the checker insists on it).
//!
//! Also: paper `004_ab8d08b3e6a5a70a.txt`'s distortion `D(M)`
//! ([`distortion_m2`]) and a per-sample weighted volume
//! ([`weighted_volume_m3`], paper 002's illumination-weighted volume error).

use rayon::prelude::*;

use super::raster::{for_each_span, for_each_span_in, Plane};
use super::Mesh;
use crate::grid::HeightGrid;
use crate::hierarchy::Pt;
use crate::progress::{Counter, Progress};

/// Exact error statistics of a mesh over the grid's samples.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Metrics {
    /// Largest |Δz| over all samples, metres.
    pub max_error_m: f64,
    /// Column and row of a sample where `max_error_m` is reached.
    pub max_error_at: [u32; 2],
    /// Root mean square of Δz, metres.
    pub rmse_m: f64,
    /// Mean |Δz|, metres.
    pub mean_abs_error_m: f64,
    /// Sum of squared Δz over the samples, m² (paper 001's quality figure).
    pub sse_m2: f64,
    /// Volume between the mesh and the grid's surface, m³ (trapezoidal rule).
    pub volume_m3: f64,
    /// Samples visited.
    pub samples: usize,
    /// Samples no triangle covers.
    pub uncovered: usize,
}

impl Metrics {
    /// The rounding allowance of a bound over `grid`: the interpolation of a
    /// triangle's plane at a sample rounds in f64 (about 10⁻¹⁴ of the
    /// heights), so a measured error may pass a bound it meets exactly by
    /// that much. The checker allows `10⁻⁹ × max(1 m, largest |height|)`.
    pub fn rounding_allowance_m(grid: &HeightGrid) -> f64 {
        1e-9 * grid
            .valid_range()
            .map(|(lo, hi)| f64::from(lo.abs().max(hi.abs())).max(1.0))
            .unwrap_or(1.0)
    }

    /// These metrics as reported against `bound_m`: a largest error above
    /// the bound by no more than [`Metrics::rounding_allowance_m`] is the
    /// bound (the excess is the plane's rounding, not error), so a script that
    /// tests `max_error_m <= bound` agrees with the checker. An error past the
    /// allowance is kept as measured.
    pub fn within_rounding_of(mut self, bound_m: Option<f64>, grid: &HeightGrid) -> Metrics {
        if let Some(b) = bound_m {
            let over = self.max_error_m - b;
            if over > 0.0 && over <= Self::rounding_allowance_m(grid) {
                self.max_error_m = b;
            }
        }
        self
    }
}

/// The triangles of `mesh` that lie on `grid`, as sample positions and the
/// plane through their vertex heights. Triangles with a bad index, a vertex off
/// the grid or no area are skipped (the checker reports them).
fn planes<'a>(grid: &'a HeightGrid, mesh: &'a Mesh) -> impl Iterator<Item = ([Pt; 3], Plane)> + 'a {
    mesh.triangles.iter().filter_map(move |t| {
        let (p, z) = corners(grid, mesh, t)?;
        Some((p, Plane::new(p, z)?))
    })
}

/// Rows per band of the parallel sample walk (see the module docs): fixed,
/// so that the figures do not depend on the number of threads.
pub const BAND_ROWS: usize = 64;

/// Triangles per run whose rows are bounded once, so that a band skips the
/// runs that miss it.
const RUN: usize = 256;

/// The sample positions and vertex heights of triangle `t` of `mesh` on
/// `grid`, `None` for a bad index or a vertex off the grid.
fn corners(grid: &HeightGrid, mesh: &Mesh, t: &[u32; 3]) -> Option<([Pt; 3], [f64; 3])> {
    let get = |i: u32| mesh.vertices.get(i as usize).copied();
    let vs = [get(t[0])?, get(t[1])?, get(t[2])?];
    if vs
        .iter()
        .any(|v| v.col as usize >= grid.width() || v.row as usize >= grid.height())
    {
        return None;
    }
    Some((vs.map(|v| [v.col, v.row]), vs.map(|v| v.z_m as f64)))
}

/// Folds `f(acc, col, row, Δz)` over every valid sample covered by `mesh`,
/// once each, with `Δz = mesh − grid` from the first triangle (in mesh order)
/// containing it: bands of rows in parallel, each from `init()`, then the
/// bands' results combined in row order by `combine`; tells
/// `progress(rows_done, rows)` as each band is done.
fn fold_samples<A: Send>(
    grid: &HeightGrid,
    mesh: &Mesh,
    init: impl Fn() -> A + Sync,
    f: impl Fn(&mut A, u32, u32, f64) + Sync,
    combine: impl Fn(A, A) -> A,
    progress: Progress<'_>,
) -> A {
    let (w, h) = (grid.width(), grid.height());
    let cull = Cull::new(grid, mesh);
    let rows = Counter::new(progress, h);
    let band = |b: usize| {
        let (y0, y1) = (b * BAND_ROWS, ((b + 1) * BAND_ROWS).min(h) - 1);
        let keep = cull.band(y0 as u32, y1 as u32);
        let mut seen = vec![0u64; ((y1 - y0 + 1) * w).div_ceil(64)];
        let mut acc = init();
        for (k, r) in cull.runs.iter().enumerate() {
            if !keep(r) {
                continue;
            }
            for t in &mesh.triangles[k * RUN..((k + 1) * RUN).min(mesh.triangles.len())] {
                let Some((p, z)) = keep(&cull.bounds(t))
                    .then(|| corners(grid, mesh, t))
                    .flatten()
                else {
                    continue;
                };
                let Some(plane) = Plane::new(p, z) else {
                    continue;
                };
                for_each_span_in(p, (y0 as i64, y1 as i64), |y, x0, x1| {
                    let base = (y as usize - y0) * w;
                    let heights = &grid.heights()[y as usize * w..];
                    for x in x0..=x1 {
                        let (i, hx) = (base + x as usize, heights[x as usize]);
                        let (word, bit) = (i / 64, 1u64 << (i % 64));
                        if seen[word] & bit != 0 || hx.is_nan() {
                            continue;
                        }
                        seen[word] |= bit;
                        f(&mut acc, x, y, plane.at(x as f64, y as f64) - hx as f64);
                    }
                });
            }
        }
        rows.add(y1 - y0 + 1);
        acc
    };
    let parts: Vec<A> = (0..h.div_ceil(BAND_ROWS))
        .into_par_iter()
        .map(band)
        .collect();
    parts.into_iter().reduce(combine).unwrap_or_else(init)
}

/// Which triangles, and runs of [`RUN`] triangles, can meet a band of rows.
/// A triangle's bounds are its least and greatest vertex index when the
/// vertices are numbered row by row (as every cota mesh's are): the rows of
/// those two vertices then bound its rows, so a band is decided on indices
/// alone. Otherwise the bounds are its rows, read from its vertices.
struct Cull<'m> {
    mesh: &'m Mesh,
    by_row: bool,
    /// Each run's bounds (least, greatest).
    runs: Vec<(u32, u32)>,
}

impl<'m> Cull<'m> {
    fn new(grid: &HeightGrid, mesh: &'m Mesh) -> Self {
        let by_row = mesh.vertices.windows(2).all(|v| v[0].row <= v[1].row);
        let mut cull = Cull {
            mesh,
            by_row,
            runs: Vec::new(),
        };
        cull.runs = mesh
            .triangles
            .par_chunks(RUN)
            .map(|run| {
                run.iter()
                    .filter(|t| by_row || corners(grid, mesh, t).is_some())
                    .map(|t| cull.bounds(t))
                    .fold((u32::MAX, 0), |(lo, hi), (a, b)| (lo.min(a), hi.max(b)))
            })
            .collect();
        cull
    }

    /// A triangle's bounds (see the type docs; rows clamped for bad indices,
    /// which [`corners`] then rejects).
    #[inline]
    fn bounds(&self, t: &[u32; 3]) -> (u32, u32) {
        if self.by_row {
            (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]))
        } else {
            let row = |i: u32| self.mesh.vertices.get(i as usize).map_or(0, |v| v.row);
            let r = t.map(row);
            (r[0].min(r[1]).min(r[2]), r[0].max(r[1]).max(r[2]))
        }
    }

    /// Whether bounds meet the rows `y0..=y1`.
    fn band(&self, y0: u32, y1: u32) -> impl Fn(&(u32, u32)) -> bool + '_ {
        let (lo, hi) = if self.by_row {
            let v = &self.mesh.vertices;
            // The first vertex on a row at or after y0; the first after y1.
            let lo = v.partition_point(|x| x.row < y0) as u32;
            let hi = v.partition_point(|x| x.row <= y1) as u32;
            // Bounds past the vertices (bad indices) always meet the band.
            (lo, if hi as usize == v.len() { u32::MAX } else { hi })
        } else {
            (y0, y1.saturating_add(1))
        };
        move |&(a, b)| b >= lo && a < hi
    }
}

/// The sums of [`measure`] over some samples.
#[derive(Debug, Clone, Copy, Default)]
struct Sums {
    max_m: f64,
    max_at: [u32; 2],
    sse_m2: f64,
    sum_abs_m: f64,
    volume_m3: f64,
    samples: usize,
}

impl Sums {
    /// `self` then `o`, in that order: the first of equal maxima is kept.
    fn then(self, o: Sums) -> Sums {
        let (max_m, max_at) = if o.max_m > self.max_m {
            (o.max_m, o.max_at)
        } else {
            (self.max_m, self.max_at)
        };
        Sums {
            max_m,
            max_at,
            sse_m2: self.sse_m2 + o.sse_m2,
            sum_abs_m: self.sum_abs_m + o.sum_abs_m,
            volume_m3: self.volume_m3 + o.volume_m3,
            samples: self.samples + o.samples,
        }
    }
}

/// The trapezoidal share of a sample in its cell area: 1 inside, halved on a
/// border, quartered at a corner.
fn trapezoid_share(grid: &HeightGrid, x: u32, y: u32) -> f64 {
    let edge = |v: u32, n: usize| {
        if v == 0 || v as usize == n - 1 {
            0.5
        } else {
            1.0
        }
    };
    edge(x, grid.width()) * edge(y, grid.height())
}

/// Measures `mesh` against `grid` at every sample.
///
/// Vertex indices out of range or off the grid are skipped (the checker reports
/// them); voids in the grid are skipped.
///
/// # Runtime
/// `O(W·H + triangles)`, plus `W·H` bits of memory.
pub fn measure(grid: &HeightGrid, mesh: &Mesh) -> Metrics {
    measure_with_progress(grid, mesh, crate::progress::NONE)
}

/// [`measure`], telling `progress(rows_done, rows)` of the grid's rows as
/// it goes.
pub fn measure_with_progress(grid: &HeightGrid, mesh: &Mesh, progress: Progress<'_>) -> Metrics {
    let (w, h) = (grid.width(), grid.height());
    let [dx, dy] = grid.cell_size_m();
    let cell_m2 = dx * dy;
    let s = crate::par::on_pool(|| {
        fold_samples(
            grid,
            mesh,
            Sums::default,
            |s, x, y, d| {
                let a = d.abs();
                if a > s.max_m {
                    s.max_m = a;
                    s.max_at = [x, y];
                }
                s.sse_m2 += d * d;
                s.sum_abs_m += a;
                s.volume_m3 += a * trapezoid_share(grid, x, y) * cell_m2;
                s.samples += 1;
            },
            Sums::then,
            progress,
        )
    });
    let mut m = Metrics {
        max_error_m: s.max_m,
        max_error_at: s.max_at,
        sse_m2: s.sse_m2,
        volume_m3: s.volume_m3,
        samples: s.samples,
        ..Metrics::default()
    };
    let valid = w * h - grid.void_count();
    m.uncovered = valid.saturating_sub(m.samples);
    if m.samples > 0 {
        m.rmse_m = (m.sse_m2 / m.samples as f64).sqrt();
        m.mean_abs_error_m = s.sum_abs_m / m.samples as f64;
    }
    m
}

/// Paper `004_ab8d08b3e6a5a70a.txt`'s distortion `D(M)`, m²: the sum over the
/// centroids of the regular grid's triangles of `(z − z_approx)²`.
///
/// The regular grid's triangles are the full-resolution bitree's unit
/// triangles: cell `(x, y)` is cut along `\` when `x + y` is even, `/` when odd.
/// `z` at a centroid is the mean of its triangle's three sample heights (the
/// full-resolution surface there) and `z_approx` the mesh's plane at the same
/// point. Centroids are visited exactly, on a lattice three times finer
/// ([`for_each_span`] on the mesh triangles scaled by 3), each once, in the
/// first mesh triangle containing it.
///
/// # Runtime
/// `O(9·W·H + triangles)`, plus `2·W·H` bits.
pub fn distortion_m2(grid: &HeightGrid, mesh: &Mesh) -> f64 {
    let (w, h) = (grid.width(), grid.height());
    let hs = grid.heights();
    let z = |x: usize, y: usize| hs[y * w + x] as f64;
    let mut seen = vec![0u64; (2 * w * h).div_ceil(64)];
    let mut d = 0f64;
    for (p, plane) in planes(grid, mesh) {
        let p3 = p.map(|q| [3 * q[0], 3 * q[1]]);
        for_each_span(p3, |yy, x0, x1| {
            let (y, ry) = ((yy / 3) as usize, yy % 3);
            if ry == 0 || y + 1 >= h {
                return;
            }
            for xx in x0..=x1 {
                let (x, rx) = ((xx / 3) as usize, xx % 3);
                if rx == 0 || x + 1 >= w {
                    continue;
                }
                // Which of the cell's two triangles has its centroid here.
                let back = (x + y).is_multiple_of(2);
                let (second, corners) = match (back, rx, ry) {
                    (true, 2, 1) => (false, [(x, y), (x + 1, y), (x + 1, y + 1)]),
                    (true, 1, 2) => (true, [(x, y), (x, y + 1), (x + 1, y + 1)]),
                    (false, 1, 1) => (false, [(x, y), (x + 1, y), (x, y + 1)]),
                    (false, 2, 2) => (true, [(x + 1, y), (x + 1, y + 1), (x, y + 1)]),
                    _ => continue,
                };
                let k = 2 * (y * w + x) + usize::from(second);
                let (word, bit) = (k / 64, 1u64 << (k % 64));
                if seen[word] & bit != 0 {
                    continue;
                }
                seen[word] |= bit;
                let truth = corners.iter().map(|&(cx, cy)| z(cx, cy)).sum::<f64>() / 3.0;
                let approx = plane.at(xx as f64 / 3.0, yy as f64 / 3.0);
                d += (truth - approx) * (truth - approx);
            }
        });
    }
    d
}

/// The volume between the mesh and the grid's surface weighted per sample,
/// m³ (times the weight's unit): `Σ |Δz|·wx·wy·dx·dy·weight(col, row)` with the
/// trapezoidal shares of [`measure`]'s `volume_m3`; each sample once, in the
/// first mesh triangle containing it. With the received light as the weight
/// (paper `002_9d6c1367b8962b6c.txt`, [`crate::criteria::light::received_light`]) this is
/// the illumination-weighted volume error.
pub fn weighted_volume_m3(
    grid: &HeightGrid,
    mesh: &Mesh,
    weight: impl Fn(u32, u32) -> f64 + Sync,
) -> f64 {
    let [dx, dy] = grid.cell_size_m();
    crate::par::on_pool(|| {
        fold_samples(
            grid,
            mesh,
            || 0f64,
            |v, x, y, d| *v += d.abs() * trapezoid_share(grid, x, y) * dx * dy * weight(x, y),
            |a, b| a + b,
            crate::progress::NONE,
        )
    })
}

#[cfg(test)]
mod test {
    #![allow(clippy::unwrap_used, reason = "tests")]
    use super::*;
    use crate::grid::GeoRef;
    use crate::refine::{refine, Mode, RefineOptions};
    use crate::{Bitree, ExtractOptions, MaxVerticalError};

    fn grid(w: usize, h: usize) -> HeightGrid {
        let v = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                40.0 * (x * 0.13).sin() * (y * 0.07).cos() + ((i * 7919) % 97) as f32 * 0.031
            })
            .collect();
        HeightGrid::new(w, h, v, GeoRef::unreferenced(25.0)).unwrap()
    }

    /// The walk as it was before bands: every triangle in mesh order, each
    /// sample once, sums in that order.
    fn sequential(g: &HeightGrid, mesh: &Mesh) -> (f64, f64, f64, usize) {
        let w = g.width();
        let mut seen = vec![false; g.len()];
        let (mut max, mut sse, mut sum, mut n) = (0f64, 0f64, 0f64, 0usize);
        for (p, plane) in planes(g, mesh) {
            for_each_span(p, |y, x0, x1| {
                for x in x0..=x1 {
                    let i = y as usize * w + x as usize;
                    if !seen[i] {
                        seen[i] = true;
                        let d = plane.at(x as f64, y as f64) - g.heights()[i] as f64;
                        max = max.max(d.abs());
                        sse += d * d;
                        sum += d.abs();
                        n += 1;
                    }
                }
            });
        }
        (max, sse, sum, n)
    }

    /// Bands, thread counts and mesh orders change neither the figures nor
    /// the samples visited; the sums agree with the sequential walk's to
    /// rounding.
    #[test]
    fn the_same_figures_on_any_number_of_threads() {
        let pool = |n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
        };
        for (w, h) in [(37, 23), (130, 200), (65, 129)] {
            let g = grid(w, h);
            let tree = Bitree::build(&g).unwrap();
            let mut meshes = vec![];
            for e in [0.0, 0.7, 3.0, 50.0] {
                meshes.push(tree.extract(&ExtractOptions::max_error_m(e)).unwrap().mesh);
            }
            let faithful = RefineOptions::DEFAULT.with_mode(Mode::Fictitious { watertight: false });
            let crit = MaxVerticalError { max_error_m: 1.5 };
            meshes.push(refine(&g, &crit, &faithful).unwrap().mesh);
            // An arbitrary order: every band must still see every run.
            let mut shuffled = meshes[1].clone();
            shuffled.triangles.reverse();
            let third = shuffled.triangles.len() / 3;
            shuffled.triangles.rotate_left(third);
            meshes.push(shuffled);
            for mesh in &meshes {
                let one = pool(1).install(|| measure(&g, mesh));
                for n in [2, 3, 8] {
                    assert_eq!(pool(n).install(|| measure(&g, mesh)), one, "{w}x{h} on {n}");
                }
                let (max, sse, sum, samples) = sequential(&g, mesh);
                assert_eq!(one.max_error_m, max);
                assert_eq!(one.samples, samples);
                assert_eq!(one.uncovered, 0);
                assert!((one.sse_m2 - sse).abs() <= 1e-12 * sse.max(1.0));
                let mean = sum / samples as f64;
                assert!((one.mean_abs_error_m - mean).abs() <= 1e-12 * mean.max(1.0));
                let [x, y] = one.max_error_at;
                assert!(x < w as u32 && y < h as u32);
            }
        }
    }
}
