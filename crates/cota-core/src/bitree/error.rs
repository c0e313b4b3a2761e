//! The exact error of a bitree triangle and the code of a split point: the
//! error kernels every build path shares.
//!
//! Papers `000_ebf7e3a88dffd361.txt` §3.2 and `001_49f2c365e8c41172.txt`: the
//! error of a triangle `T` is the largest `|plane_T − h|` over **every** grid
//! sample in or on `T`, visited row by row ([`Span`]: every edge is
//! horizontal, vertical or at 45°, so each row is one span found without
//! division), computed in `f64` with exact power-of-two arithmetic and rounded
//! **up** to `f32`, then to a 16-bit code ([`super::error_code`]). A split
//! point's code is the largest of its diamond's triangles' codes and their
//! children's codes ([`diamond_code`]), `INFINITE` when a triangle straddles
//! the grid's border.

use rayon::prelude::*;

use super::error_code::{encode_up, INFINITE};
use crate::hierarchy::{diamond, Hierarchy, Level, Placement, Pt, RowSpans, Tri};

/// A read-only view of the codes of grid rows `base / W ..`: indexed by
/// grid-wide sample index, so the per-point code reads the same whether it
/// sees the whole array or one segment of it.
#[derive(Clone, Copy)]
pub(super) struct Codes<'a> {
    pub(super) c: &'a [u16],
    pub(super) base: usize,
}

impl std::ops::Index<usize> for Codes<'_> {
    type Output = u16;
    #[inline]
    fn index(&self, i: usize) -> &u16 {
        &self.c[i - self.base]
    }
}

/// The code of `err` of the split point `m` (see the module docs).
#[inline(never)]
pub(super) fn diamond_error(
    heights: &[f32],
    hier: &Hierarchy,
    level: Level,
    m: Pt,
    codes: Codes<'_>,
) -> u16 {
    diamond_code(hier, level, m, codes, |t| {
        triangle_error(heights, hier, level, t)
    })
}

/// The code of the split point `m` of `level` from `own(T)`, the error of
/// each inside triangle `T` of its diamond: the largest of their codes and
/// their children's codes, [`INFINITE`] when a triangle straddles the border.
#[inline]
pub(super) fn diamond_code(
    hier: &Hierarchy,
    level: Level,
    m: Pt,
    codes: Codes<'_>,
    mut own: impl FnMut(&Tri) -> f64,
) -> u16 {
    let mut e = 0f64;
    let mut code = 0u16;
    for t in diamond(level, m, hier.size()).into_iter().flatten() {
        match hier.place(&t) {
            Placement::Outside => continue,
            Placement::Straddling => return INFINITE,
            Placement::Inside => {}
        }
        e = max_no_nan(e, own(&t));
        let (c0, c1) = t.children();
        if !c0.is_unit() {
            code = code.max(codes[hier.index(c0.mid())]);
            code = code.max(codes[hier.index(c1.mid())]);
        }
    }
    code.max(code_of(e))
}

/// The stored code of an error computed in `f64`: rounded up to `f32`, then
/// to a code, never understated.
#[inline]
pub(super) fn code_of(e: f64) -> u16 {
    encode_up(round_up_f32(e))
}

/// The smallest `f32` not below `e`.
pub(crate) fn round_up_f32(e: f64) -> f32 {
    let f = e as f32;
    if (f as f64) < e {
        f.next_up()
    } else {
        f
    }
}

/// Exact `e(T)`: the largest |plane − height| over the samples in or on `t`.
pub(super) fn triangle_error(heights: &[f32], hier: &Hierarchy, level: Level, t: &Tri) -> f64 {
    let w = hier.width() as usize;
    let hv = |p: Pt| heights[p[1] as usize * w + p[0] as usize] as f64;
    match level {
        // The only sample off the vertices is the split point (B(2)), or the
        // split point and the two leg midpoints, which are the children's split
        // points and are accounted for by their own errors (A(2)).
        Level::B(2) | Level::A(2) => {
            let m = t.mid();
            (hv(m) - 0.5 * (hv(t.a) + hv(t.b))).abs()
        }
        _ => span_error(heights, w, t, hv(t.a), hv(t.b), hv(t.c)),
    }
}

/// Largest |plane − h| over the samples of `t`, visited row by row.
pub(super) fn span_error(heights: &[f32], w: usize, t: &Tri, ha: f64, hb: f64, hc: f64) -> f64 {
    let span = Span::new(w, t, [ha, hb, hc]);
    let (ymin, ymax) = span.rows();
    let rows = (ymax - ymin + 1) as u64;
    if rows * rows >= PARALLEL_SPAN_SAMPLES {
        // A large triangle (the own error of a coarse split point, recomputed
        // by `exact_within` or `own_error_at`): split its rows over the cores
        // rather than leave one idle.
        let blocks = (ymax - ymin) as usize / 32 + 1;
        (0..blocks)
            .into_par_iter()
            .map(|k| {
                let y = ymin + 32 * k as i64;
                span.max_dev(heights, y, (y + 31).min(ymax))
            })
            .reduce(|| 0.0, max_no_nan)
    } else {
        span.max_dev(heights, ymin, ymax)
    }
}

/// A triangle's plane and row bounds, for [`span_error`].
pub(super) struct Span {
    spans: RowSpans,
    h0: f64,
    gx: f64,
    gy: f64,
    x0: i64,
    y0: i64,
    w: usize,
}

impl Span {
    /// The plane through `t`'s corners at heights `hs` (`a`, `b`, `c`), on a
    /// grid `w` samples wide.
    pub(super) fn new(w: usize, t: &Tri, hs: [f64; 3]) -> Self {
        let p = [t.a, t.b, t.c];
        let (x0, y0) = (p[0][0] as i64, p[0][1] as i64);
        let (dx1, dy1) = (p[1][0] as i64 - x0, p[1][1] as i64 - y0);
        let (dx2, dy2) = (p[2][0] as i64 - x0, p[2][1] as i64 - y0);
        let det = (dx1 * dy2 - dx2 * dy1) as f64; // ±power of two: exact division
        let (dh1, dh2) = (hs[1] - hs[0], hs[2] - hs[0]);
        let gx = (dh1 * dy2 as f64 - dh2 * dy1 as f64) / det;
        let gy = (dx1 as f64 * dh2 - dx2 as f64 * dh1) / det;
        Span {
            spans: RowSpans::new(p.map(|q| [i64::from(q[0]), i64::from(q[1])])),
            h0: hs[0],
            gx,
            gy,
            x0,
            y0,
            w,
        }
    }

    /// The triangle's first and last rows.
    pub(super) fn rows(&self) -> (i64, i64) {
        self.spans.rows()
    }

    /// Largest |plane − h| over the triangle's samples in rows `y0..=y1`.
    #[inline]
    pub(super) fn max_dev(&self, heights: &[f32], y0: i64, y1: i64) -> f64 {
        let mut e = 0f64;
        for y in y0..=y1 {
            let (xl, xr) = self.spans.at(y);
            if xl > xr {
                continue;
            }
            let base = self.h0 + self.gx * (xl - self.x0) as f64 + self.gy * (y - self.y0) as f64;
            let start = y as usize * self.w + xl as usize;
            let row = &heights[start..=start + (xr - xl) as usize];
            e = max_no_nan(e, row_max_dev(row, base, self.gx));
        }
        e
    }
}

/// Largest |plane − h| over the samples of `t` (global lattice
/// coordinates) inside `clip` (`[x0, y0, x1, y1]`, inclusive), the heights
/// read from `heights` (rows of `w` samples whose sample (0, 0) is at global
/// `origin`, covering `clip`), the plane through `hs`: each sample's value
/// is bit for bit the one [`span_error`] computes over the whole triangle, so
/// the maxima of disjoint (or overlapping) clips combine into it exactly.
pub(crate) fn clipped_span_error(
    heights: &[f32],
    w: usize,
    origin: [u64; 2],
    t: &Tri,
    hs: [f64; 3],
    clip: [u64; 4],
) -> f64 {
    let span = Span::new(w, t, hs);
    let (ya, yb) = span.rows();
    let (ya, yb) = (ya.max(clip[1] as i64), yb.min(clip[3] as i64));
    let row_max = |y: i64| -> f64 {
        let (xl, xr) = span.spans.at(y);
        let (a, b) = (xl.max(clip[0] as i64), xr.min(clip[2] as i64));
        if a > b {
            return 0.0;
        }
        let base = span.h0 + span.gx * (xl - span.x0) as f64 + span.gy * (y - span.y0) as f64;
        let start = (y as u64 - origin[1]) as usize * w + (a as u64 - origin[0]) as usize;
        let row = &heights[start..=start + (b - a) as usize];
        row_max_dev_from(row, base, span.gx, (a - xl) as f64)
    };
    if ya > yb {
        return 0.0;
    }
    if (yb - ya) > 64 {
        (ya..=yb)
            .into_par_iter()
            .map(row_max)
            .reduce(|| 0.0, max_no_nan)
    } else {
        (ya..=yb).map(row_max).fold(0.0, max_no_nan)
    }
}

/// [`row_max_dev`] for a row whose first sample is `k0` samples after the
/// span's start (`base` is the plane at the span's start).
fn row_max_dev_from(row: &[f32], base: f64, gx: f64, k0: f64) -> f64 {
    let mut m = [0f64; 4];
    let mut k = k0;
    let chunks = row.chunks_exact(4);
    let rest = chunks.remainder();
    for c in chunks {
        for j in 0..4 {
            let d = (base + gx * (k + j as f64) - c[j] as f64).abs();
            m[j] = if d > m[j] { d } else { m[j] };
        }
        k += 4.0;
    }
    for (j, &h) in rest.iter().enumerate() {
        let d = (base + gx * (k + j as f64) - h as f64).abs();
        m[j] = if d > m[j] { d } else { m[j] };
    }
    max_no_nan(max_no_nan(m[0], m[1]), max_no_nan(m[2], m[3]))
}

/// Triangles with at least about this many samples (a square of the row
/// count: 64 rows) are scanned in parallel, in blocks of 32 rows.
const PARALLEL_SPAN_SAMPLES: u64 = 1 << 12;

/// max_k |base + gx·k − row[k]|, with four independent maxima so the loop
/// vectorises (the index runs as an exact `f64` counter, no int→float
/// conversion per sample).
#[inline]
pub(super) fn row_max_dev(row: &[f32], base: f64, gx: f64) -> f64 {
    row_max_dev_from(row, base, gx, 0.0)
}

/// The larger of two values known not to be NaN (the build refuses voids, so
/// no NaN height reaches it): one comparison, without `f64::max`'s NaN rules.
#[inline(always)]
pub(super) fn max_no_nan(a: f64, b: f64) -> f64 {
    if b > a {
        b
    } else {
        a
    }
}
