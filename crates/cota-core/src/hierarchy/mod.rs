//! Geometry of the implicit bitree over any W×H grid.
//!
//! Paper `000_ebf7e3a88dffd361.txt` ("Triangulación jerárquica sin
//! restricciones") §2: two root right triangles cover a square; a triangle splits
//! into two by the midpoint of its hypotenuse; every grid point gets its level
//! from its position alone, so no tree is stored. This is the right-triangulated
//! irregular network (RTIN) of Evans, Kirkpatrick & Townsend (1997) and the
//! bintree of ROAM (Duchaineau et al. 1997). Paper `001_49f2c365e8c41172.txt`
//! uses the same tree over a mosaic of SRTM tiles.
//!
//! # Any W×H grid: virtual padding with exact clipping
//! The hierarchy lives on the smallest square of side `N = 2^k ≥ max(W−1, H−1)`
//! whose north-west corner is sample (0, 0). The grid occupies
//! `[0, W−1] × [0, H−1]` of it. Every triangle is classified against that
//! rectangle:
//! 1. **inside**: its three vertices are samples of the grid;
//! 2. **outside**: its bounding box does not meet the rectangle's interior; it is
//!    never emitted and never looked at;
//! 3. **straddling**: anything else. It is always split. Its children are again
//!    classified, so the recursion stops where triangles fit the rectangle, at
//!    the latest at unit cells (a unit cell meeting the interior lies inside).
//!
//! No height is ever invented: only inside triangles are emitted, all their
//! vertices are grid samples, and together they tile the rectangle exactly.
//! The price is that the east and south borders are meshed at the resolution of
//! the largest power of two dividing `W−1` (resp. `H−1`): 16 samples for a
//! 1201-wide SRTM tile, 1 for an even width. No square hierarchy can do better,
//! since any tiling of `[0, W−1]` by power-of-two blocks needs a block of that size.
//!
//! # Levels
//! With `s` a power of two (2 ≤ s ≤ N), the triangles come in two kinds:
//! * `A(s)`: halves of an axis-aligned `s × s` square cut by its diagonal. The
//!   square `(i, j)` (corner `(i·s, j·s)`) is cut along `\` when `i + j` is even
//!   and along `/` when odd. The split point is the square's centre.
//! * `B(s)`: the children of `A(s)`: hypotenuse one side of an `s`-square, apex at
//!   its centre. The split point is the side's midpoint.
//!
//! Coarse to fine: `A(N), B(N), A(N/2), B(N/2), …, A(2), B(2)`; the children of
//! `B(2)` are the unit triangles `A(1)`, which are leaves. A split point is shared
//! by the two triangles of its *diamond* (the two halves of a square for `A`, the
//! two triangles on either side of a side for `B`), which is what makes a
//! consistent decision per split point crack-free.

mod level;

pub(crate) use level::{
    diagonal_of, diamond, first_col, level_of, level_rows, level_side, levels, parent, Level,
};

/// An integer grid position (column, row), row 0 north.
pub type Pt = [u32; 2];

/// A bitree triangle: `a`–`b` is the hypotenuse, `c` the right-angle apex.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tri {
    /// First end of the hypotenuse.
    pub a: Pt,
    /// Second end of the hypotenuse.
    pub b: Pt,
    /// The right-angle apex.
    pub c: Pt,
}

impl Tri {
    /// The split point: the midpoint of the hypotenuse. Only meaningful when the
    /// hypotenuse has even coordinates differences (not a unit triangle).
    #[inline]
    pub fn mid(&self) -> Pt {
        [(self.a[0] + self.b[0]) / 2, (self.a[1] + self.b[1]) / 2]
    }

    /// The two children, split at [`Tri::mid`].
    #[inline]
    pub fn children(&self) -> (Tri, Tri) {
        let m = self.mid();
        (
            Tri {
                a: self.c,
                b: self.a,
                c: m,
            },
            Tri {
                a: self.b,
                b: self.c,
                c: m,
            },
        )
    }

    /// True for a unit triangle (legs of length 1): a leaf of the hierarchy.
    #[inline]
    pub fn is_unit(&self) -> bool {
        self.a[0].abs_diff(self.b[0]) == 1 && self.a[1].abs_diff(self.b[1]) == 1
    }

    /// The vertex with the smallest and largest coordinates (bounding box).
    #[inline]
    fn bbox(&self) -> (Pt, Pt) {
        let lo = [
            self.a[0].min(self.b[0]).min(self.c[0]),
            self.a[1].min(self.b[1]).min(self.c[1]),
        ];
        let hi = [
            self.a[0].max(self.b[0]).max(self.c[0]),
            self.a[1].max(self.b[1]).max(self.c[1]),
        ];
        (lo, hi)
    }
}

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

/// How a triangle relates to the grid rectangle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// All three vertices are grid samples.
    Inside,
    /// It does not meet the rectangle's interior.
    Outside,
    /// Partly inside: must be split.
    Straddling,
}

/// The shape of the hierarchy for a W×H grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Hierarchy {
    width: u32,
    height: u32,
    size: u32,
}

impl Hierarchy {
    /// The hierarchy for a `width × height` grid (both at least 2 and below 2^30).
    pub fn new(width: u32, height: u32) -> Self {
        let span = width.max(height).saturating_sub(1).max(1);
        Hierarchy {
            width,
            height,
            size: span.next_power_of_two(),
        }
    }

    /// Grid width W.
    #[inline]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Grid height H.
    #[inline]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Side `N` of the padded square (a power of two).
    #[inline]
    pub fn size(&self) -> u32 {
        self.size
    }

    /// The two root triangles (halves of the padded square cut along `\`).
    pub fn roots(&self) -> [Tri; 2] {
        let n = self.size;
        [
            Tri {
                a: [0, 0],
                b: [n, n],
                c: [n, 0],
            },
            Tri {
                a: [n, n],
                b: [0, 0],
                c: [0, n],
            },
        ]
    }

    /// True when `p` is a grid sample.
    #[inline]
    pub fn contains(&self, p: Pt) -> bool {
        p[0] < self.width && p[1] < self.height
    }

    /// Classifies `t` against the grid rectangle (see the module docs).
    #[inline]
    pub fn place(&self, t: &Tri) -> Placement {
        if self.contains(t.a) && self.contains(t.b) && self.contains(t.c) {
            return Placement::Inside;
        }
        let (lo, _) = t.bbox();
        if lo[0] >= self.width - 1 || lo[1] >= self.height - 1 {
            Placement::Outside
        } else {
            Placement::Straddling
        }
    }

    /// Linear index of a sample.
    #[inline]
    pub fn index(&self, p: Pt) -> usize {
        p[1] as usize * self.width as usize + p[0] as usize
    }

    /// The largest triangles of the hierarchy inside the grid, in depth-first
    /// order: the roots, split while they straddle the grid's border. A
    /// [`crate::Bitree`] computes them once; every extraction starts from them.
    pub(crate) fn inside_roots(&self) -> Vec<Tri> {
        fn walk(hier: &Hierarchy, t: Tri, out: &mut Vec<Tri>) {
            match hier.place(&t) {
                Placement::Outside => {}
                Placement::Inside => out.push(t),
                Placement::Straddling => {
                    let (c0, c1) = t.children();
                    walk(hier, c0, out);
                    walk(hier, c1, out);
                }
            }
        }
        let mut out = Vec::new();
        for r in self.roots() {
            walk(self, r, &mut out);
        }
        out
    }
}

/// Twice the signed area of `(p, q, r)` in the east/north frame (x = column,
/// y = −row): positive when counter-clockwise seen from above.
#[inline]
pub fn orient_up(p: Pt, q: Pt, r: Pt) -> i64 {
    let (px, py) = (p[0] as i64, -(p[1] as i64));
    let (qx, qy) = (q[0] as i64, -(q[1] as i64));
    let (rx, ry) = (r[0] as i64, -(r[1] as i64));
    (qx - px) * (ry - py) - (qy - py) * (rx - px)
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn padded_sizes() {
        assert_eq!(Hierarchy::new(2, 2).size(), 1);
        assert_eq!(Hierarchy::new(3, 2).size(), 2);
        assert_eq!(Hierarchy::new(513, 513).size(), 512);
        assert_eq!(Hierarchy::new(1201, 1201).size(), 2048);
        assert_eq!(Hierarchy::new(2401, 1201).size(), 4096);
        assert_eq!(Hierarchy::new(2, 17).size(), 16);
    }

    #[test]
    fn children_tile_parent_and_halve_area() {
        let h = Hierarchy::new(9, 9);
        for r in h.roots() {
            let area = orient_up(r.a, r.b, r.c).abs();
            let (l, rr) = r.children();
            assert_eq!(orient_up(l.a, l.b, l.c).abs() * 2, area);
            assert_eq!(orient_up(rr.a, rr.b, rr.c).abs() * 2, area);
            assert_eq!(l.c, r.mid());
        }
    }

    #[test]
    fn placement() {
        let h = Hierarchy::new(5, 3); // N = 4, rows 0..=2
        let [r0, r1] = h.roots();
        assert_eq!(h.place(&r0), Placement::Straddling);
        assert_eq!(h.place(&r1), Placement::Straddling);
        let unit_out = Tri {
            a: [0, 2],
            b: [1, 3],
            c: [0, 3],
        };
        assert_eq!(h.place(&unit_out), Placement::Outside);
        let unit_in = Tri {
            a: [0, 1],
            b: [1, 2],
            c: [0, 2],
        };
        assert_eq!(h.place(&unit_in), Placement::Inside);
    }
}
