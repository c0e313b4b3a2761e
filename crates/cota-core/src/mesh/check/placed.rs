//! [`check_mesh`](super::check_mesh)'s mode for meshes whose vertices are
//! not on samples: a quantized-mesh tile as a client decodes it, mapped back
//! onto the lattice it was cut from.
//!
//! Reference: the quantized-mesh-1.0 specification (CesiumGS/quantized-mesh):
//! a vertex's `u`, `v` in `0..=32767` place it linearly between the tile's
//! west and east (south and north) edges. A tile of `T` lattice cells puts a
//! vertex at `u·T / 32767` cells from its west edge: a rational position with
//! denominator `32767`. This mode keeps positions exact as `(x / den,
//! y / den)` sample units and proves the same invariants as `check_mesh`:
//!
//! 1. **vertices in the region**, finite heights, no two at one position;
//! 2. **no degenerate or flipped triangle** (exact integer orientation);
//! 3. **conformity**: no directed edge twice, every edge without its reverse
//!    on the region's border (no T-junction, no crack inside);
//! 4. **exact coverage**: the triangles' areas add up to the region's, so
//!    with (2) and (3) they tile it exactly; every sample of the grid inside
//!    the region is also checked to be covered;
//! 5. **the error bound at every sample**: each triangle's samples are found
//!    row by row with exact integer arithmetic (a sample on an edge belongs
//!    to both triangles and is checked in both) and compared with the plane
//!    through the triangle's decoded vertices. A region may extend beyond the
//!    grid over a constant background (the 0 m beyond a tiling's window):
//!    there the truth is constant and the plane linear, so the largest
//!    |plane − background| over the part of the triangle beyond the grid's
//!    samples (the triangle clipped to each of the four half-planes beyond
//!    the grid's outer sample rows and columns) is reached at a vertex of a
//!    clipped piece: that bound holds at every background sample, and it is
//!    what the report gives there.
//!
//! Vertex heights are free (they are quantized); the bound is what holds
//! them to the grid.

use super::{CheckError, CheckReport, Found, Violation};
use crate::grid::HeightGrid;
use crate::mesh::metrics::Metrics;

/// A vertex at the exact position `(x / den, y / den)` in sample units of
/// the region (x east from its west column, y south from its north row).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlacedVertex {
    /// Column times the mesh's denominator.
    pub x: u64,
    /// Row times the mesh's denominator.
    pub y: u64,
    /// Height, metres.
    pub z_m: f64,
}

/// A triangle mesh with vertices at exact rational positions.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PlacedMesh {
    /// The common denominator of the positions (at least 1).
    pub den: u64,
    /// The vertices.
    pub vertices: Vec<PlacedVertex>,
    /// Triangles, counter-clockwise seen from above (x east, y north).
    pub triangles: Vec<[u32; 3]>,
}

/// The samples a placed mesh must cover: a `size[0] × size[1]` region of a
/// lattice, whose heights are `grid`'s where it lies (its sample (0, 0) at
/// region sample `origin`) and `background_m` elsewhere.
#[derive(Debug, Clone, Copy)]
pub struct Region<'a> {
    /// The known heights.
    pub grid: &'a HeightGrid,
    /// Region column and row of the grid's sample (0, 0) (may be negative).
    pub origin: [i64; 2],
    /// Samples across and down the region (at least 2 each).
    pub size: [u64; 2],
    /// The height outside the grid, metres.
    pub background_m: f64,
}

/// Checks the invariants listed in the module docs; `max_error_m`: the bound
/// at every sample of the region, if any.
///
/// # Errors
/// A [`CheckError`] listing the violations.
///
/// # Runtime
/// `O(T·R + S)` for `T` triangles spanning `R` rows on average and `S` grid
/// samples in the region, plus `S` bits.
pub fn check_placed_mesh(
    region: &Region<'_>,
    mesh: &PlacedMesh,
    max_error_m: Option<f64>,
) -> Result<CheckReport, CheckError> {
    let mut found = Found {
        list: Vec::new(),
        total: 0,
    };
    check_vertices(region, mesh, &mut found);
    if found.total == 0 {
        check_triangles(region, mesh, &mut found);
    }
    let mut metrics = Metrics::default();
    if found.total == 0 {
        metrics = measure_placed(region, mesh);
        if metrics.uncovered > 0 {
            found.push(Violation::Uncovered {
                count: metrics.uncovered,
            });
        }
        if let Some(bound) = max_error_m {
            // Rounding slack relative to the heights at hand (the mesh's;
            // the grid's can be far larger than one tile's share of it).
            let scale = mesh
                .vertices
                .iter()
                .map(|v| v.z_m.abs())
                .fold(region.background_m.abs().max(1.0), f64::max);
            if metrics.max_error_m > bound + 1e-9 * scale {
                found.push(Violation::ErrorBound {
                    got: metrics.max_error_m,
                    bound,
                    col: metrics.max_error_at[0],
                    row: metrics.max_error_at[1],
                });
            }
        }
    }
    if found.total > 0 {
        return Err(CheckError {
            violations: found.list,
            total: found.total,
        });
    }
    Ok(CheckReport { metrics })
}

/// Sample column and row nearest a vertex, for messages.
fn near(mesh: &PlacedMesh, v: &PlacedVertex) -> [u32; 2] {
    let d = mesh.den.max(1);
    [
        ((v.x + d / 2) / d).min(u64::from(u32::MAX)) as u32,
        ((v.y + d / 2) / d).min(u64::from(u32::MAX)) as u32,
    ]
}

fn check_vertices(region: &Region<'_>, mesh: &PlacedMesh, found: &mut Found) {
    let d = mesh.den.max(1);
    let (xmax, ymax) = ((region.size[0] - 1) * d, (region.size[1] - 1) * d);
    let mut keys: Vec<(u64, u64, usize)> = Vec::with_capacity(mesh.vertices.len());
    for (k, v) in mesh.vertices.iter().enumerate() {
        let [col, row] = near(mesh, v);
        if mesh.den == 0 || v.x > xmax || v.y > ymax || !v.z_m.is_finite() {
            found.push(Violation::VertexOffGrid {
                vertex: k,
                col,
                row,
                width: region.size[0] as usize,
                height: region.size[1] as usize,
            });
            continue;
        }
        keys.push((v.x, v.y, k));
    }
    keys.sort_unstable();
    for p in keys.windows(2) {
        if (p[0].0, p[0].1) == (p[1].0, p[1].1) {
            let [col, row] = near(mesh, &mesh.vertices[p[1].2]);
            found.push(Violation::DuplicateVertex {
                first: p[0].2,
                second: p[1].2,
                col,
                row,
            });
        }
    }
}

/// Twice the signed area of a triangle, positive when counter-clockwise
/// seen from above (x east, y = −row north).
fn area2(mesh: &PlacedMesh, t: [u32; 3]) -> i128 {
    let p = |i: u32| {
        let v = mesh.vertices[i as usize];
        (v.x as i128, v.y as i128)
    };
    let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
    -((b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0))
}

fn check_triangles(region: &Region<'_>, mesh: &PlacedMesh, found: &mut Found) {
    let n = mesh.vertices.len();
    let mut total = 0i128;
    let mut edges: Vec<u64> = Vec::with_capacity(mesh.triangles.len() * 3);
    for (k, t) in mesh.triangles.iter().enumerate() {
        if let Some(&bad) = t.iter().find(|&&i| i as usize >= n) {
            found.push(Violation::IndexOutOfRange {
                tri: k,
                index: bad,
                count: n,
            });
            continue;
        }
        let a = area2(mesh, *t);
        if a == 0 {
            found.push(Violation::Degenerate { tri: k });
        } else if a < 0 {
            found.push(Violation::Flipped { tri: k });
        }
        total += a;
        for e in 0..3 {
            edges.push((u64::from(t[e]) << 32) | u64::from(t[(e + 1) % 3]));
        }
    }
    edges.sort_unstable();
    for pair in edges.windows(2) {
        if pair[0] == pair[1] {
            found.push(Violation::EdgeOveruse {
                from: (pair[0] >> 32) as u32,
                to: pair[0] as u32,
            });
        }
    }
    open_edges(region, mesh, &edges, found);
    let d = i128::from(mesh.den.max(1));
    let cells = i128::from(region.size[0] - 1) * i128::from(region.size[1] - 1);
    if total != 2 * cells * d * d {
        found.push(Violation::AreaMismatch {
            got: (total / (d * d)) as i64,
            expected: (2 * cells) as i64,
        });
    }
}

/// Every edge without its reverse must lie on the region's border.
fn open_edges(region: &Region<'_>, mesh: &PlacedMesh, edges: &[u64], found: &mut Found) {
    let d = mesh.den.max(1);
    let (xmax, ymax) = ((region.size[0] - 1) * d, (region.size[1] - 1) * d);
    for &e in edges {
        let (i, j) = ((e >> 32) as u32, e as u32);
        if edges
            .binary_search(&((u64::from(j) << 32) | u64::from(i)))
            .is_ok()
        {
            continue;
        }
        let (a, b) = (mesh.vertices[i as usize], mesh.vertices[j as usize]);
        let on_border = (a.x == 0 && b.x == 0)
            || (a.x == xmax && b.x == xmax)
            || (a.y == 0 && b.y == 0)
            || (a.y == ymax && b.y == ymax);
        if !on_border {
            let ([ac, ar], [bc, br]) = (near(mesh, &a), near(mesh, &b));
            found.push(Violation::OpenEdge { ac, ar, bc, br });
        }
    }
}

/// The plane through a triangle's three placed vertices, in sample units.
struct PlacedPlane {
    x0: f64,
    y0: f64,
    z0: f64,
    gx: f64,
    gy: f64,
}

impl PlacedPlane {
    fn new(p: [PlacedVertex; 3], den: f64) -> Self {
        let (x0, y0) = (p[0].x as f64 / den, p[0].y as f64 / den);
        let (dx1, dy1) = (p[1].x as f64 / den - x0, p[1].y as f64 / den - y0);
        let (dx2, dy2) = (p[2].x as f64 / den - x0, p[2].y as f64 / den - y0);
        let det = dx1 * dy2 - dx2 * dy1;
        let (dz1, dz2) = (p[1].z_m - p[0].z_m, p[2].z_m - p[0].z_m);
        PlacedPlane {
            x0,
            y0,
            z0: p[0].z_m,
            gx: (dz1 * dy2 - dz2 * dy1) / det,
            gy: (dx1 * dz2 - dx2 * dz1) / det,
        }
    }

    #[inline]
    fn at(&self, x: f64, y: f64) -> f64 {
        self.z0 + self.gx * (x - self.x0) + self.gy * (y - self.y0)
    }
}

/// Calls `f(row, first, last)` for each sample row from `rows.0` to
/// `rows.1` meeting the triangle, with the closed range of sample columns
/// inside or on it clipped to `cols` (exact integer arithmetic on positions
/// scaled by `den`; each bound is estimated in `f64`, then corrected with
/// exact `i128` products, so no division is needed).
fn sample_spans(
    p: [PlacedVertex; 3],
    den: u64,
    rows: (i64, i64),
    cols: (i64, i64),
    mut f: impl FnMut(u64, u64, u64),
) {
    let d = i128::from(den);
    let q: [(i128, i128); 3] = p.map(|v| (v.x as i128, v.y as i128));
    let o = (q[1].0 - q[0].0) * (q[2].1 - q[0].1) - (q[1].1 - q[0].1) * (q[2].0 - q[0].0);
    if o == 0 {
        return;
    }
    let sign = o.signum();
    let ymin = q.iter().map(|v| v.1).min().unwrap_or(0);
    let ymax = q.iter().map(|v| v.1).max().unwrap_or(0);
    let first = ((ymin + d - 1) / d).max(i128::from(rows.0));
    let last = (ymax / d).min(i128::from(rows.1));
    // Edge k holds where ca·c + cb(r) ≥ 0, cb(r) = cb0 + r·cbr.
    let edges: [(i128, i128, i128); 3] = std::array::from_fn(|k| {
        let (a, b) = (q[k], q[(k + 1) % 3]);
        let (ex, ey) = (b.0 - a.0, b.1 - a.1);
        (-sign * ey * d, sign * (ey * a.0 - ex * a.1), sign * ex * d)
    });
    for r in first..=last {
        let (mut lo, mut hi) = (i128::from(cols.0), i128::from(cols.1));
        for &(ca, cb0, cbr) in &edges {
            let cb = cb0 + r * cbr;
            if ca == 0 {
                if cb < 0 {
                    hi = lo - 1;
                }
                continue;
            }
            let holds = |c: i128| ca * c + cb >= 0;
            let mut c = (-(cb as f64) / ca as f64).round() as i128;
            if ca > 0 {
                // The smallest c that holds.
                while !holds(c) {
                    c += 1;
                }
                while holds(c - 1) {
                    c -= 1;
                }
                lo = lo.max(c);
            } else {
                // The largest c that holds.
                while !holds(c) {
                    c -= 1;
                }
                while holds(c + 1) {
                    c += 1;
                }
                hi = hi.min(c);
            }
        }
        if lo <= hi {
            f(r as u64, lo as u64, hi as u64);
        }
    }
}

/// The largest |plane − background| over the part of the triangle beyond
/// the grid's samples: the triangle clipped to each half-plane beyond the
/// box `[x0, x1] × [y0, y1]` of grid samples (in sample units), at the
/// clipped pieces' vertices. `None` when no part lies beyond.
fn background_bound(
    p: [PlacedVertex; 3],
    den: f64,
    b: [f64; 4],
    value: impl Fn(f64, f64) -> f64,
) -> Option<(f64, [f64; 2])> {
    let pts = p.map(|v| [v.x as f64 / den, v.y as f64 / den]);
    // Half-planes beyond the box: (axis, limit, keep values below the limit?).
    let halves = [
        (0, b[0] - 1.0, true),
        (0, b[2] + 1.0, false),
        (1, b[1] - 1.0, true),
        (1, b[3] + 1.0, false),
    ];
    let mut best: Option<(f64, [f64; 2])> = None;
    let mut take = |q: [f64; 2]| {
        let e = value(q[0], q[1]);
        if best.is_none_or(|(m, _)| e > m) {
            best = Some((e, q));
        }
    };
    for (axis, limit, below) in halves {
        let inside = |q: [f64; 2]| {
            if below {
                q[axis] <= limit
            } else {
                q[axis] >= limit
            }
        };
        for k in 0..3 {
            let (a, c) = (pts[k], pts[(k + 1) % 3]);
            if inside(a) {
                take(a);
            }
            if inside(a) != inside(c) {
                let t = (limit - a[axis]) / (c[axis] - a[axis]);
                take([a[0] + t * (c[0] - a[0]), a[1] + t * (c[1] - a[1])]);
            }
        }
    }
    best
}

/// The error at every sample of the region (grid samples one by one, the
/// background by [`background_bound`]), and the grid samples no triangle
/// covers.
fn measure_placed(region: &Region<'_>, mesh: &PlacedMesh) -> Metrics {
    let g = region.grid;
    let (gw, gh) = (g.width() as i64, g.height() as i64);
    let [ox, oy] = region.origin;
    // The grid's samples inside the region: region columns gx0..=gx1, rows gy0..=gy1.
    let gx0 = ox.max(0);
    let gx1 = (ox + gw - 1).min(region.size[0] as i64 - 1);
    let gy0 = oy.max(0);
    let gy1 = (oy + gh - 1).min(region.size[1] as i64 - 1);
    let bw = (gx1 - gx0 + 1).max(0) as usize;
    let bh = (gy1 - gy0 + 1).max(0) as usize;
    let mut seen = vec![0u64; (bw * bh).div_ceil(64)];
    let mut m = Metrics::default();
    let (mut sum_abs, mut unique) = (0f64, 0usize);
    let den = mesh.den as f64;
    let note = |e: f64, c: f64, r: f64, m: &mut Metrics| {
        if e > m.max_error_m || e.is_nan() {
            m.max_error_m = if e.is_nan() { f64::INFINITY } else { e };
            m.max_error_at = [
                c.round().clamp(0.0, f64::from(u32::MAX)) as u32,
                r.round().clamp(0.0, f64::from(u32::MAX)) as u32,
            ];
        }
    };
    let whole = bw == region.size[0] as usize && bh == region.size[1] as usize;
    for t in &mesh.triangles {
        let p = t.map(|i| mesh.vertices[i as usize]);
        let plane = PlacedPlane::new(p, den);
        if !whole {
            let bg = |x: f64, y: f64| (plane.at(x, y) - region.background_m).abs();
            let b = [gx0 as f64, gy0 as f64, gx1 as f64, gy1 as f64];
            if let Some((e, [x, y])) = background_bound(p, den, b, bg) {
                note(e, x, y, &mut m);
            }
        }
        if bw == 0 || bh == 0 {
            continue;
        }
        sample_spans(p, mesh.den, (gy0, gy1), (gx0, gx1), |r, c0, c1| {
            let ri = r as i64;
            let row = &g.heights()[((ri - oy) * gw) as usize..];
            let base = (ri - gy0) as usize * bw;
            for c in c0 as i64..=c1 as i64 {
                let e = plane.at(c as f64, r as f64) - row[(c - ox) as usize] as f64;
                note(e.abs(), c as f64, r as f64, &mut m);
                let k = base + (c - gx0) as usize;
                if seen[k / 64] & (1 << (k % 64)) == 0 {
                    seen[k / 64] |= 1 << (k % 64);
                    unique += 1;
                    m.sse_m2 += e * e;
                    sum_abs += e.abs();
                }
            }
        });
    }
    m.samples = unique;
    m.uncovered = bw * bh - unique;
    if unique > 0 {
        m.rmse_m = (m.sse_m2 / unique as f64).sqrt();
        m.mean_abs_error_m = sum_abs / unique as f64;
    }
    m
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::grid::GeoRef;

    fn grid(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> HeightGrid {
        let heights = (0..w * h).map(|i| f(i % w, i / w)).collect();
        HeightGrid::new(w, h, heights, GeoRef::unreferenced(10.0)).unwrap()
    }

    /// Two triangles over a 5×5 region, vertices at the corners scaled by `den`.
    fn square(den: u64, z: [f64; 4]) -> PlacedMesh {
        let v = |x: u64, y: u64, z_m: f64| PlacedVertex {
            x: x * den,
            y: y * den,
            z_m,
        };
        PlacedMesh {
            den,
            vertices: vec![v(0, 0, z[0]), v(4, 0, z[1]), v(0, 4, z[2]), v(4, 4, z[3])],
            triangles: vec![[2, 1, 0], [2, 3, 1]],
        }
    }

    #[test]
    fn a_plane_passes_and_a_bump_is_caught_where_it_is() {
        let g = grid(5, 5, |c, r| (c + 2 * r) as f32);
        let region = Region {
            grid: &g,
            origin: [0, 0],
            size: [5, 5],
            background_m: 0.0,
        };
        let m = square(7, [0.0, 4.0, 8.0, 12.0]);
        let rep = check_placed_mesh(&region, &m, Some(1e-9)).unwrap();
        assert_eq!(rep.metrics.samples, 25);
        let mut bumped = g.clone();
        bumped.heights_mut()[2 * 5 + 3] += 0.5;
        let region = Region {
            grid: &bumped,
            ..region
        };
        let err = check_placed_mesh(&region, &m, Some(0.4)).unwrap_err();
        assert!(matches!(
            err.violations[0],
            Violation::ErrorBound { col: 3, row: 2, .. }
        ));
    }

    #[test]
    fn off_sample_vertices_are_judged_where_they_are() {
        // Move the north-east corner's neighbour: a vertex a third of a cell
        // off a sample changes which samples each triangle holds.
        let g = grid(5, 5, |c, _| c as f32);
        let region = Region {
            grid: &g,
            origin: [0, 0],
            size: [5, 5],
            background_m: 0.0,
        };
        let den = 3;
        let v = |x: u64, y: u64, z_m: f64| PlacedVertex { x, y, z_m };
        let m = PlacedMesh {
            den,
            vertices: vec![
                v(0, 0, 0.0),
                v(12, 0, 4.0),
                v(0, 12, 0.0),
                v(12, 12, 4.0),
                v(7, 6, 7.0 / 3.0),
            ],
            triangles: vec![[0, 2, 4], [2, 3, 4], [3, 1, 4], [1, 0, 4]],
        };
        check_placed_mesh(&region, &m, Some(1e-9)).unwrap();
        let mut wrong = m.clone();
        wrong.vertices[4].z_m = 3.0;
        assert!(check_placed_mesh(&region, &wrong, Some(0.5)).is_err());
    }

    #[test]
    fn holes_cracks_and_background_errors_are_caught() {
        let g = grid(3, 3, |_, _| 0.0);
        // The region is 5×5 with the grid in its middle.
        let region = Region {
            grid: &g,
            origin: [1, 1],
            size: [5, 5],
            background_m: 0.0,
        };
        let m = square(1, [0.0; 4]);
        check_placed_mesh(&region, &m, Some(0.0)).unwrap();
        let tilted = square(1, [0.0, 0.0, 0.0, 2.0]);
        let err = check_placed_mesh(&region, &tilted, Some(0.5)).unwrap_err();
        assert!(matches!(
            err.violations[0],
            Violation::ErrorBound { col: 4, row: 4, .. }
        ));
        let mut hole = m.clone();
        hole.triangles.pop();
        assert!(check_placed_mesh(&region, &hole, None).is_err());
        let mut flipped = m.clone();
        flipped.triangles[0] = [0, 1, 2];
        assert!(check_placed_mesh(&region, &flipped, None).is_err());
    }
}
