//! A triangle of the bitree: its hypotenuse, its right-angle apex, its split
//! point and its two children (paper `000_ebf7e3a88dffd361.txt` §2: a
//! triangle splits into two by the midpoint of its hypotenuse).

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
    pub(super) fn bbox(&self) -> (Pt, Pt) {
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

/// Twice the signed area of `(p, q, r)` in the east/north frame (x = column,
/// y = −row): positive when counter-clockwise seen from above.
#[inline]
pub fn orient_up(p: Pt, q: Pt, r: Pt) -> i64 {
    let (px, py) = (p[0] as i64, -(p[1] as i64));
    let (qx, qy) = (q[0] as i64, -(q[1] as i64));
    let (rx, ry) = (r[0] as i64, -(r[1] as i64));
    (qx - px) * (ry - py) - (qy - py) * (rx - px)
}
