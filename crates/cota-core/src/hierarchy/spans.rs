//! The rows of a hierarchy triangle and each row's span of columns, found
//! without division: every edge of a bitree triangle is horizontal, vertical
//! or at 45° (paper `000_ebf7e3a88dffd361.txt` §2).

/// The rows a hierarchy triangle covers and, on each row, its closed range of
/// columns. Every edge is horizontal, vertical or diagonal, so each
/// non-horizontal edge bounds a row at the integer column `slope·y +
/// intercept`, from the left or from the right (the side of the opposite
/// corner).
#[derive(Debug, Clone, Copy)]
pub(crate) struct RowSpans {
    bounds: [EdgeBound; 3],
    n: usize,
    ymin: i64,
    ymax: i64,
    horizontal: Option<i64>,
}

/// A row bound set by a non-horizontal edge: `x = slope·y + intercept`.
#[derive(Debug, Clone, Copy)]
struct EdgeBound {
    slope: i64,
    intercept: i64,
    is_left: bool,
}

impl RowSpans {
    /// The spans of the triangle with corners `p` (columns, rows).
    pub(crate) fn new(p: [[i64; 2]; 3]) -> Self {
        let mut bounds = [EdgeBound {
            slope: 0,
            intercept: 0,
            is_left: true,
        }; 3];
        let (mut n, mut horizontal) = (0, None);
        for k in 0..3 {
            let (q, r, o) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
            let (ex, ey) = (r[0] - q[0], r[1] - q[1]);
            if ey == 0 {
                horizontal = Some(q[1]);
                continue;
            }
            let slope = ex / ey; // 0 or ±1 in this hierarchy
            let intercept = q[0] - slope * q[1];
            bounds[n] = EdgeBound {
                slope,
                intercept,
                is_left: o[0] > slope * o[1] + intercept,
            };
            n += 1;
        }
        RowSpans {
            bounds,
            n,
            ymin: p[0][1].min(p[1][1]).min(p[2][1]),
            ymax: p[0][1].max(p[1][1]).max(p[2][1]),
            horizontal,
        }
    }

    /// The first and last rows.
    #[inline]
    pub(crate) fn rows(&self) -> (i64, i64) {
        (self.ymin, self.ymax)
    }

    /// The row of the horizontal edge, if the triangle has one.
    #[inline]
    pub(crate) fn horizontal(&self) -> Option<i64> {
        self.horizontal
    }

    /// The closed column range `(left, right)` of row `y`; empty when
    /// `left > right`.
    #[inline]
    pub(crate) fn at(&self, y: i64) -> (i64, i64) {
        let (mut l, mut r) = (i64::MIN, i64::MAX);
        for b in &self.bounds[..self.n] {
            let x = b.slope * y + b.intercept;
            if b.is_left {
                l = l.max(x);
            } else {
                r = r.min(x);
            }
        }
        (l, r)
    }
}
