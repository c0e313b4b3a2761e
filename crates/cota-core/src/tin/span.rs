//! Exact row spans of a general triangle with integer vertices, and the exact
//! vertical error of its plane over every sample in or on it.
//!
//! Every accepted TIN edit is verified with these: a sample on an edge or at
//! a vertex belongs to the closed triangle, so a sample on an edge shared by
//! two triangles is checked by both. The spans come from an exact integer
//! walk along each edge (a DDA in quotient and remainder: the edge's column
//! at row `y` is `q + r/dy` with `0 ≤ r < dy`), so no sample is missed or
//! invented by rounding; the left end of a row is the ceiling of the left
//! edge's column, the right end the floor of the right edge's. This matches
//! [`crate::mesh::raster::for_each_span`] (tested), without its three divisions a
//! row. The plane is [`crate::mesh::raster::Plane`]'s, the checker's, with one
//! division instead of two (errors near the bound are decided exactly anyway).

/// One edge walked row by row: its column is `q + r / dy` exactly.
#[derive(Clone, Copy)]
struct Edge {
    q: i64,
    r: i64,
    dy: i64,
    step_q: i64,
    step_r: i64,
}

impl Edge {
    /// The edge from `a` to `b` (`b` below `a`: `b.1 > a.1`), at row `a.1`.
    #[inline]
    fn new(a: [i64; 2], b: [i64; 2]) -> Edge {
        let dy = b[1] - a[1];
        let dx = b[0] - a[0];
        // Most edges are steep (|dx| < dy): no division.
        let (step_q, step_r) = if dx >= 0 && dx < dy {
            (0, dx)
        } else if dx < 0 && -dx < dy {
            (-1, dx + dy)
        } else {
            (dx.div_euclid(dy), dx.rem_euclid(dy))
        };
        Edge {
            q: a[0],
            r: 0,
            dy,
            step_q,
            step_r,
        }
    }

    #[inline]
    fn step(&mut self) {
        self.q += self.step_q;
        self.r += self.step_r;
        if self.r >= self.dy {
            self.q += 1;
            self.r -= self.dy;
        }
    }

    #[inline]
    fn floor(&self) -> i64 {
        self.q
    }

    #[inline]
    fn ceil(&self) -> i64 {
        self.q + i64::from(self.r > 0)
    }
}

/// Calls `f(row, first_col, last_col)` for every row of samples in or on the
/// triangle `p` (columns, rows; any orientation), top to bottom, while `f`
/// returns true. Degenerate triangles yield nothing. Returns false when `f`
/// stopped the walk.
#[inline]
pub(crate) fn spans(p: [[i32; 2]; 3], mut f: impl FnMut(i64, i64, i64) -> bool) -> bool {
    let q = p.map(|v| [v[0] as i64, v[1] as i64]);
    // Sorted by row: a three-element network.
    let (mut a, mut b, mut c) = (q[0], q[1], q[2]);
    if a[1] > b[1] {
        std::mem::swap(&mut a, &mut b);
    }
    if b[1] > c[1] {
        std::mem::swap(&mut b, &mut c);
    }
    if a[1] > b[1] {
        std::mem::swap(&mut a, &mut b);
    }
    // Side of b against the long edge a→c: `s < 0` puts b on the right.
    let s = (c[0] - a[0]) * (b[1] - a[1]) - (c[1] - a[1]) * (b[0] - a[0]);
    if s == 0 {
        return true;
    }
    let long_left = s < 0;
    let mut long = Edge::new(a, c);
    let mut row = |y: i64, long: &Edge, short: &Edge| {
        let (lo, hi) = if long_left {
            (long.ceil(), short.floor())
        } else {
            (short.ceil(), long.floor())
        };
        lo > hi || f(y, lo, hi)
    };
    let mut y = a[1];
    if b[1] > a[1] {
        let mut short = Edge::new(a, b);
        while y <= b[1] {
            if !row(y, &long, &short) {
                return false;
            }
            long.step();
            short.step();
            y += 1;
        }
    }
    if c[1] > b[1] {
        let mut short = Edge::new(b, c);
        if y > b[1] {
            short.step();
        }
        while y <= c[1] {
            if !row(y, &long, &short) {
                return false;
            }
            long.step();
            short.step();
            y += 1;
        }
    }
    true
}

/// The plane of a triangle: `z(x, y) = z0 + gx·(x − x0) + gy·(y − y0)`, as
/// [`crate::mesh::raster::Plane`] computes it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Plane {
    x0: f64,
    y0: f64,
    z0: f64,
    gx: f64,
    gy: f64,
}

impl Plane {
    /// The plane through `p` (columns, rows) at heights `z`; `None` when
    /// degenerate.
    #[inline]
    pub(crate) fn new(p: [[i32; 2]; 3], z: [f32; 3]) -> Option<Plane> {
        // Differences and the determinant in integers (exact), one division.
        let d = |k: usize, c: usize| (p[k][c] - p[0][c]) as i64;
        let det = d(1, 0) * d(2, 1) - d(2, 0) * d(1, 1);
        if det == 0 {
            return None;
        }
        let (dx1, dy1, dx2, dy2) = (
            d(1, 0) as f64,
            d(1, 1) as f64,
            d(2, 0) as f64,
            d(2, 1) as f64,
        );
        let inv = 1.0 / det as f64;
        let z0 = z[0] as f64;
        let (dz1, dz2) = (z[1] as f64 - z0, z[2] as f64 - z0);
        Some(Plane {
            x0: p[0][0] as f64,
            y0: p[0][1] as f64,
            z0,
            gx: (dz1 * dy2 - dz2 * dy1) * inv,
            gy: (dx1 * dz2 - dx2 * dz1) * inv,
        })
    }
}

/// The grid as the error scans read it.
#[derive(Clone, Copy)]
pub(crate) struct Heights<'a> {
    /// Row-major heights.
    pub(crate) h: &'a [f32],
    /// Row length.
    pub(crate) w: usize,
    /// Errors within this of a bound are decided exactly
    /// ([`super::exact`]): far more than `f64` evaluation can be off by.
    pub(crate) margin: f64,
}

impl<'a> Heights<'a> {
    /// The heights of `grid`, with a margin of `10⁻⁹·max(1, |h|max)` metres.
    pub(crate) fn of(grid: &'a crate::grid::HeightGrid) -> Heights<'a> {
        let scale = grid
            .valid_range()
            .map_or(1.0, |(lo, hi)| (lo.abs().max(hi.abs()) as f64).max(1.0));
        Heights {
            h: grid.heights(),
            w: grid.width(),
            margin: 1e-9 * scale,
        }
    }

    /// The largest `|plane − h|` over the samples of row `y`, columns
    /// `x0..=x1`: four independent lanes (the compiler turns them into SIMD
    /// lanes), then the tail.
    #[inline]
    fn row_max(&self, pl: &Plane, y: i64, x0: i64, x1: i64) -> f64 {
        let base = pl.z0 + pl.gy * (y as f64 - pl.y0);
        let start = y as usize * self.w;
        let row = &self.h[start + x0 as usize..=start + x1 as usize];
        let dx = x0 as f64 - pl.x0;
        let mut m = [0f64; 4];
        let mut xs = [dx, dx + 1.0, dx + 2.0, dx + 3.0];
        let mut chunks = row.chunks_exact(4);
        for c in &mut chunks {
            for k in 0..4 {
                let d = ((base + pl.gx * xs[k]) - c[k] as f64).abs();
                if d > m[k] {
                    m[k] = d;
                }
                xs[k] += 4.0;
            }
        }
        let mut x = xs[0];
        for &hv in chunks.remainder() {
            let d = ((base + pl.gx * x) - hv as f64).abs();
            if d > m[0] {
                m[0] = d;
            }
            x += 1.0;
        }
        // Plain comparisons (the errors are never NaN): no NaN handling.
        let big = |a: f64, b: f64| if a > b { a } else { b };
        big(big(m[0], m[1]), big(m[2], m[3]))
    }

    /// The largest `|plane − h|` over every sample in or on triangle `p` with
    /// vertex heights `z`, or a value above `limit` as soon as one sample
    /// exceeds it. A degenerate triangle gives `+∞`.
    #[inline]
    pub(crate) fn tri_error(&self, p: [[i32; 2]; 3], z: [f32; 3], limit: f64) -> f64 {
        let Some(pl) = Plane::new(p, z) else {
            return f64::INFINITY;
        };
        let mut m = 0f64;
        spans(p, |y, x0, x1| {
            let r = self.row_max(&pl, y, x0, x1);
            if r > m {
                m = r;
            }
            m <= limit
        });
        m
    }

    /// Whether every sample in or on triangle `p` (heights `z`) is within
    /// `e` of its plane: decided in `f64` outside [`Heights::margin`] of
    /// `e`, and sample by sample in integers ([`super::exact`]) inside it.
    pub(crate) fn fits(&self, p: [[i32; 2]; 3], z: [f32; 3], e: f64) -> bool {
        let m = self.tri_error(p, z, e + self.margin);
        if m <= e - self.margin {
            return true;
        }
        m <= e + self.margin && self.fits_where(p, z, e, |_| true)
    }

    /// [`Heights::fits`] over the samples `s` for which `count(s)`, one by
    /// one (the slow path).
    pub(crate) fn fits_where(
        &self,
        p: [[i32; 2]; 3],
        z: [f32; 3],
        e: f64,
        count: impl Fn([i32; 2]) -> bool,
    ) -> bool {
        let Some(pl) = Plane::new(p, z) else {
            return false;
        };
        spans(p, |y, x0, x1| {
            let base = pl.z0 + pl.gy * (y as f64 - pl.y0);
            let start = y as usize * self.w;
            (x0..=x1).all(|x| {
                let (h, s) = (self.h[start + x as usize], [x as i32, y as i32]);
                let d = ((base + pl.gx * (x as f64 - pl.x0)) - h as f64).abs();
                d <= e - self.margin
                    || !count(s)
                    || (d <= e + self.margin && super::exact::plane_within(p, z, s, h, e))
            })
        })
    }

    /// The largest `|plane − h|` over the samples `s` of triangle `p` for
    /// which `count(s)`, and a sample where it is reached (the first in row
    /// order among equals); `(−1, p[0])` when none counts.
    pub(crate) fn tri_error_at(
        &self,
        p: [[i32; 2]; 3],
        z: [f32; 3],
        count: impl Fn([i32; 2]) -> bool,
    ) -> (f64, [i32; 2]) {
        let Some(pl) = Plane::new(p, z) else {
            return (f64::INFINITY, p[0]);
        };
        let mut best = (-1f64, p[0]);
        spans(p, |y, x0, x1| {
            let base = pl.z0 + pl.gy * (y as f64 - pl.y0);
            let start = y as usize * self.w;
            for x in x0..=x1 {
                let d =
                    ((base + pl.gx * (x as f64 - pl.x0)) - self.h[start + x as usize] as f64).abs();
                if d > best.0 && count([x as i32, y as i32]) {
                    best = (d, [x as i32, y as i32]);
                }
            }
            true
        });
        best
    }
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::mesh::raster::for_each_span;

    fn collect_ours(p: [[i32; 2]; 3]) -> Vec<(i64, i64, i64)> {
        let mut v = Vec::new();
        spans(p, |y, a, b| {
            v.push((y, a, b));
            true
        });
        v
    }

    fn collect_raster(p: [[i32; 2]; 3]) -> Vec<(i64, i64, i64)> {
        let mut v = Vec::new();
        let q = p.map(|c| [c[0] as u32, c[1] as u32]);
        for_each_span(q, |y, a, b| v.push((y as i64, a as i64, b as i64)));
        v
    }

    #[test]
    fn spans_match_the_raster_module_on_many_triangles() {
        let mut seed = 12345u64;
        let mut rnd = |n: u64| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 33) % n) as i32
        };
        for _ in 0..20000 {
            let p = [[rnd(40), rnd(40)], [rnd(40), rnd(40)], [rnd(40), rnd(40)]];
            assert_eq!(collect_ours(p), collect_raster(p), "{p:?}");
        }
        // Flat tops, flat bottoms, thin slivers.
        for p in [
            [[0, 0], [7, 0], [3, 5]],
            [[0, 5], [7, 5], [3, 0]],
            [[0, 0], [1, 9], [2, 17]],
            [[0, 0], [100, 1], [3, 2]],
        ] {
            assert_eq!(collect_ours(p), collect_raster(p), "{p:?}");
        }
    }

    #[test]
    fn error_of_a_plane_is_zero_and_of_a_bump_is_its_height() {
        let w = 9;
        let mut h: Vec<f32> = (0..w * w).map(|i| (i % w) as f32 * 2.0).collect();
        let hs = Heights {
            h: &h,
            w,
            margin: 1e-9,
        };
        let p = [[0, 0], [8, 0], [0, 8]];
        let z = p.map(|q| h[q[1] as usize * w + q[0] as usize]);
        assert_eq!(hs.tri_error(p, z, f64::INFINITY), 0.0);
        h[2 * w + 3] += 5.0;
        let hs = Heights {
            h: &h,
            w,
            margin: 1e-9,
        };
        assert_eq!(hs.tri_error(p, z, f64::INFINITY), 5.0);
        assert_eq!(hs.tri_error_at(p, z, |_| true), (5.0, [3, 2]));
        assert_eq!(hs.tri_error_at(p, z, |s| s != [3, 2]).0, 0.0);
        // Outside the triangle: not seen.
        h[2 * w + 3] -= 5.0;
        h[7 * w + 7] += 9.0;
        let hs = Heights {
            h: &h,
            w,
            margin: 1e-9,
        };
        assert_eq!(hs.tri_error(p, z, f64::INFINITY), 0.0);
    }

    #[test]
    fn ties_fit_exactly() {
        // A bump of exactly 5 on a plane: within 5, not within 5 − 1e-12.
        let w = 9;
        let mut h: Vec<f32> = (0..w * w).map(|i| (i % w) as f32 * 3.0).collect();
        h[2 * w + 3] += 5.0;
        let hs = Heights {
            h: &h,
            w,
            margin: 1e-9,
        };
        let p = [[0, 0], [8, 0], [0, 8]];
        let z = p.map(|q| (q[0] * 3) as f32);
        assert!(hs.fits(p, z, 5.0));
        assert!(!hs.fits(p, z, 5.0 - 1e-12));
        assert!(!hs.fits(p, z, 4.0));
    }
}
