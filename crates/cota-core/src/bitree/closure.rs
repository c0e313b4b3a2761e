//! The monotone closure of a per-split-point error over the bitree: for
//! each split point, the largest of its own and its descendants'.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §2–3: a split point's error is the
//! maximum of its diamond's own errors and of its children's, so that a
//! decision per split point is monotone up the tree. The same closure of
//! another own error (here: against the source's own samples,
//! [`crate::tiles::source_error`]) is a second monotone error that a
//! decision may take with the first and stay conforming.
//!
//! # Runtime
//! `O(n)`: one pass per level over its split points, in parallel over rows.

use super::by_level::fill_level;
use super::error::Codes;
#[cfg(test)]
use super::error_code::encode_up;
use crate::hierarchy::{levels, Hierarchy, Level, Pt};

/// The index of `p` in the grid.
#[inline]
fn index(hier: &Hierarchy, p: Pt) -> usize {
    p[1] as usize * hier.width() as usize + p[0] as usize
}

/// The largest code of the split points of the children of `m`'s diamond
/// at `level` (above `B(2)`): for `A(s)`, the midpoints of its square's
/// sides; for `B(s)`, the centres of the four `s/2`-squares around it.
#[inline]
fn children_max(hier: &Hierarchy, level: Level, m: Pt, codes: &Codes<'_>) -> u16 {
    let [x, y] = m;
    let (d, diagonal) = match level {
        Level::A(s) => (s / 2, false),
        Level::B(s) => (s / 4, true),
    };
    let pts: [(Option<u32>, Option<u32>); 4] = if diagonal {
        [
            (x.checked_sub(d), y.checked_sub(d)),
            (x.checked_add(d), y.checked_sub(d)),
            (x.checked_sub(d), y.checked_add(d)),
            (x.checked_add(d), y.checked_add(d)),
        ]
    } else {
        [
            (x.checked_sub(d), Some(y)),
            (x.checked_add(d), Some(y)),
            (Some(x), y.checked_sub(d)),
            (Some(x), y.checked_add(d)),
        ]
    };
    let mut c = 0u16;
    for p in pts {
        if let (Some(px), Some(py)) = p {
            if hier.contains([px, py]) {
                c = c.max(codes[index(hier, [px, py])]);
            }
        }
    }
    c
}

/// The closure of a split point's own error against the source's samples
/// ([`crate::tiles::source_error`], one code per split point in `own`):
/// the maximum of its own and its children's, so each level's value is at
/// least its children's (monotone).
pub(crate) fn source_closure(hier: &Hierarchy, own: &[u16]) -> Vec<u16> {
    let mut codes = vec![0u16; own.len()];
    for level in levels(hier.size()) {
        fill_level(hier, level, &mut codes, |m, codes| {
            let below = if level == Level::B(2) {
                0
            } else {
                children_max(hier, level, m, &codes)
            };
            own[index(hier, m)].max(below)
        });
    }
    codes
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::bitree::error_code::decode;
    use crate::hierarchy::{diamond, level_of, Placement};

    /// One own error at a split point: it reaches exactly its ancestors, and
    /// the codes grow up the tree.
    #[test]
    fn an_error_reaches_its_ancestors() {
        let (w, h) = (17usize, 17usize);
        let hier = Hierarchy::new(w as u32, h as u32);
        let mut own = vec![0u16; w * h];
        own[5 * w + 6] = encode_up(3.0);
        let d = source_closure(&hier, &own);
        // The root's centre reaches everything.
        assert!(decode(d[8 * w + 8]) >= 3.0);
        // A split point far from it does not.
        assert_eq!(d[14 * w + 14], 0);
        let n = hier.size();
        for y in 0..h as u32 {
            for x in 0..w as u32 {
                let Some(level) = level_of([x, y], n) else {
                    continue;
                };
                if level == Level::B(2) {
                    continue;
                }
                for t in diamond(level, [x, y], n).into_iter().flatten() {
                    if hier.place(&t) == Placement::Outside {
                        continue;
                    }
                    let (c0, c1) = t.children();
                    for q in [c0.mid(), c1.mid()] {
                        if hier.contains(q) {
                            let (a, b) = (
                                y as usize * w + x as usize,
                                q[1] as usize * w + q[0] as usize,
                            );
                            assert!(d[a] >= d[b], "{x},{y} below {q:?}");
                        }
                    }
                }
            }
        }
    }
}
