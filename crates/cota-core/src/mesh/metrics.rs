//! Exact approximation metrics of a mesh against its grid, over every sample.
//!
//! Paper `001_49f2c365e8c41172.txt` measures quality by the sum of squared height
//! differences between the approximation and the original grid; paper
//! `002_9d6c1367b8962b6c.txt` by the volume enclosed between them and by RMSE.
//! cota reports all of them, exactly:
//! * every sample is visited once, in the first triangle (in mesh order) that
//!   contains it; on a shared edge both triangles interpolate the same two
//!   endpoints, so the choice does not matter;
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

use super::raster::{for_each_span, Plane};
use super::Mesh;
use crate::grid::HeightGrid;
use crate::hierarchy::Pt;

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

/// The triangles of `mesh` that lie on `grid`, as sample positions and the
/// plane through their vertex heights. Triangles with a bad index, a vertex off
/// the grid or no area are skipped (the checker reports them).
fn planes<'a>(grid: &'a HeightGrid, mesh: &'a Mesh) -> impl Iterator<Item = ([Pt; 3], Plane)> + 'a {
    let (w, h) = (grid.width(), grid.height());
    mesh.triangles.iter().filter_map(move |t| {
        let get = |i: u32| mesh.vertices.get(i as usize).copied();
        let vs = [get(t[0])?, get(t[1])?, get(t[2])?];
        if vs
            .iter()
            .any(|v| v.col as usize >= w || v.row as usize >= h)
        {
            return None;
        }
        let p = vs.map(|v| [v.col, v.row]);
        Some((p, Plane::new(p, vs.map(|v| v.z_m as f64))?))
    })
}

/// Calls `f(col, row, Δz)` once for every valid sample covered by `mesh`, with
/// `Δz = mesh − grid` from the first triangle (in mesh order) containing it.
fn for_each_sample_once(grid: &HeightGrid, mesh: &Mesh, mut f: impl FnMut(u32, u32, f64)) {
    let w = grid.width();
    let heights = grid.heights();
    let mut seen = vec![0u64; grid.len().div_ceil(64)];
    for (p, plane) in planes(grid, mesh) {
        for_each_span(p, |y, x0, x1| {
            for x in x0..=x1 {
                let i = y as usize * w + x as usize;
                let (word, bit) = (i / 64, 1u64 << (i % 64));
                if seen[word] & bit != 0 || heights[i].is_nan() {
                    continue;
                }
                seen[word] |= bit;
                f(x, y, plane.at(x as f64, y as f64) - heights[i] as f64);
            }
        });
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
    let (w, h) = (grid.width(), grid.height());
    let [dx, dy] = grid.cell_size_m();
    let cell_m2 = dx * dy;
    let mut m = Metrics::default();
    let mut sum_abs = 0f64;
    for_each_sample_once(grid, mesh, |x, y, d| {
        let a = d.abs();
        if a > m.max_error_m {
            m.max_error_m = a;
            m.max_error_at = [x, y];
        }
        m.sse_m2 += d * d;
        sum_abs += a;
        m.volume_m3 += a * trapezoid_share(grid, x, y) * cell_m2;
        m.samples += 1;
    });
    let valid = w * h - grid.void_count();
    m.uncovered = valid.saturating_sub(m.samples);
    if m.samples > 0 {
        m.rmse_m = (m.sse_m2 / m.samples as f64).sqrt();
        m.mean_abs_error_m = sum_abs / m.samples as f64;
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
pub fn weighted_volume_m3(grid: &HeightGrid, mesh: &Mesh, weight: impl Fn(u32, u32) -> f64) -> f64 {
    let [dx, dy] = grid.cell_size_m();
    let mut v = 0f64;
    for_each_sample_once(grid, mesh, |x, y, d| {
        v += d.abs() * trapezoid_share(grid, x, y) * dx * dy * weight(x, y);
    });
    v
}
