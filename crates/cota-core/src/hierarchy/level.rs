//! The levels of the implicit bitree and the geometry of a split point: its
//! level from its position alone, its diamond, the diagonal it splits, and
//! a triangle's parent.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §2 (every grid point gets its level from
//! its position; a point splits the two triangles of its diamond) and §2.2
//! (a triangle exists iff its parent, whose split point is the triangle's
//! right-angle apex, is split). The levels `A(s)` and `B(s)` are described in
//! [`crate::hierarchy`].

use super::tri::{Pt, Tri};

/// One level of the hierarchy: `A(s)` or `B(s)` (see [`crate::hierarchy`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Level {
    /// Square halves of side `s`; split points at square centres.
    A(u32),
    /// Triangles on a side of length `s`; split points at side midpoints.
    B(u32),
}

/// The splittable levels of a padded square of side `n`, fine to coarse.
pub(crate) fn levels(n: u32) -> Vec<Level> {
    let mut v = Vec::new();
    let mut s = 2;
    while s <= n {
        v.push(Level::B(s));
        v.push(Level::A(s));
        s *= 2;
    }
    v
}

/// The level of the split point `p` in a padded square of side `n`, or `None`
/// for the square's corners (and points outside it), which split nothing.
///
/// With `k` the smallest number of trailing zero bits of the two coordinates
/// (0 counting as "infinitely many"), `p` is the centre of a `2^(k+1)` square
/// (`A`) when both coordinates have exactly `k`, else the midpoint of a side of
/// length `2^(k+1)` (`B`).
pub(crate) fn level_of(p: Pt, n: u32) -> Option<Level> {
    if p[0] > n || p[1] > n {
        return None;
    }
    let tz = |v: u32| if v == 0 { 40 } else { v.trailing_zeros() };
    let (kx, ky) = (tz(p[0]), tz(p[1]));
    let k = kx.min(ky);
    if k >= 31 {
        return None;
    }
    let s = 2u64 << k;
    if s > n as u64 {
        return None;
    }
    let s = s as u32;
    Some(if kx == ky { Level::A(s) } else { Level::B(s) })
}

/// The first column holding split points of `level` on row `y` (a row that
/// holds some, see [`level_rows`]); the others follow every `s` columns.
pub(crate) fn first_col(level: Level, y: u32) -> u32 {
    match level {
        Level::A(s) => s / 2,
        Level::B(s) if y.is_multiple_of(s) => s / 2,
        Level::B(_) => 0,
    }
}

/// The side `s` of `A(s)` or `B(s)`.
pub(crate) fn level_side(level: Level) -> u32 {
    match level {
        Level::A(s) | Level::B(s) => s,
    }
}

/// The rows holding split points of `level`: `(first_row, row_step)`.
pub(crate) fn level_rows(level: Level) -> (u32, u32) {
    match level {
        Level::A(s) => (s / 2, s),
        Level::B(s) => (0, (s / 2).max(1)),
    }
}

/// The triangles of the diamond whose split point is `m` at `level`.
pub(crate) fn diamond(level: Level, m: Pt, n: u32) -> [Option<Tri>; 2] {
    let [x, y] = m;
    match level {
        Level::A(s) => {
            let h = s / 2;
            let (x0, y0) = (x - h, y - h);
            let even = ((x0 / s) + (y0 / s)) % 2 == 0;
            if even {
                let (a, b) = ([x0, y0], [x0 + s, y0 + s]);
                [
                    Some(Tri {
                        a,
                        b,
                        c: [x0 + s, y0],
                    }),
                    Some(Tri {
                        a: b,
                        b: a,
                        c: [x0, y0 + s],
                    }),
                ]
            } else {
                let (a, b) = ([x0 + s, y0], [x0, y0 + s]);
                [
                    Some(Tri {
                        a,
                        b,
                        c: [x0 + s, y0 + s],
                    }),
                    Some(Tri {
                        a: b,
                        b: a,
                        c: [x0, y0],
                    }),
                ]
            }
        }
        Level::B(s) => {
            let h = s / 2;
            if y.is_multiple_of(s) {
                let (a, b) = ([x - h, y], [x + h, y]);
                [
                    (y >= h).then(|| Tri {
                        a,
                        b,
                        c: [x, y - h],
                    }),
                    (y + h <= n).then(|| Tri {
                        a: b,
                        b: a,
                        c: [x, y + h],
                    }),
                ]
            } else {
                let (a, b) = ([x, y - h], [x, y + h]);
                [
                    (x >= h).then(|| Tri {
                        a,
                        b,
                        c: [x - h, y],
                    }),
                    (x + h <= n).then(|| Tri {
                        a: b,
                        b: a,
                        c: [x + h, y],
                    }),
                ]
            }
        }
    }
}

/// The two diagonal (hypotenuse) ends of the split point `p`'s diamond.
pub(crate) fn diagonal_of(p: Pt, n: u32) -> Option<(Pt, Pt)> {
    let level = level_of(p, n)?;
    diamond(level, p, n)
        .into_iter()
        .flatten()
        .next()
        .map(|t| (t.a, t.b))
}

/// The parent of `t` (the diamond triangle of `t`'s apex that contains `t`),
/// `None` for a root.
pub(crate) fn parent(t: &Tri, n: u32) -> Option<Tri> {
    let level = level_of(t.c, n)?;
    diamond(level, t.c, n)
        .into_iter()
        .flatten()
        .find(|p| p.c == t.a || p.c == t.b)
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::hierarchy::Hierarchy;

    #[test]
    fn levels_from_positions() {
        assert_eq!(level_of([4, 4], 8), Some(Level::A(8)));
        assert_eq!(level_of([4, 0], 8), Some(Level::B(8)));
        assert_eq!(level_of([8, 4], 8), Some(Level::B(8)));
        assert_eq!(level_of([2, 2], 8), Some(Level::A(4)));
        assert_eq!(level_of([2, 4], 8), Some(Level::B(4)));
        assert_eq!(level_of([1, 1], 8), Some(Level::A(2)));
        assert_eq!(level_of([1, 0], 8), Some(Level::B(2)));
        assert_eq!(level_of([0, 0], 8), None);
        assert_eq!(level_of([8, 0], 8), None);
        assert_eq!(level_of([8, 8], 8), None);
    }

    #[test]
    fn every_child_has_its_parent() {
        let h = Hierarchy::new(17, 17);
        let mut stack = h.roots().to_vec();
        for r in h.roots() {
            assert_eq!(parent(&r, h.size()), None);
        }
        while let Some(t) = stack.pop() {
            if t.is_unit() {
                continue;
            }
            let (c0, c1) = t.children();
            for c in [c0, c1] {
                let p = parent(&c, h.size()).unwrap();
                assert_eq!(p.c, t.c);
                assert_eq!(p.mid(), t.mid());
                stack.push(c);
            }
        }
    }
}
