//! Exact enumeration of the grid samples inside or on a triangle, and the
//! exact largest deviation of a triangle's plane from them.
//!
//! Used by the metrics and the checker, which must see **every** sample, and
//! by the refinements that judge a triangle by its exact error
//! ([`max_deviation`]: the criterion-driven refinement, paper
//! `001_49f2c365e8c41172.txt`, and the restricted quadtree). Vertices are
//! integer (column, row) positions, so the three edge functions are integer
//! linear forms and each row's span is found with exact integer floor/ceil
//! division: no sample on an edge is ever missed or invented by rounding.

use crate::grid::HeightGrid;
use crate::hierarchy::Pt;

/// Calls `f(row, first_col, last_col)` for each row of samples inside or on the
/// triangle `p` (any orientation, integer vertices). Degenerate triangles yield
/// nothing.
pub fn for_each_span(p: [Pt; 3], f: impl FnMut(u32, u32, u32)) {
    for_each_span_in(p, (0, i64::MAX), f);
}

/// [`for_each_span`] on the rows `rows.0..=rows.1` only.
pub(crate) fn for_each_span_in(p: [Pt; 3], rows: (i64, i64), mut f: impl FnMut(u32, u32, u32)) {
    let q: [(i64, i64); 3] = p.map(|v| (v[0] as i64, v[1] as i64));
    let area = (q[1].0 - q[0].0) * (q[2].1 - q[0].1) - (q[1].1 - q[0].1) * (q[2].0 - q[0].0);
    if area == 0 {
        return;
    }
    let sign = area.signum();
    // Edge k from q[k] to q[k+1]: inside when sign·cross(e, r − q[k]) ≥ 0, i.e.
    // A·x + B(y) ≥ 0 with A = −sign·ey and B = sign·(ex·(y − qy) + ey·qx).
    let ymin = q.iter().map(|v| v.1).min().unwrap_or(0).max(rows.0);
    let ymax = q.iter().map(|v| v.1).max().unwrap_or(0).min(rows.1);
    for y in ymin..=ymax {
        let (mut lo, mut hi) = (i64::MIN, i64::MAX);
        let mut empty = false;
        for k in 0..3 {
            let (a, b) = (q[k], q[(k + 1) % 3]);
            let (ex, ey) = (b.0 - a.0, b.1 - a.1);
            let ca = -sign * ey;
            let cb = sign * (ex * (y - a.1) + ey * a.0);
            if ca == 0 {
                if cb < 0 {
                    empty = true;
                }
            } else if ca > 0 {
                lo = lo.max(div_ceil(-cb, ca));
            } else {
                hi = hi.min(div_floor(cb, -ca));
            }
        }
        if !empty && lo <= hi {
            f(y as u32, lo as u32, hi as u32);
        }
    }
}

/// `⌊a / b⌋` for `b > 0`. A power-of-two divisor (every edge of a bitree
/// triangle: its legs and hypotenuse run along the axes or the diagonals,
/// over a power of two of samples) is an arithmetic shift, the same value
/// without a division.
#[inline]
fn div_floor(a: i64, b: i64) -> i64 {
    if b & (b - 1) == 0 {
        return a >> b.trailing_zeros();
    }
    let d = a / b;
    if (a % b != 0) && ((a < 0) != (b < 0)) {
        d - 1
    } else {
        d
    }
}

/// `⌈a / b⌉` for `b > 0`.
#[inline]
fn div_ceil(a: i64, b: i64) -> i64 {
    -div_floor(-a, b)
}

/// The mantissa bits of an `f64`: zero for a power of two (the determinant
/// of a triangle with integer vertices is an integer, so never subnormal).
const MANTISSA: u64 = (1 << 52) - 1;

/// Linear interpolation over a triangle with integer vertices: `z(x, y)`.
#[derive(Debug, Clone, Copy)]
pub struct Plane {
    x0: f64,
    y0: f64,
    z0: f64,
    gx: f64,
    gy: f64,
}

impl Plane {
    /// The plane through three points (x, y = column, row; z = height).
    /// `None` for a degenerate triangle.
    pub fn new(p: [Pt; 3], z: [f64; 3]) -> Option<Plane> {
        let (x0, y0) = (p[0][0] as f64, p[0][1] as f64);
        let (dx1, dy1) = (p[1][0] as f64 - x0, p[1][1] as f64 - y0);
        let (dx2, dy2) = (p[2][0] as f64 - x0, p[2][1] as f64 - y0);
        let det = dx1 * dy2 - dx2 * dy1;
        if det == 0.0 {
            return None;
        }
        let (dz1, dz2) = (z[1] - z[0], z[2] - z[0]);
        let (nx, ny) = (dz1 * dy2 - dz2 * dy1, dx1 * dz2 - dx2 * dz1);
        // Dividing by a power of two is multiplying by its exact inverse
        // (both round the same real number once): the same gradient,
        // without two divisions, for every bitree triangle.
        let (gx, gy) = if det.abs().to_bits() & MANTISSA == 0 {
            let inv = 1.0 / det;
            (nx * inv, ny * inv)
        } else {
            (nx / det, ny / det)
        };
        Some(Plane {
            x0,
            y0,
            z0: z[0],
            gx,
            gy,
        })
    }

    /// Height of the plane at (x, y).
    #[inline]
    pub fn at(&self, x: f64, y: f64) -> f64 {
        self.z0 + self.gx * (x - self.x0) + self.gy * (y - self.y0)
    }
}

/// The exact largest |plane − h| over the grid samples in or on the triangle
/// `p` (columns, rows) whose corners have heights `zs` (metres): the plane
/// through the corners, evaluated in `f64` at every sample of
/// [`for_each_span`]. 0 for a degenerate triangle.
pub fn max_deviation(grid: &HeightGrid, p: [Pt; 3], zs: [f64; 3]) -> f64 {
    let Some(plane) = Plane::new(p, zs) else {
        return 0.0;
    };
    let w = grid.width();
    let heights = grid.heights();
    let mut e = 0f64;
    for_each_span(p, |y, x0, x1| {
        let row = &heights[y as usize * w..];
        for x in x0..=x1 {
            let d = (plane.at(x as f64, y as f64) - row[x as usize] as f64).abs();
            e = if d > e { d } else { e };
        }
    });
    e
}

#[cfg(test)]
mod test {
    use super::*;

    fn count(p: [Pt; 3]) -> usize {
        let mut n = 0;
        for_each_span(p, |_, a, b| n += (b - a + 1) as usize);
        n
    }

    #[test]
    fn counts_lattice_points_by_pick() {
        // Right triangle with legs 4: (4+1)(4+2)/2 = 15 points.
        assert_eq!(count([[0, 0], [4, 0], [0, 4]]), 15);
        assert_eq!(count([[0, 4], [4, 0], [0, 0]]), 15);
        // Hypotenuse 4 on an axis, apex 2 away: 9 points.
        assert_eq!(count([[0, 0], [4, 0], [2, 2]]), 9);
        // A thin general triangle, Pick: A = I + B/2 - 1.
        assert_eq!(count([[0, 0], [5, 1], [2, 3]]), 9);
        assert_eq!(count([[0, 0], [2, 2], [4, 4]]), 0);
    }

    #[test]
    fn plane_interpolates() {
        let pl = Plane::new([[0, 0], [4, 0], [0, 4]], [1.0, 5.0, 9.0]).unwrap();
        assert_eq!(pl.at(2.0, 2.0), 1.0 + 2.0 + 4.0);
    }
}
